"""Mask textures of quad lights (``QuadLight.mask``): loading, checks, and the nearest-texel lookup that the
GPU methods and the references share.

A mask is a W × H grid of cells of constant emission over the quad: u along c1 → c2, v along c1 → c4, the
image's bottom-left texel at c1 (the texture convention). Nearest texel, not bilinear: every cell is then
an exact constant-radiance parallelogram, so the GPU grids, the forward pass's samples, the NumPy reference
and Mitsuba (``filter_type = "nearest"``) all integrate the same emitter; a bilinear mask would be a
different function for each of them near the cell edges.
"""

from __future__ import annotations

import numpy as np

from ..errors import ImageError, SceneError
from .model import QuadLight, Scene

#: Rec. 709 luminance weights (linear RGB), the mask value of a coloured texel
LUMINANCE = np.array([0.2126, 0.7152, 0.0722])


def mask_values(rgb: np.ndarray) -> np.ndarray:
    """(H, W) mask values of a linear RGB image: the channel itself where R = G = B (so 1 stays exactly 1),
    the luminance elsewhere. Alpha is not used: ``reflets.imageio.read_image`` drops it for every format."""
    rgb = np.asarray(rgb, dtype=np.float64)
    grey = (rgb[..., 0] == rgb[..., 1]) & (rgb[..., 1] == rgb[..., 2])
    return np.where(grey, rgb[..., 0], rgb @ LUMINANCE)


def load_mask(scene: Scene, index: int) -> np.ndarray | None:
    """The mask of light ``index`` as float32 (H, W) with **row 0 at v = 0** (the image's bottom row, flipped),
    or None. Raises SceneError naming the file and ``light[index].mask`` for a bad mask."""
    light = scene.light[index]
    if not isinstance(light, QuadLight) or light.mask is None:
        return None
    from ..imageio import read_image

    path = scene.resolve(light.mask)
    field = f"light[{index}].mask"
    try:
        rgb = read_image(path)
    except ImageError as exc:
        raise SceneError(exc.message, file=exc.file, field=field) from None
    if not np.all(np.isfinite(rgb)) or rgb.min() < 0.0 or rgb.max() > 1.0:
        raise SceneError(
            f"mask values must lie in [0, 1] (found {np.nanmin(rgb):.4g} … {np.nanmax(rgb):.4g}"
            f"{', NaN or inf' if not np.all(np.isfinite(rgb)) else ''})",
            file=path,
            field=field,
        )
    values = mask_values(rgb)
    if not np.any(values > 0.0):
        raise SceneError("mask is zero everywhere; the light would emit nothing", file=path, field=field)
    return np.ascontiguousarray(values[::-1], dtype=np.float32)


def load_masks(scene: Scene) -> dict[int, np.ndarray]:
    """Every mask of the scene, by light index."""
    masks = {i: load_mask(scene, i) for i, light in enumerate(scene.light) if getattr(light, "mask", None)}
    return {i: m for i, m in masks.items() if m is not None}


def quad_uv(light: QuadLight, points: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(u, v) of points in the quad's plane, p = c1 + u e1 + v e2 (dual basis: exact for skewed quads)."""
    c1, c2, c4 = (np.asarray(c, dtype=np.float64) for c in light.corners)
    e1, e2 = c2 - c1, c4 - c1
    g11, g12, g22 = e1 @ e1, e1 @ e2, e2 @ e2
    det = g11 * g22 - g12 * g12
    d = np.asarray(points, dtype=np.float64) - c1
    b1, b2 = d @ e1, d @ e2
    return (g22 * b1 - g12 * b2) / det, (g11 * b2 - g12 * b1) / det


def mask_lookup(mask: np.ndarray, u: np.ndarray, v: np.ndarray) -> np.ndarray:
    """Nearest-texel value at (u, v) of a mask from :func:`load_mask` (clamped at the edges)."""
    h, w = mask.shape
    col = np.clip(np.floor(np.asarray(u) * w), 0, w - 1).astype(np.int64)
    row = np.clip(np.floor(np.asarray(v) * h), 0, h - 1).astype(np.int64)
    return mask[row, col].astype(np.float64)
