"""``biased``: the area-light document's third and recommended method (§2.5) — exact diffuse, and a constant
n×n midpoint grid over the part of the light inside the cone of useful directions of the specular lobe.

Per fragment x and parallelogram light (nothing when x is behind a one-sided light, V1, or wo is below
the surface):

1. **Diffuse term, exactly**: ρ_d/π · L · E(x) with Lambert's polygon formula and horizon clipping
   (``polygon_irradiance`` in polygon.glsl, as the ``analytic`` method). The grid then integrates
   f − ρ_d/π only (``brdf_eval`` returns the whole BRDF; ρ_d is ``lobe_info``'s Lambertian albedo), so the
   diffuse part carries no quadrature error and no cone bias. The document's scene has ρ_d = 0; with
   ρ_d = 0.3, ρ_s = 0.7, e = 500 the total is within 0.02 % of the exact integral. Materials without a lobe
   (``lobe_info`` kind 0: Lambert, …) get exactly the ``analytic`` result and evaluate no sample.
2. **Cone.** Axis r = the mirror direction of wo; half-angle α = a(e) of eq 2.22 for the tolerance
   ``threshold`` t, solved **exactly** in Python per material (``predictors.cone_half_angle``: Brent's
   method on the incomplete-beta form, 1e-13 rad) and passed as a uniform; ``cone_fit = "fit"`` uses the
   document's fit 2.23 instead (clamped to [0, π/2]), which is poor beyond e ≈ 300 (energy bias −4.5 % at
   e = 500, −40 % at e = 1000, vs −0.5 %, −0.6 % exact). Blinn-Phong lobes (kind 2): (n·h)^e falls off in
   wi like a Phong lobe of exponent e/4 in the plane of incidence, and 1/cos θo wider across it, so α =
   a(e/4) / cos θo (clamped to π/2) — a cone that holds the stretched lobe.
3. **Where the cone meets the light's plane.** With β the angle between r and the normal towards the plane,
   h the height of x and d = h / cos β the distance to the hit point c:
   - β − α ≥ 90°: the whole cone points away from the plane → no specular contribution;
   - β + α ≥ 90° (parabola / hyperbola, including r parallel to or away from the plane — the ray does not
     hit the plane in front of x): the box is the whole light, as in the document;
   - otherwise an ellipse, bounded by a box in the light's (u, v), **aligned with the light's edges** so the
     grid is a plain (u, v) grid; on skewed parallelograms (u, v) come from the dual basis of (e1, e2). The
     box is clipped to [0, 1]²; no specular contribution when it misses the light; its clipped area
     replaces the light area A (each of the n² samples weighs A · area(box) / n²).
4. **Box** (``box``), measured (table below):
   - ``"ellipse"``: the exact (u, v) bounding box of the exact ellipse — along r's in-plane direction from
     c − d sin α / cos(β − α) to c + d sin α / cos(β + α), half-width h sin α / sqrt(cos(β − α) cos(β + α))
     across (``predictors.cone_ellipse``). It bounds the cone exactly, but the cone is a 1D criterion
     (eq 2.22 holds t of the 1D profile cos^e): at the rim of a highlight, where the light overlaps only the
     lobe's tail, the part of the lobe outside the cone is most of the pixel's value; so −1.5 % of energy
     at 45°, −5.3 % (e = 500) at 67° from the normal;
   - ``"document"``: the square of half-width L = d sin α / cos β (eq 2.24) around c, aligned with the
     edges. It is narrower than the cone on the far side and at normal incidence (d sin α < d tan α) but
     1/cos β wider than the cone across the plane of incidence — which happens to catch the tails at grazing
     angles. Not a bound: −2.6 % at e = 50 (document's view), −5.4 % on a skewed light;
   - ``"union"`` (**default**): the (u, v) box bounding both — the exact cone plus the document's margin.
     Never more biased than either in every configuration measured (−1.2 … +0.03 %), at the same
     constant cost (n² samples); the box only grows, so the grid's spacing and its (small) quadrature error
     grow with it.
5. **Grid**: ``grid`` n (default 8) × n midpoint samples over the clipped box, as ``brute``'s rule.

Other convex polygons (the document only has parallelograms): diffuse exact, then ``brute``'s fan rule with
``grid``² samples per fan triangle over the whole polygon for f − ρ_d/π (no cone).

``output="samples"`` counts n² per light whose box meets the light and 0 elsewhere; the exact diffuse term
is not a light sample. On the document's scene (e = 500) that is 7 samples per plane pixel on average.

**Measured** (the document's scene, 100×75, ρ_d = 0, ρ_s = 1, un-normalised Phong; energy bias =
(Σ biased − Σ exact) / Σ exact over the highlight — plane pixels, emitter excluded, where the exact value
exceeds 10⁻³ of its maximum; "exact" = ``brute`` 64², which a 64-spp unoccluded NumPy reference confirms
to ±0.3 %; relative MSE = mean((a − b)²)/mean(b²) over the plane):

| e | union (default), t = 0.99 | t = 0.90 | ellipse | document | fit 2.23 |
|---|---|---|---|---|---|
| 50 | −0.27 % (5.5e-5) | −8.4 % | −1.48 % | −2.61 % | −0.14 % |
| 150 | −0.34 % (2.6e-5) | −9.4 % | −1.61 % | −1.49 % | −0.27 % |
| 300 | −0.44 % (2.5e-5) | −9.9 % | −1.64 % | −1.16 % | −1.14 % |
| 500 | −0.53 % (2.9e-5) | −10.5 % | −1.69 % | −1.04 % | −4.47 % |
| 1000 | −0.62 % (3.7e-5) | −10.5 % | −1.73 % | −0.97 % | −40.2 % |

Other views (t = 0.99; e = 150 / 500): grazing camera (0, 1.5, 6), highlight 67° from the normal — union
−0.17 / −0.20 %, ellipse −3.5 / −5.3 %, document −0.17 / −0.20 %; top view (camera (0, 3, 0), light moved
to x ∈ [1, 2]) — union −1.1 / −1.2 %, ellipse −1.6 / −1.7 %, document −1.5 / −1.4 %. Blinn-Phong
(e = 50 … 4000): −3.5 … +0.2 %. For e = 500 the default costs 7 samples per pixel at a relative MSE of
3.0e-5, against 400 samples and 2.0e-5 for a 20×20 brute force and 171 samples and 7.4e-5 for ``adaptive``
— the document's conclusion (its Fig 3.1) holds.

Materials whose diffuse term is not Lambertian (``lobe_info`` gives Ashikhmin-Shirley and measured BRDFs
ρ_d = 0) send their whole BRDF through the box, so their diffuse term is truncated to the cone too.

Known limit: ``lobe_info`` maps microfacet and Ward lobes to *Phong* lobes (kind 1) with e = 2/α² − 2, but
that is Walter et al.'s equivalence with a *Blinn-Phong* (half-vector) exponent; the cone is then about half
as wide as the lobe and GGX loses 31 % (α = 0.1) to 34 % (α = 0.05) of the highlight's energy. Treated as
Blinn-Phong lobes (kind 2) the same materials lose 1.6 % and 4.8 % (GGX's long tails remain outside).

Parameters: ``grid`` (8, 1 … 64), ``threshold`` t (0.99, in (0, 1)), ``cone_fit`` ("exact" | "fit"),
``box`` ("union" | "ellipse" | "document").
"""

from __future__ import annotations

from typing import ClassVar, Literal

import numpy as np
from pydantic import Field

from ..techniques.base import register_technique
from .base import SHADERS, AreaLightParams, AreaLightTechnique, lobe_info
from .predictors import cone_half_angle, cone_half_angle_fit


class BiasedParams(AreaLightParams):
    """Parameters of ``biased``."""

    grid: int = Field(8, ge=1, le=64, description="n: n×n midpoint samples over the cone's box")
    threshold: float = Field(0.99, gt=0.0, lt=1.0, description="t of eq 2.22: lobe fraction inside the cone")
    cone_fit: Literal["exact", "fit"] = Field("exact", description="a(e) solved exactly, or the fit 2.23")
    box: Literal["ellipse", "document", "union"] = Field(
        "union",
        description="box bounding the exact ellipse, the document's square of half-width d sin α / cos β, "
        "or the box bounding both",
    )


def cone_angle(kind: int, exponent: float, threshold: float, fit: str = "exact") -> float:
    """Half-angle α (radians) of the cone the box is built from, for a lobe ``kind`` (1 Phong, 2 Blinn-Phong,
    whose exponent e acts on directions as a Phong exponent e/4) of exponent e."""
    e = exponent / 4.0 if kind == 2 else exponent
    if fit == "fit":
        return float(np.clip(cone_half_angle_fit(max(e, 1e-12)), 0.0, np.pi / 2))
    return cone_half_angle(e, threshold)


@register_technique
class Biased(AreaLightTechnique):
    """Exact diffuse + constant grid over the box bounding the lobe's cone on the light (§2.5)."""

    name: ClassVar[str] = "biased"
    summary: ClassVar[str] = "area lights: constant grid over the lobe's cone ∩ light (Meunier 2007 §2.5)"
    Params: ClassVar = BiasedParams
    area_glsl: ClassVar[str] = SHADERS + "biased.glsl"
    supports_masks: ClassVar[bool] = True

    def method_uniforms(self) -> dict[str, object]:
        return {"a_grid": int(self.params.grid), "a_box": {"ellipse": 0, "document": 1, "union": 2}[self.params.box]}

    def material_uniforms(self, material) -> dict[str, object]:
        info = lobe_info(material)
        kind = int(info["u_lobe_kind"])
        alpha = cone_angle(kind, float(info["u_lobe_exponent"]), self.params.threshold, self.params.cone_fit)
        return {**super().material_uniforms(material), "a_cone": alpha if kind else 0.0}
