"""Orientation fields: a material's ``orientation`` file replaces its meshes' tangents, in every renderer."""

from __future__ import annotations

import numpy as np
import pytest

import reflets
from reflets.errors import SceneError
from reflets.metrics import relmse
from reflets.scene.geometry import mesh_data


def plate(alpha, orientation=None, method_scene=None) -> dict:
    material = {"type": "ward", "kd": [0.1, 0.1, 0.1], "ks": [0.6, 0.6, 0.6], "alpha": alpha}
    if orientation is not None:
        material["orientation"] = str(orientation)
    return {
        "camera": {"position": [0, 2.2, 2.2], "look_at": [0, 0, 0], "fov_y": 45, "size": [96, 72]},
        "materials": {"brushed": material},
        "mesh": [
            {
                "shape": "plane",
                "size": [3, 3],
                "segments": [8, 8],
                "material": "brushed",
                "transform": {"rotate": [0, 20, 0]},
            }
        ],  # fmt: skip
        "light": [{"type": "point", "position": [0.5, 1.5, -0.8], "intensity": [6, 6, 6]}],
    }


def field_file(tmp_path, u, name="field.npz"):
    path = tmp_path / name
    np.savez(path, u=u)
    return path


def n_vertices(data: dict) -> int:
    return mesh_data(reflets.load_dict(data), 0).n_vertices


def test_a_field_turned_90_degrees_swaps_the_roughnesses(tmp_path, ctx):
    """u along z on a plane whose own tangent is x: the same image as the roughnesses swapped (GPU and the
    NumPy reference), and signs flipped at random vertices change nothing (they are made consistent)."""
    count = n_vertices(plate([0.05, 0.4]))
    along_z = np.tile([0.0, 0.0, 1.0], (count, 1))
    oriented = reflets.load_dict(plate([0.05, 0.4], field_file(tmp_path, along_z)))
    swapped = reflets.load_dict(plate([0.4, 0.05]))
    image = reflets.render(oriented, method="forward")
    assert relmse(image, reflets.render(swapped, method="forward")) < 1e-8
    assert relmse(image, reflets.render(reflets.load_dict(plate([0.05, 0.4])), method="forward")) > 1e-2
    signs = np.where(np.random.default_rng(1).random(count) < 0.5, -1.0, 1.0)[:, None]
    flipped = reflets.load_dict(plate([0.05, 0.4], field_file(tmp_path, along_z * signs, "flipped.npz")))
    assert relmse(reflets.render(flipped, method="forward"), image) < 1e-8
    ref = reflets.reference(oriented, spp=16, progress=False).image
    ref_swapped = reflets.reference(swapped, spp=16, progress=False).image
    assert relmse(ref, ref_swapped) < 1e-8  # the reference reads the same tangents


def test_a_field_moves_with_its_mesh(tmp_path):
    count = n_vertices(plate(0.1))
    scene = reflets.load_dict(plate(0.1, field_file(tmp_path, np.tile([0.0, 0.0, 1.0], (count, 1)))))
    t = mesh_data(scene, 0).tangents[:, :3]
    c, s = np.cos(np.radians(20)), np.sin(np.radians(20))  # z rotated by 20° about y
    np.testing.assert_allclose(np.abs(t @ np.array([s, 0.0, c])), 1.0, atol=1e-6)


@pytest.mark.parametrize(
    "u, message",
    [
        (np.zeros((5, 3)), "expected"),
        ("nokey", "no array 'u'"),
        ("nan", "NaN"),
    ],
)
def test_a_bad_field_names_the_file_and_the_material(tmp_path, u, message):
    count = n_vertices(plate(0.1))
    path = tmp_path / "bad.npz"
    if isinstance(u, str) and u == "nokey":
        np.savez(path, v=np.zeros((count, 3)))
    elif isinstance(u, str):
        np.savez(path, u=np.full((count, 3), np.nan))
    else:
        np.savez(path, u=u)
    scene = reflets.load_dict(plate(0.1, path))
    with pytest.raises(SceneError, match=message) as info:
        mesh_data(scene, 0)
    assert "materials.brushed.orientation" in str(info.value) and "bad.npz" in str(info.value)


def test_a_missing_field_file_is_an_error_when_the_scene_loads(tmp_path):
    with pytest.raises(SceneError, match="orientation field not found"):
        reflets.load_dict(plate(0.1, tmp_path / "missing.npz"))


def test_a_vector_field_with_a_singularity_keeps_its_signs(tmp_path):
    """Concentric circles about the plate's centre: only the edges around the centre disagree, the field is kept
    as given (a sign walk would cut a seam from the singularity, a line of black pixels in a sharp lobe)."""
    data = plate(0.1)
    del data["mesh"][0]["transform"]  # the plate's own coordinates
    p = mesh_data(reflets.load_dict(data), 0).positions.astype(np.float64)
    u = np.stack([-p[:, 2], np.zeros(len(p)), p[:, 0]], axis=1) + [1e-3, 0, 0]
    u /= np.linalg.norm(u, axis=1, keepdims=True)
    data["materials"]["brushed"]["orientation"] = str(field_file(tmp_path, u))
    t = mesh_data(reflets.load_dict(data), 0).tangents[:, :3].astype(np.float64)
    np.testing.assert_allclose(t, u, atol=1e-6)
