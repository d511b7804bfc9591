"""``bezier`` and ``heightfield`` shapes: the mesh samples the exact surface that the reflection code uses (at
the mesh uv), with its normals and tangents; documented placement; every bad input is a SceneError naming
its field."""

from __future__ import annotations

import json
from math import comb

import numpy as np
import pytest

import reflets
from reflets.errors import SceneError
from reflets.reflections.scene import canonical_surface, reflector_surface
from reflets.scene.geometry import mesh_data
from reflets.scene.model import BezierMesh, HeightFieldMesh, Scene

TRANSFORM = {"rotate": [20, -35, 10], "scale": [1.2, 0.8, 1.5], "translate": [0.3, -0.2, 0.5]}


def control_net(rng: np.random.Generator) -> np.ndarray:
    """A curved patch over [-1, 1]², u along +x, v along −z (front side +y)."""
    x, z = np.meshgrid(np.linspace(-1, 1, 4), np.linspace(1, -1, 4), indexing="ij")
    return np.stack([x + 0.1 * rng.standard_normal((4, 4)), 0.5 * rng.standard_normal((4, 4)), z], axis=-1)


def bumps(rows: int = 6, cols: int = 9) -> np.ndarray:
    r, c = np.meshgrid(np.arange(rows), np.arange(cols), indexing="ij")
    return 0.3 * np.sin(0.9 * c) * np.cos(0.7 * r) + 0.05 * r


def scene_with(mesh: dict, base_dir=None) -> Scene:
    return reflets.load_dict(
        {
            "camera": {"position": [0, 3, 4], "look_at": [0, 0, 0]},
            "materials": {"m": {"type": "mirror"}},
            "mesh": [{**mesh, "material": "m", "reflector": True, "transform": TRANSFORM}],
        },
        base_dir=base_dir,
        source="scene.toml",
    )


def de_casteljau(control: np.ndarray, u: np.ndarray, v: np.ndarray) -> np.ndarray:
    """Independent evaluation: the tensor-product Bernstein sum written out."""
    bu = np.stack([comb(3, i) * u**i * (1 - u) ** (3 - i) for i in range(4)], -1)
    bv = np.stack([comb(3, j) * v**j * (1 - v) ** (3 - j) for j in range(4)], -1)
    return np.einsum("ni,nj,ijc->nc", bu, bv, control)


@pytest.fixture(params=["bezier", "heightfield", "heightfield-file"])
def scene(request, rng, tmp_path) -> Scene:
    if request.param == "bezier":
        return scene_with({"shape": "bezier", "control_points": control_net(rng).tolist(), "segments": [12, 9]})
    mesh = {"shape": "heightfield", "size": [2.0, 1.5], "height_scale": 0.7, "segments": [20, 13]}
    if request.param == "heightfield":
        return scene_with({**mesh, "heights": bumps().tolist()})
    np.save(tmp_path / "h.npy", bumps())
    return scene_with({**mesh, "file": "h.npy"}, base_dir=tmp_path)


def test_mesh_vertices_normals_and_tangents_are_the_surface_at_the_mesh_uv(scene):
    data = mesh_data(scene, 0)
    surface = reflector_surface(scene, 0)
    u, v = data.uvs[:, 0].astype(np.float64), data.uvs[:, 1].astype(np.float64)
    assert u.min() == 0 and u.max() == 1 and v.min() == 0 and v.max() == 1
    f, fu, fv = surface.evaluate(u, v, 1)
    np.testing.assert_allclose(data.positions, f, atol=1e-6, rtol=0)
    n = np.cross(fu, fv)
    n /= np.linalg.norm(n, axis=1, keepdims=True)
    np.testing.assert_allclose(surface.normal(u, v), n, atol=1e-12)  # orientation +1: normal = unit(f_u × f_v)
    np.testing.assert_allclose(np.linalg.norm(data.normals, axis=1), 1.0, atol=1e-6)
    np.testing.assert_allclose(np.linalg.norm(data.tangents[:, :3], axis=1), 1.0, atol=1e-6)
    np.testing.assert_allclose(data.normals, n, atol=2e-6)
    np.testing.assert_allclose(data.tangents[:, :3], fu / np.linalg.norm(fu, axis=1, keepdims=True), atol=2e-6)
    assert np.all(data.tangents[:, 3] == 1.0)
    # handedness: w · n × t has a positive f_v component
    assert np.all(np.sum(np.cross(data.normals, data.tangents[:, :3]) * fv, axis=1) > 0)


def test_canonical_bezier_is_the_bernstein_sum_with_the_net_order_documented(rng):
    control = control_net(rng)
    mesh = BezierMesh(shape="bezier", material="m", control_points=control.tolist())
    surface = canonical_surface(mesh)
    u, v = rng.random(200), rng.random(200)
    np.testing.assert_allclose(surface.position(u, v), de_casteljau(control, u, v), atol=1e-12)
    # corners: P00 at uv (0, 0), P30 at (1, 0), P03 at (0, 1); front side +y for this net (u → +x, v → −z)
    np.testing.assert_allclose(surface.position([0, 1, 0], [0, 0, 1]), control[[0, 3, 0], [0, 0, 3]])
    assert np.all(surface.normal(u, v)[:, 1] > 0)


def test_heightfield_nodes_sit_where_documented_and_the_normal_points_up():
    h = bumps()
    mesh = HeightFieldMesh(shape="heightfield", material="m", heights=h.tolist(), size=(2.0, 1.5), height_scale=0.5)
    surface = canonical_surface(mesh)
    rows, cols = h.shape
    r, c = np.meshgrid(np.arange(rows), np.arange(cols), indexing="ij")
    x, z = -1.0 + 2.0 * c / (cols - 1), -0.75 + 1.5 * r / (rows - 1)  # row 0 at z = −d/2, column 0 at x = −w/2
    u, v = (x + 1.0) / 2.0, (0.75 - z) / 1.5  # uv as on the plane: u along +x, v along −z
    np.testing.assert_allclose(surface.position(u, v), np.stack([x, 0.5 * h, z], -1), atol=1e-12)
    assert np.all(surface.normal(u, v)[..., 1] > 0)
    # the default tessellation has one vertex per sample
    data = reflets.scene.shapes.heightfield(heights=h.tolist(), size=(2.0, 1.5), height_scale=0.5)
    assert data.n_vertices == h.size
    got = {(round(float(p[0]), 5), round(float(p[2]), 5)): float(p[1]) for p in data.positions}
    for xi, zi, hi in zip(x.ravel(), z.ravel(), 0.5 * h.ravel(), strict=True):
        assert got[(round(xi, 5), round(zi, 5))] == pytest.approx(hi, abs=1e-6)


def test_a_file_and_inline_heights_give_the_same_mesh_from_toml(tmp_path, minimal_toml):
    np.save(tmp_path / "terrain.npy", bumps())
    inline = "[" + ", ".join("[" + ", ".join(repr(float(x)) for x in row) + "]" for row in bumps()) + "]"
    text = minimal_toml.read_text()
    text += '\n[[mesh]]\nshape = "heightfield"\nfile = "terrain.npy"\nsize = [2, 1.5]\nmaterial = "floor"\n'
    text += f'\n[[mesh]]\nshape = "heightfield"\nheights = {inline}\nsize = [2, 1.5]\nmaterial = "floor"\n'
    minimal_toml.write_text(text)
    scene = reflets.load_scene(minimal_toml)
    assert scene.mesh[1].file == tmp_path / "terrain.npy"  # resolved against the scene folder at load
    a, b = mesh_data(scene, 1), mesh_data(scene, 2)
    np.testing.assert_array_equal(a.positions, b.positions)
    np.testing.assert_array_equal(a.normals, b.normals)


def test_schema_lists_both_shapes_and_stays_json():
    schema = json.loads(json.dumps(Scene.model_json_schema()))
    text = json.dumps(schema)
    for key in ("bezier", "heightfield", "control_points", "heights", "height_scale"):
        assert key in text


def _bez(control) -> dict:
    return {"shape": "bezier", "control_points": control}


FLAT = np.stack(np.meshgrid(np.linspace(-1, 1, 4), [0.0], np.linspace(1, -1, 4), indexing="ij"), -1)[:, 0]
LINE = np.stack([np.linspace(0, 1, 16).reshape(4, 4)] * 3, -1)  # all 16 points on one line
BAD = [
    (_bez(FLAT[:3].tolist()), ["mesh[0].control_points", "4"]),
    (_bez([[p[:2] for p in row] for row in FLAT.tolist()]), ["mesh[0].control_points[0][0]", "3"]),
    (
        _bez(np.where(np.arange(48).reshape(4, 4, 3) == 16, np.nan, FLAT).tolist()),
        ["control_points[1][1][1]", "finite"],
    ),
    (_bez(LINE.tolist()), ["mesh[0].control_points", "degenerate"]),
    (_bez(np.zeros((4, 4, 3)).tolist()), ["mesh[0].control_points", "coincide"]),
    ({"shape": "bezier"}, ["mesh[0].control_points", "missing"]),
    ({**_bez(FLAT.tolist()), "segments": [0, 4]}, ["mesh[0].segments[0]"]),
    ({"shape": "heightfield", "heights": [[0, 1], [float("nan"), 0]]}, ["mesh[0].heights[1][0]", "finite"]),
    ({"shape": "heightfield", "heights": [[0, 1], [0]]}, ["mesh[0].heights", "rectangular"]),
    ({"shape": "heightfield", "heights": [[0, 1, 2]]}, ["mesh[0].heights", "2 × 2"]),
    ({"shape": "heightfield"}, ["mesh[0]", "heights", "file"]),
    ({"shape": "heightfield", "heights": [[0, 1], [1, 0]], "file": "h.npy"}, ["mesh[0]", "exactly one"]),
    ({"shape": "heightfield", "file": "missing.npy"}, ["mesh[0].file", "not found", "missing.npy"]),
    ({"shape": "heightfield", "file": "h.png"}, ["mesh[0].file", ".npy"]),
    ({"shape": "heightfield", "file": "nan.npy"}, ["mesh[0].file", "finite", "nan.npy"]),
    ({"shape": "heightfield", "file": "garbage.npy"}, ["mesh[0].file", "cannot read"]),
    ({"shape": "heightfield", "file": "flat.npy"}, ["mesh[0].file", "2D"]),
    ({"shape": "heightfield", "heights": [[0, 1], [1, 0]], "size": [1, -1]}, ["mesh[0].size[1]"]),
]


@pytest.mark.parametrize("mesh,words", BAD, ids=[str(i) for i in range(len(BAD))])
def test_bad_inputs_are_scene_errors_naming_the_field(tmp_path, mesh, words):
    np.save(tmp_path / "nan.npy", np.array([[0.0, np.nan], [1.0, 2.0]]))
    np.save(tmp_path / "flat.npy", np.zeros(5))
    (tmp_path / "garbage.npy").write_bytes(b"not an array")
    (tmp_path / "h.png").write_bytes(b"")
    with pytest.raises(SceneError) as info:
        scene_with(mesh, base_dir=tmp_path)
    message = str(info.value)
    assert "\n" not in message and message.startswith(("scene.toml: ", str(tmp_path)))
    for word in words:
        assert word in message, f"{word!r} missing from: {message}"


def test_a_heightfield_file_is_not_mistaken_for_a_mesh_file(tmp_path):
    np.save(tmp_path / "h.npy", bumps())
    scene = scene_with({"shape": "heightfield", "file": "h.npy"}, base_dir=tmp_path)
    assert isinstance(scene.mesh[0], HeightFieldMesh)
    assert canonical_surface(scene.mesh[0]).heights.shape == bumps().shape
