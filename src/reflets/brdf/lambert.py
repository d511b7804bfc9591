"""Lambertian diffuse reflection, f_r = ρ / π."""

from __future__ import annotations

from typing import ClassVar, Literal

import numpy as np

from .base import Reflectance, register_material, upper
from .maps import Mapped


@register_material
class Lambert(Mapped):
    """Ideal diffuse reflector.

    Parameters
    ----------
    albedo : [r, g, b], each in [0, 1], default [0.8, 0.8, 0.8]
        Hemispherical reflectance ρ; f_r = ρ/π.
    """

    type: Literal["lambert"] = "lambert"
    albedo: Reflectance = (0.8, 0.8, 0.8)
    lambertian_field: ClassVar[str] = "albedo"

    def lambertian_split(self):
        return tuple(float(c) for c in self.albedo), None

    def lobe_summary(self):
        return tuple(float(c) for c in self.albedo), 0, 0.0

    glsl = "reflets/brdf/glsl/lambert.glsl"

    def eval(self, wo: np.ndarray, wi: np.ndarray) -> np.ndarray:
        f = np.broadcast_to(np.asarray(self.albedo) / np.pi, np.shape(wo)[:-1] + (3,))
        return np.where(upper(wo, wi), f, 0.0)

    def brdf_uniforms(self) -> dict[str, object]:
        return {"m_albedo": tuple(self.albedo)}
