"""Parametric reflectors: analytic derivatives against finite differences, normals, segment intersections."""

from __future__ import annotations

import numpy as np
import pytest

from reflets.reflections import (
    BezierPatch,
    Cylinder,
    Ellipsoid,
    GridInterpolator,
    HeightField,
    Plane,
    SampledSurface,
    Sphere,
    Torus,
    gradient,
    hessian,
    path_length,
)


def bezier() -> BezierPatch:
    rng = np.random.default_rng(7)
    g = np.linspace(-1.0, 1.0, 4)
    x, y = np.meshgrid(g, g, indexing="ij")
    return BezierPatch(np.stack([x, y, 0.4 * rng.standard_normal((4, 4))], axis=-1))


def height_field() -> HeightField:
    x, y = np.meshgrid(np.linspace(-1, 1, 9), np.linspace(-1.5, 1.5, 11), indexing="xy")
    return HeightField(0.3 * np.sin(2 * x) * np.cos(1.5 * y) + 0.1 * x * y, (-1, 1), (-1.5, 1.5))


SURFACES = {
    "plane": Plane((0.1, 0.2, -0.3), (2.0, 0.1, 0.0), (0.0, 0.3, -1.5)),
    "sphere": Sphere((0.3, -0.2, 0.1), 1.3),
    "ellipsoid": Ellipsoid((0.2, -0.1, 0.3), (1.0, 0.6, 1.5)),
    "cylinder": Cylinder((0.0, 0.5, 0.0), 0.8, 2.5),
    "torus": Torus((0.1, 0.0, -0.2), 1.0, 0.35),
    "bezier": bezier(),
    "heightfield": height_field(),
    "sampled": SampledSurface.from_surface(Torus((0.0, 0.0, 0.0), 1.0, 0.35), 24),
}


def interior_uv(n: int, seed: int = 0) -> tuple[np.ndarray, np.ndarray]:
    """Random (u, v) away from the domain edges, the poles, and the cell boundaries of a 24- or 8/10-cell grid."""
    rng = np.random.default_rng(seed)
    cells = 240  # common multiple of the grid sizes used above (8, 10, 24 cells)
    k = rng.integers(12, cells - 12, (2, n))
    return (k[0] + rng.uniform(0.2, 0.8, n)) / cells, (k[1] + rng.uniform(0.2, 0.8, n)) / cells


@pytest.mark.parametrize("name", sorted(SURFACES))
def test_surface_derivatives_match_finite_differences(name):
    s = SURFACES[name]
    u, v = interior_uv(50)
    h = 1e-6
    f, fu, fv, fuu, fuv, fvv = s.evaluate(u, v, 2)
    np.testing.assert_allclose(f, s.position(u, v))
    scale = np.abs(f).max() + 1.0
    fd_u = (s.position(u + h, v) - s.position(u - h, v)) / (2 * h)
    fd_v = (s.position(u, v + h) - s.position(u, v - h)) / (2 * h)
    np.testing.assert_allclose(fu, fd_u, rtol=1e-6, atol=1e-6 * np.abs(fu).max())
    np.testing.assert_allclose(fv, fd_v, rtol=1e-6, atol=1e-6 * np.abs(fv).max())
    d = lambda du, dv: s.derivatives(u + du, v + dv)  # noqa: E731
    fd_uu = (d(h, 0)[0] - d(-h, 0)[0]) / (2 * h)
    fd_uv = (d(0, h)[0] - d(0, -h)[0]) / (2 * h)
    fd_vu = (d(h, 0)[1] - d(-h, 0)[1]) / (2 * h)
    fd_vv = (d(0, h)[1] - d(0, -h)[1]) / (2 * h)
    tol = 1e-6 * (np.abs(np.stack([fuu, fuv, fvv])).max() + scale)
    np.testing.assert_allclose(fuu, fd_uu, atol=tol)
    np.testing.assert_allclose(fvv, fd_vv, atol=tol)
    # Sampled surfaces with derivative grids symmetrise f_uv; here (no grids) both orders agree.
    np.testing.assert_allclose(fuv, fd_uv, atol=tol)
    np.testing.assert_allclose(fuv, fd_vu, atol=tol)
    del scale


FERMAT = ["plane", "sphere", "ellipsoid", "torus", "bezier", "heightfield"]


@pytest.mark.parametrize("name", FERMAT)
def test_path_length_gradient_and_hessian_match_finite_differences(name):
    s = SURFACES[name]
    rng = np.random.default_rng(1)
    u, v = interior_uv(40, seed=2)
    P = s.position(u, v)
    E = P + rng.uniform(1.0, 4.0, (40, 1)) * rng.standard_normal((40, 3))
    V = P + rng.uniform(1.0, 4.0, (40, 1)) * rng.standard_normal((40, 3))
    h = 1e-5
    g = gradient(s, u, v, E, V)
    fd = np.stack(
        [
            (path_length(s, u + h, v, E, V) - path_length(s, u - h, v, E, V)) / (2 * h),
            (path_length(s, u, v + h, E, V) - path_length(s, u, v - h, E, V)) / (2 * h),
        ],
        axis=-1,
    )
    np.testing.assert_allclose(g, fd, rtol=1e-6, atol=1e-6 * np.abs(g).max())
    H = hessian(s, u, v, E, V)
    h = 1e-6
    fd_h = np.stack(
        [
            (gradient(s, u + h, v, E, V) - gradient(s, u - h, v, E, V)) / (2 * h),
            (gradient(s, u, v + h, E, V) - gradient(s, u, v - h, E, V)) / (2 * h),
        ],
        axis=-1,
    )
    np.testing.assert_allclose(H, fd_h, rtol=1e-6, atol=1e-6 * np.abs(H).max())
    np.testing.assert_allclose(H, np.swapaxes(H, 1, 2), atol=1e-12 * np.abs(H).max())


def test_normals_are_unit_and_outward_on_closed_surfaces():
    u, v = np.meshgrid(np.linspace(0, 1, 17), np.linspace(0, 1, 17))
    for name in ("sphere", "ellipsoid", "cylinder"):
        s = SURFACES[name]
        n, f = s.normal(u, v), s.position(u, v)
        np.testing.assert_allclose(np.linalg.norm(n, axis=-1), 1.0, atol=1e-12)
        assert np.all(np.sum(n * (f - s.center), axis=-1) > 0), name
    tor = SURFACES["torus"]
    n, f = tor.normal(u, v), tor.position(u, v) - tor.center
    core = tor.major * f * [1, 0, 1] / np.linalg.norm(f * [1, 0, 1], axis=-1, keepdims=True)
    np.testing.assert_allclose(n, (f - core) / tor.minor, atol=1e-12)
    # Closed surfaces: the normal is the implicit gradient's direction.
    ell = SURFACES["ellipsoid"]
    x = ell.position(u, v)
    grad = 2 * (x - ell.center) / ell.radii**2
    np.testing.assert_allclose(ell.normal(u, v), grad / np.linalg.norm(grad, axis=-1, keepdims=True), atol=1e-12)


@pytest.mark.parametrize("name", sorted(SURFACES))
def test_segment_hit_lies_on_the_segment(name):
    s = SURFACES[name]
    rng = np.random.default_rng(3)
    u, v = interior_uv(60, seed=4)
    X = s.position(u, v)
    O = s.interior_point(X, X)
    P = X + rng.uniform(0.05, 0.3, (60, 1)) * (X - O) / np.linalg.norm(X - O, axis=-1, keepdims=True)
    hu, hv = s.segment_hit(P, O)
    H = s.position(hu, hv)
    d = (O - P) / np.linalg.norm(O - P, axis=-1, keepdims=True)
    off_line = np.linalg.norm(np.cross(H - P, d), axis=-1)
    assert np.max(off_line) < 1e-7
    if name != "sampled":  # short offsets: the hit is X itself (up to interpolation on the sampled torus)
        np.testing.assert_allclose(H, X, atol=1e-7)


def test_grid_interpolator_reproduces_nodes_and_linear_functions():
    rng = np.random.default_rng(5)
    grid = rng.standard_normal((6, 7, 2))
    for kind in ("bilinear", "bicubic"):
        for periodic in ((False, False), (True, False), (True, True)):
            interp = GridInterpolator(grid, periodic, kind)
            u = np.arange(7) / (7 if periodic[0] else 6)
            v = np.arange(6) / (6 if periodic[1] else 5)
            uu, vv = np.meshgrid(u, v)
            np.testing.assert_allclose(interp(uu, vv)[0], grid, atol=1e-12)
    # Bicubic with linear ghost nodes is exact on an affine function, derivatives included.
    x, y = np.meshgrid(np.linspace(0, 1, 5), np.linspace(0, 1, 4))
    interp = GridInterpolator(2 * x - 3 * y + 1, (False, False), "bicubic")
    uu, vv = rng.uniform(0, 1, (2, 30))
    val, du, dv = interp(uu, vv, 1)
    np.testing.assert_allclose(val[..., 0], 2 * uu - 3 * vv + 1, atol=1e-12)
    np.testing.assert_allclose(du[..., 0], 2.0, atol=1e-12)
    np.testing.assert_allclose(dv[..., 0], -3.0, atol=1e-12)


def test_sampled_surface_converges_to_its_source():
    sph = Sphere((0.0, 0.0, 0.0), 1.0)
    u, v = interior_uv(200, seed=6)
    errors = []
    for n in (16, 64):
        s = SampledSurface.from_surface(sph, n, "bicubic")
        errors.append(np.abs(s.position(u, v) - sph.position(u, v)).max())
    assert errors[1] < errors[0] / 30  # Catmull–Rom: third order in the cell size
    lin = SampledSurface.from_surface(sph, 64, "bilinear", derivatives=True)
    fu, _ = lin.derivatives(u, v)
    assert np.abs(fu - sph.derivatives(u, v)[0]).max() < 0.05 * np.abs(fu).max()
