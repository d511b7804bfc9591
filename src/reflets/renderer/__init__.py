"""The renderer: a scene prepared once and drawn frame after frame (``Renderer``), and ``auto``, the method that
renders every material with its own technique in one frame (``compose``)."""

from . import methods  # noqa: F401  (registers every method)
from .compose import DEFAULT_METHOD
from .persistent import Renderer

__all__ = ["Renderer", "DEFAULT_METHOD"]
