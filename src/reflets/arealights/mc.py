"""``mc``: Monte Carlo integration of each polygon light (area-light document §2.6–2.7) and its MIS successor.

Per pixel, light and frame, ``samples`` = N samples estimate L_o = L ∫_A f_r(wo, wi) cosθx cosθy / r² dA
(unoccluded, like every area-light method; shadows: the soft-shadow ratio). Strategies (``strategy``):

``uniform``
    N points uniform in area (a parallelogram: uniform (u, v); any convex polygon: a fan triangle chosen
    ∝ its area, uniform inside): L_o ≈ L · A/N · Σ f cosθx cosθy / r².
``two_region`` — the document's pdf (2.35)
    A box B (in the light's edge coordinates) holding the cone of half-angle α around the mirror direction,
    α solving the document's (2.22) t ∫_{−π/2}^{π/2} cos^e = ∫_{−α}^{α} cos^e exactly (t = ``cone_t``,
    0.5 as in the document; Blinn-Phong lobes use 2α_h, twice the half-vector angle). The box is the exact
    bounding box, along the light's edges, of the ellipse where that cone meets the light plane (dual
    conic), clipped to the light; C = A − B. N/2 samples uniform in the box, N/2 uniform in the rest by
    rejection from the whole light (accepted when outside the box — Algorithm 1 with the test the right
    way round), with the **corrected** weights: L_o ≈ L [(2B/N) Σ_box f G + (2C/N) Σ_rest f G]
    (B/⌊N/2⌋ and C/⌈N/2⌉ for odd N; N ≥ 2). Uniform sampling of the whole light instead when B > A/2 (as in
    the document), when the box misses the light (B = 0), when the lobe misses the light's plane or reaches
    its horizon (no ellipse: the region is empty or unbounded — the lobe gives no usable guidance), and
    for materials without a lobe. Note: with (2.22)'s 1-D definition a square box holds about t² of a
    narrow lobe's energy (the product of the two marginals), i.e. ~25 % at t = 0.5, not half.
``mis`` (default) — the improvement the document names (Veach & Guibas 1995)
    Per sample one light sample (uniform in area, p_light(ω) = r²/(A cosθy)) and one lobe sample, each
    weighted by the power (β = 2) or balance ``heuristic`` of both densities. The lobe sampler mixes the
    cosine-weighted hemisphere and the material's main lobe as :func:`~.base.lobe_info` sees it — a
    direction around the mirror direction with density (e+1)/(2π) cos^e (Phong-like, kind 1) or a half
    vector around n with that density and p(wi) = p(h)/(4 wo·h) (Blinn-Phong, kind 2) — chosen with the
    probability of the lobe's share of the directional albedo at normal incidence (:func:`specular_weight`).
    Lobe directions are traced to the light plane and tested against the polygon. The lobe strategy is a
    valid MIS strategy for *every* BRDF: its pdf is exact for what it samples, it only approximates the
    BRDF's shape (Ward, microfacet, Lafortune, measured get a Phong stand-in), which affects variance only;
    and light sampling alone covers the whole light, so the combination is unbiased whatever the lobe.
    Cost: 2N light-sample evaluations per frame (``output="samples"`` counts both).

Randomness: PCG hash seeded by (pixel, frame, seed, light); ``render(spp=…)`` accumulates spp/N frames of N
samples (spp must be a multiple of N), frame k using ``u_frame = k`` and the render's seed, so the same
seed gives the same image and different frames independent numbers.
"""

from __future__ import annotations

import math
from typing import ClassVar, Literal

import numpy as np
from pydantic import Field, model_validator

from ..brdf.base import luminance
from ..errors import ArgumentError
from ..techniques.base import register_technique
from .base import SHADERS, AreaLightParams, AreaLightTechnique, lobe_info

STRATEGIES = {"uniform": 0, "two_region": 1, "mis": 2}


class MCParams(AreaLightParams):
    """Parameters of the Monte Carlo area-light method."""

    strategy: Literal["uniform", "two_region", "mis"] = "mis"
    samples: int = Field(16, ge=1, le=4096, description="N: samples per pixel, light and frame")
    heuristic: Literal["power", "balance"] = Field("power", description="mis: MIS weights (power: β = 2)")
    cone_t: float = Field(0.5, gt=0.0, lt=1.0, description="two_region: lobe fraction t of the box cone (2.22)")

    @model_validator(mode="after")
    def _two_region_needs_both_regions(self):
        if self.strategy == "two_region" and self.samples < 2:
            raise ValueError("two_region draws N/2 samples in each region, so it needs samples >= 2")
        return self


def cone_half_angle(exponent: float, t: float = 0.5) -> float:
    """Exact root a of t ∫_{−π/2}^{π/2} cos^e x dx = ∫_{−a}^{a} cos^e x dx (the document's eq 2.22).

    With s = sin²x, ∫_0^a cos^e x dx = ½ B(½, (e+1)/2) I_{sin²a}(½, (e+1)/2), so sin²a = I⁻¹(t; ½, (e+1)/2).
    """
    from scipy.special import betaincinv  # imported when used (start-up time)

    return float(np.arcsin(np.sqrt(betaincinv(0.5, 0.5 * (float(exponent) + 1.0), t))))


def specular_weight(material) -> float:
    """Probability that the mis lobe sampler draws the lobe rather than the cosine: the non-Lambertian share
    of the directional albedo at normal incidence, luminance-weighted (1 with no diffuse term, 0 with no
    lobe). Estimated once per material with the material's own importance sampler (fixed seed)."""
    info = lobe_info(material)
    if info["u_lobe_kind"] == 0:
        return 0.0
    key = (type(material).__name__, material.model_dump_json())
    if key not in _SPEC_WEIGHTS:
        _SPEC_WEIGHTS[key] = _specular_weight(material, info)
    return _SPEC_WEIGHTS[key]


_SPEC_WEIGHTS: dict[tuple[str, str], float] = {}


def _specular_weight(material, info) -> float:
    diffuse = np.asarray(info["u_lobe_diffuse"])
    n = 4096
    rng = np.random.default_rng(0)
    u1 = (np.arange(n) + rng.random(n)) / n  # stratified in the first dimension
    u2 = rng.random(n)
    wo = np.broadcast_to(np.array([0.0, 0.0, 1.0]), (n, 3))
    wi, pdf = material.sample(wo, u1, u2)
    ok = (pdf > 0) & (wi[..., 2] > 0)
    f = material.eval(wo[ok], wi[ok]) - diffuse / np.pi  # the non-Lambertian part only
    spec = np.sum(f * (wi[ok, 2] / pdf[ok])[:, None], axis=0) / n
    s, d = max(luminance(spec), 0.0), luminance(diffuse)
    return 1.0 if s + d <= 0 else s / (s + d)


@register_technique
class MonteCarlo(AreaLightTechnique):
    """Monte Carlo area lights: uniform, the document's two-region pdf, or light ⊕ lobe MIS (default)."""

    name: ClassVar[str] = "mc"
    progressive: ClassVar[bool] = True
    summary: ClassVar[str] = "area lights: Monte Carlo (uniform, two-region pdf, MIS light+lobe), progressive"
    Params: ClassVar = MCParams
    area_glsl: ClassVar[str] = SHADERS + "mc.glsl"

    def method_flags(self) -> dict[str, object]:
        return {"METHOD_VARIANT": STRATEGIES[self.params.strategy]}

    def method_uniforms(self) -> dict[str, object]:
        return {"a_samples": self.params.samples, "a_heuristic": int(self.params.heuristic == "power")}

    def material_uniforms(self, material) -> dict[str, object]:
        info = lobe_info(material)
        kind, e = info["u_lobe_kind"], info["u_lobe_exponent"]
        alpha = 0.0
        if kind:
            alpha = cone_half_angle(e, self.params.cone_t) * (2.0 if kind == 2 else 1.0)
        return {
            **super().material_uniforms(material),
            "a_cone_sin": math.sin(min(alpha, 0.5 * math.pi)),
            "a_spec_weight": specular_weight(material),
        }

    @property
    def default_spp(self) -> int:
        return self.params.samples  # one frame

    def frames(self, spp: int) -> tuple[int, int]:
        n = self.params.samples
        if spp < 1 or spp % n:
            raise ArgumentError(
                f"spp={spp} is not a positive multiple of samples={n}: mc accumulates spp/samples frames of "
                f"{n} samples each (use spp={n}, {2 * n}, {4 * n}, … or set samples)",
                field="spp",
            )
        return spp // n, 1

    def frame_uniforms(self, frame: int, seed: int) -> dict[str, object]:
        s = int(seed) % (1 << 64)
        return {"u_frame": int(frame) & 0xFFFFFFFF, "u_seed": (s ^ (s >> 32)) & 0xFFFFFFFF}
