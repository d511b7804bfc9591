"""``reflets highlights``: ℓ per vertex of a scene's mesh, in the mesh's (file's) vertex order."""

from __future__ import annotations

import numpy as np
import pytest
import trimesh

import reflets
from reflets.cli import main
from reflets.demo import scene_path
from reflets.editing.highlights import mesh_highlights

TEAPOT = scene_path("52_scratched_teapot.toml")


def test_teapot_highlights_follow_the_file_s_vertex_order_and_lie_in_the_tangent_planes():
    scene = reflets.load_scene(TEAPOT)
    result = mesh_highlights(scene, 0)
    mesh = scene.mesh[0]
    loaded = trimesh.load(str(scene.resolve(mesh.file)), process=False)
    assert len(result["positions"]) == len(loaded.vertices)  # one row per vertex of the file, in its order
    from reflets.scene.transform import transform_matrix

    m = transform_matrix(**mesh.transform.model_dump())
    expected = np.asarray(loaded.vertices) @ m[:3, :3].T + m[:3, 3]
    np.testing.assert_allclose(result["positions"], expected, atol=1e-5)
    ell, n = result["ell"], result["normals"]
    assert np.abs(np.einsum("ij,ij->i", ell, n)).max() < 1e-9 * np.abs(ell).max()  # tangent to the surface
    np.testing.assert_allclose(np.linalg.norm(result["h"], axis=1), 1.0)
    assert not result["degenerate"].all() and np.all(ell[result["degenerate"]] == 0)


def test_the_command_writes_the_arrays_and_refuses_bad_input(tmp_path, capsys):
    out = tmp_path / "teapot.npz"
    assert main(["highlights", str(TEAPOT), "--mesh", "0", "-o", str(out)]) == 0
    with np.load(out) as data:
        assert {"positions", "normals", "u", "h", "ell", "degenerate"} <= set(data.files)
    assert main(["highlights", str(TEAPOT), "--mesh", "9", "-o", str(out), "--overwrite"]) == 2
    assert "no mesh[9]" in capsys.readouterr().err
    assert main(["highlights", str(TEAPOT), "--mesh", "0", "--light", "1", "-o", str(out), "--overwrite"]) == 2
    assert "not a point or directional light" in capsys.readouterr().err
    assert main(["highlights", str(TEAPOT), "--mesh", "0", "-o", str(tmp_path / "x.png")]) == 2


@pytest.mark.parametrize("shape", ["sphere", "torus"])
def test_procedural_shapes_weld_their_seams(shape):
    """A sphere's or torus's uv seam splits vertices: welded for the 1-ring, the split copies get one ℓ."""
    scene = reflets.load_dict(
        {
            "camera": {"position": [0, 1, 4], "look_at": [0, 0, 0], "fov_y": 40, "size": [64, 48]},
            "materials": {"m": {"type": "ward", "alpha": [0.1, 0.3]}},
            "mesh": [{"shape": shape, "material": "m"}],
            "light": [{"type": "point", "position": [2, 3, 2], "intensity": [1, 1, 1]}],
        }
    )
    result = mesh_highlights(scene, 0)
    keys = np.round(result["positions"], 9)
    _, inverse, counts = np.unique(keys, axis=0, return_inverse=True, return_counts=True)
    split = counts[inverse.ravel()] > 1
    assert split.any()
    for row in np.flatnonzero(split)[:50]:
        same = np.all(keys == keys[row], axis=1)
        np.testing.assert_allclose(result["ell"][same], result["ell"][same][:1].repeat(same.sum(), 0))
