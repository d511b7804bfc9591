"""The viewer's camera: an orbit about a target (yaw, pitch, distance) that pans, zooms, flies and frames, made
from a scene camera and turned back into one (``fields`` for ``Renderer.set_camera``)."""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

#: the orbit never quite reaches the poles (the view's up would flip)
MAX_PITCH = math.radians(89.0)


@dataclass
class OrbitCamera:
    """Eye = target + distance · (cos p sin y, sin p, cos p cos y): yaw y about +y, pitch p above the horizon."""

    target: np.ndarray
    distance: float
    yaw: float
    pitch: float
    fov_y: float
    size: tuple[int, int]
    up: tuple[float, float, float] = (0.0, 1.0, 0.0)
    #: the scene camera's own fields while the camera has not moved (its exact position, its own up vector)
    scene_fields: dict | None = field(default=None, repr=False)

    @classmethod
    def from_camera(cls, camera) -> OrbitCamera:
        eye = np.asarray(camera.position, np.float64)
        target = np.asarray(camera.look_at, np.float64)
        d = eye - target
        distance = float(np.linalg.norm(d))
        return cls(
            target=target,
            distance=distance,
            yaw=math.atan2(d[0], d[2]),
            pitch=math.asin(float(np.clip(d[1] / distance, -1.0, 1.0))),
            fov_y=float(camera.fov_y),
            size=tuple(camera.size),
            scene_fields={"position": list(camera.position), "look_at": list(camera.look_at), "up": list(camera.up)},
        )

    def eye(self) -> np.ndarray:
        cp = math.cos(self.pitch)
        offset = np.array([cp * math.sin(self.yaw), math.sin(self.pitch), cp * math.cos(self.yaw)])
        return self.target + self.distance * offset

    def fields(self) -> dict:
        """The camera as scene-camera fields (position, look_at, up)."""
        if self.scene_fields is not None:
            return dict(self.scene_fields)
        return {"position": self.eye().tolist(), "look_at": self.target.tolist(), "up": list(self.up)}

    def basis(self) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """(right, up, forward) unit vectors of the view."""
        forward = self.target - self.eye()
        forward /= np.linalg.norm(forward)
        right = np.cross(forward, self.up)
        right /= max(np.linalg.norm(right), 1e-12)
        return right, np.cross(right, forward), forward

    def pixel_size(self, depth: float | None = None) -> float:
        """World size of one pixel at ``depth`` along the view (default: the target's)."""
        depth = self.distance if depth is None else depth
        return 2.0 * depth * math.tan(math.radians(self.fov_y) / 2.0) / self.size[1]

    # ------------------------------------------------------------------ moves (each leaves the scene's camera)
    def _moved(self) -> None:
        self.scene_fields = None
        self.up = (0.0, 1.0, 0.0)

    def orbit(self, dyaw_degrees: float, dpitch_degrees: float) -> None:
        self._moved()
        self.yaw -= math.radians(dyaw_degrees)
        self.pitch = float(np.clip(self.pitch + math.radians(dpitch_degrees), -MAX_PITCH, MAX_PITCH))

    def look(self, dyaw_degrees: float, dpitch_degrees: float) -> None:
        """Turn the view about the eye (fly mode): the target moves, the eye stays."""
        eye = self.eye()
        self.orbit(dyaw_degrees, -dpitch_degrees)
        self.target = self.target + (eye - self.eye())

    def pan(self, dx_pixels: float, dy_pixels: float) -> None:
        """Move the target (and the eye) so that the scene follows the pointer."""
        self._moved()
        right, up, _ = self.basis()
        self.target = self.target + self.pixel_size() * (-dx_pixels * right + dy_pixels * up)

    def zoom(self, factor: float) -> None:
        """Divide the distance to the target by ``factor`` (> 1: closer)."""
        if not factor > 0:
            return
        self._moved()
        self.distance = max(self.distance / factor, 1e-4)

    def fly(self, forward: float = 0.0, right: float = 0.0, up: float = 0.0) -> None:
        """Move eye and target together along the view's axes (scene units)."""
        self._moved()
        r, u, f = self.basis()
        self.target = self.target + forward * f + right * r + up * u

    def frame(self, centre: np.ndarray, radius: float) -> None:
        """Look at a bounding sphere from the current direction, filling the view."""
        self._moved()
        self.target = np.asarray(centre, np.float64)
        half = math.radians(self.fov_y) / 2.0 * min(1.0, self.size[0] / self.size[1])
        self.distance = 1.1 * max(radius, 1e-6) / math.sin(half)
