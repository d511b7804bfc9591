"""The scenes texture maps are measured on (tests/brdf/test_maps.py, tests/translucency/test_albedo_map.py,
tools/texture_maps.py): library materials with mapped colours, and a striped translucent marble."""

from __future__ import annotations

from pathlib import Path

import numpy as np
from PIL import Image

from ..scene.loaders import load_dict
from ..scene.model import Scene

#: a colourful uv grid (a Khronos sample's texture, shipped in the package data)
UV_GRID = Path(__file__).parents[1] / "data" / "textures" / "uv_grid.png"
POINT = {"type": "point", "position": [1, 2, 2], "intensity": [30, 30, 30]}
QUAD = {"type": "quad", "corners": [[-0.5, 2.2, 0.5], [0.5, 2.2, 0.5], [-0.5, 2.2, 1.5]], "radiance": [12, 12, 12]}
#: the marble's lights
MARBLE_POINT = {"type": "point", "position": [1.5, 1.5, 2], "intensity": [6, 6, 6]}
MARBLE_QUAD = {"type": "quad", "corners": [[-0.5, 1.6, 0.5], [0.5, 1.6, 0.5], [-0.5, 1.6, 1.5]], "radiance": [8, 8, 8]}


def mapped_scene(lights: list, size=(96, 72)) -> Scene:
    """A Lambert floor with its albedo mapped (tiled 3 × 3), a Phong ball with a diffuse map and a conductor with a
    specular map."""
    grid = str(UV_GRID)
    return load_dict({
        "camera": {"position": [0, 1.2, 3.2], "look_at": [0, 0.3, 0], "fov_y": 40, "size": list(size)},
        "materials": {
            "floor": {"type": "lambert",
                      "albedo": {"texture": grid, "factor": [0.9, 0.9, 0.9], "transform": {"scale": [3, 3]}}},
            "ball": {"type": "phong", "kd": {"texture": grid, "factor": [0.6, 0.6, 0.6]}, "ks": [0.3, 0.3, 0.3],
                     "exponent": 40, "normalized": True},
            "metal": {"type": "microfacet", "alpha": 0.3, "fresnel": "conductor", "specular": {"texture": grid}},
        },
        "mesh": [{"shape": "plane", "size": [4, 4], "material": "floor"},
                 {"shape": "sphere", "radius": 0.5, "material": "ball", "transform": {"translate": [-0.6, 0.5, 0]}},
                 {"shape": "sphere", "radius": 0.5, "material": "metal", "transform": {"translate": [0.6, 0.5, 0]}}],
        "light": lights,
    })  # fmt: skip


def unmapped(scene: Scene) -> Scene:
    """The same scene with the factors alone."""
    return scene.model_copy(update={"materials": {n: m.model_copy(update={"maps": None}) if hasattr(m, "maps") else m
                                                  for n, m in scene.materials.items()}})  # fmt: skip


def striped_marble(directory: str | Path, light: dict, size=(64, 48), mapped: bool = True,
                   roughness: float = 0.0) -> Scene:  # fmt: skip
    """A marble sphere (η 1.3) with an albedo map of two coarse vertical stripes, orange and blue (nearest filtering),
    written to ``directory``/stripes.png."""
    stripes = np.zeros((16, 16, 3), np.uint8)
    stripes[:, :8], stripes[:, 8:] = (230, 120, 60), (80, 160, 230)
    Image.fromarray(stripes).save(Path(directory) / "stripes.png")
    material = {"type": "translucent", "preset": "marble", "mm_per_unit": 10, "eta": 1.3, "roughness": roughness}
    if mapped:
        material["albedo_texture"] = {"texture": str(Path(directory) / "stripes.png"), "transform": {"scale": [2, 1]},
                                      "filter": "nearest"}  # fmt: skip
    return load_dict({
        "camera": {"position": [0, 0.4, 3], "look_at": [0, 0, 0], "fov_y": 30, "size": list(size)},
        "materials": {"m": material},
        "mesh": [{"shape": "sphere", "radius": 0.6, "material": "m"}],
        "light": [light],
    })  # fmt: skip
