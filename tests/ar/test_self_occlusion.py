"""The document's self-occlusion P_V (004 §5.1), per vertex on the GPU, against the directions' quadrature, exact
form factors (Lambert's polygon formula) and ray casting (Embree) with the same directions."""

from __future__ import annotations

import time

import numpy as np
import pytest
from embreex import mesh_construction, rtcore_scene

import reflets.ar.occlusion as occlusion
from reflets.ar.lighting import face_weights_exact
from reflets.ar.occlusion import closed_orientation, fibonacci_directions, occlusion_estimate, self_occlusion
from reflets.scene import shapes
from reflets.scene.geometry import bounding_sphere
from reflets.scene.transform import transform_matrix
from reflets.validation import polygon_irradiance

WALL = np.array([[-1, 0, 0], [1, 0, 0], [1, 1, 0], [-1, 1, 0]], np.float64)  # the wall's face, z = 0
FLOOR = np.array([[-1, 0, 0], [1, 0, 0], [1, 0, 1], [-1, 0, 1]], np.float64)  # the floor's face, y = 0


def self_occlusion_reference(positions, normals, faces, directions, offset: float = 1e-3) -> np.ndarray:
    """The same estimator by ray casting: (4/N) Σ_k max(0, n·ω_k) [the ray from the vertex along ω_k escapes],
    clamped. Rays start ``offset`` × the bounding radius along the normal, past the tessellation of the vertex's
    own neighbourhood (a saddle's one-ring rises above its tangent plane)."""
    p = np.asarray(positions, np.float64)
    n = np.asarray(normals, np.float64)
    n = n / np.linalg.norm(n, axis=1, keepdims=True)
    scene = rtcore_scene.EmbreeScene()
    mesh_construction.TriangleMesh(scene, p[np.asarray(faces, np.int64)].astype(np.float32))
    start = p + offset * bounding_sphere(p)[1] * n
    total = np.zeros(len(p))
    for omega in directions:
        c = n @ omega
        lit = np.nonzero(c > 0)[0]
        rays = np.ascontiguousarray(np.broadcast_to(omega, (len(lit), 3)), np.float32)
        hit = np.asarray(scene.run(start[lit].astype(np.float32), rays, query="OCCLUDED"))
        total[lit] += np.where(hit == -1, c[lit], 0.0)
    return np.clip(4.0 / len(directions) * total, 0.0, 1.0)


def merged(*meshes):
    """Positions, normals and faces of several meshes as one."""
    offsets = np.cumsum([0] + [m.n_vertices for m in meshes[:-1]])
    return (
        np.concatenate([m.positions for m in meshes]).astype(np.float64),
        np.concatenate([m.normals for m in meshes]).astype(np.float64),
        np.concatenate([m.indices.astype(np.int64) + o for m, o in zip(meshes, offsets, strict=True)]),
    )


def floor_and_wall(closed: bool):
    """A 2 × 1 floor (y = 0, z ∈ [0, 1]) at the foot of a 2 × 1 wall (z = 0, y ∈ [0, 1]): slabs 0.1 thick
    touching along a face (closed), or bare sheets (open)."""
    if closed:
        floor = shapes.cube((2.0, 0.1, 1.0)).transformed(transform_matrix(translate=(0, -0.05, 0.5))).subdivided(8)
        wall = shapes.cube((2.0, 1.1, 0.1)).transformed(transform_matrix(translate=(0, 0.45, -0.05))).subdivided(8)
    else:
        floor = shapes.plane((2.0, 1.0), (16, 8)).transformed(transform_matrix(translate=(0, 0, 0.5)))
        wall = shapes.plane((2.0, 1.0), (16, 8)).transformed(transform_matrix(translate=(0, 0.5, 0), rotate=(90, 0, 0)))
    return merged(floor, wall)


def test_fibonacci_directions_integrate_the_clamped_cosine():
    """The directions alone: unit, balanced, and their estimate of (1/π) ∫ max(0, n·ω) dω = 1 off by at most
    5.3e-4 at N = 1000 (the quadrature error every other test inherits; 20,000 random normals)."""
    d = fibonacci_directions(1000)
    np.testing.assert_allclose(np.linalg.norm(d, axis=1), 1.0, rtol=1e-12)
    assert np.abs(d.mean(axis=0)).max() < 2e-3
    n = np.random.default_rng(0).normal(size=(20_000, 3))
    n /= np.linalg.norm(n, axis=1, keepdims=True)
    assert np.abs(occlusion_estimate(n, d) - 1.0).max() < 6e-4


def test_a_convex_mesh_is_unoccluded_at_the_default_settings(ctx):
    """A sphere (convex: every direction above a vertex's plane escapes) at the document's 1,000 directions and
    512² maps: P_V is the quadrature of the clamped cosine, no direction lost to acne (the tolerance is float32
    summation), so 1 − P_V is at most the quadrature error, 5e-4."""
    mesh = shapes.sphere(1.0, (32, 16))
    start = time.perf_counter()
    p = self_occlusion(mesh.positions, mesh.normals, mesh.indices)
    seconds = time.perf_counter() - start
    assert p.dtype == np.float32 and p.shape == (mesh.n_vertices,)
    expected = np.minimum(occlusion_estimate(mesh.normals, fibonacci_directions(1000)), 1.0)
    np.testing.assert_allclose(p, expected, atol=2e-6)
    assert 1.0 - p.min() < 6e-4
    assert seconds < 30.0  # about 0.5 s on two llvmpipe cores


@pytest.mark.parametrize("closed", [True, False], ids=["slabs", "sheets"])
def test_floor_and_wall_match_lambert_s_form_factors(ctx, closed):
    """Points of the floor see the wall's face hide 1/π of its clamped-cosine solid angle (Lambert's polygon
    formula), wall points likewise the floor's; at their common edge P_V = 1/2 exactly (3/4 at its ends) —
    closed slabs only: sheets of zero thickness meet along a line that the depth maps cannot resolve (there
    the bias lets the vertex see through, documented). Tolerance: the quadrature error of 1,000 directions for
    a polygonal occluder, taken from ray casting the same directions (≤ 0.01 here), plus the weight of two
    directions decided otherwise by the maps (4 c / N ≤ 0.004 each; one is seen)."""
    p, n, f = floor_and_wall(closed)
    floor_top = (np.abs(p[:, 1]) < 1e-6) & (n[:, 1] > 0.99) & (p[:, 2] > -1e-6)
    wall_front = (np.abs(p[:, 2]) < 1e-6) & (n[:, 2] > 0.99) & (p[:, 1] > -1e-6)
    edge = (floor_top & (p[:, 2] < 1e-6)) | (wall_front & (p[:, 1] < 1e-6))
    exact = np.full(len(p), np.nan)
    for face, occluder in ((floor_top & ~edge, WALL), (wall_front & ~edge, FLOOR)):
        exact[face] = 1.0 - polygon_irradiance(p[face], n[face], occluder, tolerance=1e-5) / np.pi
    exact[edge] = np.where(np.abs(p[edge, 0]) > 1.0 - 1e-6, 0.75, 0.5)

    directions = fibonacci_directions(1000)
    gpu = self_occlusion(p, n, f, directions, resolution=512)
    away = (floor_top | wall_front) & ~edge
    quadrature = np.abs(self_occlusion_reference(p, n, f, directions)[away] - exact[away])
    assert quadrature.max() < 0.01
    assert np.all(np.abs(gpu[away] - exact[away]) <= quadrature + 2 * 4.0 / len(directions))
    assert gpu[away].min() < 0.6  # the wall's foot: the test sees occlusion
    if closed:
        np.testing.assert_allclose(gpu[edge], exact[edge], atol=0.01)


def test_a_torus_matches_ray_casting_with_the_same_directions(ctx):
    """The inner ring of a torus (R = 1, r = 0.5) sees the far side of the ring: GPU against Embree, same 1,000
    directions, 256² maps. They differ by the maps' decisions near occluders' edges (within the bias and a
    texel), each direction weighing 4 c / N ≤ 0.004: seen 7e-4 on average, 0.006 at the 99th percentile and
    0.0095 at most; allowed 1.5e-3, 0.01 and 0.02 (five directions)."""
    mesh = shapes.torus(1.0, 0.5, (48, 24))
    directions = fibonacci_directions(1000)
    gpu = self_occlusion(mesh.positions, mesh.normals, mesh.indices, directions, resolution=256)
    ref = self_occlusion_reference(mesh.positions, mesh.normals, mesh.indices, directions)
    assert ref.min() < 0.75  # occluded enough to test something
    error = np.abs(gpu - ref)
    assert error.mean() < 1.5e-3
    assert np.quantile(error, 0.99) < 0.01
    assert error.max() < 0.02


def test_constant_environment_gives_p_v_times_the_radiance(ctx):
    """The document's diffuse term (``vertex_diffuse``) under a constant sky L: k_d (P_V/π) Σ_F L W_F(n) = k_d P_V L
    with the exact face weights (Σ_F W_F = π)."""
    from reflets.ar import capture
    from reflets.ar.document import ObjectGeometry, vertex_diffuse
    from reflets.scene import load_dict

    albedo = np.array([0.7, 0.5, 0.3])
    scene = load_dict({
        "camera": {"position": [0, 2, 3], "look_at": [0, 0, 0]},
        "materials": {"clay": {"type": "lambert", "albedo": albedo.tolist()}},
        "mesh": [{"shape": "torus", "major": 1.0, "minor": 0.5, "segments": [24, 12], "material": "clay"}],
    })  # fmt: skip
    g = ObjectGeometry.of(scene)
    p_v = self_occlusion(g.positions, g.normals, g.faces, 200, resolution=128)
    radiance = np.array([0.7, 0.9, 1.1])
    diffuse = vertex_diffuse(g, scene, capture.CubeMap.constant(8, radiance), p_v, face_weights_exact(g.normals))
    np.testing.assert_allclose(diffuse, albedo * p_v[:, None] * radiance, rtol=1e-5, atol=1e-7)
    assert p_v.min() < 0.9 < p_v.max()


def test_culling_a_closed_mesh_changes_nothing(ctx, monkeypatch):
    """Closed meshes rasterise only the faces turned to each view: the nearest surface along a line is such a
    face, so the result equals the two-sided one exactly (an inside-out mesh culls the other side)."""
    mesh = shapes.torus(1.0, 0.5, (24, 12))
    assert closed_orientation(mesh.positions, mesh.indices) == 1
    assert closed_orientation(mesh.positions, mesh.indices[:, ::-1]) == -1
    culled = self_occlusion(mesh.positions, mesh.normals, mesh.indices, 64, resolution=128)
    inside_out = self_occlusion(mesh.positions, mesh.normals, mesh.indices[:, ::-1], 64, resolution=128)
    monkeypatch.setattr(occlusion, "closed_orientation", lambda *_: 0)
    both = self_occlusion(mesh.positions, mesh.normals, mesh.indices, 64, resolution=128)
    np.testing.assert_array_equal(culled, both)
    np.testing.assert_array_equal(inside_out, both)


def test_closed_orientation_welds_seams_and_rejects_open_meshes():
    sphere = shapes.sphere(1.0, (16, 8))  # a seam column and per-cell pole vertices, welded by position
    assert closed_orientation(sphere.positions, sphere.indices) == 1
    assert closed_orientation(sphere.positions, sphere.indices[:-1]) == 0  # one triangle missing
    plane = shapes.plane()
    assert closed_orientation(plane.positions, plane.indices) == 0
    p, _, f = floor_and_wall(closed=True)  # two boxes touching along a face
    assert closed_orientation(p, f) == 1


def test_every_gl_object_is_released(ctx, monkeypatch):
    """The pass owns its buffers, textures, framebuffers and vertex arrays, and releases all of them."""
    from moderngl import InvalidObject

    owned = []
    original = occlusion.GLObjects.own

    def own(self, obj):
        owned.append(obj)
        return original(self, obj)

    monkeypatch.setattr(occlusion.GLObjects, "own", own)
    mesh = shapes.sphere(1.0, (12, 6))
    self_occlusion(mesh.positions, mesh.normals, mesh.indices, 16, resolution=64)
    assert len(owned) >= 9
    assert all(isinstance(obj.mglo, InvalidObject) for obj in owned)
    assert tuple(ctx.polygon_offset) == (0.0, 0.0)


def test_degenerate_inputs(ctx):
    """No vertex: nothing; no face: nothing occludes (the estimator, clamped); directions given as vectors."""
    assert self_occlusion(np.zeros((0, 3)), np.zeros((0, 3)), np.zeros((0, 3), int)).shape == (0,)
    n = np.array([[0.0, 1.0, 0.0], [0.0, 0.0, 2.0]])
    np.testing.assert_allclose(self_occlusion(np.zeros((2, 3)), n, np.zeros((0, 3), int), 1000), 1.0, atol=6e-4)
    one_way = self_occlusion(np.zeros((2, 3)), n, np.zeros((0, 3), int), np.array([[0.0, 3.0, 0.0]]))
    np.testing.assert_allclose(one_way, [1.0, 0.0])  # 4 × cos 0, clamped; perpendicular
