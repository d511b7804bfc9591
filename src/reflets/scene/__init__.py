"""Scene description: validated model, TOML/dict loaders, procedural shapes and mesh files."""

from .loaders import load_dict, load_scene, save_scene, scene_toml
from .model import Camera, Scene

__all__ = ["Scene", "Camera", "load_scene", "load_dict", "save_scene", "scene_toml"]
