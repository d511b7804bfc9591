"""Procedural shapes: shading frames, winding, parametrisation and validation."""

from __future__ import annotations

import numpy as np
import pytest

from reflets.errors import SceneError
from reflets.scene.meshdata import MeshData
from reflets.scene.shapes import SHAPES, bezier, cube, cylinder, heightfield, plane, sphere, torus


def triangle_derivatives(mesh: MeshData) -> tuple[np.ndarray, np.ndarray]:
    """Unit ∂p/∂u and ∂p/∂v of every triangle, solved from its edges and uv differences."""
    p, uv, idx = mesh.positions.astype(float), mesh.uvs.astype(float), mesh.indices.astype(int)
    e1, e2 = p[idx[:, 1]] - p[idx[:, 0]], p[idx[:, 2]] - p[idx[:, 0]]
    d1, d2 = uv[idx[:, 1]] - uv[idx[:, 0]], uv[idx[:, 2]] - uv[idx[:, 0]]
    det = (d1[:, 0] * d2[:, 1] - d2[:, 0] * d1[:, 1])[:, None]
    dpdu = (e1 * d2[:, 1:] - e2 * d1[:, 1:]) / det
    dpdv = (e2 * d1[:, :1] - e1 * d2[:, :1]) / det
    return (
        dpdu / np.linalg.norm(dpdu, axis=1, keepdims=True),
        dpdv / np.linalg.norm(dpdv, axis=1, keepdims=True),
    )


def surface_area(mesh: MeshData) -> float:
    p, idx = mesh.positions.astype(float), mesh.indices.astype(int)
    return 0.5 * np.linalg.norm(np.cross(p[idx[:, 1]] - p[idx[:, 0]], p[idx[:, 2]] - p[idx[:, 0]]), axis=1).sum()


_gx, _gz = np.meshgrid(np.linspace(-1, 1, 4), np.linspace(1, -1, 4), indexing="ij")
#: builders whose data has no default (a curved patch, a bumpy field)
REQUIRED = {
    "bezier": {"control_points": np.stack([_gx, 0.3 * np.sin(2 * _gx) * np.cos(_gz), _gz], -1).tolist()},
    "heightfield": {"heights": (0.1 * np.cos(np.arange(20.0)).reshape(4, 5)).tolist(), "segments": (32, 24)},
}
ALL_SHAPES = {name: builder(**REQUIRED.get(name, {})) for name, builder in SHAPES.items()}


def test_registry_lists_every_shape_builder():
    assert SHAPES == {
        "plane": plane,
        "sphere": sphere,
        "cube": cube,
        "cylinder": cylinder,
        "torus": torus,
        "bezier": bezier,
        "heightfield": heightfield,
    }


@pytest.mark.parametrize("name", sorted(ALL_SHAPES))
def test_arrays_have_meshdata_dtypes_and_shapes(name):
    m = ALL_SHAPES[name]
    n = m.n_vertices
    assert m.positions.shape == (n, 3) and m.positions.dtype == np.float32
    assert m.normals.shape == (n, 3) and m.normals.dtype == np.float32
    assert m.tangents.shape == (n, 4) and m.tangents.dtype == np.float32
    assert m.uvs.shape == (n, 2) and m.uvs.dtype == np.float32
    assert m.indices.dtype == np.uint32 and m.indices.max() < n
    assert np.array_equal(np.unique(m.indices), np.arange(n)), "every vertex is used"
    assert m.uvs.min() >= 0.0 and m.uvs.max() <= 1.0


@pytest.mark.parametrize("name", sorted(ALL_SHAPES))
def test_normals_and_tangents_are_unit_and_orthogonal(name):
    m = ALL_SHAPES[name]
    np.testing.assert_allclose(np.linalg.norm(m.normals, axis=1), 1.0, atol=1e-6)
    np.testing.assert_allclose(np.linalg.norm(m.tangents[:, :3], axis=1), 1.0, atol=1e-6)
    assert np.abs(np.sum(m.normals * m.tangents[:, :3], axis=1)).max() < 1e-6
    assert set(np.unique(m.tangents[:, 3])) <= {-1.0, 1.0}


@pytest.mark.parametrize("name", sorted(ALL_SHAPES))
def test_every_triangle_is_counter_clockwise_seen_from_its_normals(name):
    m = ALL_SHAPES[name]
    p, idx = m.positions.astype(float), m.indices.astype(int)
    face = np.cross(p[idx[:, 1]] - p[idx[:, 0]], p[idx[:, 2]] - p[idx[:, 0]])
    n_avg = m.normals[idx].sum(axis=1)
    assert np.all(np.sum(face * n_avg, axis=1) > 0.0)


@pytest.mark.parametrize("name", sorted(ALL_SHAPES))
def test_tangent_follows_du_and_handedness_follows_dv_on_every_triangle(name):
    m = ALL_SHAPES[name]
    dpdu, dpdv = triangle_derivatives(m)
    idx = m.indices.astype(int)
    t = m.tangents[idx, :3].mean(axis=1)
    b = (m.tangents[:, 3:] * np.cross(m.normals, m.tangents[:, :3]))[idx].mean(axis=1)
    # b ⟂ t: compare with the part of ∂p/∂v orthogonal to ∂p/∂u (they differ on sheared charts: height fields)
    dpdv = dpdv - dpdu * np.sum(dpdv * dpdu, axis=1, keepdims=True)
    dpdv /= np.linalg.norm(dpdv, axis=1, keepdims=True)
    cos_t = np.sum(dpdu * t, axis=1) / np.linalg.norm(t, axis=1)
    cos_b = np.sum(dpdv * b, axis=1) / np.linalg.norm(b, axis=1)
    assert cos_t.min() > 0.999
    assert cos_b.min() > 0.999


@pytest.mark.parametrize(
    ("mesh", "p_of_uv"),
    [
        (
            sphere(2.0),
            lambda u, v: (
                2.0
                * np.stack(
                    [
                        np.sin(np.pi * v) * np.sin(2 * np.pi * u),
                        np.cos(np.pi * v),
                        np.sin(np.pi * v) * np.cos(2 * np.pi * u),
                    ],
                    -1,
                )
            ),
        ),
        (
            torus(2.0, 0.5),
            lambda u, v: np.stack(
                [
                    (2.0 + 0.5 * np.cos(2 * np.pi * v)) * np.sin(2 * np.pi * u),
                    0.5 * np.sin(2 * np.pi * v),
                    (2.0 + 0.5 * np.cos(2 * np.pi * v)) * np.cos(2 * np.pi * u),
                ],
                -1,
            ),
        ),
    ],
    ids=["sphere", "torus"],
)
def test_documented_parametrisation_and_its_finite_difference_du(mesh, p_of_uv):
    u, v = mesh.uvs[:, 0].astype(float), mesh.uvs[:, 1].astype(float)
    interior = (v > 1e-6) & (v < 1 - 1e-6)  # the sphere poles have no position derivative along u
    np.testing.assert_allclose(mesh.positions[interior], p_of_uv(u, v)[interior], atol=1e-5)
    h = 1e-5
    fd = p_of_uv(u + h, v) - p_of_uv(u - h, v)
    fd = fd[interior] / np.linalg.norm(fd[interior], axis=1, keepdims=True)
    np.testing.assert_allclose(mesh.tangents[interior, :3], fd, atol=1e-4)


def test_cylinder_side_tangent_matches_finite_difference_du():
    m = cylinder(1.5, 3.0, segments=32)
    side = np.abs(m.normals[:, 1]) < 0.5
    u = m.uvs[side, 0].astype(float)
    h = 1e-5
    fd = 1.5 * (
        np.stack([np.sin(2 * np.pi * (u + h)), 0 * u, np.cos(2 * np.pi * (u + h))], -1)
        - np.stack([np.sin(2 * np.pi * (u - h)), 0 * u, np.cos(2 * np.pi * (u - h))], -1)
    )
    fd /= np.linalg.norm(fd, axis=1, keepdims=True)
    np.testing.assert_allclose(m.tangents[side, :3], fd, atol=1e-4)
    np.testing.assert_allclose(m.positions[side, 1], 1.5 - 3.0 * m.uvs[side, 1], atol=1e-5)


def test_sphere_vertices_lie_at_the_radius_and_normals_point_outwards():
    m = sphere(2.5)
    np.testing.assert_allclose(np.linalg.norm(m.positions, axis=1), 2.5, rtol=1e-6)
    np.testing.assert_allclose(m.normals, m.positions / 2.5, atol=1e-6)


def test_sphere_duplicates_the_seam_and_gives_pole_vertices_nonzero_tangents():
    nu, nv = 16, 8
    m = sphere(1.0, (nu, nv))
    assert m.n_vertices == (nu + 1) * (nv + 1) - 2  # one pole vertex per column
    seam0, seam1 = m.uvs[:, 0] == 0.0, m.uvs[:, 0] == 1.0
    assert seam0.sum() == seam1.sum() == nv - 1
    np.testing.assert_allclose(m.positions[seam0], m.positions[seam1], atol=1e-6)
    poles = np.abs(m.positions[:, 1]) > 1 - 1e-6
    assert poles.sum() == 2 * nu
    np.testing.assert_allclose(np.linalg.norm(m.tangents[poles, :3], axis=1), 1.0, atol=1e-6)
    assert np.all(m.tangents[:, 3] == -1.0)


@pytest.mark.parametrize(
    ("mesh", "area"),
    [
        (sphere(1.7), 4 * np.pi * 1.7**2),
        (torus(2.0, 0.3), 4 * np.pi**2 * 2.0 * 0.3),
        (cylinder(0.8, 2.5), 2 * np.pi * 0.8 * 2.5 + 2 * np.pi * 0.8**2),
        (cube([1.0, 2.0, 3.0]), 2 * (2.0 + 6.0 + 3.0)),
        (plane((4.0, 2.0)), 8.0),
    ],
    ids=["sphere", "torus", "cylinder", "cube", "plane"],
)
def test_surface_area_is_within_half_a_percent_of_analytic(mesh, area):
    assert surface_area(mesh) == pytest.approx(area, rel=5e-3)


def test_plane_extents_normals_and_uv_corners():
    m = plane(size=(4.0, 2.0), segments=(3, 2))
    assert m.n_vertices == 4 * 3 and m.n_triangles == 2 * 3 * 2
    np.testing.assert_allclose(m.positions.min(axis=0), [-2.0, 0.0, -1.0])
    np.testing.assert_allclose(m.positions.max(axis=0), [2.0, 0.0, 1.0])
    np.testing.assert_array_equal(m.normals, np.tile([0, 1, 0], (m.n_vertices, 1)))
    np.testing.assert_array_equal(m.tangents, np.tile([1, 0, 0, 1], (m.n_vertices, 1)))
    for uv, corner in [
        ((0, 0), (-2, 0, 1)),
        ((1, 0), (2, 0, 1)),
        ((0, 1), (-2, 0, -1)),
        ((1, 1), (2, 0, -1)),
    ]:
        k = np.flatnonzero(np.all(m.uvs == uv, axis=1))
        assert len(k) == 1
        np.testing.assert_allclose(m.positions[k[0]], corner)


def test_cube_has_24_vertices_flat_faces_and_requested_extents():
    m = cube([1.0, 2.0, 3.0])
    assert m.n_vertices == 24 and m.n_triangles == 12
    np.testing.assert_allclose(m.positions.min(axis=0), [-0.5, -1.0, -1.5])
    np.testing.assert_allclose(m.positions.max(axis=0), [0.5, 1.0, 1.5])
    p, idx = m.positions.astype(float), m.indices.astype(int)
    face = np.cross(p[idx[:, 1]] - p[idx[:, 0]], p[idx[:, 2]] - p[idx[:, 0]])
    face /= np.linalg.norm(face, axis=1, keepdims=True)
    for corner in range(3):
        np.testing.assert_allclose(m.normals[idx[:, corner]], face, atol=1e-6)
    assert np.all(m.tangents[:, 3] == 1.0)
    assert len(np.unique(m.normals, axis=0)) == 6


@pytest.mark.parametrize(
    ("call", "message"),
    [
        (lambda: sphere(-1.0), r"^radius: must be a finite number > 0 for a sphere, got -1\.0$"),
        (lambda: sphere(float("nan")), r"^radius: .* sphere"),
        (lambda: sphere(1.0, (2, 64)), r"^segments\[0\]: must be an integer >= 3 for a sphere"),
        (lambda: sphere(1.0, 64), r"^segments: must be two integers"),
        (lambda: torus(1.0, 1.0), r"^minor: must be < major \(1\) for a torus"),
        (lambda: torus(0.0, 0.5), r"^major: .* torus"),
        (lambda: cube([1.0, 2.0]), r"^size: must be a number or 3 numbers, each finite and > 0, for a cube"),
        (lambda: cube("big"), r"^size: .* cube"),
        (lambda: cylinder(1.0, 0.0), r"^height: .* cylinder"),
        (lambda: cylinder(1.0, 1.0, segments=2.5), r"^segments: must be an integer >= 3 for a cylinder"),
        (lambda: plane((1.0, -2.0)), r"^size: .* plane"),
        (lambda: plane(segments=(0, 1)), r"^segments\[0\]: .* plane"),
    ],
)
def test_invalid_parameters_raise_one_line_scene_error_naming_the_parameter(call, message):
    with pytest.raises(SceneError, match=message) as info:
        call()
    assert "\n" not in str(info.value)
