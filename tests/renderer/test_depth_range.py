"""The camera's depth range: reversed-Z float depth and an infinite far plane, so a huge ground plane neither
clips a near object nor makes distant surfaces z-fight; optional camera.near / camera.far."""

from __future__ import annotations

import numpy as np
import pytest

import reflets
from reflets.errors import SceneError
from reflets.scene import load_dict
from reflets.scene.camera import projection_matrix
from reflets.scene.geometry import camera_range

RED, GREEN, GREY = [0.8, 0.05, 0.05], [0.05, 0.8, 0.05], [0.5, 0.5, 0.5]
SIZE = (64, 48)


def _scene(meshes, camera, **light) -> dict:
    return {
        "camera": {"fov_y": 50, "size": list(SIZE), **camera},
        "materials": {c: {"type": "lambert", "albedo": v} for c, v in (("red", RED), ("green", GREEN), ("grey", GREY))},
        "mesh": meshes,
        "light": [{"type": "directional", "direction": [0.3, -1, -0.2], "irradiance": [3, 3, 3], **light}],
    }


def _ground_and_sphere(ground_side: float | None, shadows: bool = False) -> dict:
    meshes = [{"shape": "sphere", "radius": 0.1, "material": "red", "transform": {"translate": [0, 1.0, -0.5]}}]
    if ground_side is not None:
        meshes.append({"shape": "plane", "size": [ground_side, ground_side], "material": "grey"})
    return _scene(meshes, {"position": [0, 1.0, 0], "look_at": [0, 0.9, -1]}, shadows=shadows)


def _red(image: np.ndarray) -> np.ndarray:
    return (image[..., 0] > 2.0 * image[..., 1]) & (image[..., 0] > 0.01)


@pytest.mark.parametrize("method", ["forward", "auto"])
def test_a_near_sphere_is_the_same_over_ground_planes_of_any_size(ctx, method):
    """10 m, 100 km and 10,000 km ground planes: the 10 cm sphere 0.5 m away covers the same pixels with the same
    values (a 100 km plane used to push the automatic near plane past it: the sphere vanished)."""
    alone = reflets.render(_ground_and_sphere(None), method=method)
    sphere = _red(alone)
    assert sphere.sum() > 100
    for side in (10.0, 1e5, 1e7):
        image = reflets.render(_ground_and_sphere(side), method=method)
        np.testing.assert_array_equal(_red(image), sphere, err_msg=f"ground plane {side:g} m")
        np.testing.assert_allclose(image[sphere], alone[sphere], atol=2e-2, err_msg=f"ground plane {side:g} m")
        assert np.all(image[-10:].sum(axis=-1) > 0), "the ground fills the bottom of the view"


def _sphere_pixels(scene: dict) -> np.ndarray:
    """Pixels whose camera ray hits the scene's first mesh, the sphere (NumPy rays)."""
    from reflets.scene.camera import pixel_rays

    origin, rays = pixel_rays(load_dict(scene).camera)
    offset = origin - np.asarray(scene["mesh"][0]["transform"]["translate"])
    b = rays @ offset
    return b * b - (offset @ offset - scene["mesh"][0]["radius"] ** 2) > 0


def test_the_near_sphere_s_shadow_on_the_ground_holds_under_a_huge_ground_plane(ctx):
    """A grazing directional light throws the sphere's shadow onto the ground in view (its cascades are fitted
    around the camera's point of interest when the scene is over 1000 times deeper): with 100 km and 10,000 km
    planes, every pixel the 10 m plane shows is within 0.05 except at most 2 on the shadow's edge."""
    from scipy import ndimage

    images, scenes = {}, {}
    for side in (10.0, 1e5, 1e7):
        scenes[side] = _ground_and_sphere(side, shadows=True)
        scenes[side]["light"][0]["direction"] = [0.2, -1, -2.5]
        images[side] = reflets.render(scenes[side], method="forward")
    bare = reflets.render({**scenes[10.0], "mesh": scenes[10.0]["mesh"][1:]}, method="forward")  # no sphere
    reference = images[10.0]
    shadow = (bare.sum(axis=-1) > 0) & (reference.sum(axis=-1) < 0.8 * bare.sum(axis=-1))
    shadow &= ~_sphere_pixels(scenes[10.0])
    assert shadow.sum() >= 5  # the shadow is on the ground in view
    seen = reference.sum(axis=-1) > 0
    edge = ndimage.binary_dilation(shadow) & ~ndimage.binary_erosion(shadow)
    for side in (1e5, 1e7):
        differing = seen & (np.abs(images[side] - reference).sum(axis=-1) > 0.05)
        assert differing.sum() <= 2 and np.all(edge[differing]), f"ground plane {side:g} m: {np.argwhere(differing)}"


def _two_planes() -> dict:
    meshes = [
        {"shape": "plane", "size": [40, 40], "material": "red"},
        {"shape": "plane", "size": [40, 40], "material": "green", "transform": {"translate": [0, 0.001, 0]}},
        {"shape": "plane", "size": [1e7, 1e7], "material": "grey", "transform": {"translate": [0, -1, 0]}},
        {"shape": "sphere", "radius": 0.05, "material": "grey", "transform": {"translate": [0.3, 99.5, 0.2]}},
    ]
    return _scene(meshes, {"position": [0, 100, 0], "look_at": [0, 0, 0], "up": [0, 0, -1], "fov_y": 20})


def _lower_plane_pixels(image: np.ndarray) -> int:
    centre = image[8:40, 10:54]  # inside the 40 m planes, away from the sphere's corner (1,408 pixels)
    return int(np.sum(centre[..., 1] <= 4.0 * centre[..., 0]))


def test_two_planes_a_millimetre_apart_100_m_away_do_not_z_fight(ctx):
    """Seen from 100 m straight above, with a sphere 0.5 m from the camera and a 10,000 km plane below: the upper
    plane wins every pixel."""
    assert _lower_plane_pixels(reflets.render(_two_planes(), method="forward")) == 0


def test_the_two_planes_do_z_fight_in_a_24_bit_depth_buffer(ctx, monkeypatch):
    """The scene above is one the depth format decides: with moderngl's 24-bit fixed-point depth in place of the
    float one (same reversed-Z projection), the lower plane shows through (1,408 of 1,408 pixels here)."""
    from reflets.gpu import targets

    monkeypatch.setattr(targets, "float_depth_texture", lambda context, size: context.depth_texture(size))
    assert _lower_plane_pixels(reflets.render(_two_planes(), method="forward")) > 100


def test_camera_near_and_far_clip_and_are_validated(ctx):
    scene = _ground_and_sphere(10.0)
    scene["camera"]["near"] = 0.6  # past the sphere
    assert not _red(reflets.render(scene)).any()
    scene["camera"].update(near=0.01, far=0.3)  # before it
    assert not _red(reflets.render(scene)).any()
    scene["camera"].update(near=0.01, far=1000.0)
    assert _red(reflets.render(scene)).sum() > 100
    scene["camera"].update(near=2.0, far=1.0)
    with pytest.raises(SceneError, match="near .* must be less than far"):
        load_dict(scene)
    scene["camera"].update(near=-1.0, far=None)
    with pytest.raises(SceneError, match="camera.near"):
        load_dict(scene)


def test_the_automatic_near_plane_follows_the_nearest_object_not_the_scene_extent():
    camera = load_dict(_ground_and_sphere(1e7)).camera
    boxes = np.array([[[-0.1, 0.9, -0.6], [0.1, 1.1, -0.4]], [[-5e6, 0, -5e6], [5e6, 0, 5e6]]])
    near, far = camera_range(camera, boxes)
    assert far is None and near == pytest.approx(1e-3 * np.sqrt(3 * 0.2**2))
    near, _ = camera_range(camera, boxes[1:])  # the plane only: 1 m below the eye
    assert near == pytest.approx(0.5)


def test_the_projection_maps_near_to_one_and_far_or_infinity_to_zero():
    camera = load_dict(_ground_and_sphere(None)).camera
    near = 0.01
    for far in (None, 50.0):
        proj = projection_matrix(camera, *SIZE, near, far)
        for d in (near, 1.0, 50.0, 1e7):
            clip = proj @ [0.0, 0.0, -d, 1.0]
            expected = near / d if far is None else near * (far - d) / ((far - near) * d)
            assert clip[3] == pytest.approx(d) and clip[2] / clip[3] == pytest.approx(expected, rel=1e-9, abs=1e-15)


def test_the_environment_background_follows_every_camera_ray(ctx):
    """The background pass (at infinity, reversed-Z) looks the map up along the NumPy camera rays: within 1e-4 of
    the bilinear NumPy lookup (the near-plane-minus-eye construction it replaced was up to 0.019 off in the sky of
    52_scratched_teapot)."""
    from importlib import resources

    from reflets.scene.camera import pixel_rays
    from reflets.scene.environment import load_environment, lookup

    sky = resources.files("reflets") / "data" / "environments" / "sky.hdr"
    scene = load_dict({
        "camera": {"position": [0.3, 1.2, 2.5], "look_at": [0, 0.2, 0], "fov_y": 60, "size": [96, 64]},
        "light": [{"type": "environment", "file": str(sky), "rotate_y": 30}],
    })  # fmt: skip
    image = reflets.render(scene, method="forward")
    _, rays = pixel_rays(scene.camera)
    expected = lookup(load_environment(scene), scene.light[0], rays.reshape(-1, 3)).reshape(image.shape)
    assert np.abs(image - expected).max() < 1e-4 * max(1.0, float(expected.max()))
