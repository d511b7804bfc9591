"""The scene-file form of every material, chosen by its ``type`` key: the BRDF library's models and the
materials technique packages build on them (``scratched``). Here, above both, so that neither imports the other
back (the import contracts of ``.importlinter``)."""

from __future__ import annotations

from typing import Annotated

from pydantic import Field

from ..brdf import (
    AshikhminShirley,
    BlinnPhong,
    Lafortune,
    Lambert,
    Measured,
    Microfacet,
    Mirror,
    Phong,
    Translucent,
    Ward,
)
from ..scratches.material import Scratched  # registered after the base materials it nests

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
