"""Scene files and dicts: the issue's forms load as written; each mistake is one clear SceneError."""

from __future__ import annotations

import copy

import pytest

import reflets
from reflets.errors import SceneError
from reflets.scene.model import PlaneMesh, PointLight, QuadLight


def test_minimal_toml_loads_as_written(minimal_toml):
    scene = reflets.load_scene(minimal_toml)
    assert scene.camera.size == (320, 240) and scene.camera.fov_y == 45
    assert isinstance(scene.mesh[0], PlaneMesh) and scene.mesh[0].size == (4.0, 4.0)
    assert isinstance(scene.light[0], PointLight) and scene.light[0].intensity == (10, 10, 10)
    assert scene.materials["floor"].albedo == (0.8, 0.8, 0.8)


def test_quad_light_form_of_the_issue_and_its_emitting_normal(minimal_scene):
    minimal_scene["light"] = [
        {
            "type": "quad",
            "corners": [[-0.5, 1, -0.5], [0.5, 1, -0.5], [-0.5, 1, 0.5]],
            "radiance": [5, 5, 5],
            "two_sided": False,
        }
    ]
    light = reflets.load_dict(minimal_scene).light[0]
    assert isinstance(light, QuadLight)
    poly = light.polygon()
    assert poly.tolist()[2] == [0.5, 1, 0.5]  # c3 = c2 + c4 − c1
    from reflets.scene.emitters import polygon_normal

    assert polygon_normal(poly).tolist() == [0, -1, 0]  # normalize((c2−c1)×(c4−c1)): facing down


def test_every_shape_and_light_type_loads(tmp_path, minimal_scene):
    (tmp_path / "env.npy").write_bytes(b"")  # existence is checked at load; content at render
    minimal_scene["mesh"] += [
        {"shape": "sphere", "radius": 0.5, "material": "floor", "transform": {"scale": [1, 2, 1]}},
        {"shape": "cube", "size": [1, 2, 3], "material": "floor"},
        {"shape": "cylinder", "radius": 0.2, "height": 1, "material": "floor"},
        {
            "shape": "torus",
            "major": 1,
            "minor": 0.2,
            "material": "floor",
            "transform": {"rotate": [90, 0, 0]},
        },
    ]
    minimal_scene["light"] += [
        {"type": "directional", "direction": [0, -1, 0], "irradiance": [1, 1, 1]},
        {"type": "polygon", "vertices": [[0, 2, 0], [1, 2, 0], [0.5, 2, 1]], "radiance": [1, 1, 1]},
        {"type": "environment", "file": "env.npy", "scale": 2},
    ]
    scene = reflets.load_dict(minimal_scene, base_dir=tmp_path)
    assert [m.__class__.__name__ for m in scene.mesh][1:] == [
        "SphereMesh",
        "CubeMesh",
        "CylinderMesh",
        "TorusMesh",
    ]
    assert scene.environment is not None and scene.background_color() is None


BAD_INPUTS = [
    # (mutation, words the message must contain)
    (lambda s: s["mesh"][0].update(shape="cone"), ["mesh[0]", "cone" if False else "shape", "sphere"]),
    (lambda s: s["materials"]["floor"].update(type="glass"), ["materials.floor", "glass", "lambert"]),
    (lambda s: s["camera"].update(fov=45), ["camera.fov", "unknown key"]),
    (lambda s: s["light"][0].update(position=[0, 2]), ["light[0].position", "3"]),
    (
        lambda s: s["light"][0].update(intensity=[10, -1, 10]),
        ["light[0].intensity", "greater than or equal to 0"],
    ),
    (lambda s: s["light"][0].update(intensity=[10, float("nan"), 10]), ["light[0].intensity", "finite"]),
    (lambda s: s["materials"]["floor"].update(albedo=[0.8, -0.1, 0.8]), ["materials.floor.albedo"]),
    (
        lambda s: s["materials"]["floor"].update(albedo=[float("nan")] * 3),
        ["materials.floor.albedo", "finite"],
    ),
    (lambda s: s["camera"].update(size=[0, 240]), ["camera.size", "greater than or equal to 1"]),
    (lambda s: s["camera"].update(size=[100000, 240]), ["camera.size", "16384"]),
    (lambda s: s["mesh"][0].update(material="steel"), ["mesh[0].material", "steel", "floor"]),
    (lambda s: s["light"][0].update(type="spot"), ["light[0]", "spot", "point"]),
    (lambda s: s.pop("camera"), ["camera", "missing"]),
    (lambda s: s["mesh"][0].update(transform={"rotate": [0, 90]}), ["mesh[0].transform.rotate"]),
    (lambda s: s["camera"].update(look_at=[0, 3, 4]), ["camera", "coincide"]),
    (lambda s: s["mesh"].append({"file": "missing.obj", "material": "floor"}), ["mesh[1].file", "not found"]),
    (
        lambda s: s["mesh"].append({"shape": "torus", "major": 1, "minor": 2, "material": "floor"}),
        ["mesh[1]", "minor"],
    ),
]


@pytest.mark.parametrize("mutate,words", BAD_INPUTS, ids=[w[0] + "-" + str(i) for i, (_, w) in enumerate(BAD_INPUTS)])
def test_bad_scene_raises_one_line_error_naming_the_field(tmp_path, minimal_scene, mutate, words):
    scene = copy.deepcopy(minimal_scene)
    mutate(scene)
    with pytest.raises(SceneError) as info:
        reflets.load_dict(scene, base_dir=tmp_path, source="scene.toml")
    message = str(info.value)
    assert "\n" not in message
    assert message.startswith("scene.toml: ")
    for word in words:
        assert word in message, f"{word!r} missing from: {message}"


def test_invalid_toml_names_the_file_and_line(tmp_path):
    path = tmp_path / "broken.toml"
    path.write_text("[camera]\nposition = [0, 1,\n")
    with pytest.raises(SceneError, match=r"broken.toml: invalid TOML"):
        reflets.load_scene(path)


def test_missing_scene_file(tmp_path):
    with pytest.raises(SceneError, match="nope.toml: file not found"):
        reflets.load_scene(tmp_path / "nope.toml")


def test_mesh_file_paths_resolve_against_the_scene_folder(tmp_path, minimal_toml):
    (tmp_path / "meshes").mkdir()
    (tmp_path / "meshes" / "tri.obj").write_text("v 0 0 0\nv 1 0 0\nv 0 0 -1\nf 1 2 3\n")
    text = minimal_toml.read_text() + '\n[[mesh]]\nfile = "meshes/tri.obj"\nmaterial = "floor"\n'
    minimal_toml.write_text(text)
    scene = reflets.load_scene(minimal_toml)
    assert scene.resolve(scene.mesh[1].file) == tmp_path / "meshes" / "tri.obj"
