"""Direction sets and hemisphere integrals for BRDF tests (local frame, normal +z)."""

from __future__ import annotations

import numpy as np


def upper_hemisphere(rng: np.random.Generator, n: int) -> np.ndarray:
    v = rng.normal(size=(n, 3))
    v /= np.linalg.norm(v, axis=1, keepdims=True)
    v[:, 2] = np.abs(v[:, 2]) + 1e-6
    return v / np.linalg.norm(v, axis=1, keepdims=True)


def hemisphere_albedo(material, wo: np.ndarray, n: int = 400) -> np.ndarray:
    """∫ f(wo, wi) cosθi dωi by a midpoint rule in (cos²θ, φ) — exact for Lambert, fine for smooth lobes."""
    u = (np.arange(n) + 0.5) / n
    cos2, phi = np.meshgrid(u, 2 * np.pi * u, indexing="ij")
    cos = np.sqrt(cos2)
    sin = np.sqrt(1 - cos2)
    wi = np.stack([sin * np.cos(phi), sin * np.sin(phi), cos], axis=-1).reshape(-1, 3)
    f = material.eval(np.broadcast_to(wo, wi.shape), wi)
    return f.mean(axis=0) * np.pi  # dω cosθ = ½ d(cos²θ) dφ → π · mean over the unit square
