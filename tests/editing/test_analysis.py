"""Highlight-curve analysis (001, §4.2) on analytic surfaces: the angle-gradient regression, the Weingarten fit,
and eq 4.10's ℓ against n × ∇(h·u) by finite differences (the issue's acceptance)."""

from __future__ import annotations

import numpy as np
import pytest
import trimesh

from reflets.editing import SurfaceMesh, highlight_tangents, phi_gradient, weingarten
from reflets.editing.analysis import CRITICAL_COSINE

H = np.array([0.3, -0.2, 1.0]) / np.linalg.norm([0.3, -0.2, 1.0])


def jittered_grid(n: int = 24, size: float = 2.0, seed: int = 0):
    """An irregular triangulation of the square [−size/2, size/2]² in the z = 0 plane."""
    rng = np.random.default_rng(seed)
    t = np.linspace(-size / 2, size / 2, n)
    x, y = np.meshgrid(t, t, indexing="xy")
    step = size / (n - 1)
    inner = (np.abs(x) < size / 2 - 1e-9) & (np.abs(y) < size / 2 - 1e-9)
    x = x + inner * rng.uniform(-0.3, 0.3, x.shape) * step
    y = y + inner * rng.uniform(-0.3, 0.3, y.shape) * step
    positions = np.stack([x.ravel(), y.ravel(), np.zeros(x.size)], axis=1)
    idx = np.arange(n * n).reshape(n, n)
    a, b, c, d = idx[:-1, :-1].ravel(), idx[:-1, 1:].ravel(), idx[1:, :-1].ravel(), idx[1:, 1:].ravel()
    faces = np.concatenate([np.stack([a, b, d], 1), np.stack([a, d, c], 1)])
    return positions, faces


def interior(mesh: SurfaceMesh, margin: float) -> np.ndarray:
    return np.all(np.abs(mesh.positions[:, :2]) < 1.0 - margin, axis=1)


@pytest.mark.parametrize("k", [1, 2])
def test_phi_gradient_is_exact_for_linear_fields(k):
    positions, faces = jittered_grid()
    mesh = SurfaceMesh.build(positions, faces)
    g = np.array([0.7, -0.4])
    phi = 0.3 + positions[:, :2] @ g
    np.testing.assert_allclose(phi_gradient(mesh, phi, k), np.broadcast_to(g, (len(phi), 2)), atol=1e-9)
    if k == 2:  # an unoriented field: flipping some tangents (φ + π) changes nothing
        flipped = phi + np.pi * (np.arange(len(phi)) % 3 == 0)
        np.testing.assert_allclose(phi_gradient(mesh, flipped, k), phi_gradient(mesh, phi, k), atol=1e-9)


def sphere(radius: float = 1.3, subdivisions: int = 5):
    ico = trimesh.creation.icosphere(subdivisions=subdivisions, radius=radius)
    return np.asarray(ico.vertices), np.asarray(ico.faces)


def cylinder(radius: float, sections: int = 96, rings: int = 41, height: float = 2.0):
    """An open cylinder about z, its rows of vertices staggered (triangles of both diagonals)."""
    theta = np.arange(sections) / sections * 2 * np.pi
    z = np.linspace(-height / 2, height / 2, rings)
    shift = (np.arange(rings) % 2)[:, None] * (np.pi / sections)
    th = theta[None, :] + shift
    positions = np.stack([radius * np.cos(th), radius * np.sin(th), np.broadcast_to(z[:, None], th.shape)], -1)
    idx = np.arange(rings * sections).reshape(rings, sections)
    nxt = np.roll(idx, -1, axis=1)
    a, b, c, d = idx[:-1].ravel(), nxt[:-1].ravel(), idx[1:].ravel(), nxt[1:].ravel()
    faces = np.concatenate([np.stack([a, b, d], 1), np.stack([a, d, c], 1)])
    return positions.reshape(-1, 3), faces


def test_weingarten_recovers_sphere_cylinder_and_saddle_curvatures():
    positions, faces = sphere(1.3)
    mesh = SurfaceMesh.build(positions, faces, normals=positions / 1.3)
    np.testing.assert_allclose(weingarten(mesh), np.broadcast_to(-np.eye(2) / 1.3, (len(positions), 2, 2)), atol=2e-3)

    p, faces = cylinder(0.8)
    mesh = SurfaceMesh.build(p, faces, normals=p * [1, 1, 0] / 0.8)
    inner = np.abs(p[:, 2]) < 0.8  # away from the open ends
    eig = np.linalg.eigvalsh(weingarten(mesh)[inner])
    np.testing.assert_allclose(eig[:, 0], -1 / 0.8, rtol=1e-2)
    np.testing.assert_allclose(eig[:, 1], 0.0, atol=1e-2)

    positions, faces = jittered_grid(41, 1.0)
    c = 1.5
    positions[:, 2] = 0.5 * c * (positions[:, 0] ** 2 - positions[:, 1] ** 2)
    normals = np.stack([-c * positions[:, 0], c * positions[:, 1], np.ones(len(positions))], 1)
    mesh = SurfaceMesh.build(positions, faces, normals=normals / np.linalg.norm(normals, axis=1, keepdims=True))
    centre = np.argmin(np.linalg.norm(positions[:, :2], axis=1))
    np.testing.assert_allclose(np.linalg.eigvalsh(weingarten(mesh)[centre]), [-c, c], rtol=2e-2)


def fd_ell(points, normals, field, project, eps=1e-5):
    """n × ∇(h·u) at surface points by central differences along the tangent frame (h fixed)."""
    from reflets.editing.surface import tangent_frames

    t = tangent_frames(normals)
    b = np.cross(normals, t)
    grad = np.zeros_like(points)
    for axis in (t, b):
        plus, minus = project(points + eps * axis), project(points - eps * axis)
        df = (field(plus) @ H - field(minus) @ H) / (2 * eps)
        grad += df[:, None] * axis
    return np.cross(normals, grad)


def compare(mesh, u, select, field, project, k=2):
    phi = mesh.angles(u)
    ell, degenerate = highlight_tangents(mesh, phi, np.broadcast_to(H, mesh.positions.shape), k)
    critical = mesh.normals @ H > CRITICAL_COSINE  # on every highlight: flagged, ℓ meaningless
    assert np.array_equal(degenerate & ~critical, np.zeros_like(critical))
    select = select & ~critical
    ref = fd_ell(mesh.positions[select], mesh.normals[select], field, project)
    error = np.linalg.norm(ell[select] - ref, axis=1) / np.linalg.norm(ref, axis=1).max()
    print(f"relative error of ℓ: median {np.median(error):.2e}, 95th percentile {np.percentile(error, 95):.2e}")
    return float(np.median(error)), float(np.percentile(error, 95))


def test_eq_4_10_matches_finite_differences_of_h_dot_u_on_a_plane():
    positions, faces = jittered_grid()
    mesh = SurfaceMesh.build(positions, faces)

    def field(q):
        phi = 0.6 * q[:, 0] - 0.5 * q[:, 1] + 0.2
        return np.stack([np.cos(phi), np.sin(phi), 0 * phi], 1)

    median, p95 = compare(mesh, field(positions), interior(mesh, 0.1), field, lambda q: q * [1, 1, 0], k=1)
    assert p95 < 1e-6  # a linear field on a plane: the regression and W = 0 are exact


def test_eq_4_10_matches_finite_differences_of_h_dot_u_on_a_sphere():
    radius = 1.3
    positions, faces = sphere(radius)
    mesh = SurfaceMesh.build(positions, faces, normals=positions / radius)
    axis = np.array([0.2, 0.1, 1.0]) / np.linalg.norm([0.2, 0.1, 1.0])

    def field(q):  # along the circles about `axis`
        u = np.cross(axis, q)
        return u / np.linalg.norm(u, axis=1, keepdims=True)

    away = np.abs(positions @ axis) < 0.8 * radius
    median, p95 = compare(
        mesh, field(positions), away, field, lambda q: radius * q / np.linalg.norm(q, axis=1, keepdims=True)
    )
    assert median < 0.01 and p95 < 0.03


def test_eq_4_10_matches_finite_differences_of_h_dot_u_on_a_torus():
    major, minor = 1.0, 0.4
    torus = trimesh.creation.torus(major_radius=major, minor_radius=minor, major_sections=192, minor_sections=96)
    positions, faces = np.asarray(torus.vertices), np.asarray(torus.faces)

    def project(q):
        c = np.stack([q[:, 0], q[:, 1], 0 * q[:, 0]], 1)
        c = major * c / np.linalg.norm(c, axis=1, keepdims=True)
        d = q - c
        return c + minor * d / np.linalg.norm(d, axis=1, keepdims=True)

    def normal(q):
        c = np.stack([q[:, 0], q[:, 1], 0 * q[:, 0]], 1)
        c = major * c / np.linalg.norm(c, axis=1, keepdims=True)
        return (q - c) / np.linalg.norm(q - c, axis=1, keepdims=True)

    def field(q):  # a spiral: the toroidal direction turned towards the poloidal one
        n = normal(q)
        toroidal = np.cross([0.0, 0.0, 1.0], q * [1, 1, 0])
        toroidal /= np.linalg.norm(toroidal, axis=1, keepdims=True)
        poloidal = np.cross(n, toroidal)
        return 0.8 * toroidal + 0.6 * poloidal

    mesh = SurfaceMesh.build(positions, faces, normals=normal(positions))
    median, p95 = compare(mesh, field(positions), np.ones(len(positions), bool), field, project)
    assert median < 0.01 and p95 < 0.03
