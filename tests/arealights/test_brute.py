"""``brute`` (eq 2.8 of the area-light document) against the exact Lambert polygon irradiance."""

from __future__ import annotations

import numpy as np
import pytest
from meunier_helpers import document_scene, exact_lambert, light_normal, plane_pixels, relative_mse

import reflets
from reflets.errors import ArgumentError

LAMBERT = {"type": "lambert", "albedo": [0.8, 0.8, 0.8]}


def test_document_light_faces_the_plane(ctx):
    scene = document_scene(LAMBERT)
    assert np.allclose(light_normal(scene.light[0]), [0.0, -1.0, 0.0])


def test_lambert_error_decays_as_n_squared(ctx):
    """Relative MSE over the plane (emitter pixels excluded) against Lambert's exact formula: 8×8 → 16×16
    divides it by ≈ 16 (O(1/n²) error); at least 3× required."""
    scene = document_scene(LAMBERT)
    positions, mask = plane_pixels(scene)
    assert mask.sum() > 3000
    exact = exact_lambert(scene, positions, mask, 0.8)
    errors = {
        n: relative_mse(reflets.render(scene, method="brute", size=(100, 75), grid=n), exact, mask) for n in (4, 8, 16)
    }
    assert errors[8] / errors[16] >= 3.0, errors
    assert errors[4] / errors[8] >= 3.0, errors
    assert errors[16] < 1e-6, errors  # measured 2.0e-7 (8×8: 3.3e-6)


def test_one_sided_and_two_sided(ctx):
    down = {"type": "quad", "corners": [[-0.5, 1, -0.5], [0.5, 1, -0.5], [-0.5, 1, 0.5]], "radiance": [5, 5, 5]}
    up = {**down, "corners": [[-0.5, 1, -0.5], [-0.5, 1, 0.5], [0.5, 1, -0.5]]}  # emits towards +y
    images = {}
    for name, light in (("down", down), ("up", up)):
        for two_sided in (False, True):
            scene = document_scene(LAMBERT, light={**light, "two_sided": two_sided})
            images[name, two_sided] = reflets.render(scene, method="brute", size=(100, 75), grid=8)
    _, mask = plane_pixels(document_scene(LAMBERT))
    assert images["down", False][mask].min() > 0.0
    assert np.all(images["up", False][mask] == 0.0)  # the plane is behind a one-sided light
    np.testing.assert_allclose(images["up", True][mask], images["down", False][mask], rtol=1e-5)
    np.testing.assert_allclose(images["down", True][mask], images["down", False][mask], rtol=1e-5)


def test_samples_per_pixel_is_n_squared(ctx):
    scene = document_scene(LAMBERT)
    _, mask = plane_pixels(scene)
    counts = reflets.render(scene, method="brute", size=(100, 75), grid=7, output="samples")[..., 0]
    assert np.all(counts[mask] == 49)


def test_pentagon_converges_to_the_exact_formula(ctx):
    """A regular pentagon (fan of 3 triangles, n² sub-triangles each) converges to Lambert's formula."""
    angles = 2 * np.pi * np.arange(5) / 5  # counter-clockwise seen from below: emits downwards
    vertices = [[0.6 * np.cos(a) + 0.2, 0.8, 0.6 * np.sin(a)] for a in angles]
    pentagon = {"type": "polygon", "vertices": vertices, "radiance": [2, 3, 4]}
    scene = document_scene(LAMBERT, light=pentagon)
    assert np.allclose(light_normal(scene.light[0]), [0.0, -1.0, 0.0])
    positions, mask = plane_pixels(scene)
    exact = exact_lambert(scene, positions, mask, 0.8)
    errors = [
        relative_mse(reflets.render(scene, method="brute", size=(100, 75), grid=n), exact, mask) for n in (2, 4, 8, 16)
    ]
    assert all(b < a / 3 for a, b in zip(errors, errors[1:], strict=False)), errors
    assert errors[-1] < 1e-6, errors  # measured 1.0e-7
    counts = reflets.render(scene, method="brute", size=(100, 75), grid=4, output="samples")[..., 0]
    assert np.all(counts[mask] == 3 * 16)


@pytest.mark.parametrize("grid", [0, 129, 2.5])
def test_grid_is_validated(ctx, grid):
    with pytest.raises(ArgumentError):
        reflets.render(document_scene(LAMBERT), method="brute", size=(8, 6), grid=grid)
