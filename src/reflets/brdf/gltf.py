"""glTF 2.0's metallic-roughness material (the specification's Appendix B), with its textures.

    f = (1 − m) [ (1 − F_d) · c/π + F_d · D V ] + m · F_m · D V

with c the base colour, m the metallic factor, α = roughness², D the isotropic GGX distribution, V = G₂ / (4 |n·l|
|n·v|) with the height-correlated Smith G₂ = 1 / (1 + Λ(v) + Λ(l)) (the form of Appendix B's sample
implementation), F_d = F₀ + (1 − F₀)(1 − |v·h|)⁵ (the dielectric's Schlick Fresnel, F₀ = ((η − 1) / (η + 1))²: 0.04
at glTF's η = 1.5, KHR_materials_ior's ``ior`` otherwise; η = 0 makes F_d = 1, as the extension defines it) and
F_m = c + (1 − c)(1 − |v·h|)⁵ (the metal's, F₀ = c). Single scattering, like the specification: rough metals
lose energy at grazing angles.

Every factor may be read from a texture (``*_texture``: a :class:`~reflets.textures.TextureRef`), multiplied by the
factor as glTF does: base colour (sRGB, alpha in A), metallic (B) and roughness (G) of the metallic-roughness
texture, a tangent-space normal map (scaled by ``normal_scale`` in x and y), occlusion (R; only the environment's
light is occluded, as glTF defines it) and emission (sRGB) × ``emissive_strength``.

KHR_materials_clearcoat layers a second GGX lobe on top, as the extension defines it:

    f_coated = (1 − c F_c) f + c F_c · D_c V_c · (n_c·l) / (n·l)

with c = ``clearcoat`` (× R of ``clearcoat_texture``), α_c = ``clearcoat_roughness``² (× G of its texture),
F_c = 0.04 + 0.96 (1 − |v·n_c|)⁵ and n_c the coat's normal: the geometric normal, or its own normal map
(``clearcoat_normal_texture``; the base's normal map does not bend the coat). The coat lobe is lit with its own
cosine (n_c·l), like Khronos' sample viewer; the renderers multiply f by the base's n·l, hence the ratio. The
layering weighs the base by 1 − c F_c at the view direction only: a coated material is not reciprocal (the
extension's, like Appendix B's energy excess).

KHR_materials_sheen lays a fabric's back-scattering sheen over the base (under the coat), as the extension defines it:

    f_sheened = C · D_s V_s + f · min(1 − max(C) E(n·v), 1 − max(C) E(n·l))

with C = ``sheen_color`` (× RGB of ``sheen_color_texture``, sRGB), D_s the "Charlie" distribution (Conty Estevez &
Kulla 2017) of α_s = ``sheen_roughness``² (× A of ``sheen_roughness_texture``; roughness at least 0.07, as three.js
clamps it), V_s its fitted Smith visibility (the extension's "Charlie" λ, not Ashikhmin's
approximation), no Fresnel, and E(μ) the sheen lobe's directional albedo (the fourth channel of the split-sum
table, :func:`ibl_table`; both renderers interpolate the same table) — the albedo-scaling layering in its
reciprocal form. A limit of the extension's formulas: with its λ, E exceeds 1 at grazing angles for smooth
sheens (E = 2.1 at n·v = 1/64, roughness 0.07; 0.90 at 1/16: ``sheen_albedo``'s values), which would make the
scaling negative; it is clamped at 0.

KHR_materials_specular tints and weighs the dielectric's Fresnel (Khronos' ``fresnel_mix``): with w = ``specular``
(× A of ``specular_texture``) and F₀ = min(((η − 1) / (η + 1))² × ``specular_color`` (× RGB of its texture, sRGB),
1) per channel, F = F₀ + (1 − F₀)(1 − |v·h|)⁵ and the dielectric is (1 − w max(F)) c/π + w F D V.

KHR_materials_anisotropy stretches the base's GGX lobe along a direction of the tangent plane, as the extension
defines it: with s = ``anisotropy_strength`` (× B of ``anisotropy_texture``) and the direction (1, 0) — or the
texture's RG × 2 − 1 — turned by ``anisotropy_rotation`` (radians, from the tangent towards the bitangent),
α_t = mix(α, 1, s²) along it and α_b = α across it, in the anisotropic D and the height-correlated Smith V (the
extension's V = 0.5 / (n·l |(α_t t·v, α_b b·v, n·v)| + n·v |(α_t t·l, α_b b·l, n·l)|) is this G₂ / (4 n·l n·v)).
The direction lies in the (normal-mapped) shading frame in both renderers; the sample viewer builds its bitangent
from the geometric normal instead — the same where no normal map tilts the frame.

KHR_materials_unlit (``unlit``): no light is reflected; the surface shows its base colour (× texture) as the radiance
leaving it, whatever the lights — an emitter with a zero BRDF in both renderers.

KHR_materials_transmission (``transmission``, × R of ``transmission_texture``): a share t of the dielectric's diffuse
lobe is transmitted instead — f keeps (1 − m)(1 − w max F)(1 − t) c/π — and goes through the surface, tinted by
c: thin-walled, or into the volume KHR_materials_volume bounds when ``thickness`` > 0 (absorbing by
``attenuation_color`` over ``attenuation_distance``). The light through is not part of this BRDF: each renderer
carries it its own way (docs/assets.md, *Transmission*).

Both renderers evaluate the textures first into per-point parameters and then the unchanged BRDF: GLSL through
``material_surface`` (``glsl/gltf.glsl``), NumPy through :meth:`Gltf.at` (a :class:`GltfPoints` of arrays).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from pathlib import Path
from typing import Annotated, ClassVar, Literal

import numpy as np
from pydantic import Field, field_validator, model_validator

from ..cache import Cache, source_hash
from ..quantities import NonNeg
from ..textures import TextureRef, load_texture, lookup
from .base import RGB, Material, Unit, perturbed_frame, register_material
from .microfacet import Distribution, _normalize, smith_lambda_ggx

#: the smallest α = roughness² rendered (a glTF roughness of 0 is a mirror; below this GGX is a delta in float32)
MIN_ALPHA = 1e-3
DIELECTRIC_F0 = 0.04
#: the texture slots: (field, sampler uniform, sRGB by role, flag)
SLOTS = (
    ("base_color_texture", "m_base_color_map", True, "BRDF_GLTF_BASE_MAP"),
    ("metallic_roughness_texture", "m_metallic_roughness_map", False, "BRDF_GLTF_MR_MAP"),
    ("normal_texture", "m_normal_map", False, "BRDF_GLTF_NORMAL_MAP"),
    ("occlusion_texture", "m_occlusion_map", False, "BRDF_GLTF_OCCLUSION_MAP"),
    ("emissive_texture", "m_emissive_map", True, "BRDF_GLTF_EMISSIVE_MAP"),
    ("clearcoat_texture", "m_clearcoat_map", False, "BRDF_GLTF_COAT_MAP"),
    ("clearcoat_roughness_texture", "m_clearcoat_roughness_map", False, "BRDF_GLTF_COAT_ROUGHNESS_MAP"),
    ("clearcoat_normal_texture", "m_clearcoat_normal_map", False, "BRDF_GLTF_COAT_NORMAL_MAP"),
    ("sheen_color_texture", "m_sheen_color_map", True, "BRDF_GLTF_SHEEN_MAP"),
    ("sheen_roughness_texture", "m_sheen_roughness_map", False, "BRDF_GLTF_SHEEN_ROUGHNESS_MAP"),
    ("specular_texture", "m_specular_map", False, "BRDF_GLTF_SPECULAR_MAP"),
    ("specular_color_texture", "m_specular_color_map", True, "BRDF_GLTF_SPECULAR_COLOR_MAP"),
    ("anisotropy_texture", "m_anisotropy_map", False, "BRDF_GLTF_ANISOTROPY_MAP"),
    ("transmission_texture", "m_transmission_map", False, "BRDF_GLTF_TRANSMISSION_MAP"),
    ("thickness_texture", "m_thickness_map", False, "BRDF_GLTF_THICKNESS_MAP"),
)
#: the smallest sheen roughness rendered (three.js clamps it there: below, the Charlie lobe is a needle at grazing
#: half vectors)
MIN_SHEEN_ROUGHNESS = 0.07
#: the clear coat's Fresnel reflectance at normal incidence (η = 1.5)
COAT_F0 = 0.04

Rgba = tuple[Unit, Unit, Unit, Unit]


@dataclass
class GltfPoints:
    """The material at N surface points (float64 arrays): base colour (N, 3), metallic (N,), α (N,). Its
    ``eval`` / ``sample`` / ``pdf`` take (N, 3) directions, one per point."""

    base: np.ndarray
    metallic: np.ndarray
    alpha: np.ndarray
    coat: np.ndarray | None = None  # (N,) clear coat weight; None: no coat
    coat_alpha: np.ndarray | None = None  # (N,)
    coat_normal: np.ndarray | None = None  # (N, 3) in the shading frame (unit)
    f0: np.ndarray | float = DIELECTRIC_F0  # the dielectric's Fresnel at normal incidence: scalar or (N, 3)
    specular: np.ndarray | float = 1.0  # its weight (KHR_materials_specular), scalar or (N,)
    sheen: np.ndarray | None = None  # (N, 3) sheen colour; None: no sheen
    sheen_roughness: np.ndarray | None = None  # (N,), at least MIN_SHEEN_ROUGHNESS
    anisotropy: np.ndarray | None = None  # (N, 3): the direction (cos, sin) in the shading frame and s²; None: none
    unlit: bool = False  # KHR_materials_unlit: reflects nothing (its colour is emitted)
    transmission: np.ndarray | None = None  # (N,) KHR_materials_transmission's weight; None: none

    def eval(self, wo: np.ndarray, wi: np.ndarray) -> np.ndarray:
        if self.unlit:
            return np.zeros(np.broadcast_shapes(np.shape(wo), np.shape(wi)))
        value = self._base_eval(wo, wi)
        if self.sheen is not None:
            value = self._sheened(value, wo, wi)
        if self.coat is None:
            return value
        coat_fresnel, lobe = self._coat(wo, wi)
        weight = (self.coat * coat_fresnel)[..., None]
        return (1.0 - weight) * value + weight * lobe[..., None]

    def _sheened(self, base: np.ndarray, wo: np.ndarray, wi: np.ndarray) -> np.ndarray:
        """C D_s V_s + base · min(1 − max(C) E(n·v), 1 − max(C) E(n·l)) above the surface (module docstring)."""
        wo, wi = np.asarray(wo, np.float64), np.asarray(wi, np.float64)
        r = np.broadcast_to(self.sheen_roughness, wo.shape[:-1])
        nv, nl = wo[..., 2], wi[..., 2]
        up = (nv > 0) & (nl > 0)
        peak = np.max(self.sheen, axis=-1)
        scaling = np.maximum(np.minimum(1.0 - peak * sheen_albedo(nv, r), 1.0 - peak * sheen_albedo(nl, r)), 0.0)
        lobe = charlie_d(_normalize(wo + wi)[..., 2], r * r) * sheen_visibility(nv, nl, r * r)
        return np.where(up[..., None], self.sheen * lobe[..., None] + base * scaling[..., None], 0.0)

    def _coat(self, wo: np.ndarray, wi: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """F_c at wo and the coat lobe D_c V_c (n_c·l) / (n·l) (zero unless wo, wi are above both surfaces)."""
        wo, wi = np.asarray(wo, np.float64), np.asarray(wi, np.float64)
        n = np.broadcast_to(self.coat_normal, wo.shape)
        a = np.broadcast_to(self.coat_alpha, wo.shape[:-1])
        nv, nl = np.sum(n * wo, axis=-1), np.sum(n * wi, axis=-1)
        fresnel = COAT_F0 + (1.0 - COAT_F0) * (1.0 - np.clip(np.abs(nv), 0.0, 1.0)) ** 5
        up = (nv > 0) & (nl > 0) & (wo[..., 2] > 0) & (wi[..., 2] > 0)
        nh = np.sum(n * _normalize(wo + wi), axis=-1)
        with np.errstate(divide="ignore", invalid="ignore"):
            a2 = a * a
            d = np.where(nh > 0, a2 / (np.pi * (nh * nh * (a2 - 1.0) + 1.0) ** 2), 0.0)
            lam = [(np.sqrt(1.0 + a2 * (1.0 - c * c) / (c * c)) - 1.0) / 2.0 for c in (nv, nl)]
            lobe = d / (1.0 + lam[0] + lam[1]) / (4.0 * nv * nl) * nl / wi[..., 2]
        return fresnel, np.where(up, np.nan_to_num(lobe), 0.0)

    def _lobe(self, shape) -> tuple:
        """The base's GGX lobe: (into its frame, back, α_t, α_b) — KHR_materials_anisotropy's direction as the
        lobe's x axis, α_t = mix(α, 1, s²) along it; without anisotropy the shading frame and α, α."""
        a = np.broadcast_to(self.alpha, shape)
        if self.anisotropy is None:
            same = lambda w: w  # noqa: E731
            return same, same, a, a
        aniso = np.broadcast_to(self.anisotropy, (*shape, 3))
        c, s = aniso[..., 0], aniso[..., 1]
        into = lambda w: np.stack([c * w[..., 0] + s * w[..., 1], c * w[..., 1] - s * w[..., 0], w[..., 2]], -1)  # noqa: E731
        back = lambda w: np.stack([c * w[..., 0] - s * w[..., 1], s * w[..., 0] + c * w[..., 1], w[..., 2]], -1)  # noqa: E731
        return into, back, a + aniso[..., 2] * (1.0 - a), a

    def _base_eval(self, wo: np.ndarray, wi: np.ndarray) -> np.ndarray:
        wo, wi = np.asarray(wo, np.float64), np.asarray(wi, np.float64)
        up = (wo[..., 2] > 0) & (wi[..., 2] > 0)
        h = _normalize(wo + wi)
        into, _, at, ab = self._lobe(up.shape)
        cos_h = np.clip(np.sum(wo * h, axis=-1), 0.0, 1.0)
        schlick = (1.0 - cos_h) ** 5
        d = Distribution("ggx", at, ab).d(into(h))
        g2 = 1.0 / (1.0 + smith_lambda_ggx(into(wo), at, ab) + smith_lambda_ggx(into(wi), at, ab))
        with np.errstate(divide="ignore", invalid="ignore"):
            dv = np.where(up, d * g2 / (4.0 * wo[..., 2] * wi[..., 2]), 0.0)
        f0 = np.broadcast_to(self.f0, (*schlick.shape, 3)) if np.ndim(self.f0) else self.f0
        f_d = f0 + (1.0 - f0) * schlick[..., None]  # (…, 3), or (…, 1) for a grey F₀
        w = np.asarray(self.specular, np.float64)[..., None]
        f_m = self.base + (1.0 - self.base) * schlick[..., None]
        m, dv = self.metallic[..., None], dv[..., None]
        diffuse_weight = 1.0 - w * np.max(f_d, axis=-1, keepdims=True)
        if self.transmission is not None:  # the transmitted share of the diffuse lobe goes through the surface
            diffuse_weight = diffuse_weight * (1.0 - self.transmission[..., None])
        value = (1.0 - m) * (diffuse_weight * self.base / np.pi + w * f_d * dv) + m * f_m * dv
        return np.where(up[..., None], value, 0.0)

    def _specular_probability(self) -> np.ndarray:
        """The chance of sampling the GGX lobe: its normal-incidence weight against the diffuse one."""
        luminance = np.array([0.2126, 0.7152, 0.0722])
        lum = self.base @ luminance
        f0 = np.mean(self.f0, axis=-1) if np.ndim(self.f0) else self.f0
        specular = (1.0 - self.metallic) * self.specular * f0 + self.metallic * lum
        diffuse = (1.0 - self.metallic) * (1.0 - self.specular * f0) * lum
        if self.sheen is not None:  # the sheen's broad lobe: sampled by the cosine-weighted directions
            diffuse = diffuse + self.sheen @ luminance
        total = specular + diffuse
        return np.where(total > 0, np.maximum(specular / np.where(total > 0, total, 1.0), 0.1), 1.0)

    def _coat_probability(self, wo: np.ndarray) -> np.ndarray:
        """The chance of sampling the coat's lobe: its Fresnel weight at wo (at most 0.9; 0 without a coat)."""
        if self.coat is None:
            return np.zeros(np.shape(wo)[:-1])
        nv = np.sum(np.broadcast_to(self.coat_normal, np.shape(wo)) * wo, axis=-1)
        fresnel = COAT_F0 + (1.0 - COAT_F0) * (1.0 - np.clip(np.abs(nv), 0.0, 1.0)) ** 5
        return np.clip(self.coat * fresnel, 0.0, 0.9)

    def _coat_frame(self, shape) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        from .base import orthonormal_basis

        n = np.broadcast_to(self.coat_normal, (*shape, 3))
        t, b = orthonormal_basis(n)
        return t, b, n

    def sample(self, wo: np.ndarray, u1: np.ndarray, u2: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """A one-sample mixture: the coat's GGX visible normals about n_c (with probability ``c F_c``), else the
        base's cosine-weighted directions and GGX visible normals (Heitz 2018), reflected."""
        from .base import reflect

        wo = np.asarray(wo, np.float64)
        u1, u2 = np.asarray(u1, np.float64), np.asarray(u2, np.float64)
        q = np.broadcast_to(self._coat_probability(wo), u1.shape)
        if not np.any(q > 0):
            return self._base_sample(wo, u1, u2)
        coat = u1 < q
        u1b = np.clip(np.where(coat, u1 / np.maximum(q, 1e-300), (u1 - q) / np.maximum(1.0 - q, 1e-300)), 0.0,
                      np.nextafter(1.0, 0.0))  # fmt: skip
        wi, _ = self._base_sample(wo, u1b, u2)
        t, b, n = self._coat_frame(u1.shape)
        local = np.stack([np.sum(wo * t, -1), np.sum(wo * b, -1), np.sum(wo * n, -1)], axis=-1)
        a = np.broadcast_to(self.coat_alpha, u1.shape)
        hc = Distribution("ggx", a, a).sample_visible(local, u1b, u2)
        h = hc[..., :1] * t + hc[..., 1:2] * b + hc[..., 2:3] * n
        wi = np.where(coat[..., None], reflect(wo, np.nan_to_num(h)), wi)
        failed = coat & np.isnan(hc[..., 0])
        wi = np.where(failed[..., None], [0.0, 0.0, -1.0], wi)
        return wi, np.where(failed, 0.0, self.pdf(wo, wi))

    def pdf(self, wo: np.ndarray, wi: np.ndarray) -> np.ndarray:
        wo, wi = np.asarray(wo, np.float64), np.asarray(wi, np.float64)
        base = self._base_pdf(wo, wi)
        q = self._coat_probability(wo)
        if not np.any(q > 0):
            return base
        t, b, n = self._coat_frame(wo.shape[:-1])
        h = _normalize(wo + wi)
        to_coat = lambda w: np.stack([np.sum(w * t, -1), np.sum(w * b, -1), np.sum(w * n, -1)], axis=-1)  # noqa: E731
        a = np.broadcast_to(self.coat_alpha, wo.shape[:-1])
        dot = np.sum(wo * h, axis=-1)
        with np.errstate(divide="ignore", invalid="ignore"):
            lobe = np.where(dot > 0, Distribution("ggx", a, a).pdf_visible(to_coat(wo), to_coat(h)) / (4 * dot), 0.0)
        return (1.0 - q) * base + q * np.nan_to_num(lobe)

    def _base_sample(self, wo: np.ndarray, u1: np.ndarray, u2: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """The base's mixture of cosine-weighted directions and GGX visible normals (Heitz 2018) reflected."""
        from .base import reflect, sample_cosine

        wo = np.asarray(wo, np.float64)
        u1, u2 = np.asarray(u1, np.float64), np.asarray(u2, np.float64)
        p = np.broadcast_to(self._specular_probability(), u1.shape)
        lobe = u1 < p
        u1s = np.where(lobe, u1 / np.maximum(p, 1e-300), (u1 - p) / np.maximum(1.0 - p, 1e-300))
        u1s = np.clip(u1s, 0.0, np.nextafter(1.0, 0.0))
        into, back, at, ab = self._lobe(u1.shape)
        h = back(Distribution("ggx", at, ab).sample_visible(into(wo), u1s, u2))
        wi = np.where(lobe[..., None], reflect(wo, np.nan_to_num(h)), sample_cosine(u1s, u2))
        failed = lobe & np.isnan(h[..., 0])
        wi = np.where(failed[..., None], [0.0, 0.0, -1.0], wi)
        return wi, np.where(failed, 0.0, self._base_pdf(wo, wi))

    def _base_pdf(self, wo: np.ndarray, wi: np.ndarray) -> np.ndarray:
        wo, wi = np.asarray(wo, np.float64), np.asarray(wi, np.float64)
        p = self._specular_probability()
        h = _normalize(wo + wi)
        into, _, at, ab = self._lobe(h.shape[:-1])
        dot = np.sum(wo * h, axis=-1)
        with np.errstate(divide="ignore", invalid="ignore"):
            lobe = np.where(dot > 0, Distribution("ggx", at, ab).pdf_visible(into(wo), into(h)) / (4.0 * np.abs(dot)),
                            0.0)  # fmt: skip
        cosine = np.maximum(wi[..., 2], 0.0) / np.pi
        return (1.0 - p) * cosine + p * np.nan_to_num(lobe)


@register_material
class Gltf(Material):
    """glTF 2.0 metallic-roughness (Appendix B), every factor optionally textured (module docstring).

    Parameters
    ----------
    base_color : RGBA in [0, 1], default (1, 1, 1, 1)
        Linear base colour factor (× ``base_color_texture``, sRGB); alpha is coverage (``alpha_mode``).
    metallic, roughness : [0, 1], default 1, 1 (glTF's defaults)
        × the B and G channels of ``metallic_roughness_texture``; α = roughness² (at least 1e-3).
    normal_texture, normal_scale : tangent-space normal map and its xy scale (default 1).
    occlusion_texture, occlusion_strength : ambient occlusion (R) and its strength in [0, 1] (environment light).
    emissive, emissive_texture, emissive_strength : emitted radiance = emissive × texture × strength.
    clearcoat, clearcoat_texture : the clear coat's weight (× R; KHR_materials_clearcoat; default 0: none).
    clearcoat_roughness, clearcoat_roughness_texture : its roughness (× G); α_c = roughness² (at least 1e-3).
    clearcoat_normal_texture, clearcoat_normal_scale : its own tangent-space normal map (else the geometric normal).
    specular, specular_texture : the dielectric's specular weight (× A; KHR_materials_specular; default 1).
    specular_color, specular_color_texture : its Fresnel tint (× RGB, sRGB; default 1, 1, 1; F₀ at most 1).
    unlit : KHR_materials_unlit: the base colour (× texture) is the radiance leaving the surface; lights ignored.
    ior : the dielectric's index of refraction (KHR_materials_ior; default 1.5: F₀ = 0.04; ≥ 1, or 0: F = 1).
    sheen_color, sheen_color_texture : the sheen's colour (× RGB, sRGB; KHR_materials_sheen; default 0: none).
    sheen_roughness, sheen_roughness_texture : its roughness (× A; at least 0.07).
    anisotropy_strength, anisotropy_rotation, anisotropy_texture : KHR_materials_anisotropy (module docstring): the
        strength (× B), the direction's turn in radians, the direction in RG (default 0, 0, none: isotropic).
    transmission, transmission_texture : KHR_materials_transmission's weight (× R; default 0): that share of the
        dielectric's diffuse lobe is transmitted through the surface instead, tinted by the base colour (module
        docstring).
    thickness, thickness_texture : KHR_materials_volume's thickness in the mesh's units (× G; default 0: thin-walled,
        light goes through unbent; above 0 the mesh bounds a volume of index ``ior``).
    attenuation_distance, attenuation_color : the volume's Beer–Lambert absorption: light that travels
        ``attenuation_distance`` (world units; default None: none) inside keeps ``attenuation_color`` of itself.
    alpha_mode : "opaque" (default), "mask" (coverage < alpha_cutoff is a hole) or "blend" (the surface's radiance
        over what lies behind it, weighted by the coverage a: a L + (1 − a) L_behind; its shadow lets 1 − a through).
    """

    type: Literal["gltf"] = "gltf"
    glsl: ClassVar[str] = "reflets/brdf/glsl/gltf.glsl"
    fragment_ibl: ClassVar[bool] = True

    base_color: Rgba = (1.0, 1.0, 1.0, 1.0)
    base_color_texture: TextureRef | None = None
    metallic: Unit = 1.0
    roughness: Unit = 1.0
    metallic_roughness_texture: TextureRef | None = None
    normal_texture: TextureRef | None = None
    normal_scale: Annotated[float, Field(ge=-100, le=100, allow_inf_nan=False)] = 1.0
    occlusion_texture: TextureRef | None = None
    occlusion_strength: Unit = 1.0
    emissive: RGB = (0.0, 0.0, 0.0)
    emissive_texture: TextureRef | None = None
    emissive_strength: NonNeg = 1.0
    clearcoat: Unit = 0.0
    clearcoat_texture: TextureRef | None = None
    clearcoat_roughness: Unit = 0.0
    clearcoat_roughness_texture: TextureRef | None = None
    clearcoat_normal_texture: TextureRef | None = None
    clearcoat_normal_scale: Annotated[float, Field(ge=-100, le=100, allow_inf_nan=False)] = 1.0
    ior: Annotated[float, Field(ge=0, le=100, allow_inf_nan=False)] = 1.5
    specular: Unit = 1.0
    specular_texture: TextureRef | None = None
    specular_color: RGB = (1.0, 1.0, 1.0)
    specular_color_texture: TextureRef | None = None
    unlit: bool = False
    sheen_color: tuple[Unit, Unit, Unit] = (0.0, 0.0, 0.0)
    sheen_color_texture: TextureRef | None = None
    sheen_roughness: Unit = 0.0
    sheen_roughness_texture: TextureRef | None = None
    anisotropy_strength: Unit = 0.0
    anisotropy_rotation: Annotated[float, Field(ge=-1e3, le=1e3, allow_inf_nan=False)] = 0.0
    anisotropy_texture: TextureRef | None = None
    transmission: Unit = 0.0
    transmission_texture: TextureRef | None = None
    thickness: NonNeg = 0.0
    thickness_texture: TextureRef | None = None
    attenuation_distance: Annotated[float, Field(gt=0, le=1e30, allow_inf_nan=False)] | None = None
    attenuation_color: tuple[Unit, Unit, Unit] = (1.0, 1.0, 1.0)
    alpha_mode: Literal["opaque", "mask", "blend"] = "opaque"
    alpha_cutoff: Unit = 0.5
    double_sided: bool = Field(False, description="glTF's flag (reflets shades both sides of every surface)")

    lambertian_field: ClassVar[str | None] = None

    # ------------------------------------------------------------------------------------------ NumPy

    @field_validator("ior")
    @classmethod
    def _ior(cls, value: float) -> float:
        if 0 < value < 1:
            raise ValueError("must be at least 1, or 0 (KHR_materials_ior: a Fresnel of 1 everywhere)")
        return value

    @model_validator(mode="after")
    def _volume(self) -> Gltf:
        if self.volumetric and self.ior == 0:
            raise ValueError("a volume (thickness > 0 with transmission) needs an ior of at least 1, not 0")
        return self

    @property
    def alpha(self) -> float:
        return max(self.roughness * self.roughness, MIN_ALPHA)

    @property
    def dielectric_f0(self) -> float:
        """((η − 1) / (η + 1))²: 0.04 at η = 1.5, 1 at η = 0."""
        return ((self.ior - 1.0) / (self.ior + 1.0)) ** 2

    @property
    def _specular_f0(self) -> float | np.ndarray:
        """The dielectric's F₀ of the factors: the ior's, tinted by ``specular_color`` (RGB) when it is not white."""
        if tuple(self.specular_color) == (1.0, 1.0, 1.0):
            return self.dielectric_f0
        return np.minimum(self.dielectric_f0 * np.asarray(self.specular_color, np.float64), 1.0)

    def constant_points(self, shape: tuple[int, ...] = ()) -> GltfPoints:
        """The factors alone (no texture), broadcast to ``shape`` (the coat's normal: the shading normal)."""
        base = np.broadcast_to(np.asarray(self.base_color[:3], np.float64), (*shape, 3))
        points = GltfPoints(base=base, metallic=np.full(shape, float(self.metallic)), alpha=np.full(shape, self.alpha),
                            f0=self._specular_f0, specular=float(self.specular), unlit=self.unlit)  # fmt: skip
        if self.clearcoat > 0:
            points.coat = np.full(shape, float(self.clearcoat))
            points.coat_alpha = np.full(shape, max(self.clearcoat_roughness**2, MIN_ALPHA))
            points.coat_normal = np.broadcast_to(np.array([0.0, 0.0, 1.0]), (*shape, 3))
        if self.sheened:
            points.sheen = np.broadcast_to(np.asarray(self.sheen_color, np.float64), (*shape, 3))
            points.sheen_roughness = np.full(shape, max(float(self.sheen_roughness), MIN_SHEEN_ROUGHNESS))
        if self.anisotropic:
            points.anisotropy = self._anisotropy(np.array([1.0, 0.0]), np.full(shape, self.anisotropy_strength))
        if self.transmissive:
            points.transmission = np.full(shape, float(self.transmission))
        return points

    @property
    def anisotropic(self) -> bool:
        """KHR_materials_anisotropy's lobe (a zero strength factor disables it, whatever the texture)."""
        return self.anisotropy_strength > 0

    @property
    def tabulated(self) -> bool:
        return super().tabulated and not self.anisotropic

    @property
    def transmissive(self) -> bool:
        """KHR_materials_transmission (a zero factor disables it, whatever the texture; unlit transmits nothing)."""
        return self.transmission > 0 and not self.unlit

    @property
    def volumetric(self) -> bool:
        """KHR_materials_volume: a non-zero thickness factor makes the mesh the boundary of a refracting volume (as
        the extension defines it: a path tracer tests the factor only); zero: thin-walled."""
        return self.transmissive and self.thickness > 0

    @property
    def absorption(self) -> np.ndarray:
        """The volume's absorption coefficient σ (per world unit, RGB): −ln(attenuation_color) / distance."""
        if self.attenuation_distance is None:
            return np.zeros(3)
        colour = np.maximum(np.asarray(self.attenuation_color, np.float64), 1e-30)
        return -np.log(colour) / self.attenuation_distance

    @property
    def fragment_ltc(self) -> bool:
        """Textured or not, save a constant sheen, which the one-material table fits better than the per-fragment
        path's Lambertian stand-in for it (a sphere under two quad lights against the reference: 0.06 % against
        0.73 %; docs/techniques/area-lights.md). An anisotropic lobe is read as the isotropic one of the same area (as
        by the split sum), so ``auto`` lights it by ``forward``."""
        return self.textured or self.unlit or self.transmissive or not self.sheened  # no table for a transmissive one

    def _anisotropy(self, direction: np.ndarray, strength: np.ndarray) -> np.ndarray:
        """(…, 3): the direction turned by ``anisotropy_rotation`` and made unit ((1, 0) where it is zero), s²."""
        c, s = np.cos(self.anisotropy_rotation), np.sin(self.anisotropy_rotation)
        direction = np.broadcast_to(direction, (*np.shape(strength), 2))
        x, y = direction[..., 0], direction[..., 1]
        turned = np.stack([c * x - s * y, s * x + c * y], axis=-1)
        length = np.linalg.norm(turned, axis=-1, keepdims=True)
        unit = np.where(length > 1e-6, turned / np.maximum(length, 1e-300), [1.0, 0.0])
        return np.concatenate([unit, (np.asarray(strength) ** 2)[..., None]], axis=-1)

    @property
    def sheened(self) -> bool:
        """A sheen layer (the extension: a zero sheen colour factor disables it, whatever the texture)."""
        return any(c > 0 for c in self.sheen_color)

    def eval(self, wo: np.ndarray, wi: np.ndarray) -> np.ndarray:
        wo, wi = np.broadcast_arrays(np.asarray(wo, np.float64), np.asarray(wi, np.float64))
        return self.constant_points(wo.shape[:-1]).eval(wo, wi)

    def sample(self, wo, u1, u2):
        wo = np.broadcast_to(np.asarray(wo, dtype=np.float64), np.shape(u1) + (3,))
        return self.constant_points(np.shape(u1)).sample(wo, u1, u2)

    def pdf(self, wo, wi):
        wo, wi = np.broadcast_arrays(np.asarray(wo, np.float64), np.asarray(wi, np.float64))
        return self.constant_points(wo.shape[:-1]).pdf(wo, wi)

    @property
    def reciprocal(self) -> bool:
        """Not with a clear coat: KHR_materials_clearcoat weighs the base by 1 − c F_c at the view direction only."""
        return self.clearcoat == 0.0

    @property
    def energy_conserving(self) -> bool:
        """Only a pure metal: Appendix B weighs the dielectric's diffuse lobe by 1 − F at the half vector, not by
        what the specular lobe takes, so at grazing views the two add up to more than 1 (the white furnace
        measures 1.31 at θo = 1.4 for base colour 0.95, roughness 0.05 — the specification's, not a bug here)."""
        return self.metallic == 1.0 and not self.sheened  # a smooth sheen's albedo exceeds 1 at grazing views

    def lobe_summary(self):
        """The diffuse albedo at normal incidence, c (1 − m)(1 − w max F₀) (KHR_materials_specular's weight and
        tint included), and the GGX lobe as a Blinn-Phong one; an unlit material reflects nothing."""
        if self.unlit:
            return (0.0, 0.0, 0.0), 0, 0.0
        weight = 1.0 - self.specular * float(np.max(self._specular_f0))
        if self.transmissive:  # that share goes through the surface
            weight *= 1.0 - self.transmission
        diffuse = tuple(float(c) * (1.0 - self.metallic) * weight for c in self.base_color[:3])
        from .base import blinn_phong_exponent

        return diffuse, 2, blinn_phong_exponent(self.alpha)

    # ------------------------------------------------------------------------------------------ textures

    @property
    def bends_normals(self) -> bool:
        return self.normal_texture is not None or self.clearcoat_normal_texture is not None

    @property
    def cutout(self) -> bool:
        return self.alpha_mode in ("mask", "blend")

    @property
    def blended(self) -> bool:
        return self.alpha_mode == "blend"

    @property
    def see_through(self) -> bool:
        return self.blended or self.transmissive


    def holes(self, uv: np.ndarray, u: np.ndarray) -> np.ndarray:
        """Where rays go through (N,) at mesh uv, given uniform numbers ``u`` (N,): a cut-out's coverage under
        ``alpha_cutoff``; a blended surface's with probability 1 − coverage (the over operator in expectation, and
        its shadow's transmittance)."""
        coverage = self.coverage(uv)
        return coverage < (u if self.blended else self.alpha_cutoff)

    @property
    def textured(self) -> bool:
        return any(getattr(self, field) is not None for field, *_ in SLOTS)

    def texture_data(self, field: str):
        """The decoded texture of one slot (None when the slot is empty)."""
        ref = getattr(self, field)
        if ref is None:
            return None
        srgb = next(s for f, _, s, _ in SLOTS if f == field)
        return load_texture(ref, srgb)

    def _lookup(self, field: str, uv: np.ndarray) -> np.ndarray | None:
        """(N, 4) texels of a slot at mesh uv: (N, 4) both uv sets (``MeshData.uv_sets``), or (N, 2) the first
        alone; None without a texture."""
        data = self.texture_data(field)
        return None if data is None else lookup(getattr(self, field), data, uv, field)

    def at(self, uv: np.ndarray, frames: tuple[np.ndarray, np.ndarray] | None = None) -> GltfPoints:
        """The material at mesh uv (N, 4 or 2: ``_lookup``): textures × factors (the reference's per-hit
        parameters); ``frames`` (geometric, shading) place the clear coat's normal (without them: the shading
        normal)."""
        n = len(uv)
        base = np.tile(np.asarray(self.base_color[:3], np.float64), (n, 1))
        texels = self._lookup("base_color_texture", uv)
        if texels is not None:
            base = base * texels[:, :3]
        metallic, roughness = np.full(n, float(self.metallic)), np.full(n, float(self.roughness))
        texels = self._lookup("metallic_roughness_texture", uv)
        if texels is not None:
            metallic, roughness = metallic * texels[:, 2], roughness * texels[:, 1]
        points = GltfPoints(base=base, metallic=metallic, alpha=np.maximum(roughness * roughness, MIN_ALPHA),
                            f0=self._specular_f0, specular=float(self.specular), unlit=self.unlit)  # fmt: skip
        texels = self._lookup("specular_texture", uv)
        if texels is not None:
            points.specular = self.specular * texels[:, 3]
        texels = self._lookup("specular_color_texture", uv)
        if texels is not None:
            tint = np.asarray(self.specular_color, np.float64) * texels[:, :3]
            points.f0 = np.minimum(self.dielectric_f0 * tint, 1.0)
        if self.clearcoat > 0:
            self._coat_at(points, uv, frames)
        if self.anisotropic:
            direction, strength = np.array([1.0, 0.0]), np.full(n, float(self.anisotropy_strength))
            texels = self._lookup("anisotropy_texture", uv)
            if texels is not None:
                direction, strength = texels[:, :2] * 2.0 - 1.0, strength * texels[:, 2]
            points.anisotropy = self._anisotropy(direction, strength)
        if self.sheened:
            sheen = np.tile(np.asarray(self.sheen_color, np.float64), (n, 1))
            roughness = np.full(n, float(self.sheen_roughness))
            texels = self._lookup("sheen_color_texture", uv)
            if texels is not None:
                sheen = sheen * texels[:, :3]
            texels = self._lookup("sheen_roughness_texture", uv)
            if texels is not None:
                roughness = roughness * texels[:, 3]
            points.sheen, points.sheen_roughness = sheen, np.maximum(roughness, MIN_SHEEN_ROUGHNESS)
        if self.transmissive:
            points.transmission = np.full(n, float(self.transmission))
            texels = self._lookup("transmission_texture", uv)
            if texels is not None:
                points.transmission = points.transmission * texels[:, 0]
        return points

    def _coat_at(self, points: GltfPoints, uv: np.ndarray, frames) -> None:
        n = len(uv)
        coat, roughness = np.full(n, float(self.clearcoat)), np.full(n, float(self.clearcoat_roughness))
        texels = self._lookup("clearcoat_texture", uv)
        if texels is not None:
            coat = coat * texels[:, 0]
        texels = self._lookup("clearcoat_roughness_texture", uv)
        if texels is not None:
            roughness = roughness * texels[:, 1]
        normal = np.broadcast_to(np.array([0.0, 0.0, 1.0]), (n, 3))
        if frames is not None:  # the geometric normal, or the coat's own normal map on the geometric frame
            geometric, shading = frames
            world = geometric[..., 2]
            texels = self._lookup("clearcoat_normal_texture", uv)
            if texels is not None:
                local = texels[:, :3] * 2.0 - 1.0
                local[:, :2] *= self.clearcoat_normal_scale
                world = perturbed_frame(geometric, local)[..., 2]
            normal = _normalize(np.einsum("nji,nj->ni", shading, world))  # into the shading frame
        points.coat, points.coat_alpha = coat, np.maximum(roughness * roughness, MIN_ALPHA)
        points.coat_normal = normal

    def coverage(self, uv: np.ndarray) -> np.ndarray:
        """Coverage (N,) at mesh uv: the base colour's alpha × its texture's (alpha_mode "mask" cuts below
        ``alpha_cutoff``; the references let rays through there)."""
        alpha = np.full(len(uv), float(self.base_color[3]))
        texels = self._lookup("base_color_texture", uv)
        return alpha if texels is None else alpha * texels[:, 3]

    def emitted(self, uv: np.ndarray) -> np.ndarray:
        """Emitted radiance (N, 3) at mesh uv (unlit: the base colour)."""
        if self.unlit:
            texels = self._lookup("base_color_texture", uv)
            base = np.tile(np.asarray(self.base_color[:3], np.float64), (len(uv), 1))
            return base if texels is None else base * texels[:, :3]
        out = np.broadcast_to(np.asarray(self.emissive, np.float64) * self.emissive_strength, (len(uv), 3)).copy()
        texels = self._lookup("emissive_texture", uv)
        return out if texels is None else out * texels[:, :3]

    def shading_frame(self, frame: np.ndarray, uv: np.ndarray) -> np.ndarray:
        """The frame (N, 3, 3; columns t, b, n) with the normal map applied, rebuilt like GLSL's ``shading_frame``."""
        texels = self._lookup("normal_texture", uv)
        if texels is None:
            return frame
        local = texels[:, :3] * 2.0 - 1.0
        local[:, :2] *= self.normal_scale
        return perturbed_frame(frame, local)

    # ------------------------------------------------------------------------------------------ GPU

    def flags(self) -> dict[str, object]:
        # a slot's flag: 0 without a texture, else 1 + its uv set (gltf.glsl's GLTF_UV picks the set by it)
        refs = {flag: getattr(self, field) for field, _, _, flag in SLOTS}
        return {flag: 0 if ref is None else 1 + ref.uv for flag, ref in refs.items()} | {
            "BRDF_GLTF_MASK": int(self.alpha_mode == "mask"),
            "BRDF_GLTF_BLEND": int(self.alpha_mode == "blend"),
            "BRDF_GLTF_COAT": int(self.clearcoat > 0 and not self.unlit),  # unlit: no layer reflects either
            "BRDF_GLTF_SHEEN": int(self.sheened and not self.unlit),
            "BRDF_GLTF_UNLIT": int(self.unlit),
            "BRDF_GLTF_ANISOTROPY": int(self.anisotropic and not self.unlit),
            "BRDF_GLTF_TRANSMISSION": 2 if self.volumetric else int(self.transmissive),  # 2: a volume
        }

    def uniforms(self) -> dict[str, object]:
        values: dict[str, object] = {
            "m_base_color": tuple(float(c) for c in self.base_color),
            "m_metallic_roughness": (float(self.metallic), float(self.roughness)),
            "m_normal_scale": float(self.normal_scale),
            "m_occlusion_strength": float(self.occlusion_strength),
            "m_emissive": tuple(float(c) * self.emissive_strength for c in self.emissive),
            "m_alpha_cutoff": float(self.alpha_cutoff),
            "m_clearcoat": (float(self.clearcoat), float(self.clearcoat_roughness)),
            "m_clearcoat_normal_scale": float(self.clearcoat_normal_scale),
            "m_sheen": (*(float(c) for c in self.sheen_color), float(self.sheen_roughness)),
            "m_dielectric_f0": float(self.dielectric_f0),
            "m_specular": (*(float(c) for c in self.specular_color), float(self.specular)),
            "m_anisotropy": (math.cos(self.anisotropy_rotation), math.sin(self.anisotropy_rotation),
                             float(self.anisotropy_strength)),  # fmt: skip
            "m_transmission": (float(self.transmission), float(self.thickness), float(self.ior)),
            "m_absorption": tuple(float(c) for c in self.absorption),
        }
        for field, sampler, _, _ in SLOTS:
            ref = getattr(self, field)
            if ref is not None:  # mat3 of mesh uv → image uv, column-major
                values[sampler + "_uv"] = ref.uv_uniform()
        return values

    def textures(self, ctx) -> dict[str, object]:
        from ..textures import texture_for

        out = {"m_ibl_lut": ibl_table_texture(ctx)}
        for field, sampler, _, _ in SLOTS:
            data = self.texture_data(field)
            if data is not None:
                out[sampler] = texture_for(ctx, data, normal_map=field.endswith("normal_texture"))
        return out


def charlie_d(cos_h: np.ndarray, alpha: np.ndarray) -> np.ndarray:
    """The "Charlie" sheen distribution (2 + 1/α) sin^(1/α) θ_h / 2π (Conty Estevez & Kulla 2017)."""
    sin2 = np.clip(1.0 - cos_h * cos_h, 0.0, 1.0)
    return (2.0 + 1.0 / alpha) * sin2 ** (0.5 / alpha) / (2.0 * np.pi)


def _sheen_l(x: np.ndarray, alpha: np.ndarray) -> np.ndarray:
    """The fitted exponent of the Charlie Smith λ (KHR_materials_sheen's table, interpolated in (1 − α)²)."""
    t = (1.0 - alpha) ** 2
    a, b, c = 21.5473 + (25.3245 - 21.5473) * t, 3.82987 + (3.32435 - 3.82987) * t, 0.19823 + (0.16801 - 0.19823) * t
    d, e = -1.97760 + (-1.27393 + 1.97760) * t, -4.32054 + (-4.85967 + 4.32054) * t
    return a / (1.0 + b * np.abs(x) ** c) + d * x + e


def sheen_visibility(nv: np.ndarray, nl: np.ndarray, alpha: np.ndarray) -> np.ndarray:
    """V_s = 1 / ((1 + λ(n·v) + λ(n·l)) 4 n·v n·l), λ(μ) = exp(l(μ)) below ½, exp(2 l(½) − l(1 − μ)) above."""

    def lam(mu):
        return np.where(np.abs(mu) < 0.5, np.exp(_sheen_l(mu, alpha)),
                        np.exp(2.0 * _sheen_l(np.full_like(mu, 0.5), alpha) - _sheen_l(1.0 - mu, alpha)))  # fmt: skip

    with np.errstate(divide="ignore", invalid="ignore", over="ignore"):
        return np.nan_to_num(1.0 / ((1.0 + lam(nv) + lam(nl)) * (4.0 * nv * nl)), posinf=0.0)


def sheen_albedo(mu: np.ndarray, roughness: np.ndarray) -> np.ndarray:
    """E(μ): the sheen lobe's directional albedo (C = 1) at μ = n·v and the sheen roughness, interpolated
    bilinearly in the split-sum table's fourth channel exactly as the GPU's sampler does (texel centres at
    (k + ½) / size, clamped at the edges)."""
    table = ibl_table_cached()[..., 3]
    size = table.shape[0]
    x = np.clip(np.asarray(mu, np.float64) * size - 0.5, 0.0, size - 1.0)
    y = np.clip(np.asarray(roughness, np.float64) * size - 0.5, 0.0, size - 1.0)
    x0, y0 = np.minimum(np.floor(x).astype(int), size - 2), np.minimum(np.floor(y).astype(int), size - 2)
    fx, fy = x - x0, y - y0
    top = table[y0, x0] * (1 - fx) + table[y0, x0 + 1] * fx
    bottom = table[y0 + 1, x0] * (1 - fx) + table[y0 + 1, x0 + 1] * fx
    return top * (1 - fy) + bottom * fy


def sheen_albedo_table(size: int = 32, side: int = 256) -> np.ndarray:
    """(roughness, μ) E = ∫ D_s V_s cos θ_l dω_l at the table's nodes, by the midpoint rule over (cos θ_l, φ_l)
    (side² points; the lobe is smooth in both, peaked only towards grazing for the smallest roughness)."""
    nodes = (np.arange(size) + 0.5) / size
    t = (np.arange(side) + 0.5) / side
    mu_l, phi = (a.ravel() for a in np.meshgrid(t, np.pi * t, indexing="ij"))  # φ in [0, π]: symmetric
    sin_l = np.sqrt(1.0 - mu_l * mu_l)
    wi = np.stack([sin_l * np.cos(phi), sin_l * np.sin(phi), mu_l], axis=-1)
    weight = 2.0 * np.pi / (side * side)  # dω = dμ dφ over [0, 1] × [0, 2π]
    out = np.zeros((size, size))
    for j, mu in enumerate(nodes):
        wo = np.array([np.sqrt(1.0 - mu * mu), 0.0, mu])
        cos_h = _normalize(wo + wi)[:, 2]
        for i, roughness in enumerate(nodes):
            alpha = max(roughness, MIN_SHEEN_ROUGHNESS) ** 2
            f = charlie_d(cos_h, alpha) * sheen_visibility(np.full_like(mu_l, mu), mu_l, alpha)
            out[i, j] = weight * np.sum(f * mu_l)
    return out


#: the split-sum table: IBL_TABLE_SIZE nodes of μ = n·v and of roughness, each at (k + ½) / size (texel centres)
IBL_TABLE_SIZE = 32
IBL_TABLE_SAMPLES = 64  # per side of a stratified grid: 4096 samples per node


def ibl_table(size: int = IBL_TABLE_SIZE, side: int = IBL_TABLE_SAMPLES) -> np.ndarray:
    """(roughness, μ, 4) float32: A = ∫ D V cos (1 − s) dω, B = ∫ D V cos s dω (s = (1 − v·h)⁵), so that the GGX
    lobe's albedo with Schlick's F₀ is F₀ A + B, and P = (1/π) ∫ s cos dω, the dielectric's Fresnel-weighted share
    of its diffuse lobe — by stratified importance sampling (visible normals for A, B; cosine for P); and E, the
    sheen lobe's albedo (:func:`sheen_albedo_table`; the roughness axis is then the sheen roughness)."""
    from .base import sample_cosine

    t = (np.arange(side) + 0.5) / side
    u1, u2 = (a.ravel() for a in np.meshgrid(t, t, indexing="ij"))
    out = np.zeros((size, size, 3))
    nodes = (np.arange(size) + 0.5) / size
    for j, mu in enumerate(nodes):
        wo = np.broadcast_to(np.array([np.sqrt(1.0 - mu * mu), 0.0, mu]), (len(u1), 3))
        wi = sample_cosine(u1, u2)
        h = _normalize(wo + wi)
        p_mean = np.mean((1.0 - np.clip(np.sum(wo * h, axis=-1), 0.0, 1.0)) ** 5)
        for i, roughness in enumerate(nodes):
            a = np.full(len(u1), max(roughness * roughness, MIN_ALPHA))
            ndf = Distribution("ggx", a, a)
            h = ndf.sample_visible(wo, u1, u2)
            wi = 2.0 * np.sum(wo * h, axis=-1, keepdims=True) * h - wo
            up = wi[:, 2] > 0
            # D V cos / pdf with visible normals = G2 / G1(wo)
            g1 = 1.0 / (1.0 + smith_lambda_ggx(wo, a, a))
            g2 = 1.0 / (1.0 + smith_lambda_ggx(wo, a, a) + smith_lambda_ggx(np.where(up[:, None], wi, wo), a, a))
            weight = np.where(up, g2 / g1, 0.0)
            s = (1.0 - np.clip(np.sum(wo * h, axis=-1), 0.0, 1.0)) ** 5
            out[i, j] = (np.mean(weight * (1.0 - s)), np.mean(weight * s), p_mean)
    return np.concatenate([out, sheen_albedo_table(size)[..., None]], axis=-1).astype(np.float32)


IBL_TABLES = Cache("gltf-ibl", lambda path: np.load(path)["table"], lambda table, path: np.savez(path, table=table))


_TABLE: list[np.ndarray] = []


def ibl_table_cached() -> np.ndarray:
    """The split-sum table of this BRDF's source (computed once, then from the on-disk cache)."""
    if not _TABLE:
        key = f"{IBL_TABLE_SIZE}-{IBL_TABLE_SAMPLES}-{source_hash(Path(__file__))}"  # a changed BRDF: made again
        _TABLE.append(IBL_TABLES.get(key, ibl_table))
    return _TABLE[0]


def ibl_table_texture(ctx):
    """The split-sum table as a float texture of ``ctx`` (made once per context; linear, clamped)."""
    import moderngl

    from ..gpu.context import context_store

    store = context_store(ctx, "gltf-ibl")
    if "table" not in store:
        table = ibl_table_cached()
        texture = ctx.texture((table.shape[1], table.shape[0]), 4, np.ascontiguousarray(table).tobytes(), dtype="f4")
        texture.filter = (moderngl.LINEAR, moderngl.LINEAR)
        texture.repeat_x = texture.repeat_y = False
        store["table"] = texture
    return store["table"]
