"""glTF transmission (KHR_materials_transmission) and volumes (KHR_materials_volume): the GPU's screen-space
transmission (transmission.glsl) against the NumPy reference, which continues the paths through the surfaces
(reference/transmission.py); read from files."""

from __future__ import annotations

from pathlib import Path

import numpy as np

import reflets
from reflets.bench import transmission
from reflets.bench.assets import block_means as blocks
from reflets.metrics import relmse

W, H = 96, 72
DATA = Path(__file__).parents[1] / "data" / "gltf"


def glass_scene(tmp_path, glass: dict, shape: str = "sphere", scale: float = 1.0) -> reflets.Scene:
    return transmission.glass_scene(tmp_path, glass, shape, scale, (W, H))


def reference(scene, spp: int = 64) -> np.ndarray:
    return reflets.reference(scene, spp=spp, pixel="box", progress=False).image


def test_rough_thin_walled_glass_blurs_what_lies_behind_it_as_the_reference(tmp_path):
    scene = glass_scene(tmp_path, {"roughness": 0.3})
    image, ref = reflets.render(scene, spp=16), reference(scene)
    assert relmse(blocks(image), blocks(ref)) < 0.003  # measured 4.4e-4
    # the blur matters: unblurred (a smooth lobe through the same surface) is far off
    smooth = glass_scene(tmp_path, {"roughness": 0.0})
    assert relmse(blocks(reflets.render(smooth, spp=16)), blocks(ref)) > 0.008  # measured 0.017


def test_a_transmission_texture_and_a_tinted_base_colour(tmp_path):
    """Stripes of transmission 1 and 0.25 (the rest: the diffuse lobe), tinted pale red, on a box seen through."""
    glass = {"roughness": 0.1, "base_color": [1.0, 0.6, 0.5, 1.0],
             "transmission_texture": {"texture": str(tmp_path / "stripes.png")}}  # fmt: skip
    scene = glass_scene(tmp_path, glass, shape="cube")
    image, ref = reflets.render(scene, spp=16), reference(scene)
    assert relmse(blocks(image), blocks(ref)) < 5e-4  # measured 6.8e-5
    untextured = scene.model_copy(update={"materials": scene.materials | {
        "glass": scene.materials["glass"].model_copy(update={"transmission_texture": None})}})  # fmt: skip
    assert relmse(blocks(reflets.render(untextured, spp=16)), blocks(ref)) > 0.01  # measured 0.045


def test_a_volume_attenuates_over_its_thickness_in_world_units(tmp_path):
    """A tinted glass cube seen face on: at the face's centre the GPU's straight march of ``thickness`` × the
    mesh's scale is the reference's refracted path; the same cube 1.5 times larger (the same thickness factor) is
    1.5 times as deep there (red keeps exp(-2.3 d))."""
    glass = {"roughness": 0.0, "thickness": 1.0, "attenuation_distance": 1.0, "attenuation_color": [0.1, 0.5, 0.9]}
    centre = (slice(H // 2 - 3, H // 2 + 3), slice(W // 2 - 3, W // 2 + 3))
    means = {}
    for scale in (0.6, 0.9):
        scene = glass_scene(tmp_path, glass, shape="cube", scale=scale)
        image, ref = reflets.render(scene, spp=16), reference(scene)
        assert relmse(blocks(image), blocks(ref)) < 0.005, scale  # measured 5.3e-4, 1.2e-3
        means[scale] = image[centre].mean(axis=(0, 1)), ref[centre].mean(axis=(0, 1))
        np.testing.assert_allclose(*means[scale], rtol=0.02)  # measured within 0.6 % (1.11 thick: 20 % off in red)
    assert means[0.9][1][0] < 0.6 * means[0.6][1][0]  # red: exp(-2.3 x 0.3) = 0.5 darker, the wall being the same


def test_attenuation_test_reads_its_volumes():
    """Khronos' AttenuationTest (its export round trip: tests/scene/test_gltf_round_trip.py)."""
    scene = reflets.load_scene(DATA / "AttenuationTest" / "AttenuationTest.glb")
    volumes = [m for m in scene.materials.values() if m.type == "gltf" and m.volumetric]
    assert len(volumes) == 11 and {tuple(m.attenuation_color) for m in volumes} == {(0.1, 0.5, 0.9)}
    assert sum(m.thickness_texture is not None for m in volumes) == 1
    thin = [m for m in scene.materials.values() if m.type == "gltf" and m.transmissive and not m.volumetric]
    assert len(thin) == 5


def test_a_volumes_scale_survives_export_and_an_ior_of_0_is_refused(tmp_path):
    """The thickness is in the mesh's units: an exported volume keeps its mesh's scale on its node (AttenuationTest's
    node-scale row: 0.25 to 2)."""
    import pytest
    from pydantic import ValidationError

    from reflets.brdf.gltf import Gltf
    from reflets.gltf import export_gltf
    from reflets.scene.geometry import mesh_scale

    scene = reflets.load_scene(DATA / "AttenuationTest" / "AttenuationTest.glb")
    again = reflets.load_scene(export_gltf(scene, tmp_path / "out.glb")[0])
    scales = [[round(mesh_scale(s, i), 6) for i, m in enumerate(s.mesh) if s.materials[m.material].volumetric]
              for s in (scene, again)]  # fmt: skip
    assert scales[0] == scales[1] and len(set(scales[0])) > 3
    with pytest.raises(ValidationError, match="ior"):
        Gltf(transmission=1.0, thickness=1.0, ior=0.0)
