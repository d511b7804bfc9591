"""Real assets against ground truth: the GPU renderer and the NumPy reference read the same textures (base colour,
metallic-roughness, normal map, emission) and must agree (issue 28's acceptance: relative MSE ≤ 2 % on 4×4-block
means over the asset's pixels, point + directional light with shadows; reflets.bench.assets)."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

import reflets
from reflets.bench.assets import asset_error, lit_for_comparison, without_textures

ASSETS = Path(__file__).parents[1] / "data" / "gltf"
SIZE = (160, 120)


@pytest.mark.slow
@pytest.mark.parametrize("name", ["TextureCoordinateTest", "NormalTangentTest"])
def test_textured_asset_matches_the_numpy_reference(name):
    scene = lit_for_comparison(reflets.load_scene(ASSETS / name / f"{name}.glb"))
    gpu = reflets.render(scene, size=SIZE, spp=16)
    untextured = reflets.render(without_textures(scene), size=SIZE, spp=16)
    assert np.mean((gpu - untextured) ** 2) / np.mean(gpu**2) > 0.01  # the textures change the image
    error = asset_error(scene, SIZE)
    assert error["blocks"] > 50
    assert error["relmse"] <= 0.02
