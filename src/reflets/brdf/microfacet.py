"""Cook–Torrance microfacet reflection with anisotropic GGX or Beckmann normals and Smith masking-shadowing.

The distribution functions are public for reuse by other techniques, vectorised over leading axes, float64,
in the local shading frame (x = tangent, y = bitangent, z = normal; all directions unit, pointing away from
the surface). ``alpha_x`` is the roughness along the tangent (Mitsuba 3's ``alpha_u``), ``alpha_y`` along the
bitangent (``alpha_v``). References: Walter et al. 2007, "Microfacet models for refraction through rough
surfaces"; Heitz 2014, "Understanding the masking-shadowing function in microfacet-based BRDFs"; Heitz 2018,
"Sampling the GGX distribution of visible normals".
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Annotated, ClassVar, Literal

import numpy as np
from pydantic import Field, model_validator

from ..fresnel import GOLD_ETA, GOLD_K, fresnel_conductor, fresnel_dielectric, fresnel_schlick
from ..quantities import Positive
from .base import (
    RGB,
    Oriented,
    Reflectance,
    alpha_pair,
    blinn_phong_exponent,
    finish_sample,
    luminance,
    mix_pdf,
    pdf_cosine,
    reflect_or_fail,
    register_material,
    sample_cosine,
    sample_half_vector_pdf_to_wi,
    sample_mixture,
    upper,
)
from .maps import LobeMap, Mapped

_SQRT_PI = np.sqrt(np.pi)


def _dot(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    return a[..., 0] * b[..., 0] + a[..., 1] * b[..., 1] + a[..., 2] * b[..., 2]


def _normalize(v: np.ndarray) -> np.ndarray:
    return v / np.sqrt(np.maximum(_dot(v, v), 1e-300))[..., None]


def _scaled_tan2(w: np.ndarray, sx: float, sy: float) -> np.ndarray:
    """((w_x s_x)² + (w_y s_y)²) / w_z² = tan²θ (cos²φ s_x² + sin²φ s_y²); +∞ at the horizon."""
    with np.errstate(divide="ignore", invalid="ignore", over="ignore"):
        return ((w[..., 0] * sx) ** 2 + (w[..., 1] * sy) ** 2) / (w[..., 2] * w[..., 2])


def ggx_d(h: np.ndarray, alpha_x: float, alpha_y: float) -> np.ndarray:
    """GGX (Trowbridge–Reitz) normal distribution D(h); 0 for h.z ≤ 0. ∫ D(h) cosθ_h dω_h = 1.

    D = 1 / (π αx αy cos⁴θ (1 + tan²θ (cos²φ/αx² + sin²φ/αy²))²) = 1 / (π αx αy (hx²/αx² + hy²/αy² + hz²)²).
    """
    h = np.asarray(h, dtype=np.float64)
    q = (h[..., 0] / alpha_x) ** 2 + (h[..., 1] / alpha_y) ** 2 + h[..., 2] ** 2
    return np.where(h[..., 2] > 0, 1.0 / (np.pi * alpha_x * alpha_y * q * q), 0.0)


def beckmann_d(h: np.ndarray, alpha_x: float, alpha_y: float) -> np.ndarray:
    """Beckmann normal distribution D(h); 0 for h.z ≤ 0. ∫ D(h) cosθ_h dω_h = 1.

    D = exp(−tan²θ (cos²φ/αx² + sin²φ/αy²)) / (π αx αy cos⁴θ).
    """
    h = np.asarray(h, dtype=np.float64)
    up = h[..., 2] > 0
    z2 = np.where(up, h[..., 2] ** 2, 1.0)
    e = _scaled_tan2(np.where(up[..., None], h, [0.0, 0.0, 1.0]), 1.0 / alpha_x, 1.0 / alpha_y)
    return np.where(up, np.exp(-e) / (np.pi * alpha_x * alpha_y * z2 * z2), 0.0)


def smith_lambda_ggx(w: np.ndarray, alpha_x: float, alpha_y: float) -> np.ndarray:
    """Smith Λ(w) for GGX: (−1 + sqrt(1 + α²(φ) tan²θ)) / 2 with α²(φ) = cos²φ αx² + sin²φ αy².

    With a = α²(φ) tan²θ: a / (2 (1 + sqrt(1 + a))) for a ≤ 1 (no cancellation), (sqrt(1 + a) − 1)/2 above
    (which stays right up to a = ∞). Depends on |cosθ| only; +∞ at the horizon, 0 along the normal.
    """
    w = np.asarray(w, dtype=np.float64)
    a = _scaled_tan2(w, alpha_x, alpha_y)
    with np.errstate(invalid="ignore", over="ignore"):
        lam = np.where(a > 1.0, (np.sqrt(1.0 + a) - 1.0) * 0.5, a / (2.0 * (1.0 + np.sqrt(1.0 + a))))
    return np.where(np.isnan(a), 0.0, lam)  # w = (0, 0, 0): treat as the normal


def smith_lambda_beckmann(w: np.ndarray, alpha_x: float, alpha_y: float) -> np.ndarray:
    """Smith Λ(w) for Beckmann, exact: (erf(a) − 1)/2 + exp(−a²)/(2a√π) with a = 1/(α(φ) tanθ).

    Evaluated as exp(−a²)/2 · (1/(a√π) − erfcx(a)) (erfcx(a) = exp(a²) erfc(a)), which is the same
    expression without the cancellation of erf(a) − 1 for large a. Depends on |cosθ| only.
    """
    from scipy.special import erfcx  # imported when used (start-up time)

    w = np.asarray(w, dtype=np.float64)
    a2t2 = _scaled_tan2(w, alpha_x, alpha_y)
    with np.errstate(divide="ignore", invalid="ignore", over="ignore"):
        a = 1.0 / np.sqrt(a2t2)
        lam = 0.5 * np.exp(-a * a) * (1.0 / (a * _SQRT_PI) - erfcx(a))
    return np.where((a2t2 == 0.0) | np.isnan(a2t2), 0.0, lam)  # along the normal (or w = 0): no masking


@dataclass(frozen=True)
class Distribution:
    """A microfacet normal distribution with its Smith masking and sampling routines.

    ``name`` is "ggx" or "beckmann"; ``alpha_x`` along the tangent, ``alpha_y`` along the bitangent.
    """

    name: Literal["ggx", "beckmann"]
    alpha_x: float
    alpha_y: float

    def d(self, h: np.ndarray) -> np.ndarray:
        """D(h), normalised so that ∫ D(h) cosθ_h dω_h = 1."""
        return (ggx_d if self.name == "ggx" else beckmann_d)(h, self.alpha_x, self.alpha_y)

    def smith_lambda(self, w: np.ndarray) -> np.ndarray:
        """Λ(w) of the Smith masking function G1 = 1/(1 + Λ)."""
        fn = smith_lambda_ggx if self.name == "ggx" else smith_lambda_beckmann
        return fn(w, self.alpha_x, self.alpha_y)

    def g1(self, w: np.ndarray, h: np.ndarray) -> np.ndarray:
        """Smith masking G1(w, h) = χ⁺(w·h) / (1 + Λ(w)); ∫ G1(w, h) max(0, w·h) D(h) dω_h = cosθ_w."""
        visible = _dot(np.asarray(w), h) > 0
        return np.where(visible, 1.0 / (1.0 + self.smith_lambda(w)), 0.0)

    def sample_h(self, u1: np.ndarray, u2: np.ndarray) -> np.ndarray:
        """Half vectors with density D(h) cosθ_h (Walter et al. 2007, anisotropic).

        Slopes of an α = 1 surface are drawn with radius² r² = u1/(1 − u1) (GGX) or −log(1 − u1) (Beckmann) and
        angle ψ = 2π u2, then stretched by (αx, αy): h ∝ (αx r cosψ, αy r sinψ, 1). This is Walter's
        φ = atan(αy/αx tan 2πu2) (quadrant-correct) with tan²θ = r² / (cos²φ/αx² + sin²φ/αy²).
        """
        u1 = np.asarray(u1, dtype=np.float64)
        r2 = u1 / (1.0 - u1) if self.name == "ggx" else -np.log1p(-u1)
        r = np.sqrt(r2)
        psi = 2.0 * np.pi * np.asarray(u2, dtype=np.float64)
        m = np.stack([self.alpha_x * r * np.cos(psi), self.alpha_y * r * np.sin(psi), np.ones_like(r)], axis=-1)
        return _normalize(m)

    def pdf_h(self, h: np.ndarray) -> np.ndarray:
        """Density of :meth:`sample_h`: D(h) max(0, cosθ_h)."""
        return self.d(h) * np.maximum(np.asarray(h)[..., 2], 0.0)

    def sample_visible(self, wo: np.ndarray, u1: np.ndarray, u2: np.ndarray) -> np.ndarray:
        """GGX only: half vectors with the density of visible normals :meth:`pdf_visible` (Heitz 2018, listing 1).
        NaN (a failed sample) for wo at or below the horizon."""
        if self.name != "ggx":
            raise NotImplementedError("visible-normal sampling is implemented for GGX only")
        wo = np.asarray(wo, dtype=np.float64)
        # the view direction in the stretched (α = 1) configuration, and a frame (t1, t2, v) around it
        vx, vy, vz = self.alpha_x * wo[..., 0], self.alpha_y * wo[..., 1], wo[..., 2]
        norm = np.sqrt(vx * vx + vy * vy + vz * vz)
        vx, vy, vz = vx / norm, vy / norm, vz / norm
        lensq = vx * vx + vy * vy
        safe = lensq > 0
        inv = 1.0 / np.sqrt(np.where(safe, lensq, 1.0))
        t1x, t1y = np.where(safe, -vy * inv, 1.0), np.where(safe, vx * inv, 0.0)
        t2x, t2y, t2z = -vz * t1y, vz * t1x, vx * t1y - vy * t1x  # t2 = v × t1
        # a uniform point on the unit disk, its lower half squeezed onto the visible projected hemisphere
        r = np.sqrt(np.asarray(u1, dtype=np.float64))
        phi = 2.0 * np.pi * np.asarray(u2, dtype=np.float64)
        p1, p2 = r * np.cos(phi), r * np.sin(phi)
        s = 0.5 * (1.0 + vz)
        p2 = (1.0 - s) * np.sqrt(np.maximum(0.0, 1.0 - p1 * p1)) + s * p2
        p3 = np.sqrt(np.maximum(0.0, 1.0 - p1 * p1 - p2 * p2))
        # the hemisphere normal, unstretched back to the (αx, αy) surface
        nx = p1 * t1x + p2 * t2x + p3 * vx
        ny = p1 * t1y + p2 * t2y + p3 * vy
        nz = p2 * t2z + p3 * vz
        h = _normalize(np.stack([self.alpha_x * nx, self.alpha_y * ny, np.maximum(nz, 0.0)], axis=-1))
        return np.where((wo[..., 2] > 0)[..., None], h, np.nan)

    def pdf_visible(self, wo: np.ndarray, h: np.ndarray) -> np.ndarray:
        """Density of visible normals D_wo(h) = G1(wo, h) max(0, wo·h) D(h) / cosθ_o; 0 for wo.z ≤ 0."""
        wo = np.asarray(wo, dtype=np.float64)
        cos_o = wo[..., 2]
        dot = np.maximum(_dot(wo, h), 0.0)
        value = self.g1(wo, h) * dot * self.d(h) / np.where(cos_o > 0, cos_o, 1.0)
        return np.where(cos_o > 0, value, 0.0)


Alpha = Annotated[float, Field(ge=1e-3, le=1, allow_inf_nan=False)]


@register_material
class Microfacet(Oriented, Mapped):
    """Cook–Torrance microfacet reflection: an optional Lambertian term plus a rough specular lobe,

    f = diffuse/π + specular · F(wi·h) · D(h) · G(wo, wi) / (4 cosθo cosθi),  h = normalize(wo + wi),

    for wo and wi above the surface (0 otherwise). Single scattering: with rough masking the lobe loses energy
    (a white lobe reflects < 1 at grazing angles); ``diffuse`` is simply added, not energy-coupled to the lobe.

    Parameters
    ----------
    distribution : "ggx" | "beckmann", default "ggx"
        Normal distribution D (anisotropic forms of Walter et al. 2007). Beckmann's Smith Λ is the exact
        (erf) expression; Mitsuba 3 uses Walter's rational approximation of G1 (< 0.35 % off per G1, so its
        roughconductor differs from this model by up to 0.6 %; GGX agrees to float32 precision).
    alpha : float or [alpha_x, alpha_y], each in [1e-3, 1], default 0.3
        Roughness (the RMS slope for Beckmann). A single number is isotropic; ``alpha_x`` is along the tangent
        (local x, Mitsuba's ``alpha_u``), ``alpha_y`` along the bitangent (local y, ``alpha_v``).
    fresnel : "none" | "schlick" | "dielectric" | "conductor", default "none"
        Fresnel factor F, evaluated at wi·h (= wo·h). "none": F = 1 (Mitsuba's ``material = "none"``);
        "schlick": F0 + (1 − F0)(1 − wi·h)⁵ with F0 = ``specular``; "dielectric": exact unpolarised reflectance
        of a real index ``eta`` (total internal reflection → 1 for eta < 1); "conductor": exact reflectance of
        the complex index eta + i k per RGB channel.
    specular : [r, g, b] ≥ 0, default [1, 1, 1]
        Scale of the lobe, F is multiplied by it; with "schlick" it *is* F0 and must lie in [0, 1].
    eta : float > 0 or [r, g, b], default: 1.5 (dielectric), gold (conductor)
        Relative index of refraction (inside/outside). Only for "dielectric" and "conductor" (an error
        otherwise). Conductor default: gold, eta = (0.1431, 0.3750, 1.4425), k = (3.9832, 2.3857, 1.6032).
    k : [r, g, b] ≥ 0, default: gold
        Extinction coefficient, only for "conductor" (an error otherwise). A conductor gives both eta and k,
        or neither (gold).
    masking : "separable" | "correlated", default "separable"
        Smith shadowing-masking G: "separable" G1(wo)·G1(wi) (Mitsuba 3's choice); "correlated": the
        height-correlated 1/(1 + Λ(wo) + Λ(wi)) (Heitz 2014), which is never smaller.
    diffuse : [r, g, b] in [0, 1], default [0, 0, 0]
        Lambertian albedo, term diffuse/π added to the lobe.

    Sampling: for GGX the distribution of visible normals (Heitz 2018), for Beckmann D(h) cosθ_h (Walter
    2007; samples whose half vector faces away from wo fail), mixed with cosine sampling when ``diffuse`` > 0
    with probabilities ∝ the luminances of ``diffuse`` and of the lobe's reflectance at normal incidence.
    """

    type: Literal["microfacet"] = "microfacet"
    distribution: Literal["ggx", "beckmann"] = "ggx"
    alpha: Alpha | tuple[Alpha, Alpha] = 0.3
    fresnel: Literal["none", "schlick", "dielectric", "conductor"] = "none"
    specular: RGB = (1.0, 1.0, 1.0)
    eta: Positive | tuple[Positive, Positive, Positive] | None = None
    k: RGB | None = None
    masking: Literal["separable", "correlated"] = "separable"
    diffuse: Reflectance = (0.0, 0.0, 0.0)
    lambertian_field: ClassVar[str] = "diffuse"
    linear_specular: ClassVar[str] = "specular"
    lobe_maps: ClassVar[dict[str, LobeMap]] = {"alpha": LobeMap(low=1e-3, widest="max")}

    @classmethod
    def mappable(cls, data: dict | None = None) -> tuple[str, ...]:
        """Both colours, but not a Schlick F₀ (the BRDF is affine in it, not linear: ``affine_colours``)."""
        fresnel = (data or {}).get("fresnel", "none")
        return ("diffuse",) if fresnel == "schlick" else ("diffuse", "specular")

    @classmethod
    def affine_colours(cls, data: dict | None = None) -> tuple[str, ...]:
        """A Schlick F₀: F = F₀ + (1 − F₀)(1 − cos)⁵."""
        return ("specular",) if (data or {}).get("fresnel", "none") == "schlick" else ()

    def lobe_summary(self):
        return tuple(float(c) for c in self.diffuse), 2, blinn_phong_exponent(self.alpha)

    glsl = "reflets/brdf/glsl/microfacet.glsl"

    @model_validator(mode="after")
    def _check_fresnel_parameters(self) -> Microfacet:
        if self.fresnel == "schlick" and max(self.specular) > 1.0:
            raise ValueError(f'with fresnel = "schlick", specular is F0 and must lie in [0, 1], got {self.specular}')
        if self.eta is not None and self.fresnel not in ("dielectric", "conductor"):
            raise ValueError(f'eta applies only to fresnel = "dielectric" or "conductor", not "{self.fresnel}"')
        if self.k is not None and self.fresnel != "conductor":
            raise ValueError(f'k applies only to fresnel = "conductor", not "{self.fresnel}"')
        if self.fresnel == "conductor" and (self.eta is None) != (self.k is None):
            raise ValueError('fresnel = "conductor" takes both eta and k, or neither (gold)')
        return self

    # ------------------------------------------------------------------------------------------ parameters

    @property
    def alpha_xy(self) -> tuple[float, float]:
        """(alpha_x, alpha_y) = (Mitsuba's alpha_u, alpha_v)."""
        return alpha_pair(self.alpha)

    @property
    def ndf(self) -> Distribution:
        return Distribution(self.distribution, *self.alpha_xy)

    @property
    def eta_rgb(self) -> tuple[float, float, float]:
        """The effective eta per channel (defaults resolved; 1 where Fresnel does not use it)."""
        if self.eta is None:
            return {"dielectric": (1.5,) * 3, "conductor": GOLD_ETA}.get(self.fresnel, (1.0,) * 3)
        return tuple(float(e) for e in np.broadcast_to(self.eta, 3))

    @property
    def k_rgb(self) -> tuple[float, float, float]:
        """The effective k per channel (gold for a conductor without eta/k; 0 where not used)."""
        if self.k is None:
            return GOLD_K if self.fresnel == "conductor" else (0.0, 0.0, 0.0)
        return tuple(float(v) for v in self.k)

    def fresnel_rgb(self, cos: np.ndarray) -> np.ndarray:
        """The lobe's colour factor specular · F(cos), shape (..., 3) (F0 = specular for Schlick)."""
        c = np.asarray(cos, dtype=np.float64)[..., None]
        if self.fresnel == "schlick":
            return fresnel_schlick(c, self.specular)
        if self.fresnel == "dielectric":
            f = fresnel_dielectric(c, self.eta_rgb)
        elif self.fresnel == "conductor":
            f = fresnel_conductor(c, self.eta_rgb, self.k_rgb)
        else:
            f = np.ones_like(c)
        return np.asarray(self.specular) * f

    # ------------------------------------------------------------------------------------------ evaluation

    def masking_shadowing(self, wo: np.ndarray, wi: np.ndarray, h: np.ndarray) -> np.ndarray:
        """G(wo, wi, h): G1(wo, h) G1(wi, h) or χ⁺(wo·h) χ⁺(wi·h) / (1 + Λ(wo) + Λ(wi))."""
        ndf = self.ndf
        if self.masking == "separable":
            return ndf.g1(wo, h) * ndf.g1(wi, h)
        visible = (_dot(wo, h) > 0) & (_dot(wi, h) > 0)
        return np.where(visible, 1.0 / (1.0 + ndf.smith_lambda(wo) + ndf.smith_lambda(wi)), 0.0)

    def eval(self, wo: np.ndarray, wi: np.ndarray) -> np.ndarray:
        wo, wi = np.broadcast_arrays(np.asarray(wo, dtype=np.float64), np.asarray(wi, dtype=np.float64))
        up = upper(wo, wi)
        # below the horizon f = 0; substitute the normal there so nothing divides by zero
        wo = np.where(up, wo, [0.0, 0.0, 1.0])
        wi = np.where(up, wi, [0.0, 0.0, 1.0])
        h = _normalize(wo + wi)
        lobe = self.ndf.d(h) * self.masking_shadowing(wo, wi, h) / (4.0 * wo[..., 2] * wi[..., 2])
        f = np.asarray(self.diffuse) / np.pi + self.fresnel_rgb(_dot(wi, h)) * lobe[..., None]
        return np.where(up, f, 0.0)

    @property
    def reciprocal(self) -> bool:
        return True  # D, G and F(wi·h = wo·h) are all symmetric in (wo, wi)

    @property
    def energy_conserving(self) -> bool:
        """True when diffuse + max(specular · F) ≤ 1 per channel: the single-scattering lobe's albedo is at
        most max F (∫ G1(wo, h) max(0, wo·h) D dω_h = cosθo and G ≤ G1(wo)), so the sum cannot exceed 1."""
        lobe_max = (1.0, 1.0, 1.0) if self.fresnel == "schlick" else self.specular
        return all(d + s <= 1.0 for d, s in zip(self.diffuse, lobe_max, strict=True))

    # ------------------------------------------------------------------------------------------ sampling

    def _weights(self) -> list[float]:
        d = luminance(self.diffuse)
        s = luminance(self.fresnel_rgb(np.array(1.0)))
        if self.fresnel == "schlick":  # F₀ + (1 − F₀)/21: its cosine-weighted mean (a zero F₀ still reflects)
            s += (1.0 - s) / 21.0
        return [d, s] if d + s > 0 else [0.0, 1.0]

    def _sample_h(self, wo: np.ndarray, u1: np.ndarray, u2: np.ndarray) -> np.ndarray:
        ndf = self.ndf
        return ndf.sample_visible(wo, u1, u2) if self.distribution == "ggx" else ndf.sample_h(u1, u2)

    def _lobe_pdf(self, wo: np.ndarray, wi: np.ndarray) -> np.ndarray:
        h = _normalize(wo + wi)
        ndf = self.ndf
        pdf_h = ndf.pdf_visible(wo, h) if self.distribution == "ggx" else ndf.pdf_h(h)
        return sample_half_vector_pdf_to_wi(pdf_h, wo, h)

    def sample(self, wo: np.ndarray, u1: np.ndarray, u2: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Visible normals (GGX) or D(h) cosθ_h (Beckmann) reflected about h, mixed with cosine sampling."""
        wo = np.broadcast_to(np.asarray(wo, dtype=np.float64), np.shape(u1) + (3,))

        def lobe(a, b, chosen):
            return reflect_or_fail(wo[chosen], self._sample_h(wo[chosen], a, b))

        wi = sample_mixture(self._weights(), [lambda a, b, _: sample_cosine(a, b), lobe], u1, u2)
        return finish_sample(self, wo, wi)

    def pdf(self, wo: np.ndarray, wi: np.ndarray) -> np.ndarray:
        wo, wi = np.broadcast_arrays(np.asarray(wo, dtype=np.float64), np.asarray(wi, dtype=np.float64))
        return mix_pdf(self._weights(), [pdf_cosine(wi), self._lobe_pdf(wo, wi)])

    # ------------------------------------------------------------------------------------------ GPU

    def flags(self) -> dict[str, object]:
        modes = ("none", "schlick", "dielectric", "conductor")
        return {
            "BRDF_MF_DISTRIBUTION": 0 if self.distribution == "ggx" else 1,
            "BRDF_MF_FRESNEL": modes.index(self.fresnel),
            "BRDF_MF_CORRELATED": int(self.masking == "correlated"),
        }

    def brdf_uniforms(self) -> dict[str, object]:
        return {
            "m_alpha": self.alpha_xy,
            "m_specular": tuple(float(s) for s in self.specular),
            "m_eta": self.eta_rgb,
            "m_k": self.k_rgb,
            "m_diffuse": tuple(float(d) for d in self.diffuse),
        }
