"""``fermat``: per-vertex reflections in curved smooth reflectors (technique.py, shaders/)."""

from .technique import Fermat, FermatParams, Reflector, reflector_of

__all__ = ["Fermat", "FermatParams", "Reflector", "reflector_of"]
