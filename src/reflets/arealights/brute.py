"""``brute``: the area-light document's first method (§2.3, eq 2.8) — a fixed midpoint grid per light.

For every polygon light and shaded point x on its emitting side (V1), the unoccluded integral
``∫ f(wo, wi) L cosθx cosθy / r² dA`` is replaced by the midpoint rule:

- **parallelogram** lights (the document's lights): an n×n grid at u, v ∈ {(k + ½)/n}, each sample weighted
  by A/n² (S(u, v) = c1 + u e1 + v e2, exactly the document's loop);
- **other convex polygons**: each fan triangle (v0, vk, vk+1) is split into n² congruent sub-triangles
  sampled at their centroids, weight = sub-triangle area. This covers the exact shape (no mask texture,
  so none of the document's aliasing, its Fig 3.2) with the same O(1/n²) error order; a polygon of m
  vertices costs (m − 2) n² samples.

Per sample: one-sided lights contribute only where cosθy > 0, two-sided ones with |cosθy|; samples below
the horizon of x (cosθx ≤ 0, the document's V2) contribute nothing. The unoccluded integral (the document's
setting; shadows: the soft-shadow ratio; compare unoccluded scenes with ``reflets.reference(scene,
visibility=False)``). ``output="samples"``
counts every grid point of every light whose V1 test passed (n² per parallelogram light).

Accuracy: the error decays as O(1/n²) for smooth integrands (``tests/arealights/test_brute.py``: on a
Lambert plane under the document's unit light, relative MSE mean((a − b)²)/mean(b²) against the exact
polygon irradiance: 9.3·10⁻⁴, 5.4·10⁻⁵, 3.3·10⁻⁶, 2.0·10⁻⁷, 1.3·10⁻⁸ for n = 2, 4, 8, 16, 32 — ÷16 per
doubling, the O(1/n⁴) of a squared O(1/n²) error; a regular pentagon light: 4.6·10⁻⁴ … 1.0·10⁻⁷ for
n = 2 … 16, the same order). Sharp lobes need n large enough for the grid spacing seen from x to be finer
than the lobe: otherwise the light shows as a grid of point-light halos (the document's Fig 2.3).
``adaptive`` chooses n per pixel; ``biased`` samples only the part of the light inside the lobe.

Parameters: ``grid`` — n, samples per light side (default 8, 1 … 128; n = 64 … 128 is a converged reference
for unoccluded scenes, e.g. 1.1·10⁻⁷ relative MSE between 64² and 128² for Phong e = 500).

Platform limit (llvmpipe): Mesa's software rasteriser ends a shader loop after 65535 iterations
(``LP_MAX_TGSI_LOOP_ITERATIONS``); measured here, the count runs over the whole fragment invocation, all
lights together, and the sum is silently truncated: keep (number of lights) × n² ≤ 65535 there (one light
at 255² is right, at 256² 0.7 % dark; five lights at 128² 21 % dark). GPUs have no such limit. Every method
that loops over samples is exposed (the forward pass's ``area_samples`` loop too).
"""

from __future__ import annotations

from typing import ClassVar

from pydantic import Field

from ..techniques.base import register_technique
from .base import SHADERS, AreaLightParams, AreaLightTechnique


class BruteParams(AreaLightParams):
    """Parameters of ``brute``."""

    grid: int = Field(
        8,
        ge=1,
        le=128,
        description="n: n×n midpoint samples per parallelogram light (n² per fan triangle of other polygons)",
    )


@register_technique
class Brute(AreaLightTechnique):
    """Fixed n×n midpoint grid per light (eq 2.8)."""

    name: ClassVar[str] = "brute"
    summary: ClassVar[str] = "area lights: brute-force n×n midpoint grid per light (Meunier 2007 §2.3)"
    Params: ClassVar = BruteParams
    area_glsl: ClassVar[str] = SHADERS + "brute.glsl"
    supports_masks: ClassVar[bool] = True

    def method_uniforms(self) -> dict[str, object]:
        return {"a_grid": int(self.params.grid)}
