"""Rendering techniques, registered by name for ``--method`` / ``render(method=...)``."""

from . import arealights, forward, reflections, scratches, translucency  # noqa: F401  (registers every method)
from .base import TECHNIQUES, Technique, TechniqueParams, get_technique, register_technique

__all__ = [
    "TECHNIQUES",
    "Technique",
    "TechniqueParams",
    "get_technique",
    "register_technique",
]
