"""The scene glTF transmission is measured on (tests/renderer/test_transmission.py, tools/transmission_spheres.py):
one glass object before a checker wall and floor, under a point and a directional light with shadows."""

from __future__ import annotations

from pathlib import Path

import numpy as np
from PIL import Image

from ..scene.loaders import load_dict
from ..scene.model import Scene


def glass_scene(directory: str | Path, glass: dict, shape: str = "sphere", scale: float = 1.0,
                size: tuple[int, int] = (96, 72)) -> Scene:  # fmt: skip
    """``glass`` (a glTF material's fields; transmission 1 unless given) as a sphere of radius 0.6 or a unit cube
    (× ``scale``) before a checker wall and floor; ``directory`` receives the checker (checker.png) and a texture of
    vertical stripes of 1 and 0.25 in R (stripes.png, a transmission texture)."""
    directory = Path(directory)
    u, v = np.meshgrid(np.arange(64), np.arange(64))
    checker = np.where((((u // 8) + (v // 8)) % 2 == 0)[..., None], [230, 200, 40], [40, 90, 230]).astype(np.uint8)
    Image.fromarray(checker).save(directory / "checker.png")
    stripes = np.zeros((64, 64, 3), np.uint8)
    stripes[..., 0] = np.where((u // 16) % 2 == 0, 255, 64)
    Image.fromarray(stripes).save(directory / "stripes.png")
    mesh = {"shape": shape, "material": "glass", "transform": {"scale": scale}}
    return load_dict({
        "camera": {"position": [0, 0.3, 3.0], "look_at": [0, 0, 0], "fov_y": 40, "size": list(size)},
        "materials": {"glass": {"type": "gltf", "metallic": 0.0, "transmission": 1.0} | glass,
                      "wall": {"type": "gltf", "metallic": 0.0, "roughness": 0.8,
                               "base_color_texture": {"texture": str(directory / "checker.png")}}},
        "mesh": [mesh | ({"radius": 0.6} if shape == "sphere" else {}),
                 {"shape": "plane", "size": [6, 6], "material": "wall",
                  "transform": {"rotate": [90, 0, 0], "translate": [0, 0, -1.5]}},
                 {"shape": "plane", "size": [6, 6], "material": "wall", "transform": {"translate": [0, -0.8, 0]}}],
        "light": [{"type": "point", "position": [1.5, 2.0, 2.0], "intensity": [6, 6, 6]},
                  {"type": "directional", "direction": [-0.3, -1, -0.5], "irradiance": [1.0, 1.0, 1.0]}],
    })  # fmt: skip
