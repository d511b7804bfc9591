"""Texture maps on the BRDF library's materials: colours read from textures (``albedo = { texture = "wood.png" }`` for
Lambert, ``kd`` / ``ks`` for Phong, Blinn-Phong and Ward, ``diffuse`` / ``specular`` for the microfacet model, ``kd``
for Lafortune's, ``rs`` / ``rd`` for Ashikhmin–Shirley's), lobe shapes (the microfacet and Ward roughness ``alpha``, the
Phong and Blinn-Phong ``exponent``, Ashikhmin–Shirley's ``nu`` / ``nv``), and on every one of them a normal map,
emission and ambient occlusion, as glTF's material has them:

    albedo = { texture = "wood.png", factor = [0.9, 0.9, 0.9], uv = 0, srgb = true, transform = { scale = [4, 4] } }
    exponent = { texture = "wood_gloss.png", factor = 200 }
    normal_map = { texture = "wood_normal.png", scale = 1.0 }
    emission = { texture = "lamps.png", factor = [5, 5, 5] }
    occlusion = { texture = "wood_ao.png", strength = 1.0 }

A mapped colour is its factor × the texture's RGB at the point, a mapped lobe shape its factor × the texel's R (at
least the field's lowest value: ``LobeMap``) (``factor`` defaults to 1: the texture as it is; the other keys are
:class:`~reflets.textures.TextureRef`'s). The material keeps the factor in the field and the texture in ``maps``
(what a saved scene writes back: ``maps = { albedo = { texture = … } }`` is read too).

Which colours can be maps: those the BRDF is linear in, per channel — the Lambertian albedo (``lambertian_field``)
and the colour scaling the rest (``linear_specular``). Every renderer then stays exact with the map: the GLSL twin
reads the texel into the colour before ``brdf_eval`` (``material_surface``, as glTF's material does), the NumPy
reference evaluates the BRDF with per-point colours (:meth:`Mapped.at`), and the prefiltered environment scales
the material's albedos by the texels (``material_ibl_scale``: exact for a linear colour). A colour the BRDF is affine
in per channel (``affine_colours``: a Schlick F₀, Ashikhmin–Shirley's ``rs`` and ``rd``) is read the same way, and
the split sum mixes per channel between the albedo curves at 0 and at the factors (bilinearly for two such colours:
exact, the albedo being affine in each). A mirror's ``reflectance`` (or a conductor's ``eta`` and ``k``) weights its
traced reflections: ``fermat``'s composite and the reference's mirror bounce read it per point.

A mapped lobe shape: the twin recomputes per fragment the uniforms it reads for it (the value itself, or what is
derived from it in float64 for constant lobes — Ward's 1/α, a normalisation: ``LobeMap.derived``); the reference
evaluates each hit at its own value and samples by the texture's widest lobe (a density wherever any point's BRDF is
not zero); the prefiltered environment interpolates albedo curves and equivalent roughness computed at
``LOBE_NODES`` texel values (several mapped lobe fields must therefore read one texture), and with one mapped affine
colour (a roughness and a Schlick F₀: specular-glossiness) mixes them with the same curves at its 0.

The surface maps, on every library material (glTF's conventions, so that an asset's maps mean the same here):

- ``normal_map``: a tangent-space normal map (RGB = (n + 1) / 2, +y along the mesh's bitangent), its x and y scaled
  by ``scale``; it turns the shading frame in both renderers (``shading_frame``; GLSL ``normal_mapped_frame``), so
  every light and method sees the mapped normal. The GPU reads mips of unit normals (``textures.texture_for``);
  unlike glTF's material, a library lobe is not widened by the normals' spread under a pixel (Toksvig), which the
  reference's supersampled pixel shows: a far, bumpy surface looks a little shinier on the GPU;
- ``emission``: emitted radiance (W m⁻² sr⁻¹ per channel), × a map's RGB (sRGB colour) when it is a texture;
- ``occlusion``: ambient occlusion (the map's R, linear), ``1 + strength (R − 1)``: it darkens the environment's
  light only, as glTF's does; the references trace occlusion themselves and ignore the map.

In the default method ``auto``, area lights reach a material with mapped colours through ``forward`` (``tabulated``
is False: ``brdf_eval`` per fragment); ``ltc``, ``analytic`` and ``biased`` asked for by name integrate the factors
and warn that they ignore the textures. The surface maps leave the material tabulated: the area-light methods read
the fragment's mapped frame and add its emission. A scratched material's base takes maps too (``scratches.material``:
the twin over the base's).
"""

from __future__ import annotations

import hashlib
from dataclasses import dataclass
from typing import ClassVar, Literal

import numpy as np
from pydantic import Field, model_validator

from ..cache import Memo
from ..textures import FiniteFloat, TextureRef, load_texture, lookup
from .base import RGB, Material, PointsBRDF, perturbed_frame

#: the fields that are a texture of their own (not a colour × a map)
SURFACE_MAPS = ("normal_map", "occlusion")
#: texel values at which the split sum's albedo curves of a mapped lobe shape are computed (interpolated between)
LOBE_NODES = 8


@dataclass(frozen=True)
class LobeMap:
    """How a lobe-shape field reads its map: the value it is clamped to from below (``low``), which end of the
    texture's range makes the widest lobe (``widest``: "max" for a roughness, "min" for an exponent; the reference
    samples every point's lobe by that one), whether the model's NumPy eval takes per-point values as a column
    (N, 1) rather than (N,), and the GLSL twin's uniforms the fragment recomputes: ``m_<field>`` (unless
    ``own_uniform`` is False: the twin has none of the field's own) becomes max(factor × t, low), each of ``derived``
    (name, expression) its
    expression — ``{factor}`` the uniform's own value, ``{t}`` the texel's R, and the twin's uniform names standing
    for the mapped values (assigned first)."""

    low: float
    widest: Literal["min", "max"]
    column: bool = False
    own_uniform: bool = True
    derived: tuple[tuple[str, str], ...] = ()


def lobe_node_texels() -> np.ndarray:
    """The texel values the split sum's curves of a mapped lobe shape are computed at: (k / (LOBE_NODES − 1))²,
    denser near 0 — where an exponent's lobe widens fastest (a Phong exponent of 200 × t: α 1 at t = 0, 0.33 at
    t = 0.02, 0.05 at t = 1) — and interpolated in √t by the twin (``_lobe_ibl``)."""
    return np.linspace(0.0, 1.0, LOBE_NODES) ** 2


_EXTREMES = Memo()


def _red_extreme(data, widest: str) -> float:
    """The largest or smallest R of a decoded texture (remembered by its content key: the reference asks at every
    bounce)."""
    red = data.texels[..., 0]
    return _EXTREMES.get((data.key, widest), lambda: float(red.max() if widest == "max" else red.min()))


class NormalMap(TextureRef):
    """A tangent-space normal map (glTF's: RGB = (n + 1) / 2, linear) and the scale of its x and y."""

    scale: FiniteFloat = 1.0


class OcclusionMap(TextureRef):
    """Ambient occlusion in the map's R (linear): the environment's light × 1 + strength (R − 1)."""

    strength: float = Field(1.0, ge=0.0, le=1.0, allow_inf_nan=False)


class Mapped(Material):
    """A material of the BRDF library whose colours may be texture maps, with a normal map, emission and ambient
    occlusion (module docstring)."""

    maps: dict[str, TextureRef] | None = Field(None, description="colour parameters read from textures (× the field)")
    normal_map: NormalMap | None = Field(None, description="a tangent-space normal map turning the shading frame")
    emission: RGB | None = Field(None, description="emitted radiance, W/m²/sr per channel (× a map's texels)")
    occlusion: OcclusionMap | None = Field(None, description="ambient occlusion of the environment's light (R)")
    #: the colour scaling everything but the Lambertian part, linearly per channel (None: none, or not linearly)
    linear_specular: ClassVar[str | None] = None
    #: the lobe-shape fields a map may scale (a roughness, an exponent): factor × the texel's R
    lobe_maps: ClassVar[dict[str, LobeMap]] = {}
    #: mappable colours that are linear data, not sRGB-encoded colour (a mirror's complex index)
    data_maps: ClassVar[tuple[str, ...]] = ()
    #: do the mapped affine colours read one texture and mix as one (Lafortune's lobe scales)?
    affine_group: ClassVar[bool] = False

    @classmethod
    def mappable(cls, data: dict | None = None) -> tuple[str, ...]:
        """The BRDF's colours a texture may scale (with these field values: a model's Fresnel may decide); the
        emission may be mapped too."""
        return tuple(f for f in (cls.lambertian_field, cls.linear_specular) if f is not None)

    @classmethod
    def affine_colours(cls, data: dict | None = None) -> tuple[str, ...]:
        """The colours the BRDF is affine in per channel, not linear (f = f₀ + c (f₁ − f₀): a Schlick F₀, which the
        split sum interpolates between its curves at 0 and at the factor, ``affine_zeros``); none by default."""
        return ()

    @model_validator(mode="before")
    @classmethod
    def _split_maps(cls, data):
        """``field = { texture = … , factor = … }`` → the factor in the field, the texture in ``maps``."""
        if not isinstance(data, dict):
            return data
        data, maps = cls._lift_maps(dict(data), dict(data.get("maps") or {}))
        for key, value in list(data.items()):
            if isinstance(value, TextureRef):
                value = value.model_dump()
            if not (isinstance(value, dict) and "texture" in value) or key in ("maps", *SURFACE_MAPS):
                continue
            value = dict(value)
            factor = value.pop("factor", None)
            maps[key] = value
            if factor is not None:
                data[key] = factor
            elif key in cls.lobe_maps:
                data[key] = 1.0
            elif key in cls.model_fields:
                data[key] = (1.0, 1.0, 1.0)
        if maps:
            allowed = (*cls.mappable(data), *cls.affine_colours(data), *cls.lobe_maps, "emission")
            for key in maps:
                if key not in allowed:
                    name = cls.model_fields["type"].default
                    raise ValueError(
                        f"{key} cannot be a texture in a {name} material; textures are accepted for: "
                        f"{', '.join(allowed)} (the colours the BRDF is linear or affine in, the lobe shapes its "
                        'twin reads directly; normal_map and occlusion too; type = "gltf" maps the rest)'
                    )
            affine = [key for key in maps if key in cls.affine_colours(data)]  # (two at most: A-S's rs and rd)
            lobed = [key for key in maps if key in cls.lobe_maps]
            if lobed and len(affine) > 1 and not cls.affine_group:
                raise ValueError(f"{', '.join(affine)} and {', '.join(lobed)} cannot all be textures: with a mapped "
                                 "lobe shape, one affine colour at most (the prefiltered environment's curves at 0 "
                                 "for each would not fit a shader's uniforms)")
            lobes = [TextureRef.model_validate(maps[key]) for key in lobed]
            if any(ref != lobes[0] for ref in lobes):  # the same file, uv, transform…
                raise ValueError(f"{' and '.join(lobed)} read different textures: mapped lobe shapes must read "
                                 "the same one (the prefiltered environment interpolates its curves at one texel)")
            data["maps"] = maps
        if "emission" in maps and data.get("emission") is None:
            data["emission"] = (1.0, 1.0, 1.0)
        return data

    @classmethod
    def _lift_maps(cls, data: dict, maps: dict) -> tuple[dict, dict]:
        """Maps written inside a nested field moved to ``maps`` (Lafortune's lobes); none by default."""
        return data, maps

    def factor(self, field: str):
        """A mapped field's factor: the field's value (a Lafortune lobe's field for ``lobe<i>_<field>``)."""
        return getattr(self, field)

    def with_values(self, values: dict, points: bool = False) -> Mapped:
        """The material with these mapped fields' values; ``points``: per-point arrays (not validated)."""
        return self.model_construct(**{**dict(self), **values}) if points else self.model_copy(update=values)

    @classmethod
    def uniform_of(cls, field: str) -> str:
        """The GLSL twin's uniform holding a mapped field's factor (an array's element: ``m_lobe_scale[0]``)."""
        return f"m_{field}"

    def constant_dump(self) -> dict:
        # no integral reads them (and the keys of fits made before they existed stay the same)
        return {k: v for k, v in super().constant_dump().items() if k not in ("emission", *SURFACE_MAPS)}

    # ------------------------------------------------------------------ what varies over the surface

    @property
    def brdf_maps(self) -> tuple[str, ...]:
        """The mapped fields the BRDF reads (not the emission)."""
        return tuple(field for field in self.maps or {} if field != "emission")

    @property
    def surface_textures(self) -> tuple[str, ...]:
        """Every texture-read field: the mapped colours, the emission, the normal and occlusion maps."""
        return (*(self.maps or {}), *(f for f in SURFACE_MAPS if getattr(self, f) is not None))

    @property
    def bends_normals(self) -> bool:
        return self.normal_map is not None

    @property
    def textured(self) -> bool:
        return bool(self.brdf_maps)

    def at(self, uv: np.ndarray, frames=None):
        """The material at mesh uv: its BRDF with per-point colours and lobe shapes (factor × texel), sampled as
        the factors are with each mapped lobe at its widest (``widest_lobe``: a density wherever a point's BRDF is
        not zero)."""
        if not self.brdf_maps:
            return self
        values = {}
        for field in self.brdf_maps:
            if field in self.lobe_maps:
                values[field] = self.lobe_values(field, self.texels(field, uv)[:, 0])
            else:
                values[field] = np.asarray(self.factor(field), np.float64) * self.texels(field, uv)
        return PointsBRDF(self.with_values(values, points=True).eval, self.widest_lobe())

    def lobe_values(self, field: str, texels):
        """A lobe-shape field at texel values (R): factor × texel, at least the field's ``low`` (a pair of
        factors — an anisotropic roughness — scaled alike)."""
        spec, factor = self.lobe_maps[field], self.factor(field)
        if isinstance(factor, tuple | list):
            return tuple(np.maximum(f * np.asarray(texels, np.float64), spec.low) for f in factor)
        value = np.maximum(factor * np.asarray(texels, np.float64), spec.low)
        return value[:, None] if spec.column and np.ndim(value) == 1 else value

    @property
    def mapped_affine(self) -> list[str]:
        """The affine colours read from maps (at most two)."""
        return [field for field in type(self).affine_colours(dict(self)) if field in (self.maps or {})]

    def affine_zeros(self) -> list[Mapped] | None:
        """The material with its mapped affine colours at 0 — the first, the second, both — (what the split sum
        interpolates between per channel: exact, the albedo being affine in each), or None when none is mapped."""
        fields = self.mapped_affine
        if not fields:
            return None
        subsets = [fields[:1], fields[1:], fields][: 1 if len(fields) == 1 else 3]
        return [self.with_values(dict.fromkeys(subset, (0.0, 0.0, 0.0))) for subset in subsets]

    @property
    def mapped_lobes(self) -> list[str]:
        """The lobe-shape fields read from maps."""
        return [field for field in self.lobe_maps if field in (self.maps or {})]

    def _at_texel(self, texel_of) -> Mapped:
        """The material with each mapped lobe shape at one texel value (``texel_of(field)``)."""
        update = {}
        for field in self.mapped_lobes:
            value = self.lobe_values(field, np.array([texel_of(field)]))
            update[field] = tuple(float(v[0]) for v in value) if isinstance(value, tuple) else float(np.ravel(value)[0])
        return self.with_values(update)

    def widest_lobe(self) -> Mapped:
        """The material with each mapped lobe shape at the texture's value that widens it most."""

        def extreme(field: str) -> float:
            return _red_extreme(self.texture_data(field), self.lobe_maps[field].widest)

        return self._at_texel(extreme) if self.mapped_lobes else self

    def lobe_nodes(self) -> list[Mapped] | None:
        """The material at the ``LOBE_NODES`` texel values of ``lobe_node_texels`` of its mapped lobe shape (what
        the prefiltered environment's albedo curves are computed at), or None when no lobe shape is mapped."""
        if not self.mapped_lobes:
            return None
        return [self._at_texel(lambda _, t=t: t) for t in lobe_node_texels()]

    def shading_frame(self, frame: np.ndarray, uv: np.ndarray) -> np.ndarray:
        """The frames turned by the normal map (GLSL ``normal_mapped_frame``)."""
        if self.normal_map is None:
            return frame
        local = lookup(self.normal_map, self.texture_data("normal_map"), uv, "normal_map")[:, :3] * 2.0 - 1.0
        local[:, :2] *= self.normal_map.scale
        return perturbed_frame(frame, local)

    def emitted(self, uv: np.ndarray) -> np.ndarray:
        if self.emission is None:
            return np.zeros((len(uv), 3))
        out = np.broadcast_to(np.asarray(self.emission, np.float64), (len(uv), 3))
        return out * self.texels("emission", uv) if "emission" in (self.maps or {}) else out.copy()

    def texels(self, field: str, uv: np.ndarray) -> np.ndarray:
        """(N, 3) texels of a mapped field at mesh uv (as :meth:`at`)."""
        return lookup(self.maps[field], self.texture_data(field), uv, field)[:, :3]

    def texture_data(self, field: str):
        """The decoded texture of a mapped field (a colour: sRGB unless its ``srgb`` says otherwise; a lobe shape or
        a ``data_maps`` field: linear data) or of a surface map (``normal_map``, ``occlusion``: linear data)."""
        if field in SURFACE_MAPS:
            return load_texture(getattr(self, field), False)
        return load_texture(self.maps[field], field not in (*self.lobe_maps, *self.data_maps))

    # ------------------------------------------------------------------ the GLSL twin

    @property
    def brdf_source(self) -> str:
        """The model's GLSL with each mapped colour read from its texture in ``material_surface`` (the uniform
        stays the factor, the name the BRDF reads becomes a per-fragment global: ``#define``), and the surface maps'
        hooks (``material_emission``, ``material_occlusion``, the normal map turning the frame)."""
        if not self.surface_textures and self.emission is None:
            return self.glsl
        from ..gpu.programs import read_source, register_source

        def texel(sampler: str, ref: TextureRef) -> str:
            return f"MAP_TEXTURE({sampler}, ({sampler}_uv * vec3({'uvs.zw' if ref.uv else 'uvs.xy'}, 1.0)).xy)"

        lines, surface, maps = [], [], self.maps or {}
        values = self._fragment_values()  # uniform → (field, GLSL expression of {factor}, {t})
        order, assigned = list(values), {}
        for field in self.brdf_maps:
            red = field in self.lobe_maps
            lines += [f"{'float' if red else 'vec3'} t_map_{field};  // the texel{chr(39) + 's R' if red else ''}",
                      f"uniform sampler2D m_map_{field};", f"uniform mat3 m_map_{field}_uv;  // mesh uv → image uv"]
            surface.append(f"    t_map_{field} = {texel(f'm_map_{field}', maps[field])}.{'r' if red else 'rgb'};")
        for line in read_source(self.glsl).splitlines():
            lines.append(line)
            words = line.split(";")[0].split()
            if len(words) != 3 or words[0] != "uniform":
                continue
            kind, (name, _, size) = words[1], words[2].partition("[")
            size = size.rstrip("]")  # an array: its mapped elements are keys name[i]
            keys = [key for key in values if key.partition("[")[0] == name]
            if not keys:
                continue
            index, argument = ("[i]", "int i") if size else ("", "")
            lines += [f"{kind} map_factor_{name}({argument}) {{ return {name}{index}; }}",
                      f"{kind} g_map_{name}{'[' + size + ']' if size else ''};  // what the BRDF reads as {name} here",
                      f"#define {name} g_map_{name}"]  # fmt: skip
            if size:  # the unmapped elements keep their uniform's value
                assigned[name] = f"    for (int i = 0; i < {size}; ++i) g_map_{name}[i] = map_factor_{name}(i);"
            for key in keys:
                field, expression = values.pop(key)
                element = key[len(name):]  # "" or "[i]"
                value = expression.format(factor=f"map_factor_{name}({element[1:-1]})", t=f"t_map_{field}", kind=kind)
                assigned[key] = f"    g_map_{name}{element} = {value};"
        if values:
            raise RuntimeError(f"{self.glsl} declares no uniform {next(iter(values))} to map")
        arrays = [name for name in assigned if name not in order]  # copied whole before their mapped elements
        surface += [assigned[name] for name in (*arrays, *order)]  # the mapped values, then what is derived
        if self.emission is not None:
            lines += ["uniform vec3 m_emission;", "vec3 g_emission = vec3(0.0);", "#define MATERIAL_EMISSION 1",
                      "vec3 material_emission() { return g_emission; }"]  # fmt: skip
            if "emission" in maps:
                lines += ["uniform sampler2D m_map_emission;", "uniform mat3 m_map_emission_uv;"]
                surface.append(f"    g_emission = m_emission * {texel('m_map_emission', maps['emission'])}.rgb;")
            else:
                surface.append("    g_emission = m_emission;")
        if self.occlusion is not None:
            lines += ["uniform sampler2D m_occlusion;", "uniform mat3 m_occlusion_uv;",
                      "uniform float m_occlusion_strength;", "float g_occlusion = 1.0;", "#define MATERIAL_OCCLUSION 1",
                      "float material_occlusion() { return g_occlusion; }"]  # fmt: skip
            red = f"{texel('m_occlusion', self.occlusion)}.r"
            surface.append(f"    g_occlusion = 1.0 + m_occlusion_strength * ({red} - 1.0);")
        if self.normal_map is not None:
            lines += ["uniform sampler2D m_normal_map;", "uniform mat3 m_normal_map_uv;",
                      "uniform float m_normal_scale;"]  # fmt: skip
            surface += [f"    vec3 local = {texel('m_normal_map', self.normal_map)}.xyz * 2.0 - 1.0;",
                        "    local.xy *= m_normal_scale;",
                        "    frame = normal_mapped_frame(frame, local);"]  # fmt: skip
        affine = self.mapped_affine
        diffuse, specular = ([f"    {albedo} *= t_map_{field};"] if field in maps and field not in affine else []
                             for albedo, field in (("diffuse_albedo", self.lambertian_field),
                                                   ("albedo", self.linear_specular)))  # fmt: skip
        lines += self._lobe_ibl(specular)
        scale = [*diffuse, *specular, *(self._affine_ibl(affine, lines) if not self.mapped_lobes else [])]
        text = "\n".join([
            "#ifndef MAP_TEXTURE  // a pass without the mesh's own uv derivatives samples the base level",
            "#define MAP_TEXTURE texture",
            "#endif",
            *lines,
            "#define MATERIAL_SURFACE 1",
            "#define MATERIAL_IBL_SCALE 1",
            "void material_surface(vec4 uvs, inout mat3 frame) {",
            *surface,
            "}",
            "// the prefiltered environment's albedos (of the factors) scaled by the texels: exact for linear colours,",
            "// interpolated from the curves at 0 for affine ones",
            "void material_ibl_scale(float mu, vec3 untinted, inout vec3 diffuse_albedo, inout vec3 albedo) {",
            *scale,
            "}",
            '#include "reflets/brdf/glsl/surface_hooks.glsl"',
        ])  # fmt: skip
        digest = hashlib.sha256(text.encode()).hexdigest()[:16]
        return register_source(f"{self.glsl}#maps-{digest}", text)

    @staticmethod
    def _affine_ibl(affine: list[str], lines: list[str]) -> list[str]:
        """``material_ibl_scale``'s lines for mapped affine colours A (and B): the albedo at the texels t is
        mix(A at 0, the factors' albedo, t_A) per channel — bilinear with B, between the curves with A, B, both at 0
        (``u_map_ibl_zero0``, ``1``, ``2``: ``affine_zeros``, which ibl.py sets); exact, the albedo being affine in
        each. (Declared here, next to the twin's other uniforms, for a program with the prefiltered environment.)"""
        if not affine:
            return []
        count = 1 if len(affine) == 1 else 3
        lines += ["#if defined(ENV_IBL) && ENV_IBL",
                  *[f"uniform vec3 u_map_ibl_zero{j}[IBL_NODES];" for j in range(count)], "#endif"]  # fmt: skip
        at = [f"    vec3 z{j} = mix(u_map_ibl_zero{j}[k0], u_map_ibl_zero{j}[k1], fk);" for j in range(count)]
        a = f"t_map_{affine[0]}"
        mixed = (f"    albedo = mix(z0, albedo, {a});" if count == 1 else
                 f"    albedo = mix(mix(z2, z1, {a}), mix(z0, albedo, {a}), t_map_{affine[1]});")  # fmt: skip
        return ["#if defined(ENV_IBL) && ENV_IBL", "    int k0, k1;", "    float fk;", "    ibl_nodes(mu, k0, k1, fk);",
                *at, mixed, "#endif"]  # fmt: skip

    def _fragment_values(self) -> dict[str, tuple[str, str]]:
        """The twin's uniforms a mapped field replaces per fragment (uniform → (field, expression)): a colour's
        factor × texel; a lobe shape's clamped value, then the uniforms derived from it (``LobeMap``)."""
        values, derived = {}, {}
        for field in self.brdf_maps:
            spec = self.lobe_maps.get(field)
            if spec is None:
                values[self.uniform_of(field)] = (field, "{factor} * {t}")
                continue
            if spec.own_uniform:
                values[self.uniform_of(field)] = (field, f"max({{factor}} * {{t}}, {{kind}}({spec.low!r}))")
            derived.update({name: (field, expression) for name, expression in spec.derived})
        return {**values, **derived}

    def _lobe_ibl(self, specular_scale: list[str]) -> list[str]:
        """A mapped lobe shape's split sum (lights.glsl's MATERIAL_IBL): the albedo curves and equivalent roughness
        at ``LOBE_NODES`` texel values (``lobe_nodes``; ibl.py sets them) interpolated at the fragment's texel (in
        √t, the nodes' spacing), a mapped specular colour's texels on them (``specular_scale``), and a mapped affine
        colour's mix with the curves at 0, interpolated the same way (``u_map_ibl_zero_nodes``: exact in the colour,
        as ``_affine_ibl``); the diffuse albedo is the model's own (its mapped value included)."""
        if not self.mapped_lobes:
            return []
        diffuse = f"m_{self.lambertian_field}" if self.lambertian_field else "vec3(0.0)"
        affine = self.mapped_affine
        zeros = ["uniform vec3 u_map_ibl_zero_nodes[IBL_NODES * MAP_IBL_NODES];  // the same at the affine colour's 0"]
        mixed = [
            "    vec3 z0 = mix(u_map_ibl_zero_nodes[n0 + k0], u_map_ibl_zero_nodes[n0 + k1], fk);",
            "    vec3 z1 = mix(u_map_ibl_zero_nodes[n1 + k0], u_map_ibl_zero_nodes[n1 + k1], fk);",
            f"    albedo = mix(mix(z0, z1, s - float(j)), albedo, t_map_{affine[0]});",
        ] if affine else []  # fmt: skip
        return [
            "#if defined(ENV_IBL) && ENV_IBL",
            "#define MATERIAL_IBL 1",
            f"const int MAP_IBL_NODES = {LOBE_NODES};",
            "uniform vec3 u_map_ibl_albedo[IBL_NODES * MAP_IBL_NODES];  // node j's curve at [j * IBL_NODES + k]",
            "uniform float u_map_ibl_alpha[MAP_IBL_NODES];",
            *(zeros if affine else []),
            "void material_ibl(float mu, out vec3 diffuse_albedo, out vec3 albedo, out float alpha) {",
            f"    float s = sqrt(clamp(t_map_{self.mapped_lobes[0]}, 0.0, 1.0)) * float(MAP_IBL_NODES - 1);",
            "    int j = min(int(s), MAP_IBL_NODES - 2);",
            "    int k0, k1;",
            "    float fk;",
            "    ibl_nodes(mu, k0, k1, fk);",
            "    int n0 = j * IBL_NODES, n1 = n0 + IBL_NODES;",
            "    vec3 a0 = mix(u_map_ibl_albedo[n0 + k0], u_map_ibl_albedo[n0 + k1], fk);",
            "    vec3 a1 = mix(u_map_ibl_albedo[n1 + k0], u_map_ibl_albedo[n1 + k1], fk);",
            "    albedo = mix(a0, a1, s - float(j));",
            *mixed,
            "    alpha = mix(u_map_ibl_alpha[j], u_map_ibl_alpha[j + 1], s - float(j));",
            f"    diffuse_albedo = {diffuse};",
            *specular_scale,
            "}",
            "#endif",
        ]  # fmt: skip

    def brdf_uniforms(self) -> dict[str, object]:
        """The model's own uniforms (each model defines them)."""
        return {}

    def uniforms(self) -> dict[str, object]:
        """The model's uniforms, and the surface maps': factors, uv transforms (mat3, column-major)."""
        values = self.brdf_uniforms()
        refs = {f"m_map_{field}": ref for field, ref in (self.maps or {}).items()}
        refs.update({f"m_{field}": getattr(self, field) for field in SURFACE_MAPS if getattr(self, field) is not None})
        for sampler, ref in refs.items():
            values[sampler + "_uv"] = ref.uv_uniform()
        if self.emission is not None:
            values["m_emission"] = tuple(float(c) for c in self.emission)
        if self.normal_map is not None:
            values["m_normal_scale"] = float(self.normal_map.scale)
        if self.occlusion is not None:
            values["m_occlusion_strength"] = float(self.occlusion.strength)
        return values

    def textures(self, ctx) -> dict[str, object]:
        from ..textures import texture_for

        out = {f"m_map_{field}": texture_for(ctx, self.texture_data(field)) for field in self.maps or {}}
        if self.occlusion is not None:
            out["m_occlusion"] = texture_for(ctx, self.texture_data("occlusion"))
        if self.normal_map is not None:
            out["m_normal_map"] = texture_for(ctx, self.texture_data("normal_map"), normal_map=True)
        return out
