"""The orientation-field solver (001 §4.2.4) and ``reflets edit-highlights``: targets made from a hidden field,
a perturbed start, the tensor energy down ≥ 100× in ≤ 20 iterations (the issue's acceptance)."""

from __future__ import annotations

import numpy as np
import pytest
import trimesh

import reflets
from reflets.cli import main
from reflets.editing import SurfaceMesh, half_vectors, highlight_tangents
from reflets.editing.highlights import mesh_highlights
from reflets.editing.solver import HighlightProblem, solve


def hidden_field_problem(eye, light):
    ico = trimesh.creation.icosphere(subdivisions=4, radius=1.0)
    p = np.asarray(ico.vertices)
    mesh = SurfaceMesh.build(p, np.asarray(ico.faces), normals=p)
    axis = np.array([0.3, 1.0, 0.2]) / np.linalg.norm([0.3, 1.0, 0.2])
    u = np.cross(axis, p)
    phi_true = mesh.angles(u / np.linalg.norm(u, axis=1, keepdims=True)) + 0.4 * np.sin(2 * p[:, 0])
    h = half_vectors(mesh, eye, light_position=light)
    return mesh, p, phi_true, h


@pytest.mark.parametrize("amplitude", [0.2, 0.5])
def test_targets_of_a_hidden_field_are_recovered_from_a_perturbed_start(amplitude):
    mesh, p, phi_true, h = hidden_field_problem([0.5, 0.8, 4.0], [2.5, 3.0, 2.0])
    ell, degenerate = highlight_tangents(mesh, phi_true, h)
    centre = np.array([0.2, 0.35, 0.9]) / np.linalg.norm([0.2, 0.35, 0.9])
    d = np.linalg.norm(p - centre, axis=1)
    free = d < 0.35
    phi0 = phi_true + amplitude * np.clip(1 - (d / 0.35) ** 2, 0, 1) ** 2 * np.cos(5 * p[:, 1])
    result = solve(HighlightProblem(mesh, h), phi0, ell * ~degenerate[:, None], free, iterations=20)
    assert len(result.energy) - 1 <= 20
    assert result.energy[0] / result.energy[-1] >= 100.0
    np.testing.assert_array_equal(result.phi[~free], phi0[~free])  # outside the brush: untouched
    error = np.abs(np.angle(np.exp(2j * (result.phi - phi_true)))) / 2  # φ mod π
    assert error[free].max() < 1e-3


def test_critical_points_stay_critical_and_out_of_the_energy():
    """Eye and light on a brush vertex's normal: h = n there, a critical point of every field; the solver
    leaves it degenerate (ℓ = 0) and still converges around it."""
    ico = trimesh.creation.icosphere(subdivisions=4, radius=1.0)
    p = np.asarray(ico.vertices)
    vertex = int(np.argmax(p @ np.array([0.2, 0.35, 0.9])))
    eye = light = 4.0 * p[vertex]
    mesh, p, phi_true, h = hidden_field_problem(eye, light)
    ell, degenerate = highlight_tangents(mesh, phi_true, h)
    assert degenerate[vertex]
    free = np.linalg.norm(p - p[vertex], axis=1) < 0.35
    phi0 = phi_true + 0.3 * free * np.clip(1 - (np.linalg.norm(p - p[vertex], axis=1) / 0.35) ** 2, 0, 1) ** 2
    result = solve(HighlightProblem(mesh, h), phi0, ell * ~degenerate[:, None], free)
    assert result.energy[0] / result.energy[-1] >= 100.0
    assert highlight_tangents(mesh, result.phi, h)[1][vertex]  # still a critical point


def sphere_scene(orientation=None) -> dict:
    material = {"type": "ashikhmin_shirley", "rs": [0.5, 0.5, 0.5], "rd": [0.2, 0.2, 0.2], "nu": 400, "nv": 10}
    if orientation is not None:
        material["orientation"] = str(orientation)
    return {
        "camera": {"position": [0.3, 0.9, 4.0], "look_at": [0, 0, 0], "fov_y": 35, "size": [96, 72]},
        "materials": {"m": material},
        "mesh": [{"shape": "sphere", "segments": [96, 48], "material": "m", "transform": {"rotate": [0, 30, 0]}}],
        "light": [{"type": "point", "position": [2.5, 3.0, 2.0], "intensity": [8, 8, 8]}],
    }


def test_edit_highlights_finds_a_field_whose_highlights_are_the_targets(tmp_path):
    """A hidden field (the sphere's own tangents turned by a smooth bump in a brush) gives the targets; from the
    sphere's own field, `reflets edit-highlights` finds a field whose highlights match them."""
    from reflets.scene.geometry import mesh_data

    scene = reflets.load_dict(sphere_scene())
    data = mesh_data(scene, 0)
    world = data.positions.astype(np.float64)
    centre = np.array([0.25, 0.3, 0.92]) / np.linalg.norm([0.25, 0.3, 0.92])
    d = np.linalg.norm(world - centre, axis=1)
    mask = d < 0.4
    angle = 0.5 * np.clip(1 - (d / 0.4) ** 2, 0, 1) ** 2  # turn the tangent about the normal
    t, n = data.tangents[:, :3].astype(np.float64), data.normals.astype(np.float64)
    hidden_world = np.cos(angle)[:, None] * t + np.sin(angle)[:, None] * np.cross(n, t)
    linear = scene.mesh[0].transform.matrix()[:3, :3]
    np.savez(tmp_path / "hidden.npz", u=hidden_world @ np.linalg.inv(linear).T)
    targets = mesh_highlights(reflets.load_dict(sphere_scene(tmp_path / "hidden.npz")), 0)
    np.savez(tmp_path / "targets.npz", ell=targets["ell"] * mask[:, None], mask=mask)
    scene_file = tmp_path / "sphere.toml"
    reflets.scene.save_scene(scene, scene_file)
    out = tmp_path / "field.npz"
    assert main(["edit-highlights", str(scene_file), "--mesh", "0", "--targets", str(tmp_path / "targets.npz"),
                 "-o", str(out)]) == 0  # fmt: skip
    with np.load(out) as field:
        energy = field["energy"]
        assert field["u"].shape == (data.n_vertices, 3)
    assert energy[0] / energy[-1] >= 100.0
    edited = mesh_highlights(reflets.load_dict(sphere_scene(out)), 0)
    cos = np.abs(np.einsum("ij,ij->i", edited["ell"], targets["ell"]))
    cos /= np.maximum(np.linalg.norm(edited["ell"], axis=1) * np.linalg.norm(targets["ell"], axis=1), 1e-300)
    inside = mask & ~targets["degenerate"]
    angle = np.degrees(np.arccos(np.clip(cos[inside], 0, 1)))
    # where the solve stops (its energy 100× down, not to 0): 1.3° at most, measured on the solver's own float64 ℓ
    # as on the written field's; bound 2°, median 0.5°
    assert angle.max() < 2.0 and np.median(angle) < 0.5


def test_bad_targets_are_one_line_errors(tmp_path, capsys):
    scene_file = tmp_path / "sphere.toml"
    reflets.scene.save_scene(reflets.load_dict(sphere_scene()), scene_file)
    np.savez(tmp_path / "t.npz", ell=np.zeros((3, 3)), mask=np.zeros(3, bool))
    assert main(["edit-highlights", str(scene_file), "--mesh", "0", "--targets", str(tmp_path / "t.npz"), "-o",
                 str(tmp_path / "f.npz")]) == 2  # fmt: skip
    assert "one row per vertex" in capsys.readouterr().err
    assert main(["edit-highlights", str(scene_file), "--mesh", "0", "--targets", str(tmp_path / "no.npz"), "-o",
                 str(tmp_path / "f.npz")]) == 2  # fmt: skip
    assert "file not found" in capsys.readouterr().err
