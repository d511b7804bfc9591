"""The spheres' soft shadows on the ground (004 §4.3, π restored) against Monte Carlo visibility."""

from __future__ import annotations

import numpy as np
import pytest

from reflets.ar.shadows import sphere_occlusion


def monte_carlo_visible(point, centre, radius, samples=200_000, seed=0) -> float:
    """Fraction of cosine-weighted directions from ``point`` (normal +y) that miss the sphere."""
    rng = np.random.default_rng(seed)
    u1, u2 = rng.random(samples), rng.random(samples)
    r, phi = np.sqrt(u1), 2 * np.pi * u2
    d = np.stack([r * np.cos(phi), np.sqrt(1 - u1), r * np.sin(phi)], axis=1)
    oc = np.asarray(point) - np.asarray(centre)
    b = d @ oc
    c = oc @ oc - radius**2
    disc = b * b - c
    hit = (disc > 0) & (-b - np.sqrt(np.maximum(disc, 0)) > 0)
    return float(1.0 - hit.mean())


@pytest.mark.parametrize(
    "point, centre, radius",
    [([0, 0, 0], [0, 1.0, 0], 0.5), ([0.6, 0, 0], [0, 1.0, 0], 0.5), ([1.2, 0, 0.3], [0, 0.8, 0], 0.4)],
)
def test_the_sphere_shadow_matches_monte_carlo_visibility(point, centre, radius):
    """The occluded fraction within 5 % of Monte Carlo's (caps above the horizon: the formula is exact)."""
    ours = sphere_occlusion(np.array([point], float), [0, 1, 0], np.array([centre], float), np.array([radius]))[0]
    mc = monte_carlo_visible(point, centre, radius)
    assert abs((1 - ours) - (1 - mc)) <= 0.05 * (1 - mc) + 1e-3


def test_spheres_combine_as_a_product_and_far_spheres_cast_nothing():
    points = np.array([[0.0, 0.0, 0.0]])
    one = sphere_occlusion(points, [0, 1, 0], np.array([[0, 1.0, 0]]), np.array([0.5]))
    two = sphere_occlusion(points, [0, 1, 0], np.array([[0, 1.0, 0], [0, 1.0, 0]]), np.array([0.5, 0.5]))
    np.testing.assert_allclose(two, one**2)
    far = sphere_occlusion(points, [0, 1, 0], np.array([[100.0, 1.0, 0]]), np.array([0.5]))
    assert far[0] > 0.99999


def test_the_gpu_shadow_texture_equals_its_numpy_reference(ctx):
    """The document's env-weighted shadow texture, a fragment per texel (GL's mips and seamless filtering), against
    the NumPy twin (capture.lookup): within 2e-3 of the light fraction at every texel, over a non-constant map."""
    from importlib import resources

    from reflets.ar import capture
    from reflets.ar.document import shadow_texture, shadow_texture_numpy
    from reflets.imageio import read_image

    sky = read_image(resources.files("reflets") / "data" / "environments" / "sky.hdr")
    cube = capture.CubeMap.from_equirect(sky, 32)
    rng = np.random.default_rng(4)
    centres = np.c_[rng.uniform(-0.1, 0.1, 12), rng.uniform(0.02, 0.12, 12), rng.uniform(-0.1, 0.1, 12)]
    radii = rng.uniform(0.01, 0.04, 12)
    gpu, origin, spacing = shadow_texture(centres, radii, cube, texels=48)
    numpy_grid, origin_np, spacing_np = shadow_texture_numpy(centres, radii, cube, texels=48)
    np.testing.assert_array_equal(origin, origin_np)
    assert spacing == spacing_np
    assert gpu.min() < 0.8  # shadows are there
    # a GPU filters the cube map with fixed-point weights (NVIDIA H100: up to 8.8e-3 off the float lookups)
    np.testing.assert_allclose(gpu, numpy_grid, atol=1.5e-2)
