"""Equirectangular environment maps: loading, rotation, and a deterministic directional-sample grid."""

from __future__ import annotations

import numpy as np

from ..equirect import equirect_direction, equirect_uv, rotation_y, row_solid_angles
from ..errors import ImageError, SceneError
from ..quantities import MAX_MAGNITUDE
from .model import EnvironmentLight, Scene


def load_environment(scene: Scene) -> np.ndarray | None:
    """The scene's environment image (H, W, 3) float32 times its ``scale``, or None."""
    light = scene.environment
    if light is None:
        return None
    from ..imageio import read_image

    index = scene.light.index(light)
    try:
        image = read_image(scene.resolve(light.file))
    except ImageError as exc:
        raise SceneError(exc.message, file=exc.file, field=f"light[{index}].file") from None
    if not np.all(np.isfinite(image)) or np.any(image < 0):
        raise SceneError("environment image has negative or non-finite pixels", file=scene.resolve(light.file))
    brightest = float(image.max(initial=0.0)) * light.scale
    if brightest > MAX_MAGNITUDE:
        raise SceneError(f"pixels up to {image.max():.3g} × scale {light.scale:.3g} exceed {MAX_MAGNITUDE:.0e}",
                         file=scene.resolve(light.file), field=f"light[{index}].scale")  # fmt: skip
    return (image * np.float32(light.scale)).astype(np.float32)


def environment_grid(image: np.ndarray, light: EnvironmentLight, grid: tuple[int, int] = (32, 16)):
    """The map as ``grid`` = (nu, nv) distant lights: world directions (K, 3) and radiance × solid angle (K, 3).

    Each cell's radiance is the solid-angle-weighted mean of its pixels, so the sum over cells is the exact
    integral of the map; only the direction inside a cell is approximated (fine for diffuse and broad
    lobes, too coarse for sharp reflections — those belong to dedicated techniques).
    """
    h, w, _ = image.shape
    nu, nv = grid
    pix_omega = row_solid_angles(h, w)
    weighted = image.astype(np.float64) * pix_omega[:, None, None]
    row_of = np.minimum((np.arange(h) * nv) // h, nv - 1)
    col_of = np.minimum((np.arange(w) * nu) // w, nu - 1)
    power = np.zeros((nv, nu, 3))
    np.add.at(power, (row_of[:, None], col_of[None, :]), weighted)
    # Direction: solid-angle centroid of the cell's pixels.
    u_pix = (np.arange(w) + 0.5) / w
    v_pix = (np.arange(h) + 0.5) / h
    dirs_pix = equirect_direction(u_pix[None, :], v_pix[:, None]) * pix_omega[:, None, None]
    centroid = np.zeros((nv, nu, 3))
    np.add.at(centroid, (row_of[:, None], col_of[None, :]), np.broadcast_to(dirs_pix, (h, w, 3)))
    centroid /= np.maximum(np.linalg.norm(centroid, axis=-1, keepdims=True), 1e-30)
    world = centroid.reshape(-1, 3) @ rotation_y(light.rotate_y).T
    return world.astype(np.float32), power.reshape(-1, 3).astype(np.float32)


def lookup(image: np.ndarray, light: EnvironmentLight, world_dirs: np.ndarray) -> np.ndarray:
    """Radiance of the map along world directions, bilinear like the GPU's LINEAR sampler (texel centres at
    (i + ½)/size, u wraps, v clamps)."""
    local = world_dirs @ rotation_y(light.rotate_y)  # = R^T d for row vectors
    u, v = equirect_uv(local)
    h, w, _ = image.shape
    x = u * w - 0.5
    y = np.clip(v * h - 0.5, 0.0, h - 1.0)
    x0 = np.floor(x).astype(np.int64)
    y0 = np.minimum(np.floor(y).astype(np.int64), max(h - 2, 0))
    fx, fy = (x - x0)[..., None], (y - y0)[..., None]
    x0w, x1w = x0 % w, (x0 + 1) % w
    y1 = np.minimum(y0 + 1, h - 1)
    img = image.astype(np.float64)
    top = img[y0, x0w] * (1 - fx) + img[y0, x1w] * fx
    bottom = img[y1, x0w] * (1 - fx) + img[y1, x1w] * fx
    return top * (1 - fy) + bottom * fy
