"""The forward renderer against closed-form radiance (GPU float32, one sample per pixel)."""

from __future__ import annotations

import numpy as np
import pytest

import reflets
from reflets.scene.camera import project
from reflets.validation import analytic_image, max_relative_error

SPHERE_SCENE = {
    "camera": {"position": [0, 0, 5], "look_at": [0, 0, 0], "fov_y": 30, "size": [256, 256]},
    "materials": {"m": {"type": "lambert", "albedo": [0.5, 0.6, 0.7]}},
    "mesh": [{"shape": "sphere", "radius": 1, "material": "m"}],
    "light": [{"type": "directional", "direction": [-1, -1, -1], "irradiance": [3, 3, 3]}],
}


def test_lambert_plane_under_point_light_matches_closed_form_to_half_percent(ctx, minimal_scene):
    scene = reflets.load_dict(minimal_scene)
    image = reflets.render(scene)
    exact, mask = analytic_image(scene)
    assert mask.sum() > 0.4 * mask.size, "the check must cover a large part of the image"
    assert max_relative_error(image, exact, mask) < 5e-3


def test_plane_off_centre_with_two_point_lights_and_coloured_albedo(ctx, minimal_scene):
    minimal_scene["mesh"][0]["transform"] = {"translate": [0.3, -0.2, 0.1]}
    minimal_scene["materials"]["floor"]["albedo"] = [0.2, 0.5, 0.9]
    minimal_scene["light"].append({"type": "point", "position": [1.5, 0.5, -1], "intensity": [1, 4, 2]})
    scene = reflets.load_dict(minimal_scene)
    image = reflets.render(scene)
    exact, mask = analytic_image(scene)
    assert max_relative_error(image, exact, mask) < 5e-3


def test_lambert_sphere_under_directional_light_matches_closed_form(ctx):
    scene = reflets.load_dict(SPHERE_SCENE)
    image = reflets.render(scene)
    exact, mask = analytic_image(scene)
    assert mask.sum() > 10000
    assert max_relative_error(image, exact, mask) < 5e-3
    # The unlit half is black (no ambient term sneaks in).
    normals = reflets.render(scene, method="normal")
    wi = -np.asarray(SPHERE_SCENE["light"][0]["direction"], float) / np.sqrt(3)
    hit = np.linalg.norm(normals, axis=-1) > 0.5
    dark = hit & (normals @ wi < -0.05)
    assert dark.sum() > 1000 and np.all(image[dark] == 0)


def test_pixel_convention_known_point_lands_on_expected_pixel(ctx, minimal_scene):
    """A small sphere at a known point: its rendered centroid equals the projection (to 0.5 px)."""
    centre = np.array([0.7, 0.4, -0.9])
    minimal_scene["mesh"] = [
        {"shape": "sphere", "radius": 0.03, "material": "floor", "transform": {"translate": centre.tolist()}}
    ]
    scene = reflets.load_dict(minimal_scene)
    positions = reflets.render(scene, method="position", size=(640, 480))
    covered = np.linalg.norm(positions - centre, axis=-1) < 0.05
    rows, cols = np.nonzero(covered)
    centroid = np.array([cols.mean() + 0.5, rows.mean() + 0.5])
    expected = project(scene.camera, centre, size=(640, 480))
    assert covered.sum() > 20
    assert np.all(np.abs(centroid - expected) < 0.5), (centroid, expected)


def test_every_pixel_samples_the_ray_through_its_centre(ctx, minimal_scene):
    """World positions read back from the GPU lie on the NumPy camera rays through pixel centres."""
    from reflets.scene.camera import pixel_rays

    scene = reflets.load_dict(minimal_scene)
    positions = reflets.render(scene, method="position").astype(np.float64)
    origin, dirs = pixel_rays(scene.camera)
    hit = (np.abs(positions[..., 1]) < 1e-4) & np.any(positions != 0, axis=-1)  # background is 0
    rel = positions[hit] - origin
    along = np.sum(rel * dirs[hit], axis=-1, keepdims=True)
    off_ray = np.linalg.norm(rel - along * dirs[hit], axis=-1)
    pixel_size = 2 * np.tan(np.radians(45) / 2) / 240 * along[:, 0]
    assert hit.sum() > 30000
    assert np.max(off_ray / pixel_size) < 0.02


@pytest.mark.parametrize("spp", [4, 9])
def test_supersampling_averages_stratified_subpixels(ctx, minimal_scene, spp):
    scene = reflets.load_dict(minimal_scene)
    one = reflets.render(scene)
    many = reflets.render(scene, spp=spp)
    assert many.shape == one.shape
    # Smooth interior: supersampled and centre-sampled agree closely; differences only at edges.
    exact, mask = analytic_image(scene)
    assert max_relative_error(many, exact, mask) < 5e-3
    assert not np.array_equal(one, many)


def test_same_scene_renders_identically_twice(ctx):
    scene = reflets.load_dict(SPHERE_SCENE)
    assert np.array_equal(reflets.render(scene), reflets.render(scene))


def test_quad_area_light_converges_to_dense_quadrature(ctx, minimal_scene):
    """Midpoint-rule error decays like 1/n²: n = 4 and n = 8 against n = 64 on a Lambert plane."""
    minimal_scene["light"] = [
        {
            "type": "quad",
            "corners": [[-0.5, 0.5, -0.5], [0.5, 0.5, -0.5], [-0.5, 0.5, 0.5]],
            "radiance": [5, 5, 5],
        }
    ]
    scene = reflets.load_dict(minimal_scene)
    ref = reflets.render(scene, method="forward", area_samples=64)
    _, mask = analytic_image(reflets.load_dict({**minimal_scene, "light": []}))
    errors = [np.max(np.abs(reflets.render(scene, method="forward", area_samples=n) - ref)[mask]) for n in (4, 8)]
    assert errors[1] < errors[0] / 3, errors


def test_one_sided_quad_light_lights_only_its_front(ctx, minimal_scene):
    up = {"type": "quad", "corners": [[-0.5, 1, -0.5], [-0.5, 1, 0.5], [0.5, 1, -0.5]], "radiance": [5, 5, 5]}
    down = {
        "type": "quad",
        "corners": [[-0.5, 1, -0.5], [0.5, 1, -0.5], [-0.5, 1, 0.5]],
        "radiance": [5, 5, 5],
    }
    floor = lambda light: reflets.render(reflets.load_dict({**minimal_scene, "light": [light]}), method="forward")[200]  # noqa: E731
    assert np.all(floor(up) == 0)
    assert floor(down).max() > 0.05
    assert np.allclose(floor({**up, "two_sided": True}), floor(down), rtol=1e-5, atol=1e-7)
