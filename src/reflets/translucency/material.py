"""Translucent material: a homogeneous scattering medium behind a dielectric boundary (skin, milk, marble…).

The subsurface light transport itself (single scattering, dipole profiles) is computed by the ``translucent``
technique (reflets.techniques.translucency). As a BRDF — what every other technique and the surface reference
see — the material is its **far-field limit**: a rough dielectric specular reflection (Cook–Torrance with
Beckmann D, separable Smith masking and the exact dielectric Fresnel) plus the diffusion profile integrated
over the surface, i.e. the light a uniformly lit flat sample re-emits:

    f_r = F_R(h) D G / (4 cosθ_o cosθ_i) + F_T(θ_i) F_T(θ_o) R_total / (π c),   c = 1 − 2 C_1^out,

R_total = ∫ 2πr R_d(r) dr of the chosen profile (per channel; for ``multiple_fit``, which models multiple
scattering only, plus single scattering's exitance at normal incidence, so that R_total stands for all orders
as the other profiles do) and C_1^out the first Fresnel moment for light
arriving from outside, so that ∫ (diffuse term) cosθ_o dω_o = F_T(θ_i) R_total (d'Eon's normalisation).
``roughness = 0`` means a smooth interface: no glossy lobe for point lights (the mirror reflection is not
represented by a BRDF). Coefficients are per millimetre; ``mm_per_unit`` converts scene units.
"""

from __future__ import annotations

from functools import partial
from typing import Literal

import numpy as np
from pydantic import Field, model_validator

from ..brdf.base import LIGHT_TYPES, RGB, Material, PointsBRDF, register_material, upper
from ..fresnel import fresnel_dielectric
from ..textures import TextureRef, load_texture, lookup
from .optics import beckmann_d, fresnel_transmittance


@register_material
class Translucent(Material):
    """Homogeneous translucent medium with a dielectric boundary.

    Parameters
    ----------
    preset : one of the twelve measured materials of Jensen et al. 2001 (apple, chicken1, chicken2, cream,
        ketchup, marble, potato, skimmilk, skin1, skin2, spectralon, wholemilk), default none
        Sets sigma_a, sigma_s_prime and eta (1.3; marble 1.5) unless they are given explicitly.
    sigma_a : [r, g, b] in 1/mm, ≥ 0
        Absorption coefficient.
    sigma_s_prime : [r, g, b] in 1/mm, ≥ 0
        Reduced scattering coefficient σ'_s = σ_s (1 − g). Give this or ``sigma_s``.
    sigma_s : [r, g, b] in 1/mm, ≥ 0
        Scattering coefficient (with ``g``).
    g : float in (−1, 1), default 0
        Henyey–Greenstein mean cosine (single scattering's phase function).
    eta : float ≥ 1, default 1.3 (preset's)
        Relative index of refraction n_inside / n_outside; 1 = index-matched boundary (no Fresnel, no refraction).
    roughness : float ≥ 0, default 0
        Beckmann m of the specular interface; 0 = smooth (no glossy highlight).
    profile : "multiple_fit" | "dipole" | "better_dipole" | "normalized_diffusion", default "multiple_fit"
        Diffusion profile of the multiple scattering: ``multiple_fit`` models two or more scattering events only
        (fitted to volumetric Monte Carlo; the single-scattering term adds the first); the document's three
        stand for all orders, so that with single scattering on they count it twice.
    single_scattering : bool, default true
        Add the single-scattering term (technique ``translucent``).
    mm_per_unit : float > 0, default 1
        Millimetres per scene unit.
    """

    type: Literal["translucent"] = "translucent"
    preset: str | None = None
    sigma_a: RGB | None = None
    sigma_s_prime: RGB | None = None
    sigma_s: RGB | None = None
    g: float = Field(0.0, gt=-1, lt=1)
    eta: float | None = Field(None, ge=1.0, le=3.0)
    roughness: float = Field(0.0, ge=0.0, le=1.0)
    profile: Literal["dipole", "better_dipole", "normalized_diffusion", "multiple_fit"] = "multiple_fit"
    single_scattering: bool = True
    mm_per_unit: float = Field(1.0, gt=0, allow_inf_nan=False)
    albedo_texture: TextureRef | None = Field(
        None, description="an albedo map (sRGB colour): the light leaving the medium × its texel at the exit point"
    )
    glsl = "reflets/translucency/shaders/translucent.glsl"

    @model_validator(mode="after")
    def _complete(self):
        from ..translucency.medium import PRESETS

        if self.preset is not None:
            if self.preset not in PRESETS:
                raise ValueError(f"unknown preset {self.preset!r}; allowed: {', '.join(sorted(PRESETS))}")
            p = PRESETS[self.preset]
            if self.sigma_a is None:
                object.__setattr__(self, "sigma_a", tuple(p["sigma_a"]))
            if self.sigma_s_prime is None and self.sigma_s is None:
                object.__setattr__(self, "sigma_s_prime", tuple(p["sigma_s_prime"]))
            if self.eta is None:
                object.__setattr__(self, "eta", p["eta"])
        if self.eta is None:
            object.__setattr__(self, "eta", 1.3)
        if self.sigma_a is None:
            raise ValueError("give sigma_a (1/mm) or a preset")
        if (self.sigma_s_prime is None) == (self.sigma_s is None):
            raise ValueError("give exactly one of sigma_s_prime and sigma_s (1/mm), or a preset")
        if np.any(np.asarray(self.sigma_a) + np.asarray(self.reduced_scattering) <= 0):
            raise ValueError("sigma_a + sigma_s_prime must be > 0 in every channel")
        return self

    # ------------------------------------------------------------------ the medium
    @property
    def reduced_scattering(self) -> np.ndarray:
        if self.sigma_s_prime is not None:
            return np.asarray(self.sigma_s_prime, dtype=np.float64)
        return np.asarray(self.sigma_s, dtype=np.float64) * (1.0 - self.g)

    def medium(self):
        """The scattering medium (coefficients in 1/mm) as a :class:`reflets.translucency.Medium`."""
        from ..translucency.medium import Medium

        sigma_s = (
            np.asarray(self.sigma_s, dtype=np.float64)
            if self.sigma_s is not None
            else self.reduced_scattering / (1.0 - self.g)
        )
        return Medium(np.asarray(self.sigma_a, dtype=np.float64), sigma_s, self.g, float(self.eta))

    def total_reflectance(self) -> np.ndarray:
        """R_total of the profile, per channel (cached by reflets.translucency.profiles)."""
        from ..translucency.profiles import total_reflectance

        return total_reflectance(self.profile, self.medium())

    def diffuse_factor(self) -> np.ndarray:
        """R_total / (π c) per channel: the far-field diffuse term without its two Fresnel transmittances
        (R_total of all orders: profiles.far_field_reflectance)."""
        from ..translucency.optics import diffuse_normalisation
        from ..translucency.profiles import far_field_reflectance

        return far_field_reflectance(self.profile, self.medium()) / (np.pi * diffuse_normalisation(self.eta))

    @property
    def reciprocal(self) -> bool:
        return True

    # ------------------------------------------------------------------ the albedo map
    @property
    def textured(self) -> bool:
        return self.albedo_texture is not None

    def texture_data(self, field: str = "albedo_texture"):
        """The decoded albedo map (colour: sRGB unless its ``srgb`` says otherwise)."""
        return load_texture(self.albedo_texture, True)

    def tint(self, uv: np.ndarray) -> np.ndarray:
        """(N, 3) albedo-map texels at mesh uv (ones without a map): what the light leaving the medium there is
        multiplied by."""
        if self.albedo_texture is None:
            return np.ones((len(uv), 3))
        return lookup(self.albedo_texture, self.texture_data(), uv, "albedo_texture")[:, :3]

    def at(self, uv: np.ndarray, frames=None):
        """The far-field BRDF at mesh uv: its diffusion (subsurface) part × the albedo map, the interface's
        reflection as it is."""
        return self if self.albedo_texture is None else PointsBRDF(partial(self.eval, tint=self.tint(uv)), self)

    @property
    def ibl_interface(self):
        """The interface's reflection alone as a BRDF of the library (Beckmann, the dielectric's Fresnel; Smith's
        exact Λ where this model uses Walter's fit, < 0.6 % apart): the share of the split sum's albedo an albedo map
        does not tint. None without a map, or for a smooth interface (no glossy lobe)."""
        if self.albedo_texture is None or self.roughness <= 0.0:
            return None
        from ..brdf.microfacet import Microfacet

        return Microfacet(distribution="beckmann", alpha=max(self.roughness, 1e-3), fresnel="dielectric",
                          eta=self.eta)  # fmt: skip

    # ------------------------------------------------------------------ BRDF (far-field limit)
    def eval(self, wo: np.ndarray, wi: np.ndarray, tint=1.0) -> np.ndarray:
        """f_r; ``tint`` (N, 3) multiplies the diffusion part (the albedo map at N points, :meth:`at`)."""
        wo = np.asarray(wo, dtype=np.float64)
        wi = np.asarray(wi, dtype=np.float64)
        ok = upper(wo, wi)
        co = np.clip(wo[..., 2], 1e-12, 1.0)
        ci = np.clip(wi[..., 2], 1e-12, 1.0)
        ft = fresnel_transmittance(ci, self.eta) * fresnel_transmittance(co, self.eta)
        diffuse = ft[..., None] * self.diffuse_factor() * tint
        spec = 0.0
        if self.roughness > 0.0:
            h = wo + wi
            h = h / np.maximum(np.linalg.norm(h, axis=-1, keepdims=True), 1e-300)
            m = self.roughness
            ch = np.clip(h[..., 2], 1e-12, 1.0)
            d = beckmann_d(ch, m)
            g = _beckmann_g1(co, m) * _beckmann_g1(ci, m)
            fr = fresnel_dielectric(np.sum(wi * h, axis=-1), self.eta)
            spec = (fr * d * g / (4.0 * co * ci))[..., None]
        return np.where(ok, diffuse + spec, 0.0)

    def techniques(self, mesh) -> dict[str, str]:
        """Point and directional lights: the ``translucent`` pass (single + multiple scattering through the light's
        own light view). Quad / polygon lights and the environment: this far-field BRDF in the BRDF pass."""
        return dict.fromkeys(LIGHT_TYPES[:2], "translucent")

    def uniforms(self) -> dict[str, object]:
        values = {
            "m_eta": float(self.eta),
            "m_roughness": float(self.roughness),
            "m_diffuse": tuple(float(c) for c in self.diffuse_factor()),
        }
        if self.albedo_texture is not None:  # mat3 of mesh uv → image uv, column-major
            values["m_albedo_map_uv"] = self.albedo_texture.uv_uniform()
        return values

    def flags(self) -> dict[str, object]:
        """BRDF_TR_ALBEDO_MAP: 1 + the albedo map's uv set (none without a map)."""
        return {} if self.albedo_texture is None else {"BRDF_TR_ALBEDO_MAP": 1 + self.albedo_texture.uv}

    def textures(self, ctx) -> dict[str, object]:
        if self.albedo_texture is None:
            return {}
        from ..textures import texture_for

        return {"m_albedo_map": texture_for(ctx, self.texture_data())}



def _beckmann_g1(cos_theta, m):
    """Smith G1 for Beckmann, Walter et al. 2007's rational approximation (the GLSL twin uses the same)."""
    a = cos_theta / (m * np.sqrt(np.maximum(1.0 - cos_theta * cos_theta, 1e-300)))
    approx = (3.535 * a + 2.181 * a * a) / (1.0 + 2.276 * a + 2.577 * a * a)
    return np.where(a < 1.6, approx, 1.0)
