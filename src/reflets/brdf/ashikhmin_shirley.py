"""Ashikhmin–Shirley anisotropic Phong reflection (2000), stable up to very large exponents."""

from __future__ import annotations

from typing import Annotated, ClassVar, Literal

import numpy as np
from pydantic import Field

from .base import (
    HalfVectorLobeMixture,
    Oriented,
    Reflectance,
    luminance,
    register_material,
    upper,
)
from .maps import LobeMap, Mapped

#: an Ashikhmin–Shirley exponent
Exponent = Annotated[float, Field(ge=0, le=1e6, allow_inf_nan=False)]


def log_lobe(u: np.ndarray, nu: float, nv: float) -> np.ndarray:
    """log of (n·h)^((n_u h_x² + n_v h_y²)/(1 − h_z²)), h = u/|u|, for any u with u_z > 0.

    Computed as ½ E log(h_z²) with E = (n_u u_x² + n_v u_y²)/(u_x² + u_y²) ≤ max(n_u, n_v) and
    h_z² = u_z²/|u|²: no 0/0 at h = n (E is taken as 0 there, where log h_z² = 0), and no overflow for huge
    exponents (the exponential underflows to 0). In float64 the absolute error is ≈ max(n_u, n_v)·1e-16; the
    float32 twin needs a series for log(1 − s) near the normal instead.
    """
    x2, y2, z2 = u[..., 0] ** 2, u[..., 1] ** 2, u[..., 2] ** 2
    t2 = x2 + y2
    exponent = (nu * x2 + nv * y2) / np.where(t2 > 0, t2, 1.0)
    return 0.5 * exponent * np.log(np.maximum(z2, 1e-300) / np.maximum(t2 + z2, 1e-300))


def grazing_falloff(cos: np.ndarray) -> np.ndarray:
    """1 − (1 − cosθ/2)⁵, expanded as x(5 − 10x + 10x² − 5x³ + x⁴) with x = cosθ/2 (no cancellation at 0)."""
    x = 0.5 * np.maximum(cos, 0.0)
    return x * (5.0 + x * (-10.0 + x * (10.0 + x * (-5.0 + x))))


@register_material
class AshikhminShirley(HalfVectorLobeMixture, Oriented, Mapped):
    """Ashikhmin & Shirley 2000, "An anisotropic Phong BRDF model": Fresnel-weighted anisotropic Phong
    lobe (exponent n_u along the tangent, local x; n_v along y) plus a coupled, non-Lambertian diffuse term.

    Parameters
    ----------
    rs : [r, g, b] in [0, 1], default [0.05, 0.05, 0.05]
        Specular reflectance R_s at normal incidence (Schlick's Fresnel F(c) = R_s + (1 − R_s)(1 − c)⁵).
    rd : [r, g, b] in [0, 1], default [0.5, 0.5, 0.5]
        Diffuse reflectance R_d.
    nu, nv : float in [0, 1e6], default 100
        Phong-like exponents along the tangent and the bitangent. Extreme ratios such as n_u = 1e4,
        n_v = 2 (the scratches document) are evaluated stably, in float64 and in the GLSL twin.

    With h = normalize(wo + wi) and k either of wo, wi (h·wo = h·wi):

    f = sqrt((n_u + 1)(n_v + 1))/(8π) · (n·h)^((n_u h_x² + n_v h_y²)/(1 − h_z²)) / ((h·k) max(n·wo, n·wi)) · F(h·k)
      + 28 R_d/(23π) (1 − R_s)(1 − (1 − n·wo/2)⁵)(1 − (1 − n·wi/2)⁵).

    Reciprocal, and energy conserving for all parameters. The diffuse albedo is exactly
    R_d (1 − R_s)(1 − (1 − cosθ_o/2)⁵) (the 28/23 makes it 31/32 R_d (1 − R_s) at normal incidence). The
    specular albedo is ∫ p_h F cosθ_i / max(cosθ_i, cosθ_o) dω_h ≤ ∫ p_h F dω_h with p_h the normalised
    half-vector density below; for a near-mirror lobe it is F(cosθ_o), and the sum
    R_s + (1 − R_s)((1 − c)⁵ + 1 − (1 − c/2)⁵) ≤ 1 for every c = cosθ_o. For rough lobes the bound is
    numerical: the largest albedo found over R_s ∈ {0, 0.02, 0.1, 0.5, 1}, R_d = 1, n_u, n_v ∈ [0, 1e5] (anisotropic
    included) and θ_o ∈ [0°, 90°] is 0.984 (R_s = 0.5 near-mirror, normal incidence);
    tests/brdf/test_ashikhmin_shirley.py runs the white furnace on such extremes.

    Sampling: one-sample mixture of cosine-weighted directions (diffuse, weight lum(R_d)(1 − lum(R_s))) and
    the paper's half-vector sampling (weight lum(R_s) + (1 − lum(R_s))/21, the cosine-weighted mean of
    Schlick's F): φ_h = atan(sqrt((n_u + 1)/(n_v + 1)) tan(π u/2)) mapped to one of four quadrants,
    cosθ_h = (1 − u₂)^(1/(n_u cos²φ_h + n_v sin²φ_h + 1)), density sqrt((n_u + 1)(n_v + 1))/(2π)
    (n·h)^(n_u cos²φ_h + n_v sin²φ_h), reflected about h (p(wi) = p(h)/(4 wo·h)); half vectors facing away
    from wo fail.
    """

    type: Literal["ashikhmin_shirley"] = "ashikhmin_shirley"
    rs: Reflectance = (0.05, 0.05, 0.05)
    rd: Reflectance = (0.5, 0.5, 0.5)
    nu: Exponent = 100.0
    nv: Exponent = 100.0
    #: mapped exponents (one map for both: the split sum interpolates one texel) and the normalisation from them
    lobe_maps: ClassVar[dict[str, LobeMap]] = {
        name: LobeMap(low=0.0, widest="min", derived=(("m_norm", "sqrt((m_nu + 1.0) * (m_nv + 1.0)) / (8.0 * PI)"),))
        for name in ("nu", "nv")
    }

    @classmethod
    def affine_colours(cls, data: dict | None = None) -> tuple[str, ...]:
        """rs (its Fresnel term's F₀ and the diffuse term's 1 − rs) and rd (the diffuse term's colour, over an
        rs-dependent specular): affine in each, bilinear together."""
        return ("rs", "rd")

    def lobe_summary(self):  # its diffuse term is not Lambertian: none split off
        return (0.0, 0.0, 0.0), 2, float(np.sqrt(self.nu * self.nv))

    glsl = "reflets/brdf/glsl/ashikhmin_shirley.glsl"

    @property
    def norm(self) -> float | np.ndarray:
        return np.sqrt((np.asarray(self.nu) + 1.0) * (np.asarray(self.nv) + 1.0))  # per point when mapped

    def eval(self, wo: np.ndarray, wi: np.ndarray) -> np.ndarray:
        wo = np.asarray(wo, dtype=np.float64)
        wi = np.asarray(wi, dtype=np.float64)
        up = upper(wo, wi)
        u = np.where(up, wo + wi, [0.0, 0.0, 1.0])  # keep the arithmetic finite below the horizon
        length = np.linalg.norm(u, axis=-1)
        k_dot_h = 0.5 * length  # wi·(wo + wi)/|wo + wi| = (1 + wo·wi)/|u| = |u|/2
        d = wo - wi
        one_minus_kh = np.sum(d * d, axis=-1) / (2.0 * (2.0 + length))  # 1 − |u|/2 without cancellation
        lobe = np.exp(log_lobe(u, self.nu, self.nv))
        cos_max = np.maximum(np.maximum(wo[..., 2], wi[..., 2]), 1e-300)
        rs = np.asarray(self.rs)
        fresnel = rs + (1.0 - rs) * (one_minus_kh**5)[..., None]
        spec = (self.norm / (8.0 * np.pi) * lobe / (k_dot_h * cos_max))[..., None] * fresnel
        falloff = grazing_falloff(wo[..., 2]) * grazing_falloff(wi[..., 2])
        diffuse = 28.0 / (23.0 * np.pi) * np.asarray(self.rd) * (1.0 - rs) * falloff[..., None]
        return np.where(up, spec + diffuse, 0.0)

    def _weights(self) -> list[float]:
        s = luminance(self.rs)
        return [luminance(self.rd) * (1.0 - s), s + (1.0 - s) / 21.0]

    def sample_half_vector(self, u1: np.ndarray, u2: np.ndarray) -> np.ndarray:
        """Half vectors with density :meth:`pdf_half_vector`; u1 picks the quadrant and φ within it."""
        u1 = 4.0 * np.asarray(u1, dtype=np.float64)
        quadrant = np.minimum(np.floor(u1), 3.0)
        v = np.clip(u1 - quadrant, 0.0, 1.0)
        phi = np.arctan(np.sqrt((self.nu + 1.0) / (self.nv + 1.0)) * np.tan(0.5 * np.pi * v))
        phi = np.select([quadrant == 0, quadrant == 1, quadrant == 2], [phi, np.pi - phi, np.pi + phi], 2 * np.pi - phi)
        cos_phi, sin_phi = np.cos(phi), np.sin(phi)
        exponent = self.nu * cos_phi**2 + self.nv * sin_phi**2
        cos_t = np.power(1.0 - np.asarray(u2, dtype=np.float64), 1.0 / (exponent + 1.0))
        sin_t = np.sqrt(np.maximum(0.0, 1.0 - cos_t * cos_t))
        return np.stack([sin_t * cos_phi, sin_t * sin_phi, cos_t], axis=-1)

    def pdf_half_vector(self, u: np.ndarray) -> np.ndarray:
        """sqrt((n_u + 1)(n_v + 1))/(2π) (n·h)^(n_u cos²φ_h + n_v sin²φ_h) for h = u/|u| above the surface."""
        ok = u[..., 2] > 0
        safe = np.where(ok[..., None], u, [0.0, 0.0, 1.0])
        return np.where(ok, self.norm / (2.0 * np.pi) * np.exp(log_lobe(safe, self.nu, self.nv)), 0.0)

    def brdf_uniforms(self) -> dict[str, object]:
        return {
            "m_rs": tuple(self.rs),
            "m_rd": tuple(self.rd),
            "m_nu": float(self.nu),
            "m_nv": float(self.nv),
            "m_norm": float(self.norm / (8.0 * np.pi)),
        }
