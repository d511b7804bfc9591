"""A translucent material's albedo map (``albedo_texture``): the light leaving the medium × the texel where it
leaves — in the translucent technique (single + multiple scattering), its far-field BRDF (area lights, the
environment), the surface reference and the volumetric one."""

from __future__ import annotations

import numpy as np

import reflets
from reflets.bench.maps import MARBLE_POINT as POINT
from reflets.bench.maps import MARBLE_QUAD as QUAD
from reflets.bench.maps import striped_marble
from reflets.metrics import relmse
from reflets.reference.volumetric import render_volumetric


def test_the_translucent_pass_tints_single_and_multiple_scattering_where_the_light_leaves(tmp_path):
    scene, plain = striped_marble(tmp_path, POINT), striped_marble(tmp_path, POINT, mapped=False)
    mapped_image = reflets.render(scene, method="translucent")
    plain_image = reflets.render(plain, method="translucent")
    uv = reflets.render(scene, method="uv")[..., :2].reshape(-1, 2)
    tint = scene.materials["m"].tint(uv).reshape(plain_image.shape)
    # away from the stripes' edges (the same texel 1/256 either side) and two pixels inside the silhouette: where
    # the uv footprint is wide, a GPU may read a coarser mip (the H100 did at the top edge; llvmpipe did not)
    sides = [scene.materials["m"].tint(uv + [du, 0.0]).reshape(tint.shape) for du in (-1 / 256, 1 / 256)]
    inside = plain_image.min(axis=-1) > 1e-3
    for _ in range(2):
        inside[1:-1, 1:-1] &= inside[:-2, 1:-1] & inside[2:, 1:-1] & inside[1:-1, :-2] & inside[1:-1, 2:]
        inside[[0, -1], :] = inside[:, [0, -1]] = False
    lit = inside & np.all(sides[0] == sides[1], axis=-1) & np.all(sides[0] == tint, axis=-1)
    assert lit.sum() > 500
    # within the GPU's own sRGB decoding of the 8-bit texels (llvmpipe: up to 0.72 % off the exact curve)
    np.testing.assert_allclose(mapped_image[lit], (plain_image * tint)[lit], rtol=0.01, atol=1e-5)
    assert np.ptp(tint[lit], axis=0).min() > 0.1  # both stripes seen


def test_the_volumetric_reference_tints_the_light_leaving_at_the_camera_hit(tmp_path):
    scene = striped_marble(tmp_path, POINT, size=(16, 12))
    plain = striped_marble(tmp_path, POINT, size=(16, 12), mapped=False)
    # single scattering (orders = 1) suffices for what the tint does (every order leaves at the same camera hit)
    mapped, unmapped = (render_volumetric(s, spp=2, seed=3, progress=False, orders=1) for s in (scene, plain))
    uv = reflets.render(scene, method="uv")[..., :2].reshape(-1, 2)
    tint = scene.materials["m"].tint(uv).reshape(mapped.image.shape)
    inside = mapped.mask
    np.testing.assert_allclose(mapped.image[inside], unmapped.image[inside] * tint[inside], rtol=1e-5, atol=1e-7)
    np.testing.assert_allclose(mapped.stderr[inside], unmapped.stderr[inside] * tint[inside], rtol=1e-5, atol=1e-7)


def test_the_far_field_brdf_under_a_quad_light_and_the_environment_as_the_reference(tmp_path):
    """Forward with the far-field BRDF's diffusion term × the texel, against the surface reference's; under the
    environment, the split sum keeps a rough interface's reflection untinted (u_ibl_untinted): the mapped sphere is
    as close to its reference as the unmapped one to its own."""
    from reflets.scene.assets import default_environment

    scene = striped_marble(tmp_path, QUAD)
    ref = reflets.reference(scene, spp=64, progress=False).image
    assert relmse(reflets.render(scene, spp=16), ref) < 3e-3  # measured 1.2e-3 (tools/texture_maps.py)
    assert relmse(reflets.render(striped_marble(tmp_path, QUAD, mapped=False), spp=16), ref) > 0.05  # the map matters
    env = {"type": "environment", "file": str(default_environment())}
    errors = []
    for mapped in (True, False):
        scene = striped_marble(tmp_path, env, mapped=mapped, roughness=0.3)
        errors.append(relmse(reflets.render(scene, spp=16), reflets.reference(scene, spp=64, progress=False).image))
    assert errors[0] < 1.2 * errors[1]  # measured 3.3e-2 mapped, 4.1e-2 unmapped


def test_an_albedo_map_reads_back_from_a_saved_scene(tmp_path):
    from reflets.scene.loaders import scene_toml

    scene = striped_marble(tmp_path, POINT)
    path = tmp_path / "saved.toml"
    path.write_text(scene_toml(scene))
    assert reflets.load_scene(path).materials["m"] == scene.materials["m"]
