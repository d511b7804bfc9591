"""Real assets against ground truth: the GPU renderer and the NumPy reference read the same textures (base colour,
metallic-roughness, normal map, emission) and must agree (issue 28's acceptance: relative MSE ≤ 2 % on 4×4-block
means over the asset's pixels, point + directional light with shadows)."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

import reflets
from reflets.scene.model import DirectionalLight, PointLight

ASSETS = Path(__file__).parents[1] / "data" / "gltf"
SIZE = (160, 120)


def block_relmse(scene) -> float:
    gpu = reflets.render(scene, size=SIZE, spp=16)
    bare = {k: m.model_copy(update={f: None for f in type(m).model_fields if f.endswith("_texture")})
            for k, m in scene.materials.items()}  # fmt: skip
    untextured = reflets.render(scene.model_copy(update={"materials": bare}), size=SIZE, spp=16)
    assert np.mean((gpu - untextured) ** 2) / np.mean(gpu**2) > 0.01  # the textures change the image
    ref = reflets.reference(scene, spp=16, size=SIZE, pixel="box", progress=False)
    covered = np.any(reflets.render(scene, size=SIZE, method="position") != 0, axis=2)

    def blocks(a):
        return a.reshape(SIZE[1] // 4, 4, SIZE[0] // 4, 4, -1).mean(axis=(1, 3))

    inside = blocks(covered[..., None].astype(float))[..., 0] == 1
    g, r = blocks(gpu)[inside], blocks(ref.image)[inside]
    assert inside.sum() > 50
    return float(np.mean((g - r) ** 2) / np.mean(r**2))


@pytest.mark.slow
@pytest.mark.parametrize("name", ["TextureCoordinateTest", "NormalTangentTest"])
def test_textured_asset_matches_the_numpy_reference(name):
    scene = reflets.load_scene(ASSETS / name / f"{name}.glb")
    lights = [
        PointLight(type="point", position=(1.5, 2.0, 3.0), intensity=(20.0, 20.0, 20.0)),
        DirectionalLight(type="directional", direction=(-0.3, -0.5, -1.0), irradiance=(3.0, 3.0, 3.0)),
    ]
    scene = scene.model_copy(update={"light": lights, "background": (0.0, 0.0, 0.0)})
    assert block_relmse(scene) <= 0.02
