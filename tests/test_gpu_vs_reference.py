"""The GPU forward renderer against the NumPy reference for every analytic material.

With point and directional lights the reference has no noise, so the two must agree per pixel: this checks
the GLSL twins inside the real shading path (tangent frames, uniforms, light buffers), not only in isolation.
"""

from __future__ import annotations

import numpy as np
import pytest
from scipy.ndimage import binary_erosion

import reflets
from reflets.reference import reference

MATERIALS = {
    "lambert": {"type": "lambert", "albedo": [0.7, 0.5, 0.3]},
    "phong_doc": {"type": "phong", "kd": [0.2, 0.2, 0.2], "ks": [0.5, 0.5, 0.5], "exponent": 60},
    "blinn_norm": {
        "type": "blinn_phong",
        "kd": [0.3, 0.1, 0.1],
        "ks": [0.4, 0.4, 0.4],
        "exponent": 80,
        "normalized": True,
    },
    "lafortune_aniso": {
        "type": "lafortune",
        "kd": [0.2, 0.2, 0.2],
        "lobes": [{"c": [-1.0, -0.6, 1.0], "exponent": 20, "scale": [1, 1, 1]}],
    },
    "ward_aniso": {"type": "ward", "kd": [0.1, 0.1, 0.1], "ks": [0.6, 0.6, 0.6], "alpha": [0.08, 0.4]},
    "as_aniso": {"type": "ashikhmin_shirley", "rs": [0.4, 0.4, 0.4], "rd": [0.3, 0.2, 0.1], "nu": 200, "nv": 10},
    "ggx_gold_aniso": {"type": "microfacet", "distribution": "ggx", "alpha": [0.1, 0.4], "fresnel": "conductor"},
    "beckmann_dielectric": {
        "type": "microfacet",
        "distribution": "beckmann",
        "alpha": 0.2,
        "fresnel": "dielectric",
        "diffuse": [0.3, 0.3, 0.5],
        "masking": "correlated",
    },
}


@pytest.mark.parametrize("name", sorted(MATERIALS))
def test_gpu_matches_reference_per_pixel_under_delta_lights(ctx, name):
    scene = reflets.load_dict(
        {
            "camera": {"position": [0.5, 1.0, 3.5], "look_at": [0, 0, 0], "fov_y": 40, "size": [96, 72]},
            "materials": {"m": MATERIALS[name]},
            "mesh": [{"shape": "sphere", "radius": 1, "material": "m", "transform": {"rotate": [20, 30, 0]}}],
            "light": [
                {"type": "point", "position": [2, 2, 2], "intensity": [8, 8, 8]},
                {"type": "directional", "direction": [1, -0.5, -1], "irradiance": [1, 1.5, 2]},
            ],
        }
    )
    gpu = reflets.render(scene)
    ref = reference(scene, spp=1, visibility=False, progress=False).image
    normals = reflets.render(scene, method="normal")
    inside = binary_erosion(np.linalg.norm(normals, axis=-1) > 0.5, iterations=2)  # away from the silhouette
    peak = ref[inside].max()
    error = np.abs(gpu - ref)[inside]
    assert peak > 0.05
    # Per pixel: 0.5 % of the value or 0.1 % of the image peak (tessellation vs float64 normals, float32 GLSL).
    assert np.all(error <= 5e-3 * np.abs(ref[inside]) + 1e-3 * peak), f"{name}: max error {error.max():.3g}"
