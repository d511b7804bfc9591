"""The persistent Renderer: every edit leaves the image a fresh one-shot render of the edited scene gives."""

from __future__ import annotations

import numpy as np
import pytest

import reflets
from reflets.errors import ArgumentError, SceneError
from reflets.metrics import compare

from .scenes import sphere_scene

SIZE = (64, 48)


def relmse(a, b) -> float:
    return compare(a, b)["relmse"]


def showcase_like() -> dict:
    """A floor, a GGX sphere and a Lambert cube under a point light and a quad light (ltc for the quad)."""
    scene = sphere_scene("microfacet", "point", size=SIZE)
    scene["materials"]["floor"] = {"type": "lambert", "albedo": [0.5, 0.5, 0.5]}
    scene["mesh"].append(
        {"shape": "plane", "size": [6, 6], "material": "floor", "transform": {"translate": [0, -1, 0]}}
    )
    scene["mesh"].append(
        {"shape": "cube", "size": 0.5, "material": "floor", "transform": {"translate": [1.4, -0.7, 0]}}
    )
    scene["light"].append(
        {"type": "quad", "corners": [[-1, 2.5, -1], [0, 2.5, -1], [-1, 2.5, 0]], "radiance": [3, 3, 3]}
    )
    return scene


@pytest.mark.parametrize(
    "edit",
    [
        lambda r: r.set_camera(position=(1.0, 1.5, 3.0), fov_y=50),
        lambda r: r.set_light(0, position=(-1.5, 2.0, 1.0), intensity=(3, 6, 9)),
        lambda r: r.set_light(1, radiance=(1, 2, 3)),
        lambda r: r.set_material("m", alpha=0.6),
        lambda r: r.set_material("floor", type="phong", kd=(0.2, 0.4, 0.2), ks=(0.3, 0.3, 0.3), exponent=30),
        lambda r: r.set_transform(2, translate=(-1.2, -0.6, 0.5), rotate=(0, 30, 0), scale=0.8),
    ],
    ids=["camera", "point light", "quad light", "roughness", "material type", "transform"],
)
def test_an_edit_gives_the_one_shot_render_of_the_edited_scene(ctx, edit):
    with reflets.Renderer(showcase_like()) as renderer:
        before = renderer.render()
        edit(renderer)
        after = renderer.render()
        fresh = reflets.render(renderer.scene)
    assert relmse(after, fresh) < 1e-6
    assert relmse(after, before) > 1e-4  # the edit did change the image


def test_a_sequence_of_edits_and_a_camera_move_without_preparing_again(ctx):
    with reflets.Renderer(showcase_like()) as renderer:
        renderer.render()
        prepares = renderer.stats["prepares"]
        for angle in np.linspace(0, np.pi, 4):
            renderer.set_camera(position=(3.5 * np.sin(angle), 0.8, 3.5 * np.cos(angle)))
            image = renderer.render()
        assert renderer.stats["prepares"] == prepares  # camera moves re-use the prepared scene
        assert relmse(image, reflets.render(renderer.scene)) < 1e-6
        renderer.set_light(0, intensity=(20, 20, 20))
        renderer.set_material("floor", albedo=(0.2, 0.3, 0.4))
        renderer.set_camera(look_at=(0.2, -0.2, 0))
        assert relmse(renderer.render(), reflets.render(renderer.scene)) < 1e-6
        assert set(renderer.stats) >= {"prepare_ms", "frame_ms"}


def test_progressive_methods_accumulate_across_calls_and_restart_on_an_edit(ctx):
    scene = sphere_scene("lambert", "quad", size=(32, 24))
    with reflets.Renderer(scene, method="mc", samples=4) as renderer:
        renderer.render(seed=3)
        two = renderer.render(seed=3)
        assert renderer.stats["frames"] == 2
        np.testing.assert_allclose(two, reflets.render(scene, method="mc", samples=4, seed=3, spp=8), rtol=1e-6)
        renderer.set_light(0, radiance=(4, 4, 4))
        renderer.render(seed=3)
        assert renderer.stats["frames"] == 1  # restarted


def test_bad_edits_are_clear_errors(ctx):
    with reflets.Renderer(showcase_like()) as renderer:
        with pytest.raises(SceneError, match=r"camera.fov_y"):
            renderer.set_camera(fov_y=-3)
        with pytest.raises(SceneError, match=r"did you mean 'fov_y'"):
            renderer.set_camera(fov=30)
        with pytest.raises(SceneError, match=r"no light\[7\]"):
            renderer.set_light(7, intensity=(1, 1, 1))
        with pytest.raises(SceneError, match=r"unknown material 'metal'"):
            renderer.set_material("metal", alpha=0.1)
        with pytest.raises(SceneError, match=r"unknown transform field 'shear'"):
            renderer.set_transform(0, shear=1)
        with pytest.raises(ArgumentError, match=r"spp"):
            renderer.render(spp=-1)
        renderer.render()  # still usable after refused edits
    with pytest.raises(ArgumentError, match="released"):
        renderer.render()
