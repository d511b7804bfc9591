"""Rendering techniques, registered by name for ``--method`` / ``render(method=...)``."""

from . import arealights, forward  # noqa: F401  (registers forward, the AOV methods, the area-light methods)
from .base import TECHNIQUES, Technique, TechniqueParams, get_technique, register_technique

DEFAULT_METHOD = "forward"

__all__ = [
    "TECHNIQUES",
    "Technique",
    "TechniqueParams",
    "get_technique",
    "register_technique",
    "DEFAULT_METHOD",
]
