"""Smooth mirror: a delta reflection (constant reflectance or exact conductor Fresnel) plus an optional
Lambertian part.

The delta lobe has no finite BRDF value, so ``eval`` (and the GLSL twin) return only the Lambertian part:
every technique that does not trace reflections shows a mirror's non-specular part, and the techniques that
do (``fermat``, the reference's mirror bounce) weight the reflected radiance by ``reflectance(cos)``.
"""

from __future__ import annotations

from typing import ClassVar, Literal

import numpy as np
from pydantic import model_validator

from ..fresnel import GOLD_ETA, GOLD_K, fresnel_conductor
from ..quantities import Positive
from .base import LIGHT_TYPES, RGB, Reflectance, register_material, upper
from .maps import Mapped


@register_material
class Mirror(Mapped):
    """Perfectly smooth reflector (for ``reflector = true`` meshes).

    Parameters
    ----------
    reflectance : [r, g, b] in [0, 1], default [1, 1, 1]
        Constant specular reflectance (``fresnel = "none"``).
    fresnel : "none" | "conductor", default "none"
        "conductor": exact reflectance of the complex index eta + i k per RGB channel instead of
        ``reflectance`` (it rises to 1 at grazing incidence).
    eta, k : [r, g, b], default gold
        Complex index of refraction of a conductor (only with ``fresnel = "conductor"``).
    diffuse : [r, g, b] in [0, 1], default [0, 0, 0]
        Optional Lambertian part, f = diffuse/π: the only finite part of the BRDF. With a constant
        reflectance, diffuse + reflectance must not exceed 1 per channel (the factors, with maps).

    Maps: ``diffuse`` and ``reflectance`` (sRGB colours), ``eta`` and ``k`` (linear data) may be textures, factor ×
    texel: ``fermat``'s composite reads them at each reflector pixel's uv (the G-buffer keeps it), the reference's
    mirror bounce at its hit's; a normal map is refused (the reflections are traced about the mesh's own normals).
    """

    type: Literal["mirror"] = "mirror"
    reflectance: Reflectance = (1.0, 1.0, 1.0)
    fresnel: Literal["none", "conductor"] = "none"
    eta: tuple[Positive, Positive, Positive] | None = None
    k: RGB | None = None
    diffuse: Reflectance = (0.0, 0.0, 0.0)
    glsl = "reflets/brdf/glsl/mirror.glsl"
    lambertian_field: ClassVar[str] = "diffuse"
    data_maps: ClassVar[tuple[str, ...]] = ("eta", "k")

    @classmethod
    def mappable(cls, data: dict | None = None) -> tuple[str, ...]:
        """The diffuse colour and what weights the reflection: the reflectance, or a conductor's η and k (the
        finite BRDF is linear in the diffuse colour; the delta lobe is evaluated per point by its tracers)."""
        conductor = (data or {}).get("fresnel") == "conductor"
        return ("diffuse", *(("eta", "k") if conductor else ("reflectance",)))

    def lambertian_split(self):
        return tuple(float(c) for c in self.diffuse), None  # the delta lobe leaves no finite part

    def lobe_summary(self):
        return tuple(float(c) for c in self.diffuse), 0, 0.0  # the cone-based methods: the diffuse part alone

    def factor(self, field: str):
        return {"eta": self.eta_rgb, "k": self.k_rgb}.get(field) or getattr(self, field)  # (None: gold's)

    @model_validator(mode="after")
    def _check(self) -> Mirror:
        if (self.eta is not None or self.k is not None) and self.fresnel != "conductor":
            raise ValueError('eta and k apply only to fresnel = "conductor"')
        if self.fresnel == "conductor" and (self.eta is None) != (self.k is None):
            raise ValueError('fresnel = "conductor" takes both eta and k, or neither (gold)')
        total = np.add(self.diffuse, self.reflectance)
        if self.fresnel == "none" and np.any(total > 1.0 + 1e-9):
            raise ValueError(f"diffuse + reflectance exceeds 1 ({self.diffuse} + {self.reflectance})")
        if self.normal_map is not None:  # fermat and the reference's bounce reflect about the geometric normal
            raise ValueError("a mirror takes no normal_map: its reflections are traced from the mesh's own normals")
        return self

    @property
    def eta_rgb(self) -> tuple[float, float, float]:
        return tuple(self.eta) if self.eta is not None else GOLD_ETA

    @property
    def k_rgb(self) -> tuple[float, float, float]:
        return tuple(self.k) if self.k is not None else GOLD_K

    def specular_reflectance(self, cos: np.ndarray, uv: np.ndarray | None = None) -> np.ndarray:
        """Weight of the mirror-reflected radiance at incidence cosine ``cos``, shape (..., 3); ``uv``: the points'
        uv sets (N, 4), where a map reads them (the GLSL twin's ``mirror_reflectance`` after ``material_surface``)."""
        c = np.asarray(cos, dtype=np.float64)[..., None]

        def value(field: str, constant) -> np.ndarray:
            mapped = uv is not None and field in (self.maps or {})
            return np.asarray(constant, np.float64) * (self.texels(field, uv) if mapped else 1.0)

        if self.fresnel == "conductor":
            return fresnel_conductor(c, value("eta", self.eta_rgb), value("k", self.k_rgb))
        return np.broadcast_to(value("reflectance", self.reflectance), c.shape[:-1] + (3,))

    def eval(self, wo: np.ndarray, wi: np.ndarray) -> np.ndarray:
        f = np.broadcast_to(np.asarray(self.diffuse) / np.pi, np.shape(wo)[:-1] + (3,))
        return np.where(upper(wo, wi), f, 0.0)

    def techniques(self, mesh) -> dict[str, str]:
        """A reflector mesh: the ``fermat`` pass under every light (its non-specular part, then the exact
        reflections of the other meshes); a plain mesh: its BRDF."""
        return dict.fromkeys(LIGHT_TYPES, "fermat") if getattr(mesh, "reflector", False) else {}

    def brdf_uniforms(self) -> dict[str, object]:
        return {
            "m_diffuse": tuple(self.diffuse),
            "m_reflectance": tuple(self.reflectance),
            "m_eta": self.eta_rgb,
            "m_k": self.k_rgb,
        }

    def flags(self) -> dict[str, object]:
        return {"BRDF_MIRROR_CONDUCTOR": int(self.fresnel == "conductor")}
