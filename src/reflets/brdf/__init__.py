"""BRDF library: material models (NumPy reference + GLSL twin), selectable by ``type`` in scene files."""

from __future__ import annotations

from typing import Annotated, Union

from pydantic import Field

from .base import MATERIALS, Material, register_material
from .blinn_phong import BlinnPhong
from .lambert import Lambert
from .measured import Measured
from .microfacet import Microfacet

#: the scene-file form of any registered material, chosen by its ``type`` key
MaterialSpec = Annotated[Union[Lambert, BlinnPhong, Microfacet, Measured], Field(discriminator="type")]  # noqa: UP007

__all__ = ["MATERIALS", "Material", "MaterialSpec", "register_material", "Lambert", "BlinnPhong", "Microfacet", "Measured"]
