"""BRDF library: material models (NumPy reference + GLSL twin), selectable by ``type`` in scene files.

The scene-file union of every material (``reflets.scene.materials.MaterialSpec``) lives above this package: it
also names materials of technique packages (``scratched``) that build on these models."""

from __future__ import annotations

from .ashikhmin_shirley import AshikhminShirley
from .base import MATERIALS, Material, register_material
from .blinn_phong import BlinnPhong
from .gltf import Gltf
from .lafortune import Lafortune
from .lambert import Lambert
from .measured import Measured
from .microfacet import Microfacet
from .mirror import Mirror
from .phong import Phong
from .ward import Ward

__all__ = [
    "MATERIALS",
    "Material",
    "register_material",
    "Lambert",
    "Phong",
    "BlinnPhong",
    "Lafortune",
    "Ward",
    "AshikhminShirley",
    "Microfacet",
    "Gltf",
    "Measured",
    "Mirror",
]
