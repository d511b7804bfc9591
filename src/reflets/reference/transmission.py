"""Light seen through transmissive glTF surfaces (KHR_materials_transmission, KHR_materials_volume) for the reference.

A camera path that hits a transmissive surface is continued through it, one sampled direction per sample, and
the radiance found there (traced like a camera ray: direct lighting, emitters, the background) is added with the
weight of the surface's transmission lobe:

- **thin-walled** (thickness 0): the extension's BTDF — the GGX lobe of the reflection mirrored through the
  surface, so a smooth surface lets light through unbent — weighted by (1 − m) t c (1 − w max F(v·h)) (the
  ``fresnel_mix`` of glTF's Appendix B with the diffuse lobe's share t transmitted, tinted by the base colour c),
  × (1 − c_c F_c) under a clear coat and × (1 − max(C) E(n·v)) under a sheen. Half vectors are drawn from the
  visible normals (Heitz 2018), so the lobe's weight is G₂ / G₁.
- **a volume** (thickness > 0): the surface bounds a dielectric of index ``ior``: the path refracts in through a
  sampled microfacet normal (same weight, Schlick's F at v·h), travels inside with Beer–Lambert attenuation
  exp(−σ d) (σ from ``attenuation_color`` / ``attenuation_distance``), and at the next surface it meets leaves by
  refraction with probability 1 − F or reflects back inside with probability F (total internal reflection:
  always), F Schlick's at the transmitted side's cosine. The base colour tints once, where the path enters (as
  Khronos' sample viewer). The η² radiance scaling of crossing an interface is left out (it cancels over a way in
  and out; not for light met inside the volume, an emitter or an object there).

Neither renderer carries light *to* other surfaces through a transmissive one: its shadow is opaque (a caustic
or a coloured shadow is not direct lighting), and lights are not seen through a rough surface's lobe by their own
sampling — only when the continued path meets an area light or the environment. Paths cross at most
``MAX_CROSSINGS`` surfaces (each with its own three uniform numbers); beyond, they end dark.
"""

from __future__ import annotations

import numpy as np

from ..brdf.gltf import COAT_F0, sheen_albedo
from ..brdf.microfacet import Distribution, smith_lambda_ggx
from ..fresnel import fresnel_schlick

#: the most transmissive surfaces one camera path crosses (a thin-walled sphere: 2; a glass sphere with a few
#: internal reflections: 4 and more)
MAX_CROSSINGS = 6
#: uniform numbers per crossing: the half vector (2) and the choice between reflection and refraction inside
NUMBERS_PER_CROSSING = 3


class Transmission:
    """Which materials transmit, and the continued paths' radiance."""

    def __init__(self, materials: list):
        self.materials = {k: m for k, m in enumerate(materials) if getattr(m, "transmissive", False)}

    def __bool__(self) -> bool:
        return bool(self.materials)

    def radiance(self, ref, idx: np.ndarray, surf, bound: dict, wo: np.ndarray, u: np.ndarray, depth: int,
                 medium: np.ndarray | None, first: int) -> np.ndarray:  # fmt: skip
        """Radiance through the surfaces at the hits ``idx`` (their shading ``surf``, ``bound`` materials and local
        ``wo``) × its weight; ``medium`` (N, 4): σ of the volume each path travels in and 1 (outside: None, or 0
        there); ``first`` the first column of this crossing's uniform numbers in ``u``."""
        n = len(idx)
        out = np.zeros((n, 3))
        if depth >= MAX_CROSSINGS:
            return out
        u1, u2, u3 = (u[idx, first + k] for k in range(NUMBERS_PER_CROSSING))
        inside = np.zeros(n, dtype=bool) if medium is None else medium[idx, 3] > 0
        direction = np.zeros((n, 3))
        weight = np.zeros((n, 3))
        next_medium = np.zeros((n, 4))
        for m_index, (s, points) in bound.items():
            material = self.materials.get(m_index)
            if material is None:
                continue
            rows = np.flatnonzero(s)
            d, w, sigma = _crossing(material, points, wo[rows], u1[rows], u2[rows], u3[rows], inside[rows])
            direction[rows], weight[rows], next_medium[rows] = d, w, sigma
        go = np.flatnonzero(np.any(weight > 0, axis=1))
        if len(go) == 0:
            return out
        world = np.einsum("nij,nj->ni", surf.frame[go], direction[go])
        below = np.sum(world * surf.geometric_normal[go], axis=-1) < 0  # through the surface, or back to this side
        side = np.where(below, -1.0, 1.0)[:, None] * surf.geometric_normal[go]
        start = surf.position[go] + ref.geometry.epsilon * side
        rows = idx[go]
        out[go] = weight[go] * ref.trace(start, world, u[rows], depth=depth + 1, medium=next_medium[go])
        return out


def _crossing(material, points, wo, u1, u2, u3, inside):
    """(direction, weight (N, 3), the medium the path goes on in: σ and 1, or 0 outside) for one material's hits
    (local frames)."""
    n = len(wo)
    into, back, at, ab = points._lobe((n,))
    lobe = Distribution("ggx", at, ab)
    h = back(lobe.sample_visible(into(wo), u1, u2))
    failed = np.isnan(h[:, 0]) | (wo[:, 2] <= 0)
    h = np.where(failed[:, None], [0.0, 0.0, 1.0], h)
    cos_i = np.clip(np.sum(wo * h, axis=-1), 0.0, 1.0)
    f0 = np.broadcast_to(np.max(np.atleast_1d(points.f0), axis=-1), (n,))  # a scalar, (3,) or (N, 3)
    lam_o = smith_lambda_ggx(into(wo), at, ab)

    def g2_over_g1(w):  # the lobe's weight under visible-normal sampling (Λ depends on |cos θ| only)
        return (1.0 + lam_o) / (1.0 + lam_o + smith_lambda_ggx(into(w), at, ab))

    reflected = 2.0 * cos_i[:, None] * h - wo
    sigma = np.zeros((n, 4))
    if not material.volumetric:  # thin-walled: the reflection lobe mirrored through the surface
        direction = reflected * np.array([1.0, 1.0, -1.0])
        valid = ~failed & (reflected[:, 2] > 0)
        weight = _surface_weight(points, wo, fresnel_schlick(cos_i, f0)) * g2_over_g1(direction)[:, None]
        return direction, np.where(valid[:, None], weight, 0.0), sigma
    eta = np.where(inside, material.ior, 1.0 / material.ior)  # incident over transmitted index
    sin2_t = eta * eta * (1.0 - cos_i * cos_i)
    total = sin2_t >= 1.0
    cos_t = np.sqrt(np.maximum(1.0 - sin2_t, 0.0))
    refracted = -eta[:, None] * wo + (eta * cos_i - cos_t)[:, None] * h
    absorption = np.broadcast_to(np.append(material.absorption, 1.0), (n, 4))
    # entering: refract, the reflection being the BRDF's; inside: leave with 1 − F (the ior's F₀, untinted: the
    # GLSL twin's), else reflect back in
    f0 = np.where(inside, material.dielectric_f0, f0)
    fresnel = fresnel_schlick(np.where(inside, cos_t, cos_i), f0)
    stays = inside & (total | (u3 < fresnel))
    direction = np.where(stays[:, None], reflected, refracted)
    valid = ~failed & np.where(stays, reflected[:, 2] > 0, refracted[:, 2] < 0)
    weight = np.where(inside[:, None], 1.0, _surface_weight(points, wo, fresnel)) * g2_over_g1(direction)[:, None]
    sigma = np.where((stays | ~inside)[:, None], absorption, 0.0)
    return direction, np.where(valid[:, None], weight, 0.0), sigma


def _surface_weight(points, wo, fresnel):
    """(1 − m) t c (1 − w F) and the layers' shares above the base (module docstring), (N, 3)."""
    w = np.asarray(points.specular, np.float64)
    share = (1.0 - points.metallic) * points.transmission * (1.0 - w * fresnel)
    if points.coat is not None:
        nv = np.sum(points.coat_normal * wo, axis=-1)
        share = share * (1.0 - points.coat * fresnel_schlick(nv, COAT_F0))
    if points.sheen is not None:
        share = share * np.maximum(1.0 - np.max(points.sheen, axis=-1) * sheen_albedo(wo[:, 2], points.sheen_roughness),
                                   0.0)  # fmt: skip
    return share[:, None] * points.base
