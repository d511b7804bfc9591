"""Scenes of the renderer tests: one sphere of each material type under each light type."""

from __future__ import annotations

import copy
from pathlib import Path

import numpy as np

from reflets.brdf.measured import write_merl

SKY = str(Path(__file__).resolve().parents[2] / "src/reflets/data/environments/sky.hdr")

MATERIALS = {
    "lambert": {"type": "lambert", "albedo": [0.7, 0.6, 0.5]},
    "phong": {"type": "phong", "kd": [0.3, 0.3, 0.3], "ks": [0.5, 0.5, 0.5], "exponent": 60},
    "blinn_phong": {"type": "blinn_phong", "kd": [0.3, 0.3, 0.3], "ks": [0.5, 0.5, 0.5], "exponent": 60},
    "lafortune": {
        "type": "lafortune",
        "kd": [0.3, 0.3, 0.3],
        "lobes": [{"c": [-0.8, -0.8, 0.8], "scale": [0.5, 0.5, 0.5], "exponent": 20}],
    },
    "ward": {"type": "ward", "kd": [0.3, 0.3, 0.3], "ks": [0.3, 0.3, 0.3], "alpha": [0.15, 0.3]},
    "ashikhmin_shirley": {
        "type": "ashikhmin_shirley",
        "rd": [0.4, 0.4, 0.4],
        "rs": [0.1, 0.1, 0.1],
        "nu": 50,
        "nv": 200,
    },
    "microfacet": {"type": "microfacet", "distribution": "ggx", "alpha": 0.3},
    "metal": {
        "type": "microfacet",
        "distribution": "ggx",
        "alpha": 0.2,
        "fresnel": "conductor",
        "eta": [0.2, 0.9, 1.1],
        "k": [3.9, 2.4, 2.2],
    },
    "mirror": {"type": "mirror", "reflectance": [0.8, 0.8, 0.8], "diffuse": [0.15, 0.15, 0.15]},
    "translucent": {"type": "translucent", "preset": "skin1", "roughness": 0.3, "mm_per_unit": 10.0},
    "scratched": {
        "type": "scratched",
        "preset": "3.14d",
        "profile": "vgroove:0.6",
        "base": {"type": "microfacet", "distribution": "ggx", "alpha": 0.15},
    },
}

LIGHTS = {
    "point": {"type": "point", "position": [1.5, 2.5, 2.0], "intensity": [12, 12, 12]},
    "directional": {"type": "directional", "direction": [-0.5, -1, -0.6], "irradiance": [2, 2, 2]},
    # facing down onto the sphere: corners c1, c2, c4 with (c2 − c1) × (c4 − c1) pointing to −y
    "quad": {"type": "quad", "corners": [[0.3, 2.2, 0.8], [1.3, 2.2, 0.8], [0.3, 2.2, 1.8]], "radiance": [8, 8, 8]},
    "polygon": {
        "type": "polygon",
        "vertices": [[-0.5, 2.4, 1.0], [0.0, 2.4, 0.3], [0.6, 2.4, 0.6], [0.6, 2.4, 1.4], [0.0, 2.4, 1.6]],
        "radiance": [8, 8, 8],
        "two_sided": True,
    },
    "environment": {"type": "environment", "file": SKY, "scale": 1.0},
}


def sphere_scene(material: str, light: str, size=(48, 36), merl: Path | None = None, reflector=None) -> dict:
    """One unit sphere of ``material`` under one ``light`` (a mirror is a reflector with a floor to reflect)."""
    spec = copy.deepcopy(MATERIALS[material]) if material != "measured" else {"type": "measured", "file": str(merl)}
    scene = {
        "camera": {"position": [0, 0.6, 3.5], "look_at": [0, 0, 0], "fov_y": 40, "size": list(size)},
        "materials": {"m": spec, "floor": {"type": "lambert", "albedo": [0.5, 0.5, 0.5]}},
        "mesh": [
            {
                "shape": "sphere",
                "radius": 1.0,
                "segments": [64, 32],
                "material": "m",
                "reflector": material == "mirror" if reflector is None else reflector,
            }
        ],
        "light": [copy.deepcopy(LIGHTS[light])],
    }
    if material == "mirror":
        scene["mesh"].append(
            {"shape": "plane", "size": [6, 6], "material": "floor", "transform": {"translate": [0, -1.01, 0]}}
        )
    return scene


def lambert_merl(path: Path) -> Path:
    """A MERL table of a Lambertian BRDF (ρ = 0.6): the measured material without a download."""
    return write_merl(path, lambda wo, wi: np.full(np.shape(wo)[:-1] + (3,), 0.6 / np.pi))
