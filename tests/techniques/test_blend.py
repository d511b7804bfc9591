"""glTF alphaMode BLEND: a blended surface's radiance over what lies behind it, weighted by its coverage
(a L + (1 − a) L_behind), farthest first; its shadow lets 1 − a through — on the GPU (sorted blending, a dithered
shadow map) and in the NumPy reference (stochastic coverage)."""

from __future__ import annotations

import numpy as np

import reflets
from reflets.bench.assets import block_means
from reflets.metrics import relmse
from reflets.renderer.compose import pass_plan

CAMERA = {"position": [0, 0, 3], "look_at": [0, 0, 0], "fov_y": 30, "size": [48, 36]}
LIGHT = [{"type": "point", "position": [0, 2, 3], "intensity": [1, 1, 1]}]


def card(material, z, size=1.0):
    return {"shape": "plane", "size": [size, size], "material": material,
            "transform": {"rotate": [90, 0, 0], "translate": [0, 0, z]}}  # fmt: skip


def unlit(rgba, mode="blend"):
    return {"type": "gltf", "unlit": True, "base_color": rgba, "alpha_mode": mode}


def test_blended_cards_are_drawn_over_what_lies_behind_them_farthest_first():
    materials = {"red": unlit([1, 0, 0, 0.5]), "green": unlit([0, 1, 0, 0.5]), "blue": unlit([0, 0, 1, 1], "opaque")}
    meshes = [card("red", 0.5, 0.4), card("green", 0.0, 0.8), card("blue", -0.5, 3.0)]
    images = []
    for order in ([0, 1, 2], [2, 1, 0], [1, 0, 2]):  # the scene's order does not matter
        scene = reflets.load_dict({"camera": CAMERA, "materials": materials, "light": LIGHT,
                                   "mesh": [meshes[k] for k in order]})  # fmt: skip
        images.append(reflets.render(scene, method="forward"))
    for image in images[1:]:
        np.testing.assert_array_equal(image, images[0])
    centre = images[0][18, 24]
    np.testing.assert_allclose(centre, [0.5, 0.25, 0.25], atol=1e-3)  # red over green over blue
    np.testing.assert_allclose(images[0][18, 16], [0.0, 0.5, 0.5], atol=1e-3)  # green over blue
    np.testing.assert_allclose(images[0][2, 2], [0.0, 0.0, 1.0], atol=1e-3)  # blue alone


def test_a_blended_card_and_its_shadow_match_the_reference():
    """A lit half-covering card over a floor: seen through (the floor at half weight) and its shadow (half the light
    through) in both renderers."""
    scene = reflets.load_dict({
        "camera": {"position": [0, 2.2, 2.2], "look_at": [0, 0, 0], "size": [96, 72]},
        "materials": {"card": {"type": "gltf", "base_color": [0.9, 0.3, 0.2, 0.5], "metallic": 0.0, "roughness": 0.5,
                               "alpha_mode": "blend"},
                      "floor": {"type": "lambert", "albedo": [0.6, 0.6, 0.6]}},
        "mesh": [{"shape": "plane", "size": [0.8, 0.8], "material": "card", "transform": {"translate": [0, 0.4, 0]}},
                 {"shape": "plane", "size": [4, 4], "material": "floor"}],
        "light": [{"type": "point", "position": [0.3, 2.0, 0.2], "intensity": [3, 3, 3]}],
    })  # fmt: skip
    gpu = reflets.render(scene, method="forward", spp=4)
    ref = reflets.reference(scene, spp=64, progress=False).image
    assert relmse(block_means(gpu), block_means(ref)) < 3e-4  # measured 3.3e-5
    solid = scene.model_copy(update={"materials": {**scene.materials, "card": scene.materials["card"].model_copy(
        update={"alpha_mode": "opaque"})}})  # fmt: skip
    assert relmse(reflets.render(solid, method="forward", spp=4), gpu) > 0.005  # the blending is seen: 0.019


def test_blended_meshes_get_a_pass_of_their_own_after_a_reflecting_pass():
    """The blended card is drawn last, and the mirror keeps its reflections (the reflecting pass still draws the
    emitters and the background: the blended pass does not take them from it)."""

    def scene(card: bool):
        mesh = [{"shape": "sphere", "radius": 0.5, "material": "mirror", "reflector": True},
                {"shape": "plane", "size": [4, 4], "material": "floor", "transform": {"translate": [0, -0.5, 0]}}]
        if card:
            mesh.append({"shape": "plane", "size": [0.3, 0.3], "material": "glass",
                         "transform": {"rotate": [90, 0, 0], "translate": [-0.9, 0.2, 0.8]}})
        return reflets.load_dict({
            "camera": {"position": [0, 0.5, 3], "look_at": [0, 0, 0], "size": [64, 48]},
            "materials": {"mirror": {"type": "mirror"}, "floor": {"type": "lambert", "albedo": [0.6, 0.3, 0.2]},
                          "glass": {"type": "gltf", "base_color": [0.2, 0.4, 1.0, 0.4], "alpha_mode": "blend"}},
            "mesh": mesh, "light": [{"type": "point", "position": [1, 2, 2], "intensity": [3, 3, 3]}],
        })  # fmt: skip

    assert pass_plan(scene(True), "ltc")[-1][2] == frozenset({2})
    with_card, without = reflets.render(scene(True)), reflets.render(scene(False))
    sphere = np.linalg.norm(reflets.render(scene(False), method="position"), axis=-1) < 0.51
    # the card's own reflection aside, the mirror shows what it shows without the card (measured 7e-5; 0.004, with
    # the mirror 10x darker, when the blended pass took the extras from the reflecting one)
    assert relmse(with_card[sphere][None], without[sphere][None]) < 5e-4


def test_a_scene_of_blended_meshes_only_renders_in_auto():
    """Every mesh blended: the BRDF pass draws the background, then them (auto failed to choose the pass that draws
    the background and the emitters)."""
    scene = reflets.load_dict({
        "camera": {"position": [0, 0, 2], "look_at": [0, 0, 0], "size": [32, 24]},
        "background": [0.0, 0.0, 1.0],
        "materials": {"glass": {"type": "gltf", "base_color": [1, 0, 0, 0.5], "alpha_mode": "blend", "unlit": True}},
        "mesh": [{"shape": "plane", "size": [4, 4], "material": "glass", "transform": {"rotate": [90, 0, 0]}}],
    })  # fmt: skip
    image = reflets.render(scene)
    assert np.allclose(image[12, 16], [0.5, 0.0, 0.5], atol=1e-3)  # a (red) + (1 - a) background (blue)
