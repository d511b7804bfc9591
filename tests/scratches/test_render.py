"""``--method scratches`` on llvmpipe / a GPU against its NumPy twin (reflets.scratches.shading), and the built-in
scratch scenes."""

from __future__ import annotations

import warnings

import numpy as np
import pytest

import reflets
from reflets.errors import ArgumentError, RefletsWarning
from reflets.scene import load_dict, load_scene
from reflets.scene.environment import environment_grid, load_environment, lookup
from reflets.scratches import shading
from reflets.techniques import get_technique

from .plates import MATERIAL, write_smooth_sky

SIZE = (40, 30)
EYE = np.array([0.0, 1.3, 1.6])
LIGHT = np.array([0.4, 1.2, -0.8])


@pytest.fixture(autouse=True)
def _cache(tmp_path, monkeypatch):
    monkeypatch.setenv("XDG_CACHE_HOME", str(tmp_path / "cache"))


def _plate(tmp_path, material: dict) -> dict:
    write_smooth_sky(tmp_path / "env.npy")
    return {
        "camera": {"position": EYE.tolist(), "look_at": [0, 0, -0.2], "fov_y": 45, "size": list(SIZE)},
        "materials": {"m": material},
        "mesh": [{"shape": "plane", "size": [2, 2], "material": "m"}],
        "light": [
            {"type": "point", "position": LIGHT.tolist(), "intensity": [2.0, 1.5, 1.0]},
            {"type": "environment", "file": str(tmp_path / "env.npy"), "rotate_y": 30},
        ],
        "background": [0, 0, 0],
    }


def test_gpu_matches_numpy_twin(ctx, tmp_path):
    scene = load_dict(_plate(tmp_path, MATERIAL), base_dir=tmp_path)
    # the twin lights the base layer by the environment grid
    tech = get_technique("scratches")(ctx, samples=8, table_backend="numpy", thickness=4.0, environment="grid")
    tech.prepare(scene)
    image = tech.render(spp=8 * 48, seed=3).astype(np.float64)
    pos = get_technique("position")(ctx)
    pos.prepare(scene)
    p = pos.render()
    tech.release()
    pos.release()
    hit = np.linalg.norm(p, axis=-1) > 0
    x = p[hit].astype(np.float64)
    # the plate's frame: t = +x (u), b = −z (v), n = +y; rows of `frame` map world → local
    frame = np.array([[1.0, 0, 0], [0, 0, -1.0], [0, 1.0, 0]])
    wo = EYE - x
    wo = (wo / np.linalg.norm(wo, axis=1, keepdims=True)) @ frame.T
    d = LIGHT - x
    r2 = np.sum(d * d, axis=1)
    wl = (d / np.sqrt(r2)[:, None]) @ frame.T
    E = np.array([2.0, 1.5, 1.0]) / r2[:, None]
    env_image = load_environment(scene)
    light = scene.environment
    dirs, power = environment_grid(env_image, light, (32, 16))
    lights = shading.Lights(
        directional=[(wl, E)],
        env=lambda w: lookup(env_image, light, w @ frame),  # local → world: w @ frame
        env_grid=(dirs @ frame.T, power),
    )
    material = scene.materials["m"]
    twin = shading.shade(
        material.table(backend="numpy"),
        material.layer_angles(),
        np.full(3, 0.3),
        wo,
        lights,
        base=material.base,
        thickness=np.radians(4.0),
    )
    gpu = image[hit]
    assert twin.mean() > 0.05
    rel = np.abs(gpu.mean(axis=0) / twin.mean(axis=0) - 1.0)
    assert np.all(rel < 0.01), rel  # measured 0.14 / 0.06 / 0.03 % (llvmpipe, 384 samples per pixel)
    per_pixel = np.abs(gpu - twin).mean() / twin.mean()
    assert per_pixel < 0.02, per_pixel  # measured 0.77 %; a twin with H = 3° instead of 4° gives 4.2 %


def test_alpha_zero_renders_the_base_like_forward(ctx, tmp_path):
    scene = load_dict(_plate(tmp_path, {**MATERIAL, "coverage": 0.0}), base_dir=tmp_path)
    images = []
    for name in ("scratches", "forward"):
        tech = get_technique(name)(ctx)
        tech.prepare(scene)
        images.append(tech.render())
        tech.release()
    np.testing.assert_allclose(images[0], images[1], rtol=1e-4, atol=1e-6)


def test_spp_short_of_a_frame_is_rounded_up_with_one_note(ctx, tmp_path):
    """``reflets.render(scene, spp=1)`` of a scratched plate under a point light alone: the image of one whole frame
    (spp = samples = 8) and one note saying so, which speaks of no environment (the scene has none)."""
    data = _plate(tmp_path, {**MATERIAL, "profile": "quartic:0.4", "alpha_size": 16})  # a mirror peak: no warning
    data["camera"]["size"], data["light"] = [16, 12], data["light"][:1]
    scene = load_dict(data, base_dir=tmp_path)
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        one = reflets.render(scene, spp=1)
    said = [str(w.message) for w in caught if issubclass(w.category, RefletsWarning)]
    assert len(said) == 1 and "spp 1 rounded up to 8" in said[0] and "environment" not in said[0], said
    np.testing.assert_array_equal(one, reflets.render(scene, spp=8))
    with pytest.raises(ArgumentError, match="spp"):
        reflets.render(scene, spp=0)


@pytest.mark.parametrize("name", ["50_brushed_plate.toml", "51_scratched_plate.toml", "52_scratched_teapot.toml"])
def test_builtin_scenes_load(name):
    from reflets.demo import DEMO, scene_path

    scene = load_scene(scene_path(name))
    assert any(m.type == "scratched" for m in scene.materials.values())
    entry = next(e for e in DEMO if e.scene == name)
    assert {m.name for m in entry.methods} == {"scratches", "forward"}
