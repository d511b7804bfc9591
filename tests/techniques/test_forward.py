"""The forward pass's compile-time light counts: each light type's code exists only when the scene has one."""

from __future__ import annotations

import numpy as np

import reflets

LIGHTS = {
    "point": {"type": "point", "position": [0.5, 1.5, 0.2], "intensity": [3, 2, 1]},
    "directional": {"type": "directional", "direction": [0.3, -1, -0.2], "irradiance": [0.5, 0.6, 0.7]},
    "quad": {"type": "quad", "corners": [[-0.5, 1, -0.5], [0.5, 1, -0.5], [-0.5, 1, 0.5]], "radiance": [2, 2, 2]},
}


def scene(lights):
    return reflets.load_dict(
        {
            "camera": {"position": [0, 3, 4], "look_at": [0, 0, 0], "fov_y": 45, "size": [64, 48]},
            "materials": {"m": {"type": "microfacet", "distribution": "ggx", "alpha": 0.4, "diffuse": [0.3] * 3}},
            "mesh": [{"shape": "plane", "size": [4, 4], "material": "m"}],
            "light": lights,
        }
    )


def test_every_light_type_adds_its_own_contribution():
    """Linearity: the image with all light types is the sum of the images with each alone (a type whose code
    were compiled out by a wrong count would be missing from the sum; an empty scene is black)."""
    alone = {name: reflets.render(scene([light]), method="forward") for name, light in LIGHTS.items()}
    together = reflets.render(scene(list(LIGHTS.values())), method="forward")
    # the quad's emitter hides part of the plane in every image that has it: compare where the plane is seen
    positions = reflets.render(scene([LIGHTS["quad"]]), method="position")
    plane = (np.abs(positions[..., 1]) < 1e-4) & np.any(positions != 0, axis=-1)
    seen = plane & np.any(alone["quad"] > 0, axis=-1)  # the camera sees the emitter's black back side
    expected = sum(alone.values())
    assert all(img[seen].max() > 0.01 for img in alone.values())
    np.testing.assert_allclose(together[seen], expected[seen], rtol=1e-5, atol=1e-6)
    assert reflets.render(scene([]), method="forward").max() == 0.0


def test_depth_prepass_shades_the_nearest_surface_only_with_the_same_image(monkeypatch):
    """The helmet (textured, self-occluding) in front of a textured cut-out plane, under the map with its occlusion
    and a point light: with the depth pre-pass (the helmet's depths first, then each pixel shaded once) the image
    is the one drawn without it, bit for bit; the cut-out mesh is left out of the pre-pass (its holes would
    hide what is behind)."""
    import warnings

    from reflets.scene.assets import asset_path, default_environment
    from reflets.techniques.forward import Forward

    helmet = str(asset_path("DamagedHelmet/DamagedHelmet.glb"))
    cut = {"type": "gltf", "alpha_mode": "mask", "alpha_cutoff": 0.5,
           "base_color_texture": {"texture": helmet, "image": 0, "channels": "rgbr"}}  # fmt: skip
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        scene = reflets.load_dict({
            "camera": {"position": [0, 0.3, 3.2], "look_at": [0, 0, 0], "fov_y": 45, "size": [96, 72]},
            "materials": {"cut": cut},
            "mesh": [{"file": helmet},
                     {"shape": "plane", "size": [3, 3], "material": "cut",
                      "transform": {"rotate": [90, 0, 0], "translate": [0, 0, -0.7]}}],
            "light": [{"type": "environment", "file": str(default_environment())},
                      {"type": "point", "position": [1.5, 2.0, 3.0], "intensity": [5, 5, 5]}],
        })  # fmt: skip
    drawn = []
    prepass = Forward._depth_prepass
    monkeypatch.setattr(Forward, "_depth_prepass", lambda self, *a: drawn.append(prepass(self, *a)) or drawn[-1])
    with_prepass = reflets.render(scene, method="forward")
    assert drawn and drawn[0] == {0}, drawn  # the helmet only (draw 0), not the cut-out plane
    monkeypatch.setattr(Forward, "depth_prepass", False)
    without = reflets.render(scene, method="forward")
    assert np.array_equal(with_prepass, without)
    assert with_prepass.mean() > 0.01 and np.ptp(with_prepass) > 0.5  # an image, not a cleared target


def test_texture_anisotropy_is_each_renderers_own():
    """Two renderers on one context share the helmet's textures: the second one's texture_anisotropy must not
    change the first one's frames (it did when prepare set it on the shared textures)."""
    from reflets.scene.assets import asset_path

    scene = reflets.load_scene(asset_path("DamagedHelmet/DamagedHelmet.glb"))
    scene = scene.model_copy(update={"camera": scene.camera.model_copy(update={"size": (96, 72)})})
    with reflets.Renderer(scene, texture_anisotropy=1.0) as trilinear:
        first = trilinear.render()
        with reflets.Renderer(scene, texture_anisotropy=16.0) as anisotropic:
            sharp = anisotropic.render()
            again = trilinear.render()
    assert not np.array_equal(first, sharp)  # the setting matters for this view
    np.testing.assert_array_equal(first, again)
