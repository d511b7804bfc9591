"""The scenes texture maps are measured on (tests/brdf/test_maps.py, tests/translucency/test_albedo_map.py,
tools/texture_maps.py): library materials with mapped colours, and a striped translucent marble."""

from __future__ import annotations

from pathlib import Path

import numpy as np
from PIL import Image

from ..api import render
from ..metrics import relmse
from ..reference import reference
from ..scene.loaders import load_dict
from ..scene.model import Scene
from .assets import block_means

#: a colourful uv grid (a Khronos sample's texture, shipped in the package data)
UV_GRID = Path(__file__).parents[1] / "data" / "textures" / "uv_grid.png"
POINT = {"type": "point", "position": [1, 2, 2], "intensity": [30, 30, 30]}
QUAD = {"type": "quad", "corners": [[-0.5, 2.2, 0.5], [0.5, 2.2, 0.5], [-0.5, 2.2, 1.5]], "radiance": [12, 12, 12]}
#: the marble's lights
MARBLE_POINT = {"type": "point", "position": [1.5, 1.5, 2], "intensity": [6, 6, 6]}
MARBLE_QUAD = {"type": "quad", "corners": [[-0.5, 1.6, 0.5], [0.5, 1.6, 0.5], [-0.5, 1.6, 1.5]], "radiance": [8, 8, 8]}


def reference_image(scene: Scene) -> np.ndarray:
    """The NumPy reference texture maps are measured against: 32 samples over each pixel's box."""
    return reference(scene, spp=32, pixel="box", progress=False).image


def block_error(scene: Scene, ref: np.ndarray | None = None) -> float:
    """Relative MSE of the GPU image (16 spp) against ``ref`` (default: ``reference_image(scene)``) on 4 × 4-pixel
    block means — how the tests and tools/texture_maps.py measure texture maps."""
    ref = reference_image(scene) if ref is None else ref
    return relmse(block_means(render(scene, spp=16)), block_means(ref))


def without_maps(scene: Scene, name: str = "back") -> Scene:
    """The scene with one material's maps left out (its factors kept): how much they change the image."""
    materials = {**scene.materials, name: scene.materials[name].model_copy(update={"maps": None})}
    return scene.model_copy(update={"materials": materials})


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


def write_bumps(path: str | Path, size: int = 64, waves: int = 2, slope: float = 0.5) -> Path:
    """A tangent-space normal map of the height field A sin(2π k u) sin(2π k v) (k = ``waves``, steepest slope
    ``slope``), glTF's encoding (RGB = (n + 1) / 2, +y along increasing v; image row 0 at v = 1), written to
    ``path``."""
    u = (np.arange(size) + 0.5) / size
    v = 1.0 - (np.arange(size) + 0.5) / size
    uu, vv = np.meshgrid(u, v)  # rows: v from 1 down
    k = 2.0 * np.pi * waves
    dh_du = slope * np.cos(k * uu) * np.sin(k * vv)
    dh_dv = slope * np.sin(k * uu) * np.cos(k * vv)
    n = np.dstack([-dh_du, -dh_dv, np.ones_like(uu)])
    n /= np.linalg.norm(n, axis=-1, keepdims=True)
    Image.fromarray(np.rint((n + 1.0) * 0.5 * 255.0).astype(np.uint8)).save(path)
    return Path(path)


def surface_maps_scene(directory: str | Path, lights: list, size=(96, 72), maps: bool = True) -> Scene:
    """The surface maps of library materials: a Lambert floor and a Phong ball with a normal map of bumps
    (``write_bumps``, written to ``directory``), and a small ball whose emission is the uv grid; ``maps`` False: the
    same without the normal maps."""
    bumps = str(write_bumps(Path(directory) / "bumps.png"))
    floor = {"type": "lambert", "albedo": [0.7, 0.7, 0.7]}
    ball = {"type": "phong", "kd": [0.4, 0.3, 0.2], "ks": [0.4, 0.4, 0.4], "exponent": 30, "normalized": True}
    if maps:
        floor["normal_map"] = {"texture": bumps, "transform": {"scale": [3, 3]}}
        ball["normal_map"] = {"texture": bumps, "scale": 0.8}
    lamp = {"type": "lambert", "albedo": [0.2, 0.2, 0.2], "emission": {"texture": str(UV_GRID), "factor": [2, 2, 2]}}
    return load_dict({
        "camera": {"position": [0, 1.2, 3.2], "look_at": [0, 0.3, 0], "fov_y": 40, "size": list(size)},
        "materials": {"floor": floor, "ball": ball, "lamp": lamp},
        "mesh": [{"shape": "plane", "size": [4, 4], "material": "floor"},
                 {"shape": "sphere", "radius": 0.5, "material": "ball", "transform": {"translate": [-0.5, 0.5, 0]}},
                 {"shape": "sphere", "radius": 0.3, "material": "lamp", "transform": {"translate": [0.7, 0.3, 0.2]}}],
        "light": lights,
    })  # fmt: skip


def _bands(directory: str | Path) -> str:
    """A map of four grey bands (R 0.125, 0.375, 0.625, 1 along v: linear data), written to ``directory``/bands.png."""
    bands = np.repeat(np.array([32, 96, 159, 255], np.uint8), 4)[:, None].repeat(16, axis=1)
    Image.fromarray(np.dstack([bands] * 3)).save(Path(directory) / "bands.png")
    return str(Path(directory) / "bands.png")


def _two_balls(materials: dict, lights: list, size) -> Scene:
    """Two balls (materials "ball", "metal") on a grey Lambert floor, and a small one in front (material "front")
    and one behind ("back") when ``materials`` has them."""
    extra = {name: {"shape": "sphere", "radius": radius, "material": name, "transform": {"translate": [0, radius, z]}}
             for name, radius, z in (("front", 0.25, 0.9), ("back", 0.35, -0.9))}
    return load_dict({
        "camera": {"position": [0, 1.2, 3.2], "look_at": [0, 0.3, 0], "fov_y": 40, "size": list(size)},
        "materials": {"floor": {"type": "lambert", "albedo": [0.5, 0.5, 0.5]}, **materials},
        "mesh": [{"shape": "plane", "size": [4, 4], "material": "floor"},
                 {"shape": "sphere", "radius": 0.5, "material": "ball", "transform": {"translate": [-0.6, 0.5, 0]}},
                 {"shape": "sphere", "radius": 0.5, "material": "metal", "transform": {"translate": [0.6, 0.5, 0]}},
                 *(mesh for name, mesh in extra.items() if name in materials)],
        "light": lights,
    })  # fmt: skip


def lobe_maps_scene(directory: str | Path, lights: list, size=(96, 72), maps: bool = True) -> Scene:
    """Lobe shapes read from a map of four grey bands (``_bands``): a GGX conductor's roughness α (factor 0.6), a
    Phong ball's exponent (factor 200), and a small ball in front with both a roughness (factor 0.5) and a Schlick F₀
    from the uv grid (factor 0.8: specular-glossiness); ``maps`` False: the factors alone."""
    texture = _bands(directory)
    metal = {"type": "microfacet", "fresnel": "conductor", "alpha": 0.6}
    ball = {"type": "phong", "kd": [0.3, 0.2, 0.1], "ks": [0.5, 0.5, 0.5], "exponent": 200, "normalized": True}
    front = {"type": "microfacet", "fresnel": "schlick", "diffuse": [0.2, 0.1, 0.05], "alpha": 0.5,
             "specular": [0.8, 0.8, 0.8]}  # fmt: skip
    if maps:
        metal["alpha"] = {"texture": texture, "factor": 0.6}
        ball["exponent"] = {"texture": texture, "factor": 200}
        front["alpha"] = {"texture": texture, "factor": 0.5}
        front["specular"] = {"texture": str(UV_GRID), "factor": [0.8, 0.8, 0.8]}
    return _two_balls({"ball": ball, "metal": metal, "front": front}, lights, size)


def other_lobe_maps_scene(directory: str | Path, lights: list, size=(96, 72)) -> Scene:
    """The other lobe shapes a map may give, on the bands: a Blinn-Phong ball's exponent (factor 300; its
    normalisation per fragment), an anisotropic Ward ball's α (factors [0.5, 0.15]; the twin's 1/α per fragment) and
    a small Ashikhmin-Shirley ball's exponents (factors 400 and 40, one map; its normalisation per fragment), and a
    Lafortune ball behind, the exponents of its two lobes (factors 60 and 8, one map)."""
    texture = _bands(directory)
    ball = {"type": "blinn_phong", "kd": [0.2, 0.3, 0.2], "ks": [0.5, 0.5, 0.5], "normalized": True,
            "exponent": {"texture": texture, "factor": 300}}  # fmt: skip
    metal = {"type": "ward", "kd": [0.1, 0.1, 0.1], "ks": [0.6, 0.5, 0.3],
             "alpha": {"texture": texture, "factor": [0.5, 0.15]}}  # fmt: skip
    front = {"type": "ashikhmin_shirley", "rs": [0.05, 0.05, 0.05], "rd": [0.4, 0.3, 0.2],
             "nu": {"texture": texture, "factor": 400}, "nv": {"texture": texture, "factor": 40}}  # fmt: skip
    back = {"type": "lafortune", "kd": [0.2, 0.15, 0.1], "lobes": [
        {"c": [-1, -1, 1], "scale": [0.6, 0.6, 0.6], "exponent": {"texture": texture, "factor": 60}},
        {"c": [-0.6, -0.6, 0.9], "scale": [0.4, 0.3, 0.2], "exponent": {"texture": texture, "factor": 8}}]}
    return _two_balls({"ball": ball, "metal": metal, "front": front, "back": back}, lights, size)


def affine_maps_scene(lights: list, size=(96, 72), maps: bool = True) -> Scene:
    """Colours a BRDF is affine in, from the uv grid: a GGX ball's Schlick F₀ (factor 0.6), an Ashikhmin-Shirley
    ball's rs (factor 0.3) and rd (factor 0.6, the grid tiled 2 × 2), and behind, the scale of the first of a
    Lafortune ball's two lobes (factor 0.8); ``maps`` False: the factors alone."""
    grid = str(UV_GRID)
    ball = {"type": "microfacet", "fresnel": "schlick", "alpha": 0.25, "diffuse": [0.2, 0.2, 0.2],
            "specular": [0.6, 0.6, 0.6]}  # fmt: skip
    metal = {"type": "ashikhmin_shirley", "rs": [0.3, 0.3, 0.3], "rd": [0.6, 0.6, 0.6], "nu": 200, "nv": 20}
    back = {"type": "lafortune", "kd": [0.1, 0.1, 0.1], "lobes": [
        {"c": [-1, -1, 1], "scale": [0.8, 0.8, 0.8], "exponent": 40},
        {"c": [-0.6, -0.6, 0.9], "scale": [0.3, 0.3, 0.3], "exponent": 6}]}
    if maps:
        back["lobes"][0]["scale"] = {"texture": grid, "factor": [0.8, 0.8, 0.8]}
        ball["specular"] = {"texture": grid, "factor": [0.6, 0.6, 0.6]}
        metal["rs"] = {"texture": grid, "factor": [0.3, 0.3, 0.3]}
        metal["rd"] = {"texture": grid, "factor": [0.6, 0.6, 0.6], "transform": {"scale": [2, 2]}}
    return _two_balls({"ball": ball, "metal": metal, "back": back}, lights, size)
