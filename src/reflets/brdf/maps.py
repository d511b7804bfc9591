"""Texture maps on the BRDF library's colours: ``albedo = { texture = "wood.png" }`` for Lambert, ``kd`` / ``ks`` for
Phong, Blinn-Phong and Ward, ``diffuse`` / ``specular`` for the microfacet model, ``kd`` for Lafortune's.

A mapped colour is its factor × the texture's RGB at the point, like glTF's factors and textures:

    albedo = { texture = "wood.png", factor = [0.9, 0.9, 0.9], uv = 0, srgb = true, transform = { scale = [4, 4] } }

(``factor`` defaults to 1: the texture as it is; the other keys are :class:`~reflets.textures.TextureRef`'s). The
material keeps the factor in the field and the texture in ``maps`` (what a saved scene writes back: ``maps = {
albedo = { texture = … } }`` is read too).

Which colours can be maps: those the BRDF is linear in, per channel — the Lambertian albedo (``lambertian_field``)
and the colour scaling the rest (``linear_specular``). Every renderer then stays exact with the map: the GLSL twin
reads the texel into the colour before ``brdf_eval`` (``material_surface``, as glTF's material does), the NumPy
reference evaluates the BRDF with per-point colours (:meth:`Mapped.at`), and the prefiltered environment scales
the material's albedos by the texels (``material_ibl_scale``: exact for a linear colour). A colour the BRDF is not
linear in (a Schlick F₀, Ashikhmin–Shirley's ``rs``) and lobe shapes (exponents, roughness) are refused with the
list of what can be mapped: glTF's material (``type = "gltf"``) maps roughness and metalness.

In the default method ``auto``, area lights reach a mapped material through ``forward`` (``tabulated`` is False:
``brdf_eval`` per fragment); ``ltc``, ``analytic`` and ``biased`` asked for by name integrate the factors and warn
that they ignore the textures. A scratched material's base takes no maps (``scratches.material``).
"""

from __future__ import annotations

import hashlib
from typing import ClassVar

import numpy as np
from pydantic import Field, model_validator

from ..textures import TextureRef, load_texture, lookup
from .base import Material, PointsBRDF


class Mapped(Material):
    """A material of the BRDF library whose colours may be texture maps (module docstring)."""

    maps: dict[str, TextureRef] | None = Field(None, description="colour parameters read from textures (× the field)")
    #: the colour scaling everything but the Lambertian part, linearly per channel (None: none, or not linearly)
    linear_specular: ClassVar[str | None] = None

    @classmethod
    def mappable(cls, data: dict | None = None) -> tuple[str, ...]:
        """The fields a texture may scale (with these field values: a model's Fresnel may decide)."""
        return tuple(f for f in (cls.lambertian_field, cls.linear_specular) if f is not None)

    @model_validator(mode="before")
    @classmethod
    def _split_maps(cls, data):
        """``field = { texture = … , factor = … }`` → the factor in the field, the texture in ``maps``."""
        if not isinstance(data, dict):
            return data
        data, maps = dict(data), dict(data.get("maps") or {})
        for key, value in list(data.items()):
            if isinstance(value, TextureRef):
                value = value.model_dump()
            if not (isinstance(value, dict) and "texture" in value) or key == "maps":
                continue
            value = dict(value)
            factor = value.pop("factor", None)
            maps[key] = value
            if factor is not None:
                data[key] = factor
            elif key in cls.model_fields:
                data[key] = (1.0, 1.0, 1.0)
        if maps:
            allowed = cls.mappable(data)
            for key in maps:
                if key not in allowed:
                    name = cls.model_fields["type"].default
                    raise ValueError(
                        f"{key} cannot be a texture in a {name} material; textures are accepted for: "
                        f"{', '.join(allowed) or 'none'} (the colours the BRDF is linear in; type = \"gltf\" maps "
                        "roughness and metalness)"
                    )
            data["maps"] = maps
        return data

    # ------------------------------------------------------------------ what varies over the surface

    @property
    def textured(self) -> bool:
        return bool(self.maps)

    def at(self, uv: np.ndarray, frames=None):
        """The material at mesh uv: its BRDF with per-point colours (factor × texel), sampled as the factors are
        (the lobes' shapes do not vary, so the factors' densities cover every point's BRDF)."""
        if not self.maps:
            return self
        colours = {field: np.asarray(getattr(self, field), np.float64) * self.texels(field, uv) for field in self.maps}
        return PointsBRDF(self.model_construct(**{**dict(self), **colours}).eval, self)

    def texels(self, field: str, uv: np.ndarray) -> np.ndarray:
        """(N, 3) texels of a mapped field at mesh uv (as :meth:`at`)."""
        return lookup(self.maps[field], self.texture_data(field), uv, field)[:, :3]

    def texture_data(self, field: str):
        """The decoded texture of a mapped field (colour: sRGB unless its ``srgb`` says otherwise)."""
        return load_texture(self.maps[field], True)

    # ------------------------------------------------------------------ the GLSL twin

    @property
    def brdf_source(self) -> str:
        """The model's GLSL with each mapped colour read from its texture in ``material_surface``: the uniform
        stays the factor, the name the BRDF reads becomes a per-fragment global (``#define``)."""
        if not self.maps:
            return self.glsl
        from ..gpu.programs import read_source, register_source

        lines, surface = [], []
        for line in read_source(self.glsl).splitlines():
            lines.append(line)
            words = line.split(";")[0].split()
            if len(words) == 3 and words[0] == "uniform" and words[2][2:] in self.maps:
                kind, name, field = words[1], words[2], words[2][2:]
                m = self.maps[field].uv_matrix().T.ravel()  # column-major: mesh uv (v up) → image uv
                lines += [
                    f"{kind} map_factor_{field}() {{ return {name}; }}",
                    f"vec3 t_map_{field};  // the texel",
                    f"{kind} g_map_{field};  // factor × texel: what the BRDF reads as {name}",
                    f"uniform sampler2D m_map_{field};",
                    f"const mat3 MAP_UV_{field} = mat3({', '.join(repr(float(v)) for v in m)});",
                    f"#define {name} g_map_{field}",
                ]
                uvs = "uvs.zw" if self.maps[field].uv else "uvs.xy"
                surface += [f"    t_map_{field} = texture(m_map_{field}, (MAP_UV_{field} * vec3({uvs}, 1.0)).xy).rgb;",
                            f"    g_map_{field} = map_factor_{field}() * t_map_{field};"]  # fmt: skip
        missing = [field for field in self.maps if f"#define m_{field} g_map_{field}" not in lines]
        if missing:
            raise RuntimeError(f"{self.glsl} declares no uniform m_{missing[0]} to map")
        scale = [f"    {albedo} *= t_map_{field};"
                 for albedo, field in (("diffuse_albedo", self.lambertian_field), ("albedo", self.linear_specular))
                 if field in self.maps]  # fmt: skip
        text = "\n".join([
            *lines,
            "#define MATERIAL_SURFACE 1",
            "#define MATERIAL_IBL_SCALE 1",
            "void material_surface(vec4 uvs, inout mat3 frame) {",
            *surface,
            "}",
            "// the prefiltered environment's albedos (of the factors) scaled by the texels: exact for linear colours",
            "void material_ibl_scale(vec3 untinted, inout vec3 diffuse_albedo, inout vec3 albedo) {",
            *scale,
            "}",
            '#include "reflets/brdf/glsl/surface_hooks.glsl"',
        ])  # fmt: skip
        digest = hashlib.sha256(text.encode()).hexdigest()[:16]
        return register_source(f"{self.glsl}#maps-{digest}", text)

    def textures(self, ctx) -> dict[str, object]:
        from ..textures import texture_for

        return {f"m_map_{field}": texture_for(ctx, self.texture_data(field)) for field in self.maps or {}}

