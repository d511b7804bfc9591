"""BRDF library: material models (NumPy reference + GLSL twin), selectable by ``type`` in scene files."""

from __future__ import annotations

from typing import Annotated

from pydantic import Field

from .ashikhmin_shirley import AshikhminShirley
from .base import MATERIALS, Material, register_material
from .blinn_phong import BlinnPhong
from .lafortune import Lafortune
from .lambert import Lambert
from .measured import Measured
from .microfacet import Microfacet
from .mirror import Mirror
from .phong import Phong
from .translucent import Translucent
from .ward import Ward

# isort: split
from ..scratches.material import Scratched  # registered after the base materials it nests

#: the scene-file form of any registered material, chosen by its ``type`` key
MaterialSpec = Annotated[
    Lambert
    | Phong
    | BlinnPhong
    | Lafortune
    | Ward
    | AshikhminShirley
    | Microfacet
    | Measured
    | Translucent
    | Mirror
    | Scratched,
    Field(discriminator="type"),
]

__all__ = [
    "MATERIALS",
    "Material",
    "MaterialSpec",
    "register_material",
    "Lambert",
    "Phong",
    "BlinnPhong",
    "Lafortune",
    "Ward",
    "AshikhminShirley",
    "Microfacet",
    "Measured",
    "Translucent",
    "Mirror",
    "Scratched",
]
