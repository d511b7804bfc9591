"""``scratches``: the layered scratched SV-BRDF on the GPU (chapter 3 of the scratches document)."""

from .technique import Scratches, ScratchesParams  # noqa: F401  (registers the method)
