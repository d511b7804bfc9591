"""Scene description: validated model, TOML/dict loaders, procedural shapes and mesh files."""

from .loaders import load_dict, load_scene
from .model import Camera, Scene

__all__ = ["Scene", "Camera", "load_scene", "load_dict"]
