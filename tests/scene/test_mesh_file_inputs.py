"""Every way a mesh file enters (issue 32): glTF and GLB (Khronos' Draco-compressed Box among them), OBJ, PLY and
STL, as a whole scene, in a scene TOML without and with a material, and read by ``load_mesh_file`` — each decoded
(the bounds of the uncompressed Box) or refused in one line naming the file, never vertices at 0; DracoPy absent
likewise; nothing trimesh logs reaches stderr; a scene material replacing a file's own is said in one line."""

from __future__ import annotations

import shutil
import sys
import warnings
from pathlib import Path

import numpy as np
import pytest

import reflets
from reflets.errors import RefletsError, RefletsWarning
from reflets.scene.geometry import mesh_data
from reflets.scene.meshfile import load_mesh_file

BOX = Path(__file__).parents[1] / "data" / "gltf" / "Box"
#: Khronos' uncompressed Box spans [−0.5, 0.5]³; its Draco twin's quantized positions are within 10⁻³ of it
BOX_BOUNDS, TOLERANCE = np.array([[-0.5] * 3, [0.5] * 3]), 1e-3
FILES = ("Box.gltf", "BoxDraco.glb", "plain.glb", "plain.obj", "plain.ply", "plain.stl")
ENTRIES = ("scene", "toml", "toml + material", "load_mesh_file")
SCENE = """[camera]
position = [0, 0, 3]
look_at = [0, 0, 0]
size = [16, 12]
[materials.grey]
type = "lambert"
albedo = [0.5, 0.5, 0.5]
[[light]]
type = "point"
position = [1, 2, 3]
intensity = [5, 5, 5]
[[mesh]]
file = "{file}"
"""


def _write_files(folder: Path) -> Path:
    """The Draco Box as .gltf + .bin and as a .glb, and trimesh's unit box as .glb, .obj, .ply, .stl."""
    import pygltflib
    import trimesh

    for name in ("Box.gltf", "Box.bin"):
        shutil.copy(BOX / name, folder / name)
    with warnings.catch_warnings():  # pygltflib: "Box.bin orphaned" (the .gltf is not saved again)
        warnings.simplefilter("ignore")
        document = pygltflib.GLTF2().load(str(folder / "Box.gltf"))
        document.convert_buffers(pygltflib.BufferFormat.BINARYBLOB)
    document.save_binary(str(folder / "BoxDraco.glb"))
    box = trimesh.creation.box(extents=(1.0, 1.0, 1.0))
    for ext in ("glb", "obj", "ply", "stl"):
        box.export(folder / f"plain.{ext}")
    return folder


@pytest.fixture(scope="module")
def folder(tmp_path_factory) -> Path:
    return _write_files(tmp_path_factory.mktemp("meshes"))


def _positions(path: Path, entry: str) -> np.ndarray:
    """The file's vertices as ``entry`` reads them (every mesh of the scene it makes)."""
    if entry == "load_mesh_file":
        return load_mesh_file(path).positions
    if entry == "scene":
        scene = reflets.load_scene(path)
    else:
        toml = path.parent / f"{path.name}.{entry.replace(' + ', '-')}.toml"
        material = 'material = "grey"\n' if entry == "toml + material" else ""
        toml.write_text(SCENE.format(file=path.name) + material, "utf-8")
        scene = reflets.load_scene(toml)
    return np.concatenate([mesh_data(scene, i).positions for i in range(len(scene.mesh))])


def _read(path: Path, entry: str, capfd):
    """(vertices or the error's one line, RefletsWarning lines); stderr must stay empty."""
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        try:
            result = _positions(path, entry)
        except RefletsError as exc:
            result = str(exc)
    assert capfd.readouterr().err == ""  # no trimesh log lines, no tracebacks
    return result, [str(w.message) for w in caught if issubclass(w.category, RefletsWarning)]


@pytest.mark.parametrize("entry", ENTRIES)
@pytest.mark.parametrize("name", FILES)
def test_every_entry_decodes_the_file_or_refuses_in_one_line(folder, name, entry, capfd):
    result, _ = _read(folder / name, entry, capfd)
    carries_materials = name.endswith((".gltf", ".glb", ".obj"))
    if entry in ("scene", "toml") and not carries_materials:  # a PLY or STL file needs a scene's material
        assert "\n" not in result and name in result and "material" in result, result
        return
    assert not isinstance(result, str), result
    bounds = np.stack([result.min(axis=0), result.max(axis=0)])
    np.testing.assert_allclose(bounds, BOX_BOUNDS, atol=TOLERANCE)


@pytest.mark.parametrize("entry", ENTRIES)
@pytest.mark.parametrize("name", ["Box.gltf", "BoxDraco.glb"])
def test_without_dracopy_draco_files_are_refused_in_one_line(tmp_path, monkeypatch, name, entry, capfd):
    _write_files(tmp_path)  # files never decoded in this process: nothing cached
    monkeypatch.setitem(sys.modules, "DracoPy", None)
    result, _ = _read(tmp_path / name, entry, capfd)
    assert isinstance(result, str), "decoded without DracoPy?"
    assert "\n" not in result and name in result and "pip install DracoPy" in result, result


def test_the_cli_renders_the_draco_box_and_refuses_a_bare_mesh_file(folder, tmp_path, capsys):
    from reflets.cli import main

    out = tmp_path / "box.png"
    assert main(["render", str(folder / "BoxDraco.glb"), "-o", str(out), "--size", "16x12"]) == 0
    assert out.is_file() and capsys.readouterr().err == ""
    assert main(["render", str(folder / "plain.ply"), "-o", str(tmp_path / "ply.png")]) == 2
    err = capsys.readouterr().err.strip()
    assert "\n" not in err and "plain.ply" in err and "material" in err, err


def test_a_scene_material_replacing_a_files_own_is_said_in_one_line(folder, capfd):
    (folder / "red.mtl").write_text("newmtl red\nKd 1 0 0\n", "utf-8")
    lines = (folder / "plain.obj").read_text("utf-8").splitlines()
    (folder / "red.obj").write_text("\n".join(["mtllib red.mtl", "usemtl red", *lines]) + "\n", "utf-8")
    said = {name: _read(folder / name, "toml + material", capfd)[1] for name in ("Box.gltf", "red.obj")}
    for name, lines in said.items():
        assert len(lines) == 1 and name in lines[0] and "replaces" in lines[0] and "'grey'" in lines[0], said
    assert "'Red'" in said["Box.gltf"][0] and "'red'" in said["red.obj"][0]
    for name in ("plain.glb", "plain.obj", "plain.ply"):  # no materials of their own: nothing to say
        assert _read(folder / name, "toml + material", capfd)[1] == [], name
    assert _read(folder / "Box.gltf", "toml", capfd)[1] == []  # its own materials, kept


def test_what_trimesh_logs_is_one_warning_line(tmp_path, capfd):
    """A PLY naming a texture that is not there: trimesh logs it with a traceback; reflets says one line."""
    ply = tmp_path / "textured.ply"
    ply.write_text("ply\nformat ascii 1.0\ncomment TextureFile gone.png\nelement vertex 3\nproperty float x\n"
                   "property float y\nproperty float z\nproperty float s\nproperty float t\nelement face 1\n"
                   "property list uchar int vertex_indices\nend_header\n0 0 0 0 0\n1 0 0 1 0\n0 1 0 0 1\n3 0 1 2\n",
                   "ascii")  # fmt: skip
    positions, said = _read(ply, "load_mesh_file", capfd)
    assert len(positions) == 3 and len(said) == 1 and "textured.ply" in said[0] and "\n" not in said[0], said


def test_damaged_mesh_files_load_or_are_refused_in_one_line(folder, tmp_path_factory, capfd):
    """Hypothesis, seeded: the files above with bytes changed, cut short or inserted — each read by
    ``load_mesh_file`` gives finite vertices or one line (a RefletsError naming the file), never another exception
    nor anything on stderr."""
    from hypothesis import HealthCheck, given, settings
    from hypothesis import strategies as st

    names = ("Box.gltf", "BoxDraco.glb", "plain.obj", "plain.ply", "plain.stl")
    originals = {name: (folder / name).read_bytes() for name in names}
    work = tmp_path_factory.mktemp("damaged")
    shutil.copy(folder / "Box.bin", work / "Box.bin")

    edits = st.lists(st.tuples(st.sampled_from(["set", "cut", "insert"]), st.floats(0, 1), st.binary(max_size=4)),
                     min_size=1, max_size=3)  # fmt: skip

    @settings(derandomize=True, deadline=None, database=None, max_examples=60,
              suppress_health_check=list(HealthCheck))  # fmt: skip
    @given(st.sampled_from(names), edits)
    def check(name, changes):
        data = bytearray(originals[name])
        for kind, where, value in changes:
            at = int(where * len(data))
            if kind == "cut":
                del data[at:]
            elif kind == "insert":
                data[at:at] = value
            else:
                data[at : at + len(value)] = value
        path = work / name
        path.write_bytes(bytes(data))
        try:
            positions = load_mesh_file(path).positions
        except RefletsError as exc:
            assert "\n" not in str(exc), str(exc)
        else:
            assert np.isfinite(positions).all() and len(positions) > 0

    with warnings.catch_warnings():
        warnings.simplefilter("ignore", RefletsWarning)
        check()
    assert capfd.readouterr().err == ""
