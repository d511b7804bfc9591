"""Camera rays and projection in NumPy, with the renderer's pixel convention.

Pixel (row i, column j) samples the ray through the image-plane point ((j + ½)/W, (i + ½)/H) measured
from the top-left corner; ``fov_y`` is the full vertical field of view. The GPU path rasterises pixel
centres, so both agree exactly; references (NumPy, Mitsuba) use these functions.
"""

from __future__ import annotations

import numpy as np

from .model import Camera
from .transform import look_at, perspective


def camera_basis(camera: Camera) -> np.ndarray:
    """Rows: right, up, backward (−forward) unit vectors in world space."""
    return look_at(camera.position, camera.look_at, camera.up)[:3, :3]


def local_directions(camera: Camera, columns, rows, width: int, height: int) -> np.ndarray:
    """Camera-space directions (…, 3), not normalised (z = −1), through continuous pixel positions (x = columns,
    y = rows from the top-left corner): the principal point at the image centre moved by
    ``principal_offset``, the horizontal focal length ``pixel_aspect`` times the vertical one."""
    tan_half = np.tan(np.radians(camera.fov_y) / 2.0)
    ox, oy = camera.principal_offset
    x = (2.0 * np.asarray(columns, np.float64) / width - 1.0 - 2.0 * ox) * tan_half * width / height
    y = (1.0 - 2.0 * np.asarray(rows, np.float64) / height + 2.0 * oy) * tan_half
    x = x / camera.pixel_aspect
    return np.stack(np.broadcast_arrays(x, y, -np.ones((1,) * np.ndim(x))), axis=-1)


def pixel_rays(camera: Camera, size: tuple[int, int] | None = None, offsets=(0.5, 0.5)):
    """Ray origin (3,) and unit directions (H, W, 3) through pixel positions (j + ox, i + oy)."""
    width, height = size or camera.size
    local = local_directions(
        camera, (np.arange(width) + offsets[0])[None, :], (np.arange(height) + offsets[1])[:, None], width, height
    )
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
    ox, oy = camera.principal_offset
    with np.errstate(divide="ignore", invalid="ignore"):
        ndc_x = local[..., 0] * camera.pixel_aspect / (depth * tan_half * width / height)
        ndc_y = local[..., 1] / (depth * tan_half)
    px = np.stack([(ndc_x + 1.0 + 2.0 * ox) * 0.5 * width, (1.0 - ndc_y + 2.0 * oy) * 0.5 * height], axis=-1)
    px[depth <= 0] = np.nan
    return px


def projection_matrix(
    camera: Camera, width: int, height: int, near: float, far: float | None = None
) -> np.ndarray:
    """The scene camera's projection (row-major) for reversed-Z depth (``reflets.gpu.depth``): clip z in [0, 1],
    depth = near / distance (1 at ``near``, 0 at ``far`` or, with ``far=None``, at infinity); the horizontal
    scale of ``pixel_aspect`` and the principal point moved by ``principal_offset`` — the same pixels as
    ``pixel_rays``."""
    proj = perspective(camera.fov_y, width / height / camera.pixel_aspect, near, 2.0 * near)  # x, y rows only
    proj[0, 2] = -2.0 * camera.principal_offset[0]
    proj[1, 2] = 2.0 * camera.principal_offset[1]
    if far is None:
        proj[2, 2], proj[2, 3] = 0.0, near
    else:
        proj[2, 2], proj[2, 3] = near / (far - near), near * far / (far - near)
    return proj
