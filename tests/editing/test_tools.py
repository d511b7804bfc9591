"""The bend and expand tools (001 §4.3): warp targets equal the original ℓ on the brush's boundary, move it
inside, and the solver follows them."""

from __future__ import annotations

import numpy as np
import pytest
import trimesh

from reflets.editing import SurfaceMesh, half_vectors, highlight_tangents
from reflets.editing.solver import HighlightProblem, solve
from reflets.editing.tools import WARPS, Brush, warp_targets


def angle_between_lines(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    cos = np.abs(np.einsum("ij,ij->i", a, b)) / np.maximum(
        np.linalg.norm(a, axis=1) * np.linalg.norm(b, axis=1), 1e-300
    )
    return np.degrees(np.arccos(np.clip(cos, 0.0, 1.0)))


@pytest.fixture(scope="module")
def sphere():
    ico = trimesh.creation.icosphere(subdivisions=6, radius=1.0)
    p = np.asarray(ico.vertices)
    mesh = SurfaceMesh.build(p, np.asarray(ico.faces), normals=p)
    axis = np.array([0.3, 1.0, 0.2]) / np.linalg.norm([0.3, 1.0, 0.2])
    u = np.cross(axis, p)
    phi = mesh.angles(u / np.linalg.norm(u, axis=1, keepdims=True))
    h = half_vectors(mesh, [0.5, 0.8, 4.0], light_position=[2.5, 3.0, 2.0])
    ell, degenerate = highlight_tangents(mesh, phi, h)
    return mesh, phi, h, ell, degenerate


@pytest.mark.parametrize("warp", ["bend", "expand"])
def test_warp_targets_equal_the_original_highlights_on_the_brush_boundary(sphere, warp):
    mesh, phi, h, ell, degenerate = sphere
    brush = Brush(centre=np.array([0.2, 0.35, 0.9]), radius=0.5, stroke=np.array([0.0, 1.0, 0.0]))
    targets, inside = warp_targets(mesh, ell, brush, warp)
    _, xy = brush.coordinates(mesh)
    r = np.linalg.norm(xy, axis=1)
    rim = inside & (r > 0.995) & ~degenerate  # the warp's derivative grows as 1 − r inside: a thin rim
    assert rim.sum() > 10
    assert angle_between_lines(targets[rim], ell[rim]).max() < 1.0
    core = inside & (r < 0.5) & ~degenerate
    assert angle_between_lines(targets[core], ell[core]).max() > 5.0  # the warp does move it inside
    assert np.all(targets[~inside] == 0)


def test_the_warps_vanish_with_their_derivatives_on_the_unit_circle():
    t = np.linspace(0, 2 * np.pi, 50)
    x, y = np.cos(t), np.sin(t)
    for warp in WARPS.values():
        f, fx, fy = warp(x, y)
        np.testing.assert_allclose([f, fx, fy], 0.0, atol=1e-12)


def test_the_solver_follows_a_bend(sphere):
    mesh, phi, h, ell, degenerate = sphere
    brush = Brush(centre=np.array([0.2, 0.35, 0.9]), radius=0.3, stroke=np.array([0.0, 1.0, 0.0]))
    targets, inside = warp_targets(mesh, ell, brush, "bend")
    result = solve(HighlightProblem(mesh, h), phi, targets * ~degenerate[:, None], inside, iterations=20)
    # a warped pattern is not always the highlight of some field: the energy falls 5× (measured 6.9×), not to 0
    assert result.energy[-1] < 0.2 * result.energy[0]
    np.testing.assert_array_equal(result.phi[~inside], phi[~inside])


def test_the_demo_s_scripted_bend_reproduces_its_shipped_field(tmp_path):
    """data/strokes/spun_plate_bend.json through `reflets edit-highlights --strokes` gives the field the
    gallery's 54_spun_plate_bent.toml ships (tools/make_highlight_edit.py wrote it), and the stroke's energy
    falls over 100×."""
    from reflets.cli import main
    from reflets.demo import scene_path

    data = scene_path("53_spun_plate.toml").parent.parent
    out = tmp_path / "bent.npz"
    strokes = data / "strokes" / "spun_plate_bend.json"
    assert main(["edit-highlights", str(scene_path("53_spun_plate.toml")), "--mesh", "0", "--strokes", str(strokes),
                 "-o", str(out)]) == 0  # fmt: skip
    with np.load(out) as made, np.load(data / "fields" / "spun_plate_bent.npz") as shipped:
        np.testing.assert_allclose(made["u"], shipped["u"], atol=1e-5)
        assert made["energy"][0, 0] > 100 * made["energy"][0, 1]


def test_the_stencil_makes_a_highlight_region_inside_the_brush(sphere):
    from reflets.editing.tools import stencil

    mesh, phi, h, ell, degenerate = sphere
    brush = Brush(centre=np.array([0.2, 0.35, 0.9]), radius=0.3, stroke=np.array([0.0, 1.0, 0.0]))
    new = stencil(mesh, phi, h, brush)
    near, xy = brush.coordinates(mesh, margin=1.5)
    core = near & (np.linalg.norm(xy, axis=1) < 0.8)
    u = mesh.field(new)
    assert np.abs(np.einsum("ij,ij->i", h[core], u[core])).max() < 1e-9  # h·u = 0: the whole core highlights
    far = ~near | (np.linalg.norm(xy, axis=1) > 1.2)
    np.testing.assert_array_equal(new[far], phi[far])


def test_the_light_tool_finds_the_light_that_draws_a_given_highlight(sphere):
    """ℓ at a vertex under a known light: asked for that ℓ, the tool finds a light whose ℓ there matches
    (within the search's step), the known light's direction among the candidates."""
    from reflets.editing.tools import light_tool

    mesh, phi, h, ell, degenerate = sphere
    eye = np.array([0.5, 0.8, 4.0])
    vertex = int(np.argmax(mesh.positions @ np.array([0.2, 0.35, 0.9])))
    direction, error = light_tool(mesh, phi, vertex, ell[vertex], eye)
    assert error < 0.5
    assert direction @ mesh.normals[vertex] > np.pi / 8
    # the half vector of the found light is perpendicular to u there: the vertex is on its highlight
    out = (eye - mesh.positions[vertex]) / np.linalg.norm(eye - mesh.positions[vertex])
    half = (out + direction) / np.linalg.norm(out + direction)
    assert abs(half @ mesh.field(phi)[vertex]) < 1e-9
