"""reflets — real-time rendering of realistic materials and lighting, checked against ground truth.

>>> import reflets
>>> scene = reflets.load_scene("scene.toml")
>>> image = reflets.render(scene)            # float32 (H, W, 3), linear radiance
>>> with reflets.Renderer(scene) as r:     # prepared once: a frame loop
...     r.set_camera(position=(0, 2, 5))
...     frame = r.render()
>>> truth = reflets.reference(scene, spp=256) # NumPy Monte Carlo: .image, .stderr
>>> reflets.Viewer(scene)                     # in Jupyter: an interactive view (the 'viewer' extra)
"""

from . import materials  # noqa: F401  (first: completes the scene model with every material type)
from .api import compare, render
from .errors import RefletsError
from .reference import reference  # the function; the subpackage stays importable as reflets.reference.*
from .renderer import Renderer
from .scene import Scene, load_dict, load_scene

__version__ = "0.1.0"


def __getattr__(name: str):
    """``reflets.Viewer`` (the Jupyter widget) is imported on first use: it needs the 'viewer' extra."""
    if name == "Viewer":
        from .viewer.notebook import Viewer

        return Viewer
    raise AttributeError(f"module 'reflets' has no attribute {name!r}")


__all__ = [
    "Scene",
    "load_scene",
    "load_dict",
    "render",
    "Renderer",
    "reference",
    "compare",
    "RefletsError",
    "Viewer",
    "__version__",
]
