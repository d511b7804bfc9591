"""Light sampling for the reference: uniform points on polygon lights, and an importance-sampled
environment map (piecewise-constant 2D distribution in (u, v))."""

from __future__ import annotations

import numpy as np

from ..equirect import equirect_direction, equirect_uv, rotation_y
from ..scene.environment import lookup
from ..scene.lightmask import mask_lookup, quad_uv
from ..scene.model import EnvironmentLight, PolygonLight, QuadLight


class PolygonSampler:
    """Uniform area sampling of a planar convex polygon (fan triangles chosen ∝ area); pdf_A = 1 / area.

    A quad's ``mask`` (from ``scene.lightmask.load_mask``) multiplies the emission at each point
    (:meth:`radiance_at`); the area sampling stays uniform over the whole quad, so it stays unbiased."""

    def __init__(self, light: QuadLight | PolygonLight, mask: np.ndarray | None = None):
        self.light = light
        self.mask = mask
        poly = light.polygon()
        self.a = poly[0]
        self.b, self.c = poly[1:-1], poly[2:]
        areas = 0.5 * np.linalg.norm(np.cross(self.b - self.a, self.c - self.a), axis=-1)
        self.area = float(areas.sum())
        self.cdf = np.cumsum(areas) / self.area
        n = np.sum(np.cross(poly, np.roll(poly, -1, axis=0)), axis=0)
        self.normal = n / np.linalg.norm(n)
        self.radiance = np.asarray(light.radiance, dtype=np.float64)
        self.two_sided = light.two_sided

    def sample(self, u1: np.ndarray, u2: np.ndarray) -> np.ndarray:
        """Points on the polygon; u1 picks the triangle then is re-stretched (one stratified 2D sample)."""
        k = np.minimum(np.searchsorted(self.cdf, u1, side="right"), len(self.cdf) - 1)
        lo = np.where(k > 0, self.cdf[np.maximum(k - 1, 0)], 0.0)
        u1 = np.clip((u1 - lo) / (self.cdf[k] - lo), 0.0, 1.0)
        s = np.sqrt(u1)  # uniform in a triangle (Osada et al. 2002)
        return (1 - s)[:, None] * self.a + (s * (1 - u2))[:, None] * self.b[k] + (s * u2)[:, None] * self.c[k]

    def radiance_at(self, points: np.ndarray) -> np.ndarray:
        """(N, 3) emitted radiance at points on the light (the mask's nearest texel times the radiance)."""
        if self.mask is None:
            return np.broadcast_to(self.radiance, (len(points), 3))
        return mask_lookup(self.mask, *quad_uv(self.light, points))[:, None] * self.radiance

    def emitted(self, direction_to_light: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """(cosθ at the light, mask of rays that see the emitting side)."""
        cos_l = -direction_to_light @ self.normal
        if self.two_sided:
            cos_l = np.abs(cos_l)
        return cos_l, cos_l > 0


class EnvironmentSampler:
    """Importance sampling of an equirectangular map by luminance × sinθ.

    The map is evaluated bilinearly (as the GPU samples it); so that the density is positive wherever the
    bilinear radiance is, each texel's weight is the maximum luminance of its 3×3 neighbourhood.
    """

    def __init__(self, image: np.ndarray, light: EnvironmentLight):
        self.image, self.light = image, light
        h, w, _ = image.shape
        self.h, self.w = h, w
        lum = image.astype(np.float64) @ np.array([0.2126, 0.7152, 0.0722])
        padded = np.pad(lum, 1, mode="edge")
        padded[:, 0], padded[:, -1] = padded[:, -2], padded[:, 1]  # u wraps around
        dilated = np.max(
            [padded[1 + dy : h + 1 + dy, 1 + dx : w + 1 + dx] for dy in (-1, 0, 1) for dx in (-1, 0, 1)], axis=0
        )
        sin_theta = np.sin(np.pi * (np.arange(h) + 0.5) / h)
        weights = dilated * sin_theta[:, None] + 1e-12 * sin_theta[:, None]  # never exactly zero
        self.pmf = weights / weights.sum()
        self.row_cdf = np.cumsum(self.pmf.sum(axis=1))
        self.row_cdf /= self.row_cdf[-1]
        self.col_cdf = np.cumsum(self.pmf, axis=1)
        self.col_cdf /= self.col_cdf[:, -1:]
        self._shifted_cdf = (np.arange(h)[:, None] + self.col_cdf).ravel()
        self.rotation = rotation_y(light.rotate_y)

    def sample(self, u1: np.ndarray, u2: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """World directions and their solid-angle pdf."""
        row = np.minimum(np.searchsorted(self.row_cdf, u1, side="right"), self.h - 1)
        # Per-row inverse CDFs in one search: row r's conditional CDF is shifted to [r, r + 1].
        flat = np.searchsorted(self._shifted_cdf, row + np.minimum(u2, np.nextafter(1.0, 0.0)), side="right")
        col = np.clip(flat - row * self.w, 0, self.w - 1)
        # Uniform position inside the texel (remapped from the same numbers keeps stratification).
        row_lo = np.where(row > 0, self.row_cdf[np.maximum(row - 1, 0)], 0.0)
        fv = np.clip((u1 - row_lo) / np.maximum(self.row_cdf[row] - row_lo, 1e-300), 0.0, 1.0)
        col_lo = np.where(col > 0, self.col_cdf[row, np.maximum(col - 1, 0)], 0.0)
        fu = np.clip((u2 - col_lo) / np.maximum(self.col_cdf[row, col] - col_lo, 1e-300), 0.0, 1.0)
        u, v = (col + fu) / self.w, (row + fv) / self.h
        local = equirect_direction(u, v)
        return local @ self.rotation.T, self.pdf_local(local)

    def pdf_local(self, local: np.ndarray) -> np.ndarray:
        u, v = equirect_uv(local)
        row = np.minimum((v * self.h).astype(np.int64), self.h - 1)
        col = np.minimum((u * self.w).astype(np.int64), self.w - 1)
        sin_theta = np.sqrt(np.maximum(0.0, 1.0 - local[..., 1] ** 2))
        return self.pmf[row, col] * self.h * self.w / (2.0 * np.pi**2 * np.maximum(sin_theta, 1e-12))

    def pdf(self, world_dirs: np.ndarray) -> np.ndarray:
        return self.pdf_local(world_dirs @ self.rotation)

    def radiance(self, world_dirs: np.ndarray) -> np.ndarray:
        return lookup(self.image, self.light, world_dirs)
