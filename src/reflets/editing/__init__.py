"""Editing anisotropic highlights (001, chapter 4): the orientation field of an anisotropic BRDF on a mesh,
its potential highlight curves, and (next) the solver and tools that move them."""

from .analysis import half_vectors, highlight_tangents, phi_gradient, weingarten
from .surface import SurfaceMesh

__all__ = ["SurfaceMesh", "half_vectors", "highlight_tangents", "phi_gradient", "weingarten"]
