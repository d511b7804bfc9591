"""Camera rays and projection in NumPy, with the renderer's pixel convention.

Pixel (row i, column j) samples the ray through the image-plane point ((j + ½)/W, (i + ½)/H) measured
from the top-left corner; ``fov_y`` is the full vertical field of view. The GPU path rasterises pixel
centres, so both agree exactly; references (NumPy, Mitsuba) use these functions.
"""

from __future__ import annotations

import numpy as np

from .model import Camera
from .transform import look_at


def camera_basis(camera: Camera) -> np.ndarray:
    """Rows: right, up, backward (−forward) unit vectors in world space."""
    return look_at(camera.position, camera.look_at, camera.up)[:3, :3]


def pixel_rays(camera: Camera, size: tuple[int, int] | None = None, offsets=(0.5, 0.5)):
    """Ray origin (3,) and unit directions (H, W, 3) through pixel positions (j + ox, i + oy)."""
    width, height = size or camera.size
    tan_half = np.tan(np.radians(camera.fov_y) / 2.0)
    aspect = width / height
    x = (2.0 * (np.arange(width) + offsets[0]) / width - 1.0) * tan_half * aspect
    y = (1.0 - 2.0 * (np.arange(height) + offsets[1]) / height) * tan_half
    local = np.stack(np.broadcast_arrays(x[None, :], y[:, None], -np.ones((1, 1))), axis=-1)
    dirs = local @ camera_basis(camera)  # local coordinates → world (rows of the basis are the axes)
    dirs /= np.linalg.norm(dirs, axis=-1, keepdims=True)
    return np.asarray(camera.position, dtype=np.float64), dirs


def project(camera: Camera, points: np.ndarray, size: tuple[int, int] | None = None) -> np.ndarray:
    """Continuous pixel coordinates (x = column, y = row) of world points; the centre of pixel (i, j)
    is (j + ½, i + ½). Points behind the camera get NaN."""
    width, height = size or camera.size
    rel = np.asarray(points, dtype=np.float64) - np.asarray(camera.position, dtype=np.float64)
    local = rel @ camera_basis(camera).T
    depth = -local[..., 2]
    tan_half = np.tan(np.radians(camera.fov_y) / 2.0)
    with np.errstate(divide="ignore", invalid="ignore"):
        ndc_x = local[..., 0] / (depth * tan_half * width / height)
        ndc_y = local[..., 1] / (depth * tan_half)
    px = np.stack([(ndc_x + 1.0) * 0.5 * width, (1.0 - ndc_y) * 0.5 * height], axis=-1)
    px[depth <= 0] = np.nan
    return px
