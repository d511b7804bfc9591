"""The document's soft shadows of a virtual object on the real ground (004 §4.3), from its sphere decomposition
(``spheres.py``): a sphere of radius r at distance D from a ground point, seen at an angle ω from the ground's
normal, hides the spherical cap of half-angle α (sin α = r / D), whose cosine-weighted solid angle is
π sin²α cos ω when the cap is above the horizon [erratum: eq 4.3.1.3 drops the π]. Under a uniform sky the
ground keeps the fraction 1 − sin²α cos ω of its light; spheres combine as Π (1 − a_i) (the document's code,
where the text says a sum)."""

from __future__ import annotations

import numpy as np


def sphere_occlusion(points: np.ndarray, normal, centres: np.ndarray, radii: np.ndarray) -> np.ndarray:
    """The fraction of a uniform sky's cosine-weighted light that the spheres leave to ground points (N, 3) of
    normal ``normal``: Π_i (1 − sin²α_i cos ω_i) (a point inside a sphere, or under it with the cap cut by
    the horizon, keeps the clamped value)."""
    normal = np.asarray(normal, np.float64) / np.linalg.norm(normal)
    visible = np.ones(len(points))
    for centre, radius in zip(np.atleast_2d(centres), np.atleast_1d(radii), strict=True):
        d = centre - points
        distance = np.linalg.norm(d, axis=1)
        sin2 = np.clip(radius / np.maximum(distance, 1e-12), 0.0, 1.0) ** 2
        cos_w = np.clip(d @ normal / np.maximum(distance, 1e-12), 0.0, 1.0)
        visible *= 1.0 - sin2 * cos_w
    return visible
