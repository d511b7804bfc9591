"""``reflets export-gltf``: an edited orientation field leaves reflets as the glTF tangents, with the material's
anisotropy (KHR_materials_anisotropy), in a file glTF readers load."""

from __future__ import annotations

import math

import numpy as np
import pygltflib
import pytest
import trimesh

import reflets
from reflets.cli import main
from reflets.demo import scene_path
from reflets.gltf import material_to_gltf
from reflets.scene.geometry import mesh_data


def accessor_array(document: pygltflib.GLTF2, index: int) -> np.ndarray:
    accessor = document.accessors[index]
    view = document.bufferViews[accessor.bufferView]
    width = {"SCALAR": 1, "VEC2": 2, "VEC3": 3, "VEC4": 4}[accessor.type]
    dtype = {pygltflib.FLOAT: np.float32, pygltflib.UNSIGNED_INT: np.uint32}[accessor.componentType]
    blob = document.binary_blob()
    data = np.frombuffer(blob[view.byteOffset : view.byteOffset + view.byteLength], dtype)
    return data.reshape(accessor.count, width)


def test_the_bent_plate_exports_its_field_as_tangents_and_its_anisotropy(tmp_path, capsys):
    out = tmp_path / "bent.glb"
    assert main(["export-gltf", str(scene_path("54_spun_plate_bent.toml")), "-o", str(out)]) == 0
    assert "approximated: spun: ashikhmin_shirley exported as anisotropic GGX" in capsys.readouterr().out
    document = pygltflib.GLTF2.load(str(out))
    scene = reflets.load_scene(scene_path("54_spun_plate_bent.toml"))
    tangents = accessor_array(document, document.meshes[0].primitives[0].attributes.TANGENT)
    np.testing.assert_allclose(tangents, mesh_data(scene, 0).tangents, atol=1e-6)  # the edited field itself
    material = document.materials[0]
    anisotropy = material.extensions["KHR_materials_anisotropy"]
    nu, nv = scene.materials["spun"].nu, scene.materials["spun"].nv
    along, across = math.sqrt(2 / (nu + 2)), math.sqrt(2 / (nv + 2))  # the smoother direction is the tangent
    assert anisotropy["anisotropyRotation"] == pytest.approx(math.pi / 2)  # the rougher one: the bitangent
    assert material.pbrMetallicRoughness.roughnessFactor == pytest.approx(math.sqrt(along))
    strength = anisotropy["anisotropyStrength"]
    assert along + strength**2 * (1 - along) == pytest.approx(across)  # α_t = mix(α_b, 1, strength²)
    assert "KHR_materials_anisotropy" in document.extensionsUsed
    loaded = trimesh.load(str(out))  # another reader
    assert len(loaded.geometry) == 1


def test_a_ggx_conductor_maps_exactly_and_other_models_are_reported():
    gold = reflets.load_dict(
        {
            "camera": {"position": [0, 1, 3], "look_at": [0, 0, 0], "size": [32, 24]},
            "materials": {
                "gold": {
                    "type": "microfacet",
                    "alpha": 0.09,
                    "fresnel": "conductor",
                    "eta": [0.2, 0.9, 1.1],
                    "k": [3.9, 2.4, 2.2],
                },  # fmt: skip
                "clay": {"type": "phong", "kd": [0.5, 0.4, 0.3], "ks": [0.2, 0.2, 0.2], "exponent": 30},
            },
            "mesh": [{"shape": "plane", "material": "gold"}],
            "light": [{"type": "point", "position": [0, 2, 0], "intensity": [1, 1, 1]}],
        }
    )
    material, notes = material_to_gltf("gold", gold.materials["gold"])
    assert material["pbrMetallicRoughness"]["metallicFactor"] == 1.0
    assert material["pbrMetallicRoughness"]["roughnessFactor"] == pytest.approx(0.3)
    assert notes == []
    _, notes = material_to_gltf("clay", gold.materials["clay"])
    assert notes and "phong exported as GGX" in notes[0]


def test_a_wrong_extension_is_a_one_line_error(tmp_path, capsys):
    assert main(["export-gltf", str(scene_path("03_shapes.toml")), "-o", str(tmp_path / "x.gltf")]) == 2
    assert ".glb" in capsys.readouterr().err


def test_cameras_export_and_read_back_both_projections(tmp_path):
    """A scene's camera written to glTF and read back by reflets' own reader: perspective and orthographic."""
    from reflets.gltf import export_gltf

    base = {
        "materials": {"m": {"type": "lambert", "albedo": [0.5, 0.5, 0.5]}},
        "mesh": [{"shape": "sphere", "radius": 0.5, "segments": [16, 8], "material": "m"}],
        "light": [{"type": "point", "position": [1, 2, 3], "intensity": [5, 5, 5]}],
    }
    cameras = [
        {"position": [0, 0, 3], "look_at": [0, 0, 0], "fov_y": 30, "size": [64, 48]},
        {"position": [0, 0, 3], "look_at": [0, 0, 0], "size": [64, 48], "projection": "orthographic",
         "ortho_height": 1.5},
    ]  # fmt: skip
    for k, camera in enumerate(cameras):
        path, _ = export_gltf(reflets.load_dict({**base, "camera": camera}), tmp_path / f"c{k}.glb")
        back = reflets.load_scene(path).camera
        assert back.projection == camera.get("projection", "perspective")
        assert back.size[0] / back.size[1] == pytest.approx(64 / 48, abs=0.01)
        if back.orthographic:  # its required far plane just behind the sphere (3.5 away), not at 10^6
            assert back.ortho_height == pytest.approx(1.5)
            assert 3.5 <= back.far < 4.0, back.far
        else:
            assert back.fov_y == pytest.approx(30)


def test_outputs_are_checked_before_anything_is_written(tmp_path, capsys):
    """An existing file (the input itself among them), a directory, a missing folder: one line, exit 2, nothing
    written or created; a new name is written whole (no temporary file left)."""
    scene = str(scene_path("03_shapes.toml"))
    existing = tmp_path / "existing.glb"
    existing.write_bytes(b"mine")
    (tmp_path / "folder.glb").mkdir()
    for output, phrase in [(existing, "exists already"), (tmp_path / "folder.glb", "is a directory"),
                           (tmp_path / "missing" / "x.glb", "does not exist")]:  # fmt: skip
        assert main(["export-gltf", scene, "-o", str(output)]) == 2
        err = capsys.readouterr().err.strip().splitlines()
        assert len(err) == 1 and phrase in err[0] and str(output) in err[0], err
    assert existing.read_bytes() == b"mine" and not (tmp_path / "missing").exists()
    first = tmp_path / "first.glb"
    assert main(["export-gltf", scene, "-o", str(first)]) == 0
    before = first.read_bytes()
    assert main(["export-gltf", str(first), "-o", str(first)]) == 2  # its own input
    assert first.read_bytes() == before
    assert sorted(p.name for p in tmp_path.iterdir()) == ["existing.glb", "first.glb", "folder.glb"]


def test_an_orthographic_far_plane_holds_the_exported_emitters(tmp_path):
    """The quad light, exported as emissive geometry 2 units behind the sphere, lies within the camera's zfar."""
    from reflets.gltf import export_gltf

    scene = reflets.load_dict({
        "camera": {"position": [0, 0, 3], "look_at": [0, 0, 0], "size": [64, 48], "projection": "orthographic",
                   "ortho_height": 1.5},
        "materials": {"m": {"type": "lambert", "albedo": [0.5, 0.5, 0.5]}},
        "mesh": [{"shape": "sphere", "radius": 0.5, "segments": [16, 8], "material": "m"}],
        "light": [{"type": "quad", "corners": [[-1, -1, -2], [1, -1, -2], [-1, 1, -2]], "radiance": [1, 1, 1],
                   "two_sided": True}],
    })  # fmt: skip
    path, _ = export_gltf(scene, tmp_path / "o.glb")
    assert reflets.load_scene(path).camera.far >= 5.0  # the quad is 5 away along the view (was 3.5: the sphere's)
