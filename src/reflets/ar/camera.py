"""Camera intrinsics (OpenCV's pinhole K and 5 distortion coefficients) and the OpenGL matrices built from them
and a pose — for any principal point (the document's projection is right only for a centred one), with the
axis flip between OpenCV's camera (x right, y down, z forward) and OpenGL's (x right, y up, z backward):
diag(1, −1, −1) [erratum: the document says OpenCV's x axis points left; it points right]. JSON:
``{"K": 3 × 3, "dist": [5], "size": [w, h]}``.

A camera.json is checked where it is read, for what the tracking and the renderer take: K = [[fx, s, cx],
[0, fy, cy], [0, 0, 1]] with fx, fy > 0 (so K is invertible) and a field of view a pinhole can have, fx / fy and
the principal point within the renderer's pixel aspect and principal offset, OpenCV's distortion lengths with
the coefficients beyond k3 zero (the capture models k1 k2 p1 p2 k3), a size a frame may have."""

from __future__ import annotations

import math
from dataclasses import dataclass
from pathlib import Path
from typing import Annotated

import numpy as np
from pydantic import Field, ValidationInfo, field_validator

from ..arguments import read_model, validated
from ..errors import ArgumentError
from ..quantities import JsonNumber as Number
from ..scene.model import MAX_IMAGE_SIDE
from . import InputFile, write_json

CV_TO_GL = np.diag([1.0, -1.0, -1.0])

#: the largest focal length (and skew) in pixels: 10⁷, a field of view of 0.1° across the widest image
MAX_FOCAL = 1e7
#: the widest field of view across the image's width or height: a pinhole K describes less than 180°
MAX_FOV_DEGREES = 175.0
#: the lengths of OpenCV's distortion vector: k1 k2 p1 p2 [k3 [k4 k5 k6 [s1 s2 s3 s4 [τx τy]]]]
DIST_LENGTHS = (4, 5, 8, 12, 14)
#: fx / fy, open interval: the renderer's pixel aspect (reflets.scene.model.Camera.pixel_aspect)
PIXEL_ASPECT = (0.1, 10.0)
#: how far the principal point may be from the image's centre, in widths and heights: the renderer's
#: principal_offset (reflets.scene.model.Camera), half an image outside its edges
MAX_PRINCIPAL_OFFSET = 1.0

Side = Annotated[int, Field(strict=True, ge=1, le=MAX_IMAGE_SIDE)]
Row = tuple[Number, Number, Number]


class _CameraFile(InputFile):
    """camera.json as Intrinsics.save writes it (``size`` first: K's checks use it)."""

    size: tuple[Side, Side]
    K: tuple[Row, Row, Row]
    dist: list[Number] = Field(default_factory=lambda: [0.0] * 5, max_length=max(DIST_LENGTHS))

    @field_validator("size")
    @classmethod
    def _a_frame(cls, size: tuple[int, int]) -> tuple[int, int]:
        from .images import FRAME_LIMITS, fits_a_frame

        if not fits_a_frame(*size):
            raise ValueError(f"{size[0]}x{size[1]} is {size[0] * size[1]:,} pixels; {FRAME_LIMITS}")
        return size

    @field_validator("K")
    @classmethod
    def _pinhole(cls, K: tuple, info: ValidationInfo) -> tuple:
        (fx, skew, cx), (k10, fy, cy), bottom = K
        if k10 != 0 or tuple(bottom) != (0, 0, 1):
            raise ValueError(f"the bottom row is {list(bottom)} and K[1][0] {k10:g}; OpenCV's camera matrix is "
                             "[[fx, s, cx], [0, fy, cy], [0, 0, 1]]")  # fmt: skip
        for name, f in (("fx", fx), ("fy", fy)):
            if not 0 < f <= MAX_FOCAL:
                raise ValueError(f"{name} is {f:g}; a focal length is more than 0 and at most {MAX_FOCAL:g} pixels")
        if abs(skew) > MAX_FOCAL:
            raise ValueError(f"the skew K[0][1] is {skew:g}; at most {MAX_FOCAL:g} in magnitude")
        if not PIXEL_ASPECT[0] < fx / fy < PIXEL_ASPECT[1]:
            raise ValueError(f"fx / fy is {fx / fy:g}; the pixel aspect is between {PIXEL_ASPECT[0]:g} and "
                             f"{PIXEL_ASPECT[1]:g}")  # fmt: skip
        if "size" not in info.data:  # refused already
            return K
        for name, f, c, n in (("x", fx, cx, info.data["size"][0]), ("y", fy, cy, info.data["size"][1])):
            fov = math.degrees(2 * math.atan(0.5 * n / f))
            if fov > MAX_FOV_DEGREES:
                least = 0.5 * n / math.tan(math.radians(MAX_FOV_DEGREES / 2))
                raise ValueError(f"f{name} = {f:g} gives a {fov:.1f}° field of view across {n} pixels; at most "
                                 f"{MAX_FOV_DEGREES:g}° (f{name} ≥ {least:.3g})")  # fmt: skip
            if abs((c + 0.5) / n - 0.5) > MAX_PRINCIPAL_OFFSET:
                low, high = (0.5 - MAX_PRINCIPAL_OFFSET) * n - 0.5, (0.5 + MAX_PRINCIPAL_OFFSET) * n - 0.5
                raise ValueError(f"the principal point's c{name} = {c:g} is far outside the image; c{name} is from "
                                 f"{low:g} to {high:g} ({n} pixels)")  # fmt: skip
        return K

    @field_validator("dist")
    @classmethod
    def _five(cls, dist: list[float]) -> list[float]:
        """OpenCV's lengths, as k1 k2 p1 p2 k3 (a 4-vector's k3 is 0, as OpenCV reads it)."""
        if len(dist) not in DIST_LENGTHS:
            raise ValueError(f"{len(dist)} coefficients; OpenCV's lens model has {', '.join(map(str, DIST_LENGTHS))} "
                             "(k1 k2 p1 p2 [k3 ...])")  # fmt: skip
        if any(dist[5:]):
            raise ValueError("the coefficients after k3 (k4 ... τy) are not modelled by the capture; they must be 0 "
                             "(calibrate with k1 k2 p1 p2 k3)")  # fmt: skip
        return [*dist[:5], 0.0][:5]


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
        """A camera.json, checked (:class:`_CameraFile`): any problem is one ArgumentError naming the file."""
        return cls._of(read_model(_CameraFile, path, field="--intrinsics", what="camera intrinsics (camera.json)"))

    @classmethod
    def checked(cls, K, dist, size) -> Intrinsics:
        """Intrinsics computed elsewhere (a calibration), checked as a camera.json is (ArgumentError)."""
        data = {"K": np.asarray(K).tolist(), "dist": np.asarray(dist).ravel().tolist(), "size": [int(v) for v in size]}
        return cls._of(validated(_CameraFile, data))

    @classmethod
    def _of(cls, data: _CameraFile) -> Intrinsics:
        return cls(np.array(data.K, np.float64), np.array(data.dist, np.float64), tuple(data.size))

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
