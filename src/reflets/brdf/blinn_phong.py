"""Blinn–Phong reflection, in the area-light document's un-normalised form or energy-normalised."""

from __future__ import annotations

from typing import ClassVar, Literal

import numpy as np
from pydantic import Field

from .base import (
    HalfVectorLobeMixture,
    Reflectance,
    luminance,
    pdf_power_cosine,
    register_material,
    sample_power_cosine,
    upper,
)
from .maps import LobeMap, Mapped

_Z = np.array([0.0, 0.0, 1.0])


def normalization(e: float) -> float:
    """c(e) with ∫ c (n·h)^e cosθ_i dω_i = 1 for wo = n (Giesen 2009)."""
    return (e + 2.0) * (e + 4.0) / (8.0 * np.pi * (2.0 ** (-e / 2.0) + e))


@register_material
class BlinnPhong(HalfVectorLobeMixture, Mapped):
    """Diffuse + Blinn–Phong specular lobe around the half vector h = normalize(wo + wi).

    Parameters
    ----------
    kd : [r, g, b] in [0, 1], default [0, 0, 0]
        Diffuse reflectance ρ_d (term ρ_d/π).
    ks : [r, g, b] in [0, 1], default [1, 1, 1]
        Specular coefficient ρ_s.
    exponent : float ≥ 0, default 100
        Lobe exponent e.
    normalized : bool, default false
        false: the document's form (its eq 1.6), f = ρ_d/π + ρ_s (n·h)^e / (n·wi), so that f cosθ_i =
        ρ_s (n·h)^e — reproduces the document's figures but is not energy conserving.
        true: f = ρ_d/π + ρ_s c(e) (n·h)^e with c(e) = (e + 2)(e + 4) / (8π (2^(−e/2) + e)), the exact
        factor for which the specular lobe reflects all energy at normal incidence (Giesen 2009, "The
        Blinn-Phong normalization zoo"). The popular (e + 8)/(8π) overestimates it — by 6 % at e = 20,
        so a white lobe would reflect more than it receives (tests/brdf/test_blinn_phong.py measures this).
    """

    type: Literal["blinn_phong"] = "blinn_phong"
    kd: Reflectance = (0.0, 0.0, 0.0)
    ks: Reflectance = (1.0, 1.0, 1.0)
    exponent: float = Field(default=100.0, ge=0, le=1e6, allow_inf_nan=False)
    normalized: bool = False
    lambertian_field: ClassVar[str] = "kd"
    specular_field: ClassVar[str] = "ks"
    linear_specular: ClassVar[str] = "ks"
    #: a mapped exponent recomputes the normalisation per fragment (in float32: 1e-6 relative)
    lobe_maps: ClassVar[dict[str, LobeMap]] = {"exponent": LobeMap(low=0.0, widest="min", column=True, derived=(
        ("m_norm", "(m_exponent + 2.0) * (m_exponent + 4.0) / (8.0 * PI * (exp2(-0.5 * m_exponent) + m_exponent))"),
    ))}  # fmt: skip

    def lobe_summary(self):
        return tuple(float(c) for c in self.kd), 2, float(self.exponent)

    glsl = "reflets/brdf/glsl/blinn_phong.glsl"

    def eval(self, wo: np.ndarray, wi: np.ndarray) -> np.ndarray:
        wo = np.asarray(wo, dtype=np.float64)
        wi = np.asarray(wi, dtype=np.float64)
        h = wo + wi
        h /= np.maximum(np.linalg.norm(h, axis=-1, keepdims=True), 1e-300)
        lobe = np.maximum(h[..., 2:3], 0.0) ** self.exponent
        if self.normalized:
            spec = normalization(self.exponent) * lobe
        else:
            spec = lobe / np.maximum(wi[..., 2:3], 1e-300)
        f = np.asarray(self.kd) / np.pi + np.asarray(self.ks) * spec
        return np.where(upper(wo, wi), f, 0.0)

    @property
    def reciprocal(self) -> bool:
        return self.normalized  # the document's 1/(n·wi) factor breaks reciprocity

    @property
    def energy_conserving(self) -> bool:
        return self.normalized and all(d + s <= 1.0 for d, s in zip(self.kd, self.ks, strict=True))

    def _weights(self) -> list[float]:
        d, s = luminance(self.kd), luminance(self.ks)
        return [d, s] if d + s > 0 else [1.0, 0.0]

    def sample_half_vector(self, u1: np.ndarray, u2: np.ndarray) -> np.ndarray:
        """Half vectors with density (e + 1)/(2π) cos^e θ_h around the normal."""
        return sample_power_cosine(_Z, self.exponent, u1, u2)

    def pdf_half_vector(self, h: np.ndarray) -> np.ndarray:
        return pdf_power_cosine(_Z, self.exponent, h)

    def brdf_uniforms(self) -> dict[str, object]:
        return {
            "m_kd": tuple(self.kd),
            "m_ks": tuple(self.ks),
            "m_exponent": float(self.exponent),
            "m_normalized": bool(self.normalized),
            "m_norm": float(normalization(self.exponent)),
        }
