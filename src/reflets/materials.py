"""The scene-file form of every material, chosen by its ``type`` key: the BRDF library's models and the
materials of technique packages (``translucent``, ``scratched``, whose precomputations are their techniques').

``Scene.materials`` names this union without importing it (the scene model sits below the technique packages,
whose passes read scenes); importing ``reflets`` imports this module first, which completes the scene model
(``Scene.model_rebuild``), so that no package imports another back (``.importlinter``)."""

from __future__ import annotations

from typing import Annotated

from pydantic import Field

from .brdf import (
    AshikhminShirley,
    BlinnPhong,
    Gltf,
    Lafortune,
    Lambert,
    Measured,
    Microfacet,
    Mirror,
    Phong,
    Ward,
)
from .scene.model import Scene
from .scratches.material import Scratched  # registered after the base materials it nests
from .translucency.material import Translucent

MaterialSpec = Annotated[
    Lambert
    | Phong
    | BlinnPhong
    | Lafortune
    | Ward
    | AshikhminShirley
    | Microfacet
    | Gltf
    | Measured
    | Translucent
    | Mirror
    | Scratched,
    Field(discriminator="type"),
]

Scene.model_rebuild(_types_namespace={"MaterialSpec": MaterialSpec})
