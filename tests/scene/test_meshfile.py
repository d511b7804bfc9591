"""Loading mesh files through trimesh and generating tangents from uv."""

from __future__ import annotations

import numpy as np
import pytest

from reflets.errors import SceneError
from reflets.scene.meshdata import MeshData
from reflets.scene.meshfile import compute_tangents, load_mesh_file
from reflets.scene.shapes import sphere, torus

QUAD_WITH_UV = """\
v 0 0 0
v 2 0 0
v 2 1 0
v 0 1 0
vt 0 0
vt 1 0
vt 1 1
vt 0 1
vn 0 0 1
f 1/1/1 2/2/1 3/3/1 4/4/1
"""

TETRAHEDRON = """\
v 0 0 0
v 1 0 0
v 0 1 0
v 0 0 1
f 1 3 2
f 1 2 4
f 1 4 3
f 2 3 4
"""

CUBE_PLY = """\
ply
format ascii 1.0
element vertex 8
property float x
property float y
property float z
element face 12
property list uchar int vertex_indices
end_header
0 0 0
1 0 0
1 1 0
0 1 0
0 0 1
1 0 1
1 1 1
0 1 1
3 0 2 1
3 0 3 2
3 4 5 6
3 4 6 7
3 0 1 5
3 0 5 4
3 2 3 7
3 2 7 6
3 1 2 6
3 1 6 5
3 3 0 4
3 3 4 7
"""


def assert_valid_frame(m: MeshData) -> None:
    np.testing.assert_allclose(np.linalg.norm(m.normals, axis=1), 1.0, atol=1e-5)
    np.testing.assert_allclose(np.linalg.norm(m.tangents[:, :3], axis=1), 1.0, atol=1e-5)
    assert np.abs(np.sum(m.normals * m.tangents[:, :3], axis=1)).max() < 1e-5
    assert set(np.unique(m.tangents[:, 3])) <= {-1.0, 1.0}
    assert m.uvs.shape == (m.n_vertices, 2) and np.all(np.isfinite(m.uvs))
    assert m.indices.dtype == np.uint32 and m.indices.max() < m.n_vertices


def assert_outward_ccw(m: MeshData) -> None:
    p, idx = m.positions.astype(float), m.indices.astype(int)
    face = np.cross(p[idx[:, 1]] - p[idx[:, 0]], p[idx[:, 2]] - p[idx[:, 0]])
    assert np.all(np.sum(face * m.normals[idx].sum(axis=1), axis=1) > 0)


def test_obj_with_uv_and_normals_keeps_them_and_derives_tangent_from_u(tmp_path):
    path = tmp_path / "quad.obj"
    path.write_text(QUAD_WITH_UV)
    m = load_mesh_file(path)
    assert m.n_vertices == 4 and m.n_triangles == 2
    assert_valid_frame(m)
    np.testing.assert_allclose(m.normals, np.tile([0, 0, 1], (4, 1)))
    np.testing.assert_allclose(m.tangents, np.tile([1, 0, 0, 1], (4, 1)), atol=1e-6)
    by_position = {tuple(p): tuple(uv) for p, uv in zip(m.positions.tolist(), m.uvs.tolist(), strict=True)}
    assert by_position[(2.0, 1.0, 0.0)] == (1.0, 1.0)
    assert_outward_ccw(m)


def test_mirrored_uv_gives_negative_handedness(tmp_path):
    path = tmp_path / "mirrored.obj"
    path.write_text(QUAD_WITH_UV.replace("vt 0 0\nvt 1 0\nvt 1 1\nvt 0 1", "vt 0 1\nvt 1 1\nvt 1 0\nvt 0 0"))
    m = load_mesh_file(path)
    np.testing.assert_allclose(m.tangents, np.tile([1, 0, 0, -1], (4, 1)), atol=1e-6)


def test_obj_without_uv_gets_smooth_normals_and_generated_uv(tmp_path):
    path = tmp_path / "tetra.obj"
    path.write_text(TETRAHEDRON)
    m = load_mesh_file(path)
    assert m.n_vertices == 4 and m.n_triangles == 4
    assert_valid_frame(m)
    assert_outward_ccw(m)
    centre = m.positions.mean(axis=0)
    assert np.all(np.sum(m.normals * (m.positions - centre), axis=1) > 0)
    assert m.uvs.min() >= 0.0 and m.uvs.max() <= 1.0


def test_ascii_ply_cube_loads_all_triangles(tmp_path):
    path = tmp_path / "cube.ply"
    path.write_text(CUBE_PLY)
    m = load_mesh_file(path)
    assert m.n_vertices == 8 and m.n_triangles == 12
    assert_valid_frame(m)
    assert_outward_ccw(m)
    np.testing.assert_allclose(
        m.normals, (m.positions - 0.5) / np.linalg.norm(m.positions - 0.5, axis=1)[:, None], atol=1e-5
    )


def test_glb_scene_is_flattened_with_node_transforms(tmp_path):
    trimesh = pytest.importorskip("trimesh")
    scene = trimesh.Scene()
    box = trimesh.creation.box(extents=(1.0, 1.0, 1.0))
    scene.add_geometry(box, transform=trimesh.transformations.translation_matrix([5.0, 0.0, 0.0]))
    scene.add_geometry(box, transform=trimesh.transformations.translation_matrix([0.0, -3.0, 0.0]))
    path = tmp_path / "two_boxes.glb"
    scene.export(path)
    m = load_mesh_file(path)
    assert m.n_triangles == 24
    assert_valid_frame(m)
    assert_outward_ccw(m)
    np.testing.assert_allclose(m.positions.max(axis=0), [5.5, 0.5, 0.5], atol=1e-6)
    np.testing.assert_allclose(m.positions.min(axis=0), [-0.5, -3.5, -0.5], atol=1e-6)


@pytest.mark.parametrize("mesh", [sphere(1.0, (64, 32)), torus(1.0, 0.3, (64, 32))], ids=["sphere", "torus"])
def test_compute_tangents_reproduces_analytic_frames(mesh):
    t = compute_tangents(mesh.positions, mesh.normals, mesh.uvs, mesh.indices)
    assert t.shape == (mesh.n_vertices, 4) and t.dtype == np.float32
    # Seam vertices only see the cells on one side: their tangent is off by half a cell, π/64.
    assert np.sum(t[:, :3] * mesh.tangents[:, :3], axis=1).min() > np.cos(np.pi / 64) - 1e-6
    np.testing.assert_array_equal(t[:, 3], mesh.tangents[:, 3])


def test_compute_tangents_falls_back_to_any_orthonormal_vector_when_uv_is_degenerate():
    mesh = sphere(1.0, (16, 8))
    t = compute_tangents(mesh.positions, mesh.normals, np.zeros_like(mesh.uvs), mesh.indices)
    np.testing.assert_allclose(np.linalg.norm(t[:, :3], axis=1), 1.0, atol=1e-6)
    assert np.abs(np.sum(t[:, :3] * mesh.normals, axis=1)).max() < 1e-6
    assert np.all(t[:, 3] == 1.0)


def test_missing_file_is_a_scene_error(tmp_path):
    with pytest.raises(SceneError, match=r"nothere\.obj: mesh file not found"):
        load_mesh_file(tmp_path / "nothere.obj")


def test_unsupported_extension_lists_the_allowed_ones(tmp_path):
    path = tmp_path / "model.fbx"
    path.write_text("whatever")
    with pytest.raises(SceneError, match=r"model\.fbx: unsupported mesh extension '\.fbx'; allowed: \.obj, \.ply"):
        load_mesh_file(path)


def test_corrupt_file_is_a_one_line_scene_error(tmp_path):
    path = tmp_path / "broken.ply"
    path.write_bytes(b"this is not\na ply file\n")
    with pytest.raises(SceneError, match=r"broken\.ply: cannot read mesh file") as info:
        load_mesh_file(path)
    assert "\n" not in str(info.value)


def test_file_without_triangles_is_a_scene_error(tmp_path):
    path = tmp_path / "points.obj"
    path.write_text("v 0 0 0\nv 1 0 0\nv 0 1 0\n")
    with pytest.raises(SceneError, match=r"points\.obj: contains no triangles"):
        load_mesh_file(path)


@pytest.mark.parametrize("suffix", [".stl", ".off"])
def test_stl_and_off_exported_by_trimesh_load_with_valid_frames(tmp_path, suffix):
    trimesh = pytest.importorskip("trimesh")
    path = tmp_path / f"ico{suffix}"
    trimesh.creation.icosphere(subdivisions=1).export(path)
    m = load_mesh_file(path)
    assert m.n_triangles == 80
    assert_valid_frame(m)
    assert_outward_ccw(m)
