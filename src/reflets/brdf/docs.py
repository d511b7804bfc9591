"""docs/brdfs.md is generated from the material classes' docstrings (one source of truth):
``python -m reflets.brdf.docs > docs/brdfs.md``; a test fails when the page is out of date."""

from __future__ import annotations

import inspect

from . import MATERIALS

HEADER = """# BRDF library

Every material exists twice: a NumPy float64 model (`eval`, `sample`, `pdf` — the reference) and a GLSL twin
(`brdf_eval`) used by the GPU techniques. They are selected by `type` in scene files:

```toml
[materials.metal]
type = "microfacet"
distribution = "ggx"
alpha = [0.1, 0.4]
fresnel = "conductor"
```

## Conventions

- **Local shading frame**: x = the surface tangent (from the mesh's tangents, so anisotropic models follow
  the surface), y = bitangent (= handedness · n × t), z = the shading normal.
- **Argument order** (pbrt's, everywhere in NumPy and GLSL): `eval(wo, wi)` — `wo` points to the viewer,
  `wi` to the light, both away from the surface, unit length. Values are f_r **without** the cosine, and 0
  when either direction is below the surface. Non-reciprocal models (the documents' un-normalised Phong and
  Blinn-Phong) are defined with `wi` as the light direction l of the documents.
- **Sampling**: `sample(wo, u1, u2) -> (wi, pdf)` with pdf in solid angle; a failed sample (a half vector
  facing away from `wo`) returns pdf 0 and a direction below the surface. `pdf(wo, wi)` is the density that
  `sample` draws with; it integrates over the sphere to 1 minus the failure probability.
- **Properties** declared by each model for its parameters: `reciprocal` (f(wo, wi) = f(wi, wo)) and
  `energy_conserving` (directional albedo ≤ 1 for every wo).

## How every model is tested (tests/brdf/)

For each model and several parameter sets (isotropic and anisotropic, sharp and rough):
a closed-form sweep against a formula written independently in the test; zero below the horizon;
Helmholtz reciprocity where declared; `sample` returns `pdf(wo, wi)`; ∫pdf dω = 1 − P(failure), estimated
with a defensive mixture of uniform and model sampling (so a `sample` that does not follow `pdf` is caught);
the albedo estimated with the model's sampling agrees with uniform sampling within 3 standard errors; the
white furnace (albedo ≤ 1 within 3 standard errors) at θo ∈ {0, 0.5, 1.0, 1.4} where energy conservation is
declared; GLSL vs NumPy on 10,000 random direction pairs with max relative error < 1e-3 where f > 1e-4;
and, for every analytic model, the GPU forward renderer against the NumPy reference per pixel on an
anisotropically oriented sphere (tests/test_gpu_vs_reference.py).

## Texture maps

A colour the BRDF is linear in — the Lambertian albedo and the colour scaling the rest — or affine in (a Schlick F₀,
Ashikhmin–Shirley's `rs` and `rd`) may be read from an image, multiplied by a factor (the field's value; default 1), as
glTF's factors and textures are (`reflets.brdf.maps`); so may the lobe shapes (the microfacet and Ward roughness
`alpha`, the Phong and Blinn-Phong `exponent`, Ashikhmin–Shirley's `nu` / `nv`: factor × the texel's R); and every
library material but `measured` takes a normal map (not a mirror: its reflections are traced), an emission and an
ambient occlusion map:

```toml
[materials.wood]
type = "phong"
kd = { texture = "wood.png", factor = [0.9, 0.9, 0.9], transform = { scale = [4, 4] } }
ks = [0.04, 0.04, 0.04]
exponent = { texture = "wood_gloss.png", factor = 200 }
normal_map = { texture = "wood_normal.png", scale = 1.0 }
emission = { texture = "embers.png", factor = [3, 1, 0.2] }
occlusion = { texture = "wood_ao.png", strength = 1.0 }
```

The other keys are a texture's (`uv`, `srgb`, `transform`, `wrap`, `filter`, `channels`: docs/assets.md, *Textures*).
Both renderers read the texels into the parameters before evaluating the BRDF (GPU: `material_surface`, trilinear and
anisotropic mips; reference: bilinear lookups at each hit, averaged over a supersampled pixel). The prefiltered
environment scales the albedos by a colour map's texels — exact for a linear colour —, mixes per channel between the
albedo curves at 0 and at the factors for an affine one (bilinearly for two: exact too) and, for a mapped lobe shape,
interpolates albedo curves and prefiltered levels computed at eight texel values (and the curves at 0 of one mapped
affine colour with it: a roughness and a Schlick F₀ — specular-glossiness). A normal map (glTF's encoding) turns
the shading frame in both renderers; emission adds to every pass; occlusion darkens the environment's light only (glTF's
rule; the references trace occlusion themselves). A mirror's colours weight its traced reflections (`fermat`'s
composite and the reference's mirror bounce read them per point). Refused in one line: a Lafortune lobe's `c`, two
affine colours with a mapped lobe shape (Ashikhmin–Shirley's rs, rd and nu / nv); glTF's material (`type = "gltf"`)
maps metalness and the rest. The area-light methods that integrate constant parameters (`ltc`, `analytic`,
`biased`) leave a material with mapped colours or lobes to `forward` in `auto` (asked for by name, they integrate the
factors and say so); a normal map, emission or occlusion alone keeps them. Measured against the reference:
docs/assets.md, *Textures on the library's materials*.

| type | reciprocal | energy conserving | texture maps |
|---|---|---|---|
"""

PROPERTIES = {
    "lambert": ("yes", "yes (albedo ≤ 1)"),
    "phong": ("normalised form only", "normalised form with kd + ks ≤ 1"),
    "blinn_phong": ("normalised form only", "normalised form with kd + ks ≤ 1"),
    "lafortune": ("yes", "not guaranteed (depends on fitted lobes)"),
    "ward": ("yes", '"duer" variant with kd + ks ≤ 1; "original" exceeds 1 at grazing angles'),
    "ashikhmin_shirley": ("yes", "yes"),
    "microfacet": ("yes", "when diffuse + specular·max F ≤ 1 (single scattering loses energy)"),
    "gltf": ("yes", "pure metals only: Appendix B's dielectric mix exceeds 1 at grazing views (up to 1.31)"),
    "measured": ("yes (φd folding)", "not guaranteed (measured noise, extrapolation near grazing)"),
    "translucent": ("yes", "yes (F_R + F_T·R_total ≤ 1; the far-field BRDF of the medium, see translucency.md)"),
    "mirror": ("yes", "diffuse + reflectance ≤ 1 (checked); the delta lobe is traced by fermat / the reference"),
    "scratched": ("as its base", "as its base (finite part: base × its mean uncovered share; lobes: `scratches`)"),
}


#: what may be a texture, where the model does not say it itself (``Mapped.mappable``)
MAPS = {
    "microfacet": "`diffuse`, `specular` (a Schlick F₀ too: affine), `alpha`",
    "gltf": "every factor (its `*_texture` slots)",
    "scratched": "its base's textures and maps",
    "lafortune": "`kd`; a lobe's `scale` (one texture for all: affine) or `exponent` (one texture for all)",
    "mirror": "`diffuse`, `reflectance` (a conductor's `eta`, `k`: linear data)",
    "translucent": "`albedo_texture`: the light leaving the medium × its texel",
}


def maps(name: str) -> str:
    from .maps import Mapped

    cls = MATERIALS[name]
    if name in MAPS:
        return MAPS[name]
    mappable = (*cls.mappable(), *cls.affine_colours(), *cls.lobe_maps) if issubclass(cls, Mapped) else ()
    return ", ".join(f"`{field}`" for field in mappable) or "none"


def markdown() -> str:
    lines = [HEADER.rstrip("\n")]
    for name in MATERIALS:
        reciprocal, energy = PROPERTIES[name]
        lines.append(f"| `{name}` | {reciprocal} | {energy} | {maps(name)} |")
    for name, cls in MATERIALS.items():
        doc = inspect.cleandoc(cls.__doc__ or "")
        module = inspect.getmodule(cls).__name__
        lines += [
            "",
            f"## `{name}`",
            "",
            f"`{module}.{cls.__name__}` — GLSL twin `{cls.glsl}`",
            "",
            "```text",
            doc,
            "```",
        ]
    return "\n".join(lines) + "\n"


if __name__ == "__main__":
    print(markdown(), end="")
