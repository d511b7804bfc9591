"""``adaptive`` (§2.4 of the area-light document) on the document's scene.

Ground truth: the unoccluded integral by a 128×128 midpoint grid (``brute``), converged to a relative MSE
of 1·10⁻⁷ (64² vs 128²) — far below the errors compared here (≥ 2·10⁻⁵), which a Monte Carlo reference cannot
reach in test time (1024 spp: 6·10⁻⁵ of noise). The truth itself is checked against the unoccluded NumPy
reference (64 spp): same energy within 3 standard errors, and a difference no larger than the reference's
own noise. Relative MSE = mean((a − b)²)/mean(b²) over the plane, pixels where the camera sees the emitter
excluded; samples per pixel = ``output="samples"`` averaged over the same pixels.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from meunier_helpers import SIZE, document_scene, phong, plane_pixels, relative_mse

import reflets
from reflets.errors import ArgumentError

BLINN500 = {"type": "blinn_phong", "kd": [0, 0, 0], "ks": [1, 1, 1], "exponent": 500}


def _run(scene, method, **params):
    image = reflets.render(scene, method=method, size=SIZE, **params)
    samples = reflets.render(scene, method=method, size=SIZE, output="samples", **params)[..., 0]
    return image, samples


@pytest.fixture(scope="module")
def phong500():
    scene = document_scene(phong(500))
    _, mask = plane_pixels(scene)
    truth = reflets.render(scene, method="brute", size=SIZE, grid=128)
    return scene, mask, truth


def test_converged_brute_force_agrees_with_the_reference(ctx, phong500):
    scene, mask, truth = phong500
    ref = reflets.reference(scene, spp=64, visibility=False, size=SIZE, progress=False)
    noise = np.mean(ref.stderr[mask].astype(np.float64) ** 2) / np.mean(ref.image[mask].astype(np.float64) ** 2)
    assert relative_mse(truth, ref.image, mask) <= noise  # measured 9.5e-4 vs a noise estimate of 3.4e-3
    energy = truth[mask].sum(dtype=np.float64) - ref.image[mask].sum(dtype=np.float64)
    assert abs(energy) <= 3 * math.sqrt(np.sum(ref.stderr[mask].astype(np.float64) ** 2))
    assert relative_mse(reflets.render(scene, method="brute", size=SIZE, grid=64), truth, mask) < 1e-6


def test_adaptive_vs_brute_force_on_the_document_scene(ctx, phong500):
    """Phong ρ_d = 0, ρ_s = 1, e = 500 (the document's Fig 2.14). With the document's safety factors adaptive
    takes 171 samples per pixel instead of 400 and is more accurate than a brute force of the same cost
    (7.4e-5 vs 9.1e-5 for 14² = 196 samples, 1.25e-4 for 13² = 169), but not as accurate as the 20×20 brute
    force (2.0e-5): its distance predictor puts the most samples right under the light, where this lobe
    sees nothing, and 14²–17² in the highlight. The 20×20 accuracy needs the highlight at the 0.05 floor:
    safety_phong = 0.5 reaches it (2.0e-5, equal) with 366 samples per pixel."""
    scene, mask, truth = phong500
    brute20, n20 = _run(scene, "brute", grid=20)
    image, samples = _run(scene, "adaptive")
    spp, err = samples[mask].mean(), relative_mse(image, truth, mask)
    err20 = relative_mse(brute20, truth, mask)
    assert spp < 0.5 * n20[mask].mean()
    side = math.ceil(math.sqrt(spp))
    same_cost = relative_mse(reflets.render(scene, method="brute", size=SIZE, grid=side), truth, mask)
    assert err < 0.9 * same_cost, (err, same_cost, side)
    assert err20 < err < 5 * err20, (err, err20)
    strict, strict_samples = _run(scene, "adaptive", safety_phong=0.5)
    assert strict_samples[mask].mean() < 0.95 * n20[mask].mean()
    assert relative_mse(strict, truth, mask) <= err20 * (1 + 1e-3)


def test_dithering_is_seeded_and_trades_bands_for_samples(ctx, phong500):
    scene, mask, truth = phong500
    plain, plain_samples = _run(scene, "adaptive")
    a, a_samples = _run(scene, "adaptive", dither=True)
    b = reflets.render(scene, method="adaptive", size=SIZE, dither=True, seed=0)
    c = reflets.render(scene, method="adaptive", size=SIZE, dither=True, seed=7)
    np.testing.assert_array_equal(a, b)
    assert np.any(a != c)
    assert a_samples[mask].mean() > plain_samples[mask].mean()  # 338 vs 171
    assert np.all(a_samples[mask] >= plain_samples[mask])  # Δ − 0.1 ξ never coarsens the grid
    assert relative_mse(a, truth, mask) < 0.5 * relative_mse(plain, truth, mask)  # 2.7e-5 vs 7.4e-5


def test_blinn_fit_inverted_vs_printed(ctx):
    """Eq 2.13 as printed (outer exponent 2.4589) puts every pixel at the 0.05 floor for e = 500: it is the
    20×20 brute force. The inverted exponent 1/2.4589 takes 141 samples per pixel at 3.3e-5, better than a
    brute force of the same cost (12² = 144: 4.9e-5)."""
    scene = document_scene(BLINN500)
    _, mask = plane_pixels(scene)
    truth = reflets.render(scene, method="brute", size=SIZE, grid=128)
    printed, printed_samples = _run(scene, "adaptive", blinn_fit="printed")
    assert np.all(printed_samples[mask] == 400)
    inverted, inverted_samples = _run(scene, "adaptive")
    spp = inverted_samples[mask].mean()
    assert spp < 0.4 * 400
    same_cost = reflets.render(scene, method="brute", size=SIZE, grid=math.ceil(math.sqrt(spp)))
    assert relative_mse(inverted, truth, mask) < relative_mse(same_cost, truth, mask)


def test_grid_shapes_and_fallbacks(ctx):
    """Counts: n × ceil(n |e2|/|e1|) on a non-square parallelogram, 3 n² on a pentagon (fan rule)."""
    scene = document_scene(phong(500))
    _, mask = plane_pixels(scene)
    square = _run(scene, "adaptive")[1]
    n = np.sqrt(square)
    assert np.all(n[mask] == np.round(n[mask]))
    wide = {"type": "quad", "corners": [[-1, 1, -0.25], [1, 1, -0.25], [-1, 1, 0.25]], "radiance": [5, 5, 5]}
    scene_wide = document_scene(phong(500), light=wide)
    image, samples = _run(scene_wide, "adaptive")
    _, mask_wide = plane_pixels(scene_wide)
    forms = {k * math.ceil(k / 4) for k in range(1, 21)}  # n along e1 (width 2), ceil(n/4) along e2 (0.5)
    assert set(np.unique(samples[mask_wide]).astype(int)) <= forms
    assert samples[mask_wide].max() == 20 * 5  # the floor: 20 per width along e1, 5 along e2
    assert np.all(np.isfinite(image))
    angles = 2 * np.pi * np.arange(5) / 5
    pentagon = {
        "type": "polygon",
        "vertices": [[0.6 * np.cos(a), 1.0, 0.6 * np.sin(a)] for a in angles],
        "radiance": [5, 5, 5],
    }
    counts = _run(document_scene(phong(500), light=pentagon), "adaptive")[1]
    per_triangle = counts[counts > 0] / 3
    assert np.all(np.sqrt(per_triangle) == np.round(np.sqrt(per_triangle)))


def test_lambert_uses_the_lambert_predictor(ctx):
    """Every plane point is ≥ 1 light width away: Δ = 0.95 (0.727 d + 0.055) ≥ 0.74 → 2×2 samples."""
    scene = document_scene({"type": "lambert", "albedo": [0.8, 0.8, 0.8]})
    _, mask = plane_pixels(scene)
    samples = _run(scene, "adaptive")[1]
    assert np.all(samples[mask] == 4)
    near = document_scene(
        {"type": "lambert", "albedo": [0.8, 0.8, 0.8]},
        light={
            "type": "quad",
            "corners": [[-0.5, 0.1, -0.5], [0.5, 0.1, -0.5], [-0.5, 0.1, 0.5]],
            "radiance": [5, 5, 5],
        },
    )
    samples = _run(near, "adaptive")[1]
    assert samples.max() == 81  # d = 0.1 under the light: Δ = 0.95 (0.0727 + 0.055) = 0.121 → n = 9


@pytest.mark.parametrize(
    ("name", "value"),
    [("safety_phong", 0.0), ("safety_blinn", 2.5), ("min_step", 0.001), ("min_step", 1.5), ("blinn_fit", "x")],
)
def test_parameters_are_validated(ctx, name, value):
    with pytest.raises(ArgumentError):
        reflets.render(document_scene(phong(50)), method="adaptive", size=(8, 6), **{name: value})
