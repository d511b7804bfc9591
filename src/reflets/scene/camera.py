"""Camera rays and projection in NumPy, with the renderer's pixel convention.

Pixel (row i, column j) samples the ray through the image-plane point ((j + ½)/W, (i + ½)/H) measured
from the top-left corner; ``fov_y`` is the full vertical field of view. The GPU path rasterises pixel
centres, so both agree exactly; references (NumPy, Mitsuba) use these functions.

An orthographic camera's rays are parallel (the view direction) and start on the camera's plane, over a window
``ortho_height`` high; its shaders get a view vector from :func:`view_eye`, an eye point so far back that
``normalize(eye − p)`` is the view direction to float32's precision.
"""

from __future__ import annotations

import numpy as np

from .model import Camera
from .transform import look_at, perspective


def camera_basis(camera: Camera) -> np.ndarray:
    """Rows: right, up, backward (−forward) unit vectors in world space."""
    return look_at(camera.position, camera.look_at, camera.up)[:3, :3]


#: how far behind an orthographic camera its shaders' eye point lies, in units of the view window's height: the
#: view vector then differs from the view direction by at most 1e-7 rad (float32's own precision)
ORTHO_EYE_DISTANCE = 1e7


def view_eye(camera: Camera) -> tuple[float, float, float]:
    """The point shaders take view vectors towards (``u_eye``): the camera's position, or for an orthographic
    camera a point :data:`ORTHO_EYE_DISTANCE` window heights behind it on its axis."""
    eye = np.asarray(camera.position, np.float64)
    if camera.orthographic:
        eye = eye + camera_basis(camera)[2] * ORTHO_EYE_DISTANCE * max(camera.ortho_height, 1.0)
    return tuple(float(c) for c in eye)


def _image_plane(camera: Camera, columns, rows, width: int, height: int) -> tuple[np.ndarray, np.ndarray]:
    """(x, y) of continuous pixel positions on the camera's image plane: at depth 1 (perspective) or in scene
    units (orthographic); the principal point moved by ``principal_offset``, x scaled by 1 / ``pixel_aspect``."""
    half = camera.ortho_height / 2.0 if camera.orthographic else np.tan(np.radians(camera.fov_y) / 2.0)
    ox, oy = camera.principal_offset
    x = (2.0 * np.asarray(columns, np.float64) / width - 1.0 - 2.0 * ox) * half * width / height
    y = (1.0 - 2.0 * np.asarray(rows, np.float64) / height + 2.0 * oy) * half
    return x / camera.pixel_aspect, y


def camera_rays(camera: Camera, columns, rows, width: int, height: int) -> tuple[np.ndarray, np.ndarray]:
    """World ray origins and unit directions (…, 3) through continuous pixel positions (x = columns, y = rows
    from the top-left corner), for either projection; the origin is the camera's position (3,) for a perspective
    camera (it broadcasts against the directions), one point per ray for an orthographic one."""
    basis = camera_basis(camera)
    x, y = np.broadcast_arrays(*_image_plane(camera, columns, rows, width, height))
    position = np.asarray(camera.position, np.float64)
    if camera.orthographic:
        origins = position + x[..., None] * basis[0] + y[..., None] * basis[1]
        return origins, np.broadcast_to(-basis[2], origins.shape).copy()
    dirs = np.stack([x, y, -np.ones_like(x)], axis=-1) @ basis
    dirs /= np.linalg.norm(dirs, axis=-1, keepdims=True)
    return position, dirs


def pixel_rays(camera: Camera, size: tuple[int, int] | None = None, offsets=(0.5, 0.5)):
    """Ray origin and unit directions (H, W, 3) through pixel positions (j + ox, i + oy); the origin is the
    camera's position (3,) for a perspective camera, one point per pixel (H, W, 3) for an orthographic one."""
    width, height = size or camera.size
    columns, rows = (np.arange(width) + offsets[0])[None, :], (np.arange(height) + offsets[1])[:, None]
    return camera_rays(camera, columns, rows, width, height)


def project(camera: Camera, points: np.ndarray, size: tuple[int, int] | None = None) -> np.ndarray:
    """Continuous pixel coordinates (x = column, y = row) of world points; the centre of pixel (i, j)
    is (j + ½, i + ½). Points behind the camera get NaN."""
    width, height = size or camera.size
    rel = np.asarray(points, dtype=np.float64) - np.asarray(camera.position, dtype=np.float64)
    local = rel @ camera_basis(camera).T
    depth = -local[..., 2]
    ox, oy = camera.principal_offset
    # an orthographic camera divides by a constant window instead of the depth
    half = camera.ortho_height / 2.0 if camera.orthographic else np.tan(np.radians(camera.fov_y) / 2.0)
    scale = np.ones_like(depth) if camera.orthographic else depth
    with np.errstate(divide="ignore", invalid="ignore"):
        ndc_x = local[..., 0] * camera.pixel_aspect / (scale * half * width / height)
        ndc_y = local[..., 1] / (scale * half)
    px = np.stack([(ndc_x + 1.0 + 2.0 * ox) * 0.5 * width, (1.0 - ndc_y + 2.0 * oy) * 0.5 * height], axis=-1)
    px[depth <= 0] = np.nan
    return px


def projection_matrix(
    camera: Camera, width: int, height: int, near: float, far: float | None = None
) -> np.ndarray:
    """The scene camera's projection (row-major) for reversed-Z depth (``reflets.gpu.depth``): clip z in [0, 1],
    depth = near / distance (1 at ``near``, 0 at ``far`` or, with ``far=None``, at infinity); the horizontal
    scale of ``pixel_aspect`` and the principal point moved by ``principal_offset`` — the same pixels as
    ``pixel_rays``. An orthographic camera needs a finite ``far``: depth falls linearly from 1 at ``near`` to 0
    at ``far``."""
    if camera.orthographic:
        if far is None:
            raise ValueError("an orthographic projection needs a finite far distance")
        half_height = camera.ortho_height / 2.0
        proj = np.zeros((4, 4))
        proj[0, 0] = camera.pixel_aspect / (half_height * width / height)
        proj[1, 1] = 1.0 / half_height
        proj[0, 3] = 2.0 * camera.principal_offset[0]  # (the perspective rows divide −z by w = −z: the same)
        proj[1, 3] = -2.0 * camera.principal_offset[1]
        proj[2, 2], proj[2, 3] = 1.0 / (far - near), far / (far - near)
        proj[3, 3] = 1.0
        return proj
    proj = perspective(camera.fov_y, width / height / camera.pixel_aspect, near, 2.0 * near)  # x, y rows only
    proj[0, 2] = -2.0 * camera.principal_offset[0]
    proj[1, 2] = 2.0 * camera.principal_offset[1]
    if far is None:
        proj[2, 2], proj[2, 3] = 0.0, near
    else:
        proj[2, 2], proj[2, 3] = near / (far - near), near * far / (far - near)
    return proj
