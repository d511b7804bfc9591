"""Phong reflection, in the area-light document's un-normalised form (its eq 1.5) or energy-normalised."""

from __future__ import annotations

from typing import ClassVar, Literal

import numpy as np
from pydantic import Field

from .base import (
    Reflectance,
    finish_sample,
    luminance,
    mix_pdf,
    pdf_cosine,
    register_material,
    sample_cosine,
    sample_mixture,
    sample_power_cosine,
    upper,
)
from .maps import LobeMap, Mapped


def mirror(wo: np.ndarray) -> np.ndarray:
    """r = reflect(wo, n) = (−wo.x, −wo.y, wo.z) in the local frame."""
    return np.asarray(wo, dtype=np.float64) * np.array([-1.0, -1.0, 1.0])


def phong_lobe(cos_a: np.ndarray, exponent: float) -> np.ndarray:
    """max(0, cos α)^e with the lobe zero behind its axis (cos α ≤ 0) for every e, including e = 0."""
    return np.where(cos_a > 0.0, np.maximum(cos_a, 0.0) ** exponent, 0.0)


def pdf_lobe(axis: np.ndarray, exponent: float, w: np.ndarray) -> np.ndarray:
    """Density of :func:`~reflets.brdf.base.sample_power_cosine`: (e + 1)/(2π) cos^e α on the hemisphere
    around ``axis`` and 0 behind it (``base.pdf_power_cosine`` returns 1/(2π) there when e = 0)."""
    return (exponent + 1.0) / (2.0 * np.pi) * phong_lobe(np.sum(axis * w, axis=-1), exponent)


@register_material
class Phong(Mapped):
    """Diffuse + Phong specular lobe around the mirror direction r = reflect(wo, n).

    Parameters
    ----------
    kd : [r, g, b] in [0, 1], default [0, 0, 0]
        Diffuse reflectance ρ_d (term ρ_d/π).
    ks : [r, g, b] in [0, 1], default [1, 1, 1]
        Specular coefficient ρ_s.
    exponent : float in [0, 1e6], default 100
        Lobe exponent e. The lobe max(0, r·wi)^e is zero where r·wi ≤ 0, also for e = 0 (then it is the
        indicator of the hemisphere around r).
    normalized : bool, default false
        false: the document's form (its eq 1.5), f = ρ_d/π + ρ_s (r·wi)^e / (n·wi), so that f cosθ_i =
        ρ_s (r·wi)^e — reproduces the document's figures but is neither reciprocal nor energy conserving.
        true: f = ρ_d/π + ρ_s (e + 2)/(2π) (r·wi)^e (Lafortune & Willems 1994, "Using the modified Phong
        reflectance model for physically based rendering"): reciprocal, the lobe reflects exactly ρ_s at
        normal incidence and less elsewhere, so energy conserving when ρ_d + ρ_s ≤ 1 per channel.

    Sampling: one-sample mixture of cosine-weighted directions (diffuse) and directions with density
    (e + 1)/(2π) cos^e α around r (specular), chosen by the luminances of ρ_d and ρ_s. Lobe directions may
    fall below the surface (f = 0 there); no sample fails.
    """

    type: Literal["phong"] = "phong"
    kd: Reflectance = (0.0, 0.0, 0.0)
    ks: Reflectance = (1.0, 1.0, 1.0)
    exponent: float = Field(default=100.0, ge=0, le=1e6, allow_inf_nan=False)
    normalized: bool = False
    lambertian_field: ClassVar[str] = "kd"
    specular_field: ClassVar[str] = "ks"
    linear_specular: ClassVar[str] = "ks"
    lobe_maps: ClassVar[dict[str, LobeMap]] = {"exponent": LobeMap(low=0.0, widest="min", column=True)}

    def lobe_summary(self):
        return tuple(float(c) for c in self.kd), 1, float(self.exponent)

    glsl = "reflets/brdf/glsl/phong.glsl"

    def eval(self, wo: np.ndarray, wi: np.ndarray) -> np.ndarray:
        wo = np.asarray(wo, dtype=np.float64)
        wi = np.asarray(wi, dtype=np.float64)
        lobe = phong_lobe(np.sum(mirror(wo) * wi, axis=-1, keepdims=True), self.exponent)
        if self.normalized:
            spec = (self.exponent + 2.0) / (2.0 * np.pi) * lobe
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

    def sample(self, wo: np.ndarray, u1: np.ndarray, u2: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Mixture of cosine sampling (diffuse) and a cos^e lobe around the mirror direction (specular)."""
        wo = np.broadcast_to(np.asarray(wo, dtype=np.float64), np.shape(u1) + (3,))
        r = mirror(wo)

        def lobe(a, b, chosen):
            return sample_power_cosine(r[chosen], self.exponent, a, b)

        wi = sample_mixture(self._weights(), [lambda a, b, _: sample_cosine(a, b), lobe], u1, u2)
        return finish_sample(self, wo, wi)

    def pdf(self, wo: np.ndarray, wi: np.ndarray) -> np.ndarray:
        wi = np.asarray(wi, dtype=np.float64)
        lobe = pdf_lobe(mirror(wo), self.exponent, wi)
        return mix_pdf(self._weights(), [pdf_cosine(wi), lobe])

    def brdf_uniforms(self) -> dict[str, object]:
        return {
            "m_kd": tuple(self.kd),
            "m_ks": tuple(self.ks),
            "m_exponent": float(self.exponent),
            "m_normalized": bool(self.normalized),
        }
