"""How a kind of material is shaded: its program, include slots, flags, uniforms, textures and input passes.

The forward pass draws every mesh with the shading of its material. A technique shades the BRDF library its own
way (the forward pass: the midpoint rule; the area-light methods: their polygon integrals) and adds the
shadings of the materials it exists for: ``ScratchLobes`` for scratched materials (also used by the Fermat
reflections of scratched meshes), ``TranslucentShading`` for translucent ones (with the light view it draws
before the meshes). The pass finds a material's shading by type, not through ``isinstance`` in every hook.
"""

from __future__ import annotations

from typing import ClassVar

from ..gpu import ProgramSpec


class MaterialShading:
    """The shading of the materials of one type (``material_type``) in a forward pass."""

    #: the materials this shading draws (subclasses included)
    material_type: ClassVar[type]
    #: the mesh program (mesh.vert's vertex layout); its fragment stage includes the material's BRDF slot
    program: ClassVar[ProgramSpec]

    def slots(self, material) -> dict[str, str]:
        return {"BRDF": material.brdf_source}

    def flags(self, material) -> dict[str, object]:
        """Compile-time flags besides the pass's own (output, light counts)."""
        return dict(material.flags())

    def uniforms(self, material) -> dict[str, object]:
        return dict(material.uniforms())

    def ibl_material(self, material):
        """The material whose split sum the prefiltered environment gives this shading's programs (lights.glsl's
        ``brdf_eval`` there): the material itself, unless the shading lights a part of it."""
        return material

    def textures(self, material) -> dict[str, object]:
        """Textures by sampler name (bound from unit 1 on); the shading releases what it creates. The dict
        returned is the one the pass binds every frame: a shading may replace its entries later."""
        return {}

    def frame_uniforms(self, frame: int, seed: int) -> dict[str, object]:
        """Uniforms that change per frame (a progressive shading's random stream)."""
        return {}

    def draw_inputs(self, target, vp_bytes: bytes) -> None:
        """Draw what the meshes read before they are shaded (a light view, screen-space maps); none here."""

    def release(self) -> None:
        """Free what the shading created on the GPU."""


def shading_for(material, shadings: list[MaterialShading]) -> MaterialShading | None:
    """The first of ``shadings`` that draws ``material``, or None (the technique's own BRDF shading)."""
    return next((s for s in shadings if isinstance(material, s.material_type)), None)
