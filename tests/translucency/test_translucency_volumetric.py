"""The ``translucent`` technique against volumetric path tracing of the same medium (index-matched sphere), and
the volumetric reference through a refracting boundary against closed forms."""

from __future__ import annotations

import numpy as np
import pytest

import reflets
from reflets.errors import ArgumentError
from reflets.reference.volumetric import render_volumetric, sample_blocks
from reflets.translucency import half_space_single_scattering


def sphere_scene(eta=1.0, lights=None):
    return reflets.load_dict(
        {
            "camera": {"position": [0, 0.5, 3], "look_at": [0, 0, 0], "fov_y": 35, "size": [48, 36]},
            "materials": {"skin": {"type": "translucent", "preset": "skin1", "eta": eta, "mm_per_unit": 25.0}},
            "mesh": [{"shape": "sphere", "radius": 1.0, "material": "skin"}],
            "light": lights or [{"type": "point", "position": [2, 3, 2], "intensity": [20, 20, 20]}],
        }
    )


@pytest.mark.slow
def test_default_technique_within_5_percent_relative_mse_of_volumetric_path_tracing():
    scene = sphere_scene()
    ref = render_volumetric(scene, spp=32, seed=1, progress=False)
    m = ref.mask
    noise = float(np.mean(ref.stderr[m] ** 2) / np.mean(ref.image[m] ** 2))
    assert noise < 0.02, f"reference too noisy for this check: {noise:.3f}"
    image = reflets.render(scene, method="translucent")
    error = float(np.mean((image[m] - ref.image[m]) ** 2) / np.mean(ref.image[m] ** 2))
    assert error < 0.05
    # and the two subsurface terms are both needed: either alone is far off
    for term in ("single", "multiple"):
        alone = reflets.render(scene, method="translucent", terms=[term])
        assert np.mean((alone[m] - ref.image[m]) ** 2) / np.mean(ref.image[m] ** 2) > 0.05


def test_volumetric_reference_is_deterministic_and_rejects_what_it_cannot_render():
    scene = sphere_scene()
    a = render_volumetric(scene, spp=1, seed=4, size=(16, 12), progress=False)
    b = render_volumetric(scene, spp=1, seed=4, size=(16, 12), progress=False)
    np.testing.assert_array_equal(a.image, b.image)
    with pytest.raises(ArgumentError, match="exactly one point, directional, quad, polygon or environment light"):
        two = [{"type": "point", "position": [2, 3, 2], "intensity": [1, 1, 1]}] * 2
        render_volumetric(sphere_scene(lights=two), spp=1, progress=False)


@pytest.mark.parametrize("eta", [1.0, 1.3])
def test_a_tiny_quad_light_is_the_point_light_at_its_centre(eta):
    """Quad lights: each scattering vertex connects to a uniform point y of the emitter with intensity L A cos θ_y
    (the point's samples come from their own stream, so the walks are the same as with a point light). A quad of
    side 0.02 facing the unit sphere from 20 units (cos θ_y ≥ 0.9987 towards it) lights it as a point light of
    intensity L A at its centre."""
    side, height, radiance = 0.02, 20.0, 1e6
    h = side / 2
    quad = {
        "type": "quad",
        "corners": [[-h, height, -h], [h, height, -h], [-h, height, h]],  # emitting downwards, towards the sphere
        "radiance": [radiance, 0.5 * radiance, 0.25 * radiance],
    }
    point = {"type": "point", "position": [0, height, 0], "intensity": [radiance * side**2 * s for s in (1, 0.5, 0.25)]}
    kwargs = {"spp": 2, "seed": 7, "size": (20, 15), "progress": False}
    by_quad = render_volumetric(sphere_scene(eta, lights=[quad]), **kwargs)
    by_point = render_volumetric(sphere_scene(eta, lights=[point]), **kwargs)
    m = by_point.mask
    assert m.sum() > 100 and by_point.image[m].mean() > 0.0
    ratio = by_quad.image[m].sum(axis=0) / by_point.image[m].sum(axis=0)
    np.testing.assert_allclose(ratio, 1.0, atol=3e-3)
    # the one-sided emitter turned away lights nothing
    away = {**quad, "corners": [[-h, height, -h], [-h, height, h], [h, height, -h]]}
    assert render_volumetric(sphere_scene(eta, lights=[away]), **kwargs).image.max() == 0.0


@pytest.mark.parametrize("eta", [1.0, 1.3])
def test_a_sky_of_one_bright_texel_is_the_directional_light_from_it(eta, tmp_path):
    """The environment: each scattering vertex connects to an importance-sampled sky direction ω as a directional
    light of irradiance L(ω) / p(ω). A sky black but for one texel (2.8° across; the map is read bilinearly, a
    tent of the same integral) lights the sphere as the directional light from the texel's centre with the
    texel's irradiance L ΔΩ: the image sums agree within 4 standard errors (the sky's directions are noisy)."""
    from reflets.equirect import equirect_direction

    h, w, row, col, radiance = 64, 128, 20, 40, 500.0
    sky = np.zeros((h, w, 3), np.float32)
    sky[row, col] = (radiance, 0.5 * radiance, 0.25 * radiance)
    np.save(tmp_path / "sky.npy", sky)
    towards = equirect_direction(np.array([(col + 0.5) / w]), np.array([(row + 0.5) / h]))[0]
    solid_angle = (2 * np.pi / w) * (np.pi / h) * np.sin(np.pi * (row + 0.5) / h)
    directional = {
        "type": "directional",
        "direction": (-towards).tolist(),
        "irradiance": [radiance * solid_angle * s for s in (1, 0.5, 0.25)],
    }
    environment = {"type": "environment", "file": str(tmp_path / "sky.npy")}
    kwargs = {"spp": 8, "seed": 7, "size": (20, 15), "progress": False}
    by_sky = render_volumetric(sphere_scene(eta, lights=[environment]), **kwargs)
    by_sun = render_volumetric(sphere_scene(eta, lights=[directional]), **kwargs)
    m = by_sun.mask
    assert m.sum() > 100 and by_sun.image[m].mean() > 0.0
    difference = by_sky.image[m].sum(axis=0) - by_sun.image[m].sum(axis=0)
    sigma = np.sqrt((by_sky.stderr[m] ** 2).sum(axis=0) + (by_sun.stderr[m] ** 2).sum(axis=0))
    assert np.all(np.abs(difference) < 4 * sigma)
    assert np.all(sigma < 0.05 * by_sun.image[m].sum(axis=0))  # a test that can fail: the noise is 5 % at most


@pytest.mark.slow
@pytest.mark.parametrize("eta", [1.0, 1.3])
def test_worker_processes_draw_the_one_process_reference_bit_for_bit(eta):
    """Samples split over two or three processes: the same seed gives the one-process image and standard error
    bit for bit (blocks fixed by spp and the pixels, their sums added in block order), and another seed agrees
    within the noise (means within 4σ of the difference)."""
    scene = sphere_scene(eta)
    a = render_volumetric(scene, spp=8, seed=3, size=(24, 18), workers=2, progress=False)
    b = render_volumetric(scene, spp=8, seed=3, size=(24, 18), workers=3, progress=False)
    same = render_volumetric(scene, spp=8, seed=3, size=(24, 18), progress=False)
    one = render_volumetric(scene, spp=8, seed=5, size=(24, 18), progress=False)
    for other in (b, same):
        np.testing.assert_array_equal(a.image, other.image)
        np.testing.assert_array_equal(a.stderr, other.stderr)
    assert np.array_equal(a.mask, one.mask) and a.spp == 8 and len(sample_blocks(8, int(a.mask.sum()))) == 8
    m = a.mask
    diff = a.image[m].mean(axis=0) - one.image[m].mean(axis=0)
    sigma = np.sqrt(np.mean(a.stderr[m] ** 2 + one.stderr[m] ** 2, axis=0) / m.sum())
    assert np.all(np.abs(diff) < 4 * sigma + 1e-4 * one.image[m].mean(axis=0)), (diff, sigma)


def test_stored_reference_is_used_only_while_everything_matches(tmp_path):
    """reflets.reference.store: a second call reads the stored file (no render); another seed, sample count or
    scene renders anew; the stored image equals the rendered one to float16 rounding."""
    from reflets.reference.store import stored_or_rendered

    calls = []

    def make(scene, spp, seed):
        def render():
            calls.append(seed)
            return render_volumetric(scene, spp=spp, seed=seed, size=(16, 12), progress=False)

        return render

    path = tmp_path / "refs" / "sphere.npz"
    scene = sphere_scene()
    first, info = stored_or_rendered(path, scene, make(scene, 2, 1), spp=2, seed=1)
    again, info2 = stored_or_rendered(path, scene, make(scene, 2, 1), spp=2, seed=1)
    assert calls == [1] and not info["stored"] and info2["stored"] and info2["fingerprint"] == info["fingerprint"]
    np.testing.assert_array_equal(first.mask, again.mask)
    np.testing.assert_allclose(again.image, first.image, rtol=1e-3, atol=1e-7)
    np.testing.assert_allclose(again.stderr, first.stderr, rtol=1e-3, atol=1e-7)
    stored_or_rendered(path, scene, make(scene, 2, 2), spp=2, seed=2)
    other = sphere_scene(eta=1.3)
    stored_or_rendered(path, other, make(other, 2, 2), spp=2, seed=2)
    assert calls == [1, 2, 2]


@pytest.mark.parametrize("eta", [1.0, 1.3])
def test_single_scattering_through_a_refracting_boundary_matches_hanrahan_krueger(eta):
    """One scattering event (orders = 1) under a 100 mm flat top lit at 37° and seen at 45°: the manifold
    connection to the light through the boundary (Snell, F_T, beam compression) and the camera's own refraction
    (F_T/η²) give the closed form within 3σ + 0.5 %."""
    scene = reflets.load_dict(
        {
            "camera": {"position": [0, 2, 2], "look_at": [0, 0, 0], "fov_y": 4, "size": [12, 12]},
            "materials": {"m": {"type": "translucent", "preset": "skin1", "g": 0.3, "eta": eta, "mm_per_unit": 10.0}},
            "mesh": [{"shape": "cube", "size": [10, 5, 10], "material": "m", "transform": {"translate": [0, -2.5, 0]}}],
            "light": [{"type": "directional", "direction": [0.6, -0.8, 0], "irradiance": [1, 1, 1]}],
        }
    )
    ref = render_volumetric(scene, spp=64, seed=3, progress=False, orders=1, refract=True)
    medium = scene.materials["m"].medium()
    expected = half_space_single_scattering(medium, 0.8, np.sqrt(0.5), np.pi / 2)
    mean = ref.image.reshape(-1, 3).mean(axis=0)
    sigma = np.sqrt(np.mean(ref.stderr.reshape(-1, 3) ** 2, axis=0) / 144)
    assert np.all(np.abs(mean - expected) < 3 * sigma + 0.005 * expected), (mean, expected, sigma)


@pytest.mark.slow
def test_refracting_walk_reduces_to_the_index_matched_one_at_eta_1():
    """All orders on the index-matched sphere: the refracting walk (manifold connection, Fresnel at every
    crossing) forced at η = 1 agrees with the straight shadow-ray walk within their noise."""
    scene = sphere_scene().model_copy(update={"camera": sphere_scene().camera.model_copy(update={"size": (24, 18)})})
    a = render_volumetric(scene, spp=24, seed=1, progress=False)
    b = render_volumetric(scene, spp=24, seed=2, progress=False, refract=True)
    m = a.mask
    error = np.mean((a.image[m] - b.image[m]) ** 2) / np.mean(a.image[m] ** 2)
    noise = np.mean(a.stderr[m] ** 2 + b.stderr[m] ** 2) / np.mean(a.image[m] ** 2)
    assert error < 1.5 * noise
    sigma = np.sqrt(np.sum(a.stderr[m] ** 2 + b.stderr[m] ** 2, axis=0)) / m.sum()
    mean_a, mean_b = a.image[m].mean(axis=0), b.image[m].mean(axis=0)
    assert np.all(np.abs(mean_b - mean_a) < 3 * sigma + 0.005 * mean_a), (mean_a, mean_b, sigma)


@pytest.mark.slow
def test_refracting_boundary_keeps_light_inside_by_total_internal_reflection():
    """The same sphere at η = 1.3 renders (no longer refused) and differs from η = 1 beyond noise: less light
    enters and leaves (Fresnel), paths are trapped longer (total internal reflection)."""
    a = render_volumetric(sphere_scene(), spp=8, seed=1, size=(24, 18), progress=False)
    b = render_volumetric(sphere_scene(eta=1.3), spp=8, seed=1, size=(24, 18), progress=False)
    m = a.mask & b.mask
    assert np.all(b.image[m].mean(axis=0) < 0.9 * a.image[m].mean(axis=0))


def test_manifold_connection_finds_the_refracted_light_paths_a_brute_force_search_finds():
    """Points inside a unit sphere (η = 1.3) under a point light: the connection is found for at least 90 % of
    the points that some refracted light ray passes (brute force over a grid of light directions, analytic
    sphere), and its flux density is I/d² at η = 1."""
    from reflets.reference.geometry import SceneGeometry
    from reflets.reference.volumetric import _refract, _refracted_connection

    geometry = SceneGeometry(sphere_scene())
    rng = np.random.default_rng(0)
    v = rng.normal(size=(150, 3))
    u = v / np.linalg.norm(v, axis=1, keepdims=True) * (1 - 0.2 * rng.random((150, 1)))
    light = np.array([2.0, 3.0, 2.0])
    _, factor, _, valid, _ = _refracted_connection(geometry, u, 1.0, light_pos=light)
    assert valid.mean() > 0.99
    np.testing.assert_allclose(factor[valid] * np.sum((u[valid] - light) ** 2, axis=1), 1.0, rtol=2e-3)
    _, _, _, valid, _ = _refracted_connection(geometry, u, 1.3, light_pos=light)
    axis = -light / np.linalg.norm(light)
    a, b = np.linalg.svd(np.eye(3) - np.outer(axis, axis))[0][:, :2].T
    half = np.arcsin(1 / np.linalg.norm(light))
    x, y = np.meshgrid(np.linspace(-half, half, 500), np.linspace(-half, half, 500))
    d = axis + x.reshape(-1, 1) * a + y.reshape(-1, 1) * b
    d /= np.linalg.norm(d, axis=1, keepdims=True)
    bq = d @ light
    disc = bq**2 - (light @ light - 1)
    d, bq, disc = d[disc > 0], bq[disc > 0], disc[disc > 0]
    entry = light + (-bq - np.sqrt(disc))[:, None] * d
    t, _ = _refract(d, entry, 1 / 1.3)
    chord = -2 * np.sum(entry * t, axis=1)
    reachable = np.zeros(len(u), dtype=bool)
    for i, point in enumerate(u):
        w = point - entry
        s = np.sum(w * t, axis=1)
        miss = np.linalg.norm(w - s[:, None] * t, axis=1)
        reachable[i] = np.any((s > 0) & (s < chord) & (miss < 0.003))
    assert 0.3 < reachable.mean() < 0.9  # the critical-angle shadow exists
    assert valid[reachable].mean() > 0.9


def test_cli_reference_volumetric_engine(tmp_path, capsys):
    """``reflets reference --engine volumetric``: the image and its standard error, the same as the Python call;
    what it cannot do is a one-line error with exit code 2."""
    from reflets.cli import main
    from reflets.imageio import read_image

    scene_file = tmp_path / "sphere.toml"
    scene_file.write_text(
        "[camera]\nposition = [0, 0.5, 3]\nlook_at = [0, 0, 0]\nfov_y = 35\nsize = [16, 12]\n"
        '[materials.skin]\ntype = "translucent"\npreset = "skin1"\neta = 1.0\nmm_per_unit = 25.0\n'
        '[[mesh]]\nshape = "sphere"\nradius = 1.0\nmaterial = "skin"\n'
        '[[light]]\ntype = "point"\nposition = [2, 3, 2]\nintensity = [20, 20, 20]\n'
    )
    out = tmp_path / "ref.exr"
    args = ["reference", str(scene_file), "-o", str(out), "--engine", "volumetric", "--spp", "2", "-q"]
    assert main([*args, "--workers", "2"]) == 0 and "samples/s" in capsys.readouterr().out
    image, stderr = read_image(out), read_image(tmp_path / "ref.stderr.exr")
    expected = render_volumetric(reflets.load_scene(scene_file), spp=2, seed=0, workers=2, progress=False)
    np.testing.assert_allclose(image, expected.image, rtol=1e-6)
    assert stderr.shape == (12, 16, 3) and np.all(stderr[expected.mask] >= 0)
    assert main([*args, "--visibility", "off", "--overwrite"]) == 2
    assert main([*args, "--workers", "0", "--overwrite"]) == 2
    err = capsys.readouterr().err
    assert "pixel centres with shadows" in err and "workers must be at least 1" in err and "Traceback" not in err
