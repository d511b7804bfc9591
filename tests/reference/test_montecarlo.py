"""The NumPy Monte Carlo reference against closed forms, with its own standard error."""

from __future__ import annotations

import copy

import numpy as np
import pytest

import reflets
from reflets.errors import ArgumentError
from reflets.reference import reference
from reflets.scene.camera import pixel_rays
from reflets.validation import analytic_image, polygon_irradiance

QUAD = {"type": "quad", "corners": [[-0.5, 1, -0.5], [0.5, 1, -0.5], [-0.5, 1, 0.5]], "radiance": [5, 5, 5]}


def small(scene: dict, size=(64, 48)) -> dict:
    scene = copy.deepcopy(scene)
    scene["camera"]["size"] = list(size)
    return scene


def plane_polygon_exact(scene) -> tuple[np.ndarray, np.ndarray]:
    """Lambert plane y = 0 under one polygon light: exact radiance and the plane-interior mask."""
    _, mask = analytic_image(reflets.load_dict({**scene.model_dump(exclude={"base_dir"}), "light": []}))
    origin, dirs = pixel_rays(scene.camera)
    hit = origin + (-origin[1] / dirs[..., 1])[..., None] * dirs
    normals = np.broadcast_to([0.0, 1.0, 0.0], hit.shape).reshape(-1, 3)
    e = polygon_irradiance(hit.reshape(-1, 3), normals, scene.light[0].polygon()).reshape(mask.shape)
    rho = np.asarray(scene.materials["floor"].albedo)
    return rho / np.pi * np.asarray(scene.light[0].radiance) * e[..., None], mask


def test_point_light_plane_is_exact_without_noise(minimal_scene):
    scene = reflets.load_dict(small(minimal_scene))
    result = reference(scene, spp=4, progress=False)
    exact, mask = analytic_image(scene)
    assert np.max(np.abs(result.image - exact)[mask] / exact[mask]) < 1e-5
    assert np.all(result.stderr[mask] == 0)  # delta lights carry no variance


@pytest.mark.parametrize("visibility", [True, False])
@pytest.mark.parametrize("heuristic", ["power", "balance"])
def test_quad_light_plane_matches_lambert_polygon_formula_within_standard_error(minimal_scene, visibility, heuristic):
    scene = reflets.load_dict({**small(minimal_scene), "light": [QUAD]})
    result = reference(scene, spp=64, progress=False, visibility=visibility, heuristic=heuristic)
    exact, mask = plane_polygon_exact(scene)
    keep = mask & (result.stderr[..., 0] > 0)  # pixels where the camera sees the light's back are excluded
    assert keep.sum() > 0.8 * mask.sum()
    z = ((result.image - exact)[keep] / result.stderr[keep]).ravel()
    assert abs(z.mean()) < 0.15, f"biased: mean z = {z.mean():.3f}"
    assert np.abs(z).mean() < 1.0 and np.abs(z).max() < 5.0


def test_constant_environment_on_lambert_sphere_is_a_white_furnace(tmp_path):
    """Uniform sky of radiance L on a convex Lambert sphere: L_o = ρ L everywhere (no self-occlusion)."""
    np.save(tmp_path / "white.npy", np.full((16, 32, 3), 2.0, dtype=np.float32))
    scene = reflets.load_dict(
        {
            "camera": {"position": [0, 0, 4], "look_at": [0, 0, 0], "fov_y": 35, "size": [48, 48]},
            "materials": {"m": {"type": "lambert", "albedo": [0.5, 0.7, 0.9]}},
            "mesh": [{"shape": "sphere", "radius": 1, "material": "m"}],
            "light": [{"type": "environment", "file": "white.npy"}],
        },
        base_dir=tmp_path,
    )
    result = reference(scene, spp=32, progress=False)
    normals = reflets.render(scene, method="normal")
    on_sphere = np.linalg.norm(normals, axis=-1) > 0.5
    expected = 2.0 * np.array([0.5, 0.7, 0.9])
    z = (result.image[on_sphere] - expected) / np.maximum(result.stderr[on_sphere], 1e-9)
    assert np.abs(result.image[on_sphere].mean(axis=0) - expected).max() < 0.01
    assert np.abs(z).mean() < 1.0
    assert np.allclose(result.image[~on_sphere], 2.0)  # background is the map itself


def test_shadows_on_block_a_point_light_and_off_does_not(minimal_scene):
    minimal_scene["materials"]["ball"] = {"type": "lambert", "albedo": [0.5, 0.5, 0.5]}
    minimal_scene["mesh"].append(
        {"shape": "sphere", "radius": 0.3, "material": "ball", "transform": {"translate": [0, 1, 0]}}
    )
    scene = reflets.load_dict(small(minimal_scene))
    on = reference(scene, spp=1, progress=False, visibility=True).image
    off = reference(scene, spp=1, progress=False, visibility=False).image
    exact, mask = analytic_image(reflets.load_dict(small({**minimal_scene, "mesh": minimal_scene["mesh"][:1]})))
    positions = reflets.render(scene, method="position")
    on_floor = mask & (np.abs(positions[..., 1]) < 1e-4)
    in_shadow = on_floor & (np.hypot(positions[..., 0], positions[..., 2]) < 0.25)
    assert in_shadow.sum() > 5
    assert np.all(on[in_shadow] == 0)
    assert np.allclose(off[in_shadow], exact[in_shadow], rtol=1e-5)


def test_same_seed_same_image_other_seed_other_noise(minimal_scene):
    scene = reflets.load_dict({**small(minimal_scene, (24, 16)), "light": [QUAD]})
    a = reference(scene, spp=8, seed=3, progress=False).image
    b = reference(scene, spp=8, seed=3, progress=False).image
    c = reference(scene, spp=8, seed=4, progress=False).image
    assert np.array_equal(a, b) and not np.array_equal(a, c)


def test_box_pixel_filter_averages_over_the_pixel(minimal_scene):
    scene = reflets.load_dict(small(minimal_scene, (32, 24)))
    centre = reference(scene, spp=16, progress=False, pixel="center").image
    box = reference(scene, spp=16, progress=False, pixel="box").image
    exact, mask = analytic_image(scene)
    interior = mask & (exact[..., 0] > 0)
    assert not np.array_equal(centre, box)
    assert np.max(np.abs(box - centre)[interior] / centre[interior]) < 0.02  # smooth interior: nearly equal


def test_bad_arguments_are_clear_errors(minimal_scene):
    scene = reflets.load_dict(small(minimal_scene, (8, 8)))
    with pytest.raises(ArgumentError, match="spp"):
        reference(scene, spp=0, progress=False)
    with pytest.raises(ArgumentError, match="engine.*numpy, mitsuba, volumetric"):
        reference(scene, engine="pbrt", progress=False)
    with pytest.raises(ArgumentError, match="pixel"):
        reference(scene, pixel="gauss", progress=False)


def test_cli_reference_writes_image_and_standard_error(tmp_path, minimal_toml, capsys):
    from reflets.cli import main
    from reflets.imageio import read_image

    out = tmp_path / "ref.exr"
    code = main(["reference", str(minimal_toml), "-o", str(out), "--spp", "2", "--size", "16x12", "-q"])
    assert code == 0 and "samples/s" in capsys.readouterr().out
    assert read_image(out).shape == (12, 16, 3)
    assert read_image(tmp_path / "ref.stderr.exr").shape == (12, 16, 3)


def test_gpu_environment_lighting_is_within_the_reference_noise(ctx):
    """The forward renderer's 32×16 distant-light grid vs the importance-sampled reference (diffuse sphere)."""
    from reflets.demo import scene_path
    from reflets.metrics import zscores

    scene = reflets.load_scene(scene_path("12_ref_sphere_env.toml"))
    ref = reference(scene, spp=32, size=(48, 36), progress=False)
    gpu = reflets.render(scene, size=(48, 36))
    stats = zscores(gpu, ref.image, ref.stderr)
    assert abs(stats["mean_z"]) < 0.3 and stats["within_3_stderr"] > 0.99, stats


def test_cli_compare_reads_the_reference_standard_error(tmp_path, minimal_toml, capsys):
    import json

    from reflets.cli import main

    main(["reference", str(minimal_toml), "-o", str(tmp_path / "r.exr"), "--spp", "2", "--size", "16x12", "-q"])
    main(["render", str(minimal_toml), "-o", str(tmp_path / "g.exr"), "--size", "16x12"])
    capsys.readouterr()
    assert main(["compare", str(tmp_path / "g.exr"), str(tmp_path / "r.exr"), "--json"]) == 0
    result = json.loads(capsys.readouterr().out)
    assert {"mean_z", "mean_abs_z", "within_3_stderr"} <= set(result)


def test_adaptive_rounds_refine_noisy_pixels_without_bias(minimal_scene):
    """A quad light on the Lambert plane at 4 spp, refined to 2 % relative standard error: the noisy pixels get
    more samples (and only they), their error shrinks, and the image stays unbiased against the exact formula."""
    scene = reflets.load_dict({**small(minimal_scene, (32, 24)), "light": [QUAD]})
    plain = reference(scene, spp=4, progress=False)
    refined = reference(scene, spp=4, progress=False, adaptive_error=0.02, adaptive_spp=1024)
    exact, mask = plane_polygon_exact(scene)
    keep = mask & (refined.stderr[..., 0] > 0)
    assert plain.pixel_spp is None and refined.pixel_spp.max() > 4 and refined.pixel_spp.min() == 4
    assert np.all(refined.pixel_spp[plain.stderr.sum(axis=-1) == 0] == 4)  # no variance, no refinement
    luminance = refined.image @ np.array([0.2126, 0.7152, 0.0722])
    error = refined.stderr @ np.array([0.2126, 0.7152, 0.0722])
    converged = refined.pixel_spp < 1024
    assert np.all(error[keep & converged] <= 0.02 * np.maximum(luminance, luminance.mean())[keep & converged] + 1e-7)
    z = ((refined.image - exact)[keep] / refined.stderr[keep]).ravel()
    assert abs(z.mean()) < 0.15 and np.abs(z).max() < 5.0
    again = reference(scene, spp=4, progress=False, adaptive_error=0.02, adaptive_spp=1024)
    assert np.array_equal(again.image, refined.image)  # seeded rounds: the same image
    for bad in (-1.0, 0.0, float("nan"), float("inf"), "x"):
        with pytest.raises(ArgumentError, match="adaptive_error"):
            reference(scene, spp=4, progress=False, adaptive_error=bad)
    for bad in (0, 2, 10**9, 1.5):  # below spp, or a pixel's samples past memory
        with pytest.raises(ArgumentError, match="adaptive_spp"):
            reference(scene, spp=4, progress=False, adaptive_error=0.02, adaptive_spp=bad)
