"""Camera intrinsics (OpenCV's pinhole K and 5 distortion coefficients) and the OpenGL matrices built from them
and a pose — for any principal point (the document's projection is right only for a centred one), with the
axis flip between OpenCV's camera (x right, y down, z forward) and OpenGL's (x right, y up, z backward):
diag(1, −1, −1) [erratum: the document says OpenCV's x axis points left; it points right]. JSON:
``{"K": 3 × 3, "dist": [5], "size": [w, h]}``."""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np

from ..arguments import read_json
from ..errors import ArgumentError
from . import write_json

CV_TO_GL = np.diag([1.0, -1.0, -1.0])


@dataclass
class Intrinsics:
    K: np.ndarray
    dist: np.ndarray
    size: tuple[int, int]

    @classmethod
    def from_fov(cls, size: tuple[int, int], fov_y: float, principal: tuple[float, float] | None = None) -> Intrinsics:
        """A distortion-free camera of vertical field of view ``fov_y`` (degrees)."""
        f = 0.5 * size[1] / np.tan(np.radians(fov_y) / 2)
        cx, cy = principal if principal is not None else (0.5 * size[0], 0.5 * size[1])
        return cls(np.array([[f, 0, cx], [0, f, cy], [0, 0, 1.0]]), np.zeros(5), tuple(size))

    @classmethod
    def load(cls, path: str | Path) -> Intrinsics:
        def parse(data: dict) -> Intrinsics:
            K = np.asarray(data["K"], np.float64).reshape(3, 3)
            dist = np.asarray(data.get("dist", [0] * 5), np.float64).reshape(5)
            return cls(K, dist, (int(data["size"][0]), int(data["size"][1])))

        return read_json(path, "--intrinsics", "an intrinsics file", parse)

    def save(self, path: str | Path) -> Path:
        return write_json(path, {"K": self.K.tolist(), "dist": self.dist.tolist(), "size": list(self.size)})

    def gl_projection(self, near: float, far: float) -> np.ndarray:
        """The OpenGL projection matching K exactly (principal point anywhere, skew included): OpenCV puts pixel
        (0, 0)'s centre at coordinate 0, OpenGL at 0.5 — hence the half-pixel shift; row 0 at the top."""
        (fx, s, cx), (_, fy, cy) = self.K[0], self.K[1]
        cx, cy = cx + 0.5, cy + 0.5
        w, h = self.size
        return np.array(
            [
                [2 * fx / w, -2 * s / w, 1 - 2 * cx / w, 0],
                [0, 2 * fy / h, 2 * cy / h - 1, 0],
                [0, 0, -(far + near) / (far - near), -2 * far * near / (far - near)],
                [0, 0, -1, 0],
            ]
        )


def gl_view(R_world_to_cam: np.ndarray, t_world_to_cam: np.ndarray) -> np.ndarray:
    """The OpenGL view matrix of an OpenCV pose (x_cam = R x_world + t)."""
    view = np.eye(4)
    view[:3, :3] = CV_TO_GL @ R_world_to_cam
    view[:3, 3] = CV_TO_GL @ np.asarray(t_world_to_cam, np.float64)
    return view


def camera_fields(intrinsics: Intrinsics, R_world_to_cam: np.ndarray, t_world_to_cam: np.ndarray) -> dict:
    """The reflets scene camera (``[camera]`` fields) of a pose seen through ``intrinsics``: eye −Rᵀt, looking
    along OpenCV's +z, up −y; the vertical field of view from fy, the principal point as ``principal_offset``
    (fractions of the image from its centre; pixel centres at OpenCV's integers), fx / fy as ``pixel_aspect``.
    Lens distortion is not modelled by the renderer (undistort the photograph first); skew must be zero."""
    (fx, skew, cx), (_, fy, cy) = intrinsics.K[0], intrinsics.K[1]
    if abs(skew) > 1e-6 * fx:
        raise ArgumentError("the renderer's camera has no skew: K[0][1] must be 0", field="K")
    w, h = intrinsics.size
    R = np.asarray(R_world_to_cam, np.float64)
    eye = -R.T @ np.asarray(t_world_to_cam, np.float64)
    return {
        "position": eye.tolist(),
        "look_at": (eye + R[2]).tolist(),
        "up": (-R[1]).tolist(),
        "fov_y": float(np.degrees(2.0 * np.arctan(0.5 * h / fy))),
        "size": [int(w), int(h)],
        "principal_offset": [float((cx + 0.5) / w - 0.5), float((cy + 0.5) / h - 0.5)],
        "pixel_aspect": float(fx / fy),
    }
