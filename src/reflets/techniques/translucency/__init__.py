"""The ``translucent`` technique (subsurface scattering through a light view)."""

from . import technique  # noqa: F401  (registers the method)
