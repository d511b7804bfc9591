"""Fermat reflection solvers: planar closed form, sphere reference, convergence rates, validity, sampling."""

from __future__ import annotations

import numpy as np
import pytest
from scipy.optimize import brentq

from reflets.reflections import (
    Ellipsoid,
    Plane,
    SampledSurface,
    Sphere,
    Torus,
    convergence_statistics,
    planar_reflection,
    random_valid_pairs,
    reflection_residual,
    solve_document,
    solve_robust,
    sphere_reflection,
    third_point,
)

SPHERE = Sphere()


@pytest.fixture(scope="module")
def sphere_pairs():
    return random_valid_pairs(SPHERE, 10_000, rng=20240606)


def test_planar_reflection_closed_form_obeys_the_law_of_reflection():
    rng = np.random.default_rng(0)
    P0, n = np.array([0.3, -0.2, 0.5]), np.array([0.2, 1.0, -0.3]) / np.linalg.norm([0.2, 1.0, -0.3])
    tangential = rng.standard_normal((2, 100, 3))
    tangential -= (tangential @ n)[..., None] * n
    E = P0 + tangential[0] + rng.uniform(0.1, 3.0, (100, 1)) * n
    V = P0 + tangential[1] + rng.uniform(0.1, 3.0, (100, 1)) * n
    P = planar_reflection(P0, n, E, V)
    np.testing.assert_allclose((P - P0) @ n, 0.0, atol=1e-12)
    assert reflection_residual(P, n, E, V).max() < 1e-12


def test_solvers_reach_the_planar_mirror_point_in_three_iterations():
    pl = Plane((0.1, 0.0, -0.2), (4.0, 0.0, 0.0), (0.0, 0.3, -4.0))
    rng = np.random.default_rng(3)
    n = pl.unit_normal
    E = pl.position(*rng.uniform(0.3, 0.7, (2, 500))) + n * rng.uniform(0.5, 3, (500, 1))
    V = pl.position(*rng.uniform(0.2, 0.8, (2, 500))) + n * rng.uniform(0.2, 3, (500, 1))
    closed = planar_reflection(pl.point, n, E, V)
    r = solve_robust(pl, E, V, iterations=3)
    assert np.abs(r.position - closed).max() < 1e-6
    assert r.valid.all() and r.iterations.max() <= 3
    # A point beyond the mirror's extent is no reflection on it.
    far = solve_robust(pl, pl.point + n, pl.point + 10 * pl.axis_u + n, iterations=8)
    assert not far.valid.any()


def test_robust_solver_converges_on_the_sphere(sphere_pairs):
    E, V = sphere_pairs
    r = solve_robust(SPHERE, E, V, iterations=8, history=True)
    assert r.converged.mean() >= 0.995
    assert r.valid.mean() >= 0.995
    assert r.history.shape == (len(E), 9)
    ref = sphere_reflection(SPHERE, E, V)
    ok = r.valid
    assert np.linalg.norm(r.position[ok] - ref[ok], axis=-1).max() < 1e-6
    rates = {k: float((r.history[:, k] < 1e-5).mean()) for k in (4, 5, 8)}
    doc = dict(zip((4, 5, 8), convergence_statistics(SPHERE, solve_document, E, V, (4, 5, 8)), strict=True))
    doc_chart = convergence_statistics(
        SPHERE, solve_document, E, V, (4, 5, 8), local_chart=True, singular="least_squares"
    )
    print(f"\nsphere robust {rates}\nsphere document {doc}\nsphere document in local chart {doc_chart}")
    assert all(0.0 <= x <= 1.0 for x in doc.values())


def test_robust_solution_matches_an_independent_arc_search(sphere_pairs):
    """1D root of the law of reflection on the great-circle arc AB, with scipy, in the plane (E, V, centre)."""
    E, V = (x[:200] for x in sphere_pairs)
    r = solve_robust(SPHERE, E, V, iterations=8)
    for e, v, p in zip(E, V, r.position, strict=True):
        x = v / np.linalg.norm(v)
        y = e - (e @ x) * x
        y /= np.linalg.norm(y)
        e2, v2 = np.array([e @ x, e @ y]), np.array([v @ x, v @ y])  # 2D, centre at 0, A at angle 0

        def tangential(theta, e2=e2, v2=v2):
            p2 = np.array([np.cos(theta), np.sin(theta)])
            t2 = np.array([-np.sin(theta), np.cos(theta)])
            return t2 @ ((e2 - p2) / np.linalg.norm(e2 - p2) + (v2 - p2) / np.linalg.norm(v2 - p2))

        theta = brentq(tangential, 0.0, np.arctan2(e2[1], e2[0]), xtol=1e-15)
        ref = np.cos(theta) * x + np.sin(theta) * y
        assert np.linalg.norm(p - ref) < 1e-7


@pytest.mark.parametrize(
    ("surface", "minimum"),
    [(Ellipsoid((0.2, -0.1, 0.3), (1.0, 0.6, 1.5)), 0.995), (Torus((0.0, 0.0, 0.0), 1.0, 0.35), 0.95)],
    ids=["ellipsoid", "torus"],
)
def test_robust_solver_converges_on_ellipsoid_and_torus(surface, minimum):
    E, V = random_valid_pairs(surface, 3000, rng=11)
    r = solve_robust(surface, E, V, iterations=8, history=True)
    robust = {k: float((r.history[:, k] < 1e-5).mean()) for k in (4, 5, 8)}
    doc = convergence_statistics(surface, solve_document, E, V, (4, 5, 8))
    print(f"\n{type(surface).__name__} robust {robust} valid {r.valid.mean():.4f} document {doc}")
    assert r.valid.mean() >= minimum
    assert np.all(r.residual[r.valid] < 1e-5)


def test_back_facing_stationary_points_are_rejected():
    # E and V on either side of the reflector: d has a stationary point on the arc AB, but it faces one side.
    ell = Ellipsoid((0.0, 0.0, 0.0), (1.0, 0.6, 1.5))
    E = np.array([[0.3, 0.1, 4.0], [3.0, 0.2, 0.1]])
    V = np.array([[0.2, -0.1, -4.0], [-3.0, 0.1, 0.2]])
    for surface in (SPHERE, ell):
        r = solve_robust(surface, E, V, iterations=12)
        assert r.converged.all() and not r.valid.any()  # found, law of reflection holds, but faces away
        facing = np.minimum(np.sum(r.normal * (E - r.position), -1), np.sum(r.normal * (V - r.position), -1))
        assert np.all(facing < 0)
    # Above and below the tube of a torus: no reflection near A and B, whatever the solver ends on.
    tor = Torus((0.0, 0.0, 0.0), 1.0, 0.35)
    for solve in (solve_robust, solve_document):
        r = solve(tor, [[0.05, 2.0, 1.0]], [[-0.05, -2.0, 1.0]], iterations=12)
        assert not r.valid.any()


def test_sampled_sphere_error_shrinks_with_resolution():
    E, V = random_valid_pairs(SPHERE, 1000, rng=5)
    ref = sphere_reflection(SPHERE, E, V)
    away = np.abs(ref[:, 1]) < 0.9  # the lat-long texture's poles are a known weak spot
    errors = {}
    for kind, derivatives in (("bicubic", False), ("bilinear", True)):
        for n in (32, 128, 512):
            s = SampledSurface.from_surface(SPHERE, n, kind, derivatives=derivatives)
            r = solve_robust(s, E, V, iterations=8)
            errors[kind, n] = float(np.linalg.norm(r.position - ref, axis=-1)[away & r.valid].max())
            assert r.valid[away].mean() > 0.99
        assert errors[kind, 512] < errors[kind, 128] < errors[kind, 32]
    print("\nsampled sphere max reflection-point error", errors)
    assert errors["bicubic", 512] < 1e-6 and errors["bilinear", 512] < 1e-4


def test_document_solver_survives_degenerate_triangles():
    # Eye and vertex on the same ray from the centre: A = B, the triangle must still be non-flat.
    E = np.array([[0.0, 0.0, 3.0], [0.0, 2.0, 0.0], [1e-9, 3.0, 0.0]])
    V = np.array([[0.0, 0.0, 2.0], [0.0, 5.0, 0.0], [0.0, 4.0, 1e-9]])
    for kwargs in ({}, {"local_chart": True}, {"singular": "least_squares"}, {"unwrap": False}):
        r = solve_document(SPHERE, E, V, iterations=6, **kwargs)
        assert np.all(np.isfinite(r.position)) and r.iterations.max() <= 6
    b, c = third_point(np.zeros((1, 2)), np.zeros((1, 2)))
    assert np.linalg.norm(b) > 0 and np.linalg.norm(c - b) == pytest.approx(np.linalg.norm(b))


def test_random_valid_pairs_are_seeded_and_valid():
    E1, V1 = random_valid_pairs(SPHERE, 500, rng=3)
    E2, V2 = random_valid_pairs(SPHERE, 500, rng=3)
    np.testing.assert_array_equal(E1, E2)
    np.testing.assert_array_equal(V1, V2)
    r = np.linalg.norm(np.concatenate([E1, V1]), axis=-1)
    assert r.min() >= 1.5 and r.max() <= 10.0
    d = V1 - E1
    t = np.clip(-np.sum(E1 * d, -1) / np.sum(d * d, -1), 0, 1)
    assert np.all(np.linalg.norm(E1 + t[:, None] * d, axis=-1) > 1.0)
