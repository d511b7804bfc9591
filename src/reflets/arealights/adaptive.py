"""``adaptive``: the area-light document's second method (§2.4) — a midpoint grid whose step is predicted per
fragment from the distance to the light and the material's lobe.

Per fragment and light (x on the light's emitting side, V1):

1. **Distance.** d = |x − y*| / w, y* the light's nearest point to x, w = |c2 − c1| the light width. y* is
   exact for every convex polygon (projection onto the plane if inside, else the nearest boundary point);
   the document's clamped (u, v) projection (2.14–2.20) — with its erratum fixed (divide by the *squared*
   edge length) — is the same point on rectangles (``predictors.nearest_point_document``).
2. **Predicted step** Δ (light widths), ``predictors.py``: Lambert (2.9), Phong (2.12 with the corrected
   exponent 1/2.0990 and + 0.0017), Blinn-Phong (2.13, see below), chosen by the material's lobe kind
   (``lobe_info``: Phong 1 — also Ward, microfacet and Lafortune through their equivalent exponent —,
   Blinn-Phong 2, none 0 → Lambert). As in the document the specular predictor drives the whole BRDF (its
   diffuse part always needs fewer samples); when the material also has a diffuse part the Lambert step
   is taken too and the smaller step wins (never coarser than the document; equal in practice).
   Each predictor is multiplied by its safety factor (95 / 90 / 50 %).
3. **Dithering** (optional, eq 2.21): Δ = max(floor, Δ − 0.1 ξ), ξ ∈ [0, 1) from the PCG hash of
   (pixel, light index, seed) (``rng_*`` in common.glsl): same seed, same image. It trades the bands where
   n changes (the document's Fig 2.11) for noise, and always adds samples.
4. **Floor and quantisation**: Δ ≥ ``min_step`` (0.05: at most 20×20 samples), Δ ≤ 1, then n = ceil(1/Δ)
   (Δ → 1/ceil(1/Δ), an exact grid) and the midpoint n×n grid of ``brute``. On a non-square parallelogram
   the spacing is the same along e2: n_v = ceil(n |e2| / |e1|) (capped at 128). Other convex polygons fall
   back to ``brute``'s fan rule with the predicted n (n² centroid samples per fan triangle); d is still
   normalised by the first edge |v1 − v0|, which the document's fits were not measured for.

**How it is measured** (here and in the tests): the document's scene — camera (0, 3, 4) looking at the
origin, fov 45°, 4×4 plane, unit square one-sided light at height 1 facing down, radiance 5 — at 100×75.
"exact" is the unoccluded integral by a 128×128 midpoint grid (``brute``; 64² vs 128²: 1·10⁻⁷), "ref" the
unoccluded NumPy Monte Carlo reference at 1024 spp, whose own noise (≈ 6·10⁻⁵ … 1.4·10⁻⁴ against the exact
image) dominates that column — the exact column is the one that separates the methods. Relative MSE =
mean((a − b)²)/mean(b²) over the plane pixels, pixels where the camera sees the emitter excluded; spp =
light samples per plane pixel (``output="samples"``).

**Blinn-Phong exponent (2.13): 1/2.4589 (``blinn_fit = "inverted"``, the default).** The Phong fit has the
form ``Δ = (a (d + b)^c / e)^(1/p) + q``; printed with the outer exponent 2.4589 (= p, not 1/p), the
Blinn-Phong one makes Δ ∝ e^−2.46, while a lobe's width — and the step it needs — goes as e^−½ (Phong's fit:
e^−0.476; inverted: e^−0.407); for any glossy lobe its base is ≪ 1, so Δ ≈ 0.0082 → the 0.05 floor. Measured
(ρ_d = 0, ρ_s = 1, un-normalised; each cell: spp / relative MSE vs exact / vs ref):

| e | inverted (1/2.4589) | printed (2.4589) | brute, ≈ same cost as inverted | brute 20² (400 spp) |
|---|---|---|---|---|
| 10 | 9 / 1.6e-4 / 2.2e-4 | 114 / 4.6e-6 / 6.5e-5 | 3² / 3.1e-4 / 3.7e-4 | 1.4e-7 / 6.0e-5 |
| 50 | 25 / 6.5e-5 / 1.9e-4 | 400 / 4.4e-7 / 1.4e-4 | 5² / 1.2e-4; 6² / 5.9e-5 / 1.9e-4 | 4.4e-7 / 1.4e-4 |
| 500 | 141 / 3.3e-5 / 1.3e-4 | 400 / 5.9e-6 / 1.1e-4 | 12² / 4.9e-5 / 1.5e-4 | 5.9e-6 / 1.1e-4 |

"printed" is the 20×20 brute force for e ≥ 50 (every pixel at the floor) — the predictor does nothing;
"inverted" adapts like the Phong predictor and is more accurate than a brute force of the same cost.

**Phong e = 500 (the document's Fig 2.14)**, ρ_d = 0, ρ_s = 1, un-normalised:

| setting | spp | relMSE vs exact | vs ref |
|---|---|---|---|
| brute 13² / 14² / 16² | 169 / 196 / 256 | 1.2e-4 / 9.1e-5 / 5.1e-5 | 1.9e-4 / 1.6e-4 / 1.2e-4 |
| brute 20² / 24² | 400 / 576 | 2.0e-5 / 9.3e-6 | 8.2e-5 / 7.0e-5 |
| adaptive (defaults) | 171 | 7.4e-5 | 1.4e-4 |
| adaptive, dither | 338 | 2.7e-5 | 9.1e-5 |
| adaptive, safety_phong = 0.7 | 262 | 2.9e-5 | 9.2e-5 |
| adaptive, safety_phong = 0.5 | 366 | 2.0e-5 | 8.2e-5 |
| biased (defaults: 8², t = 0.99) | 7 | 3.0e-5 | 9.1e-5 |

With the document's safety factors adaptive needs 43 % of the 20×20 brute force's samples and beats a
brute force of the same cost, but its error is 3.7× that of 20×20: the predictor depends on the distance
only, so it spends its most samples (18² at d = 1) right under the light, where this lobe sees nothing,
and 13²–17² in the highlight, which is seen at 45° (d ≈ 1.1–1.3). Matching the 20×20 error needs the floor
in the highlight (safety_phong = 0.5: equal error, 366 spp). The document judged "enough samples"
visually, on tone-mapped images whose highlight centre saturates; the relative MSE is stricter. Its
proposed fix, predicting from the solid angle and the lobe's direction rather than the distance, is what
``biased`` does. On a Lambert plane under the same light every pixel gets 2×2 samples (d ≥ 1: Δ ≥ 0.74,
× 0.95, rounded down to 1/2), relative MSE 9.3e-4 against Lambert's exact formula.

Parameters: ``dither`` (false), ``safety_lambert`` (0.95), ``safety_phong`` (0.90), ``safety_blinn`` (0.50)
— each in (0, 2] —, ``min_step`` (0.05, in [0.01, 1]), ``blinn_fit`` ("inverted" | "printed").
``output="samples"`` counts n × n_v per light (the cost measure of ``reflets bench arealights``).
"""

from __future__ import annotations

from typing import ClassVar, Literal

from pydantic import Field

from ..techniques.base import register_technique
from .base import SHADERS, AreaLightParams, AreaLightTechnique
from .predictors import BLINN_FITS, MIN_STEP, SAFETY


class AdaptiveParams(AreaLightParams):
    """Parameters of ``adaptive``."""

    dither: bool = Field(False, description="dither the step (eq 2.21) against banding")
    safety_lambert: float = Field(SAFETY["lambert"], gt=0.0, le=2.0, description="factor on Δ_lambert")
    safety_phong: float = Field(SAFETY["phong"], gt=0.0, le=2.0, description="factor on Δ_phong")
    safety_blinn: float = Field(SAFETY["blinn"], gt=0.0, le=2.0, description="factor on Δ_blinn")
    min_step: float = Field(MIN_STEP, ge=0.01, le=1.0, description="floor of the step, in light widths")
    blinn_fit: Literal["inverted", "printed"] = Field("inverted", description="outer exponent of eq 2.13")


@register_technique
class Adaptive(AreaLightTechnique):
    """Midpoint grid with a per-fragment step predicted from distance and lobe exponent (§2.4)."""

    name: ClassVar[str] = "adaptive"
    summary: ClassVar[str] = "area lights: midpoint grid with predicted per-pixel step (Meunier 2007 §2.4)"
    Params: ClassVar = AdaptiveParams
    area_glsl: ClassVar[str] = SHADERS + "adaptive.glsl"
    supports_masks: ClassVar[bool] = True

    def method_uniforms(self) -> dict[str, object]:
        p = self.params
        return {
            "a_safety": (float(p.safety_lambert), float(p.safety_phong), float(p.safety_blinn)),
            "a_min_step": float(p.min_step),
            "a_dither": bool(p.dither),
            "a_blinn_power": float(BLINN_FITS[p.blinn_fit]),
        }

    def frame_uniforms(self, frame: int, seed: int) -> dict[str, object]:
        return {"a_seed": int(seed) & 0x7FFFFFFF}
