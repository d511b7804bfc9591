"""Mesh text files (OBJ, MTL, ASCII PLY, OFF, ASCII STL) in any common encoding and line ending load alike."""

from __future__ import annotations

import struct
import sys

import numpy as np
import pytest

import reflets
from reflets.cli import main
from reflets.errors import SceneError
from reflets.scene.geometry import mesh_data
from reflets.scene.meshfile import _load_trimesh, decode_text, load_mesh_file

# Non-ASCII in comments, object, group and material names; {x} takes cp1252-only characters (’ € œ) where the
# encoding has them. A quad (triangulated by trimesh) and a triangle, with uv and normals.
OBJ = """\
# Créé par Exporteur 3D © 2009{x}
mtllib {mtllib}
o Boîte{x}
g Façade{x}
v 0 0 0
v 2 0 0
v 2 1 0
v 0 1 0
v 1 2 0.5
vt 0 0
vt 1 0
vt 1 1
vt 0 1
vt 0.5 1
vn 0 0 1
usemtl Matériau{x}
f 1/1/1 2/2/1 3/3/1 4/4/1
f 4/4/1 3/3/1 5/5/1
"""

MTL = """\
# Bibliothèque de matériaux © {x}
newmtl Matériau{x}
Ka 0 0 0
Kd 0.8 0.25 0.1
Ks 0 0 0
Ns 10
"""

PLY = """\
ply
format ascii 1.0
comment Créé par Exporteur © 2009{x}
obj_info Modèle déposé{x}
element vertex 5
property float x
property float y
property float z
element face 2
property list uchar int vertex_indices
end_header
0 0 0
2 0 0
2 1 0
0 1 0
1 2 0.5
4 0 1 2 3
3 3 2 4
"""

OFF = """\
OFF
# Créé par Exporteur © 2009{x}
5 2 0
0 0 0
2 0 0
2 1 0
0 1 0
1 2 0.5
4 0 1 2 3
3 3 2 4
"""

STL = """\
solid Modèle{x}
facet normal 0 0 1
outer loop
vertex 0 0 0
vertex 2 0 0
vertex 2 1 0
endloop
endfacet
endsolid Modèle{x}
"""

ENCODINGS = ["utf-8", "utf-8-sig", "latin-1", "cp1252"]
CP1252_ONLY = "’€œ"  # not in Latin-1: 0x92, 0x80, 0x9C in cp1252
MTLLIB = "mes matériaux.mtl"  # a space and a non-ASCII character in the library's file name


def _text(template: str, encoding: str, newline: str) -> bytes:
    extra = "" if encoding == "latin-1" else CP1252_ONLY
    text = template.format(x=extra, mtllib=MTLLIB).replace("\n", newline)
    return text.encode(encoding)


def _write(directory, fmt: str, encoding: str = "utf-8", newline: str = "\n", mtl_encoding: str | None = None):
    """The file of ``fmt`` (obj, obj+mtl, ply, off, stl) under a non-ASCII name; its path."""
    directory.mkdir(parents=True, exist_ok=True)
    template = {"obj": OBJ, "obj+mtl": OBJ, "ply": PLY, "off": OFF, "stl": STL}[fmt]
    path = directory / f"modèle ©.{fmt.split('+')[0]}"
    path.write_bytes(_text(template, encoding, newline))
    if fmt == "obj+mtl":
        (directory / MTLLIB).write_bytes(_text(MTL, mtl_encoding or encoding, newline))
    return path


def _assert_same_mesh(got, want):
    for name in ("positions", "normals", "uvs", "tangents", "indices"):
        np.testing.assert_array_equal(getattr(got, name), getattr(want, name), err_msg=name)


@pytest.fixture(autouse=True)
def no_charset_guessing(monkeypatch):
    """As if trimesh's optional charset_normalizer were not installed: any guess of an encoding by trimesh fails."""
    monkeypatch.setitem(sys.modules, "charset_normalizer", None)


def test_the_guard_catches_trimesh_guessing_an_encoding(tmp_path):
    """Without our decoding, trimesh would reach for charset_normalizer on a Latin-1 file (and fail here)."""
    import trimesh

    path = _write(tmp_path, "obj", "latin-1")
    with pytest.raises(ImportError, match="charset_normalizer"):
        trimesh.load(str(path), file_type="obj", process=False)


@pytest.mark.parametrize("newline", ["\n", "\r\n"], ids=["LF", "CRLF"])
@pytest.mark.parametrize("encoding", ENCODINGS)
@pytest.mark.parametrize("fmt", ["obj", "obj+mtl", "ply"])
def test_text_mesh_in_any_encoding_and_line_ending_loads_like_utf8_lf(tmp_path, fmt, encoding, newline):
    want = load_mesh_file(_write(tmp_path / "reference", fmt))
    assert want.n_vertices == 5 and len(want.indices) == 3
    got = load_mesh_file(_write(tmp_path / "variant", fmt, encoding, newline))
    _assert_same_mesh(got, want)


@pytest.mark.parametrize("newline", ["\n", "\r\n"], ids=["LF", "CRLF"])
@pytest.mark.parametrize("encoding", ENCODINGS)
@pytest.mark.parametrize("fmt", ["off", "stl"])
def test_off_and_ascii_stl_in_any_encoding_load(tmp_path, fmt, encoding, newline):
    want = load_mesh_file(_write(tmp_path / "reference", fmt))
    _assert_same_mesh(load_mesh_file(_write(tmp_path / "variant", fmt, encoding, newline)), want)


@pytest.mark.parametrize("newline", ["\n", "\r\n"], ids=["LF", "CRLF"])
@pytest.mark.parametrize(
    ("obj_encoding", "mtl_encoding"),
    [(e, e) for e in ENCODINGS] + [("utf-8", "cp1252"), ("cp1252", "utf-8-sig")],
)
def test_mtl_next_to_the_obj_is_decoded_too(tmp_path, obj_encoding, mtl_encoding, newline):
    """The material library's name, colour and the OBJ's ``usemtl`` meet only if both files decode right."""
    path = _write(tmp_path, "obj+mtl", obj_encoding, newline, mtl_encoding)
    loaded = _load_trimesh(path, ".obj")
    meshes = list(loaded.geometry.values()) if hasattr(loaded, "geometry") else [loaded]
    extra = "" if "latin-1" in (obj_encoding, mtl_encoding) else CP1252_ONLY
    assert [m.visual.material.name for m in meshes] == [f"Matériau{extra}"]
    np.testing.assert_array_equal(meshes[0].visual.material.diffuse, [204, 64, 26, 255])  # Kd 0.8 0.25 0.1


def test_utf16_with_bom_loads(tmp_path):
    want = load_mesh_file(_write(tmp_path / "reference", "obj"))
    for encoding in ("utf-16-le", "utf-16-be"):
        bom = "\ufeff".encode(encoding)
        path = _write(tmp_path / encoding, "obj")
        path.write_bytes(bom + path.read_text(encoding="utf-8").replace("\n", "\r\n").encode(encoding))
        _assert_same_mesh(load_mesh_file(path), want)


def test_decode_text_fallback_order():
    assert decode_text("é’\r\nx\ry\n".encode()) == "é’\nx\ny\n"
    assert decode_text(b"\xef\xbb\xbfv 0") == "v 0"  # BOM dropped
    assert decode_text("Créé par l’outil, 5 €".encode("cp1252")) == "Créé par l’outil, 5 €"  # Windows-1252
    assert decode_text(b"\x81 \xe9 \x8d") == "\x81 é \x8d"  # bytes cp1252 leaves undefined: Latin-1


def test_binary_ply_body_is_kept_byte_for_byte(tmp_path):
    """Only the header of a binary PLY is text: a body with CR, LF and bytes over 0x7F must not be decoded."""
    xyz = np.array([struct.unpack("<f", b"\r\n\xe9\x3f")[0], 0.0, 0.0], dtype="<f4")
    vertices = np.array([xyz, [2, 0, 0], [struct.unpack("<f", b"\n\r\x92\x3f")[0], 1, 0]], dtype="<f4")
    header = (
        "ply\r\nformat binary_little_endian 1.0\r\ncomment Créé par Exporteur © ’\r\n"
        "element vertex 3\r\nproperty float x\r\nproperty float y\r\nproperty float z\r\n"
        "element face 1\r\nproperty list uchar int vertex_indices\r\nend_header\r\n"
    ).encode("cp1252")
    body = vertices.tobytes() + struct.pack("<Biii", 3, 0, 1, 2)
    path = tmp_path / "binaire é.ply"
    path.write_bytes(header + body)
    mesh = load_mesh_file(path)
    np.testing.assert_array_equal(mesh.positions, vertices)
    np.testing.assert_array_equal(mesh.indices, [[0, 1, 2]])


@pytest.mark.parametrize("ext", [".obj", ".ply", ".off", ".stl"])
def test_a_file_that_is_no_mesh_is_our_error_naming_it(tmp_path, rng, ext):
    path = tmp_path / f"pas un maillage{ext}"
    path.write_bytes(rng.integers(0, 256, 4096, dtype=np.uint8).tobytes())
    with pytest.raises(SceneError) as info:
        load_mesh_file(path)
    message = str(info.value)
    assert message.startswith(f"{path}: ") and "\n" not in message
    assert "charset" not in message.lower() and "codec" not in message


def _scene_toml(directory, mesh_name: str):
    path = directory / "scène.toml"
    path.write_text(
        f'[camera]\nposition = [0, 3, 4]\nlook_at = [0, 0, 0]\n\n[materials.m]\ntype = "lambert"\n\n'
        f'[[mesh]]\nfile = "{mesh_name}"\nmaterial = "m"\n',
        encoding="utf-8",
    )
    return path


def test_scene_referencing_a_latin1_crlf_obj_loads(tmp_path):
    want = load_mesh_file(_write(tmp_path / "reference", "obj+mtl"))
    mesh = _write(tmp_path, "obj+mtl", "latin-1", "\r\n")
    scene = reflets.load_scene(_scene_toml(tmp_path, mesh.name))
    _assert_same_mesh(mesh_data(scene, 0), want)


def test_cli_exports_a_scene_with_a_cp1252_obj_and_rejects_a_non_mesh_with_exit_2(tmp_path, capsys):
    mesh = _write(tmp_path, "obj+mtl", "cp1252", "\r\n")
    out = tmp_path / "out.glb"
    assert main(["export-gltf", str(_scene_toml(tmp_path, mesh.name)), "-o", str(out)]) == 0
    assert "wrote" in capsys.readouterr().out
    assert load_mesh_file(out).n_vertices == 5

    (tmp_path / "bruit.obj").write_bytes(bytes(range(256)) * 8)
    code = main(["export-gltf", str(_scene_toml(tmp_path, "bruit.obj")), "-o", str(tmp_path / "no.glb")])
    err = capsys.readouterr().err.strip()
    assert code == 2 and len(err.splitlines()) == 1 and "bruit.obj" in err and "mesh[0]" in err
    assert "charset" not in err and "Traceback" not in err and not (tmp_path / "no.glb").exists()
