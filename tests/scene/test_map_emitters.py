"""Compact emitters split off an environment map (scene/map_emitters.py): found by the stated rule, power kept
exactly between the residual map and the emitters, directions in the world, and the GPU's scene."""

from __future__ import annotations

import numpy as np
import pytest

import reflets
from reflets.equirect import equirect_direction, equirect_uv, row_solid_angles
from reflets.scene.environment import load_environment
from reflets.scene.map_emitters import find_emitters, is_split, split_map, with_map_emitters


def sky_with_sun(column: int = 80, row: int = 20, size=(128, 256)) -> np.ndarray:
    """A uniform sky (0.5, 0.6, 0.8) with a 3 × 3 sun of 4000 and a wide bright band (60, not compact) below it."""
    h, w = size
    sky = np.empty((h, w, 3), np.float32)
    sky[...] = (0.5, 0.6, 0.8)
    cols = np.arange(column - 1, column + 2) % w
    sky[row - 1 : row + 2][:, cols] = (4000.0, 3800.0, 3000.0)
    sky[60:68] = (60.0, 60.0, 60.0)  # 8 rows around the horizon: a bright but wide region
    return sky


def power(image: np.ndarray) -> np.ndarray:
    h, w, _ = image.shape
    return np.sum(image.astype(np.float64) * row_solid_angles(h, w)[:, None, None], axis=(0, 1))


def test_the_sun_is_found_and_the_power_is_kept_exactly():
    sky = sky_with_sun()
    emitters, residual = find_emitters(sky)
    assert len(emitters) == 1  # the band is bright but not compact: it stays in the map
    sun = emitters[0]
    expected = equirect_direction((80 + 0.5) / 256, (20 + 0.5) / 128)
    assert np.degrees(np.arccos(np.clip(np.dot(sun.direction, expected), -1, 1))) < 1.0
    assert sun.texels == 9 and sun.solid_angle == pytest.approx(9 * row_solid_angles(128, 256)[20], rel=0.05)
    np.testing.assert_allclose(power(residual) + np.array(sun.power), power(sky), rtol=1e-6)
    assert np.all(residual <= sky) and np.array_equal(residual[60:68], sky[60:68])
    assert residual.max() < 100  # the sun's texels keep the threshold's luminance: the map stays continuous


def test_a_sun_across_the_seam_is_one_emitter_and_rotate_y_turns_it(tmp_path):
    sky = sky_with_sun(column=0)  # columns 255, 0 and 1
    emitters, _ = find_emitters(sky)
    assert len(emitters) == 1 and emitters[0].texels == 9
    u, _ = equirect_uv(np.asarray(emitters[0].direction))
    assert min(u, 1 - u) < 1 / 256
    np.save(tmp_path / "sky.npy", sky)
    turned, _ = split_map(reflets.load_dict({"camera": {"position": [0, 0, 3], "look_at": [0, 0, 0]}, "light": [
        {"type": "environment", "file": "sky.npy", "rotate_y": 90.0}]}, base_dir=tmp_path))  # fmt: skip
    x, y, z = emitters[0].direction
    np.testing.assert_allclose(turned[0].direction, (z, y, -x), atol=1e-9)  # R_y(90°) of the direction


def test_a_map_without_a_compact_emitter_is_left_whole():
    sky = sky_with_sun()
    sky[18:22] = 0.5  # no sun: only the wide band
    emitters, residual = find_emitters(sky)
    assert emitters == [] and np.array_equal(residual, sky)


def test_the_gpu_scene_gets_the_sun_as_a_shadowed_directional_light(tmp_path, ctx):
    from reflets.techniques.prepared import PreparedScene

    np.save(tmp_path / "sky.npy", sky_with_sun())
    sun = find_emitters(sky_with_sun())[0][0]
    data = {"camera": {"position": [0, 0, 0], "look_at": list(4 * np.array(sun.direction)), "fov_y": 20,
                       "size": [32, 24]},
            "materials": {"m": {"type": "lambert"}}, "mesh": [{"shape": "sphere", "material": "m",
                                                               "transform": {"translate": [0, -5, 0]}}],
            "light": [{"type": "point", "position": [0, 2, 2], "intensity": [1, 1, 1]},
                      {"type": "environment", "file": "sky.npy", "scale": 0.5}]}  # fmt: skip
    scene = reflets.load_dict(data, base_dir=tmp_path)  # emitters = "extract": the default
    gpu = with_map_emitters(scene)
    assert [light.type for light in gpu.light] == ["point", "environment", "directional"]
    assert is_split(gpu) and not is_split(scene) and with_map_emitters(gpu) is gpu
    np.testing.assert_allclose(gpu.light[2].irradiance, 0.5 * np.array(sun.power), rtol=1e-6)
    np.testing.assert_allclose(gpu.light[2].direction, -np.array(sun.direction), atol=1e-9)
    assert gpu.light[2].shadows and gpu.light[2].shadows == scene.light[1].shadows
    whole, rest = load_environment(scene), split_map(scene)[1]
    np.testing.assert_allclose(power(rest) + np.array(gpu.light[2].irradiance), power(whole), rtol=1e-6)
    for prepared_from, lit_by in ((gpu, rest), (scene, whole)):  # prepared without the split: the whole map lights
        prepared = PreparedScene(ctx, prepared_from)
        try:
            assert np.array_equal(prepared.environment, lit_by)
        finally:
            prepared.release()
    assert reflets.render(scene).max() > 1000  # the sun seen in the background: the whole map is shown
    kept = scene.model_copy(update={"light": [scene.light[0], scene.light[1].model_copy(update={"emitters": "keep"})]})
    assert with_map_emitters(kept) is kept and split_map(kept) is None


def test_a_night_map_gives_every_lamp_and_two_of_them_cascades(tmp_path, ctx):
    """Twelve small lamps of a dark map all become lights (up to MAX_COUNT = 32), each shadowed; only the two
    brightest directional lights get cascades (shadows.CASCADED_LIGHTS), the others one view of the scene."""
    from reflets.techniques.prepared import PreparedScene
    from reflets.techniques.shadows import CASCADED_LIGHTS

    night = np.full((128, 256, 3), 0.02, np.float32)
    columns = np.arange(12) * 21 + 5
    for k, column in enumerate(columns):
        night[30 + 3 * (k % 5), column] = 500.0 + 100.0 * k  # the brightest last
    np.save(tmp_path / "night.npy", night)
    emitters, _ = find_emitters(night)
    assert len(emitters) == 12
    data = {"camera": {"position": [0, 2, 6], "look_at": [0, 0, 0], "fov_y": 30, "size": [320, 240]},
            "materials": {"m": {"type": "lambert"}},
            "mesh": [{"shape": "plane", "size": [100, 100], "material": "m"},
                     {"shape": "sphere", "material": "m", "transform": {"translate": [0, 1, 0]}}],
            "light": [{"type": "environment", "file": "night.npy"}]}  # fmt: skip
    gpu = with_map_emitters(reflets.load_dict(data, base_dir=tmp_path))
    lamps = [light for light in gpu.light if light.type == "directional"]
    assert len(lamps) == 12
    prepared = PreparedScene(ctx, gpu)
    try:
        views = [prepared.shadows.cascade_count(lamp) for lamp in lamps]
    finally:
        prepared.release()
    brightest = np.argsort([-lamp.irradiance[0] for lamp in lamps])[:CASCADED_LIGHTS]
    assert all(views[k] > 1 for k in brightest)  # a large floor seen from afar: cascades
    assert sorted(views)[: 12 - CASCADED_LIGHTS] == [1] * (12 - CASCADED_LIGHTS)
