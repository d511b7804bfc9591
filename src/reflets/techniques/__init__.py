"""The technique interface and name registry (``base.py``) and the forward pass every technique builds on
(``forward.py``, shaders/). The techniques themselves live in their packages (arealights, translucency,
reflections, scratches) and register by name when ``reflets.renderer.methods`` imports them."""

from . import forward  # noqa: F401  (registers forward and the AOV methods)
from .base import TECHNIQUES, Technique, TechniqueParams, get_technique, register_technique

__all__ = [
    "TECHNIQUES",
    "Technique",
    "TechniqueParams",
    "get_technique",
    "register_technique",
]
