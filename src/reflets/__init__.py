"""reflets — real-time rendering of realistic materials and lighting, checked against ground truth.

>>> import reflets
>>> scene = reflets.load_scene("scene.toml")
>>> image = reflets.render(scene)            # float32 (H, W, 3), linear radiance
>>> with reflets.Renderer(scene) as r:     # prepared once: a frame loop
...     r.set_camera(position=(0, 2, 5))
...     frame = r.render()
>>> truth = reflets.reference(scene, spp=256) # NumPy Monte Carlo: .image, .stderr
"""

from . import materials  # noqa: F401  (first: completes the scene model with every material type)
from .api import compare, render
from .errors import RefletsError
from .reference import reference  # the function; the subpackage stays importable as reflets.reference.*
from .renderer import Renderer
from .scene import Scene, load_dict, load_scene

__version__ = "0.1.0"
__all__ = [
    "Scene",
    "load_scene",
    "load_dict",
    "render",
    "Renderer",
    "reference",
    "compare",
    "RefletsError",
    "__version__",
]
