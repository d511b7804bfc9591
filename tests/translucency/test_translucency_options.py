"""Options of the ``translucent`` technique: the document's curvature rejection and image-space refraction,
against closed forms (flat slabs, spheres of known curvature)."""

from __future__ import annotations

import numpy as np
import pytest

import reflets
from reflets.scene.camera import pixel_rays, project
from reflets.translucency import half_space_single_scattering
from reflets.translucency.optics import fresnel_transmittance

OVERHEAD = {"type": "directional", "direction": [0, -1, 0], "irradiance": [1, 1, 1]}


def test_curvature_rejection_leaves_a_flat_slab_unchanged():
    scene = reflets.load_dict(
        {
            "camera": {"position": [0, 3, 0.001], "look_at": [0, 0, 0], "fov_y": 20, "size": [32, 32]},
            "materials": {"m": {"type": "translucent", "preset": "skin1", "mm_per_unit": 10.0}},
            "mesh": [{"shape": "plane", "size": [10, 10], "material": "m"}],
            "light": [OVERHEAD],
        }
    )
    off = reflets.render(scene, method="translucent", terms=["multiple"])
    on = reflets.render(scene, method="translucent", terms=["multiple"], curvature_rejection=0.01)
    np.testing.assert_allclose(on, off, rtol=1e-5, atol=1e-7)


def test_curvature_rejection_threshold_is_the_surface_curvature_per_mm():
    """A sphere of radius 5 mm curves by 0.2 per mm: κ_max above that changes almost nothing, below it every
    spoke stops at its first node (only the centre's share of the first cell is left)."""
    scene = reflets.load_dict(
        {
            "camera": {"position": [0, 0.5, 3], "look_at": [0, 0, 0], "fov_y": 35, "size": [48, 36]},
            "materials": {"m": {"type": "translucent", "preset": "skin1", "eta": 1.0, "mm_per_unit": 5.0}},
            "mesh": [{"shape": "sphere", "radius": 1.0, "material": "m"}],
            "light": [{"type": "point", "position": [2, 3, 2], "intensity": [20, 20, 20]}],
        }
    )
    off, above, below = (
        reflets.render(scene, method="translucent", terms=["multiple"], curvature_rejection=k)
        for k in (None, 0.3, 0.15)
    )
    m = np.any(off > 0, axis=-1)
    assert np.all(np.abs(above[m].mean(axis=0) / off[m].mean(axis=0) - 1) < 0.03)
    assert np.all(below[m].mean(axis=0) < 0.8 * off[m].mean(axis=0))


# ------------------------------------------------------------------------------------------- refraction
THICKNESS = 0.3  # scene units (3 mm)
ETA = 1.5


def slab_scene(theta_deg: float, eta: float = ETA, light=OVERHEAD):
    """A 10 × 0.3 × 10 box (top face at y = 0) of a weakly scattering medium, seen at theta from the normal."""
    theta = np.radians(theta_deg)
    return reflets.load_dict(
        {
            "camera": {
                "position": [0, 3 * np.cos(theta), 3 * np.sin(theta) + 1e-3],
                "look_at": [0, 0, 0],
                "fov_y": 10,
                "size": [33, 33],
            },
            "materials": {
                "m": {
                    "type": "translucent",
                    "sigma_a": [0.01, 0.02, 0.05],
                    "sigma_s_prime": [0.05, 0.05, 0.05],
                    "g": 0.0,
                    "eta": eta,
                    "mm_per_unit": 10.0,
                }
            },
            "mesh": [
                {
                    "shape": "cube",
                    "size": [10, THICKNESS, 10],
                    "material": "m",
                    "transform": {"translate": [0, -0.15, 0]},
                }
            ],
            "light": [light],
            "background": [0.5, 0.7, 0.9],
        }
    )


@pytest.mark.parametrize("theta", [0.0, 30.0, 55.0])
def test_refracted_exit_through_a_slab_has_the_closed_form_lateral_shift(theta):
    """Exit of the refracted view ray through a slab of thickness d: x + t d/cos θ_t, i.e. shifted by
    d (tan θ_i − tan θ_t) from the straight ray's exit, at every pixel of the slab."""
    scene = slab_scene(theta)
    exit_point = reflets.render(scene, method="translucent", refraction="exit").reshape(-1, 3).astype(np.float64)
    front = reflets.render(scene, method="position").reshape(-1, 3).astype(np.float64)
    origin, dirs = pixel_rays(scene.camera)
    dirs = dirs.reshape(-1, 3)
    cos_i = -dirs[:, 1]
    sin_t = np.sqrt(1 - cos_i**2) / ETA
    cos_t = np.sqrt(1 - sin_t**2)
    # refracted direction: tangential part scaled by 1/η, normal part −cos θ_t
    t = dirs / ETA
    t[:, 1] = -cos_t
    expected = front + t * (THICKNESS / cos_t)[:, None]
    straight = front + dirs * (THICKNESS / cos_i)[:, None]
    shift = np.linalg.norm(expected - straight, axis=1)
    np.testing.assert_allclose(
        shift.mean(), THICKNESS * np.mean(np.sqrt(1 - cos_i**2) / cos_i - sin_t / cos_t), rtol=1e-9
    )
    # image space: an exit that projects outside the frame cannot be found (0 there), every other one is
    pixel = project(scene.camera, expected)
    inside = np.all((pixel > 0.5) & (pixel < 32.5), axis=1)
    np.testing.assert_allclose(exit_point[inside], expected[inside], atol=2e-5)
    outside = np.all((pixel < -0.5) | (pixel > 33.5), axis=1)
    assert np.all(exit_point[outside] == 0)
    if theta > 0:
        assert shift.min() > 50 * 2e-5  # the test sees the shift


def test_transmitted_background_through_a_slab():
    """Background × F_T(front) F_T(back, from inside) × e^{−σ_t d/cos θ_t} (the η² in and out cancel)."""
    theta = np.radians(40.0)
    scene = slab_scene(40.0)
    image = reflets.render(scene, method="translucent", refraction="on", terms=["transmission"])
    sin_t = np.sin(theta) / ETA
    cos_t = np.sqrt(1 - sin_t**2)
    ft = fresnel_transmittance(np.cos(theta), ETA) * fresnel_transmittance(cos_t, 1 / ETA)
    sigma_t = scene.materials["m"].medium().sigma_t
    expected = np.array([0.5, 0.7, 0.9]) * ft * np.exp(-sigma_t * 10 * THICKNESS / cos_t)
    np.testing.assert_allclose(image[16, 16], expected, rtol=1e-3)
    off = reflets.render(scene, method="translucent", terms=["transmission"])
    assert np.all(off[16, 16] == 0)  # no back-face pass: nothing is transmitted


@pytest.mark.parametrize("theta", [0.0, 40.0])
def test_single_scattering_in_a_finite_slab_stops_at_the_back_face(theta):
    """Hanrahan–Krueger on a slab of thickness d: the half-space value × (1 − e^{−σ_t d (1/μ'_i + 1/μ'_o)}).
    Without the back-face pass the march runs c_l mean free paths deep, past the slab (> 2× too bright here)."""
    scene = slab_scene(theta)
    medium = scene.materials["m"].medium()
    cos_o = np.cos(np.radians(theta))
    mu_o = np.sqrt(1 - (1 - cos_o**2) / ETA**2)
    half_space = half_space_single_scattering(medium, 1.0, cos_o)
    expected = half_space * (1 - np.exp(-medium.sigma_t * 10 * THICKNESS * (1 + 1 / mu_o)))
    on = reflets.render(scene, method="translucent", refraction="on", terms=["single"])
    off = reflets.render(scene, method="translucent", terms=["single"])
    np.testing.assert_allclose(on[16, 16], expected, rtol=0.02)
    assert np.all(off[16, 16] > 2 * expected)


def test_refracted_exit_through_a_sphere_converges_to_the_ray_sphere_exit():
    """On a curved back surface the first (parallel-faces) estimate is off; the tangent-plane refinement
    converges to the analytic exit of the refracted ray from the unit sphere."""
    scene = reflets.load_dict(
        {
            "camera": {"position": [0, 0.5, 4], "look_at": [0, 0, 0], "fov_y": 35, "size": [40, 40]},
            "materials": {"m": {"type": "translucent", "preset": "skin1", "eta": 1.3, "mm_per_unit": 10.0}},
            "mesh": [{"shape": "sphere", "radius": 1.0, "material": "m"}],
            "light": [OVERHEAD],
        }
    )
    exit_point = reflets.render(scene, method="translucent", refraction="exit").reshape(-1, 3).astype(np.float64)
    front = reflets.render(scene, method="position").reshape(-1, 3).astype(np.float64)
    origin, dirs = pixel_rays(scene.camera)
    dirs = dirs.reshape(-1, 3)
    n = front / np.maximum(np.linalg.norm(front, axis=1, keepdims=True), 1e-12)
    cos_i = -np.sum(dirs * n, axis=1)
    seen = (np.linalg.norm(front, axis=1) > 0.5) & (cos_i > 0.3)
    ratio = 1 / 1.3
    cos_t = np.sqrt(1 - ratio**2 * (1 - cos_i**2))
    t = ratio * dirs + (ratio * cos_i - cos_t)[:, None] * n
    expected = front + t * (2 * cos_t)[:, None]  # chord of the unit sphere along t from a point on it
    np.testing.assert_allclose(exit_point[seen], expected[seen], atol=3e-3)  # tessellation: 256 × 128
    # the parallel-faces start (the back face on the camera ray is 2 cos θ_o away) misses by far more
    first_guess = front + t * (2 * cos_i**2 / cos_t)[:, None]
    assert seen.sum() > 300 and np.abs(first_guess[seen] - expected[seen]).max() > 0.05
