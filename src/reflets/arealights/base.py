"""Shared machinery of the area-light methods (brute, adaptive, biased, mc, analytic, ltc).

Each method is a technique built on the forward pass (``Forward``): point, directional and environment lights
are shaded as there, and every quad / polygon light is handed to the method's GLSL function
``vec3 area_light_contribution(int i, vec3 x, mat3 frame, vec3 wo)`` (slot ``AREA``), with the light records
below in the std430 buffer at binding 4. Each method computes the light's **unoccluded** integral (the
area-light document's setting); shadows are then applied by the soft-shadow ratio of ``arealight.frag``
(docs/techniques/shadows.md). ``shadows = false`` on the lights gives the document's unoccluded setting, to
compare with ``reflets.reference(..., visibility=False)``.

Polygon-light record: 16 vec4 per light —
  [0] radiance.rgb, two_sided   [1] c1.xyz, vertex count   [2] e1 = c2 − c1, is_parallelogram
  [3] e2 = c4 − c1, area        [4] emitting normal, width |e1|   [5..12] vertices (counter-clockwise seen
  from the emitting side)       [13] mask: texel offset, width W, height H, 1 (all 0: no mask)
  [14] soft-shadow code (``ShadowMaps.soft_code``; 0: no shadows), 0, 0, 0   [15] reserved

Quad-light masks (``QuadLight.mask``) go to one float SSBO at binding 5 (``MASK_BINDING``), each mask's
W × H texels row by row from v = 0, compiled in only when the scene has one (flag ``LIGHT_MASKS``). A buffer
rather than a ``sampler2DArray``: every mask keeps its own size, so the nearest texel the GPU fetches is
the texel the references read (an array texture needs one common size, and resampling to it moves the cell
edges unless the size is a common multiple), and no texture unit is taken from the materials. Offsets are
float32 in the record: at most 2²⁴ texels in all. Methods that honour masks set ``supports_masks``; the
others refuse a masked scene rather than ignore the mask.
"""

from __future__ import annotations

from typing import ClassVar

import numpy as np
from pydantic import Field

from ..errors import ArgumentError, SceneError
from ..gpu import ProgramSpec
from ..scene.emitters import polygon_normal
from ..scene.model import PolygonLight, QuadLight, Scene
from ..techniques.forward import LIGHT_FLAGS, Forward, ForwardParams

SHADERS = "reflets/arealights/shaders/"
POLY_STRIDE = 16
MAX_POLY_VERTICES = 8
MASK_BINDING = 5
MAX_MASK_TEXELS = 1 << 24  # offsets travel as float32

AREA_PROGRAM = ProgramSpec(
    "arealight",
    vertex="reflets/techniques/shaders/mesh.vert",
    fragment=SHADERS + "arealight.frag",
    flags=frozenset({"OUTPUT", "METHOD_VARIANT", "N_POLYGONS", "LIGHT_MASKS"}) | LIGHT_FLAGS,
)


class AreaLightParams(ForwardParams):
    """Parameters shared by every area-light method (plus ``output = "samples"``: light samples per pixel)."""

    output: str = Field("radiance", pattern="^(radiance|position|normal|uv|samples)$")


def polygon_record(
    light: QuadLight | PolygonLight, mask: tuple[int, int, int] | None = None, shadow_code: float = 0.0
) -> list[tuple]:
    """The 16 rows of one light's record in the polygon buffer (layout in the module docstring); ``mask`` =
    (texel offset, W, H) in the mask buffer; ``shadow_code``: its soft-shadow views."""
    poly = light.polygon()
    if len(poly) > MAX_POLY_VERTICES:
        raise ArgumentError(
            f"area-light methods handle polygons of up to {MAX_POLY_VERTICES} vertices, got {len(poly)}",
            field="light.vertices",
        )
    e1, e2 = poly[1] - poly[0], poly[-1] - poly[0]
    parallelogram = len(poly) == 4 and np.allclose(poly[0] + poly[2], poly[1] + poly[3], atol=1e-9 * np.ptp(poly))
    normal = polygon_normal(poly)
    fan = [0.5 * np.linalg.norm(np.cross(poly[k] - poly[0], poly[k + 1] - poly[0])) for k in range(1, len(poly) - 1)]
    rows = [
        (*light.radiance, float(light.two_sided)),
        (*poly[0], float(len(poly))),
        (*e1, float(parallelogram)),
        (*e2, float(sum(fan))),
        (*normal, float(np.linalg.norm(e1))),
    ]
    rows += [(*p, 0.0) for p in poly] + [(0.0, 0.0, 0.0, 0.0)] * (13 - 5 - len(poly))
    rows.append((*(float(k) for k in mask), 1.0) if mask is not None else (0.0, 0.0, 0.0, 0.0))
    rows.append((float(shadow_code), 0.0, 0.0, 0.0))
    return rows + [(0.0, 0.0, 0.0, 0.0)] * (POLY_STRIDE - 15)


def lobe_info(material) -> dict[str, object]:
    """The uniforms of how the methods see a material (``Material.lobe_summary``): its Lambertian albedo, and its
    main specular lobe as a Phong (kind 1) or Blinn-Phong (kind 2) lobe of exponent e (kind 0: no lobe);
    microfacet and Ward roughness α map to the equivalent Blinn-Phong exponent (``brdf.base.blinn_phong_exponent``)."""
    diffuse, kind, exponent = material.lobe_summary()
    return {"u_lobe_diffuse": tuple(float(c) for c in diffuse), "u_lobe_kind": kind, "u_lobe_exponent": float(exponent)}


class AreaLightTechnique(Forward):
    """Base of the area-light methods: swaps the fragment stage and uploads polygon lights."""

    Params: ClassVar = AreaLightParams
    program_spec: ClassVar[ProgramSpec] = AREA_PROGRAM
    #: package path of the method's GLSL file (defines area_light_contribution)
    area_glsl: ClassVar[str]
    #: does the method's GLSL honour quad-light masks (``light_mask`` in polygon.glsl)?
    supports_masks: ClassVar[bool] = False

    def slots(self, material) -> dict[str, str]:
        return {"BRDF": material.brdf_source, "AREA": self.area_glsl}

    def flags(self, material) -> dict[str, object]:
        return {**super().flags(material), **self.method_flags()}

    def method_flags(self) -> dict[str, object]:
        """Compile-time variants of the method (e.g. METHOD_VARIANT)."""
        return {}

    def method_uniforms(self) -> dict[str, object]:
        """The method's own uniforms (prefix a_)."""
        return {}

    def material_uniforms(self, material) -> dict[str, object]:
        return {**lobe_info(material), **self.method_uniforms()}

    def area_light_rows(self, light) -> list[tuple]:
        return []  # no midpoint samples: the method integrates the polygons itself

    def polygon_rows(self, scene: Scene) -> list[tuple]:
        rows, texels, offset = [], [], 0
        for i, light in enumerate(scene.light):
            if not isinstance(light, QuadLight | PolygonLight):
                continue
            slot = None
            mask = self.prepared.mask_of(light)
            if mask is not None:
                if not self.supports_masks:
                    raise SceneError(
                        f"supported by {', '.join(mask_methods())}; not by {self.name}", field=f"light[{i}].mask"
                    )
                h, w = mask.shape
                slot, offset = (offset, w, h), offset + w * h
                texels.append(mask.ravel())
            rows += polygon_record(light, slot, self.prepared.shadows.soft_code(light))
        if offset > MAX_MASK_TEXELS:
            raise SceneError(f"the masks hold {offset} texels in all; at most {MAX_MASK_TEXELS}", field="light.mask")
        self._mask_texels = np.concatenate(texels).astype(np.float32) if texels else None
        return rows

    def extra_light_flags(self, polygon_rows: list[tuple]) -> dict[str, int]:
        return {"N_POLYGONS": len(polygon_rows) // POLY_STRIDE, "LIGHT_MASKS": int(self._mask_texels is not None)}

    def prepare(self, scene: Scene) -> None:
        super().prepare(scene)
        self._mask_buffer = None
        if self._mask_texels is not None:
            self._mask_buffer = self.ctx.buffer(self._mask_texels.tobytes())
            self._objects.append(self._mask_buffer)

    def _draw(self, *args, **kwargs) -> None:
        if getattr(self, "_mask_buffer", None) is not None:
            self._mask_buffer.bind_to_storage_buffer(MASK_BINDING)
        super()._draw(*args, **kwargs)


def mask_methods() -> list[str]:
    """The methods that honour quad-light masks: ``forward`` (its midpoint samples carry them) and the
    area-light methods with ``supports_masks``."""
    from ..techniques.base import TECHNIQUES

    return ["forward"] + [n for n, t in TECHNIQUES.items() if getattr(t, "supports_masks", False)]
