"""Careless and hostile glTF files and texture references: one line naming the file and the field, exit 2, nothing
written (each case was first tried by hand; see docs/assets.md)."""

from __future__ import annotations

import base64
import copy
import json
import struct

import pytest

from reflets.cli import main

NAN = float("nan")
TRIANGLE = struct.pack("<9f", 0, 0, 0, 1, 0, 0, 0, 1, 0)
BASE = {
    "asset": {"version": "2.0"},
    "scene": 0,
    "scenes": [{"nodes": [0, 1]}],
    "nodes": [{"mesh": 0}, {"camera": 0, "translation": [0, 0, 3]}],
    "cameras": [{"type": "perspective", "perspective": {"yfov": 0.8, "znear": 0.01, "aspectRatio": 1.5}}],
    "meshes": [{"primitives": [{"attributes": {"POSITION": 0}, "material": 0}]}],
    "materials": [{"pbrMetallicRoughness": {"baseColorFactor": [1, 1, 1, 1]}}],
    "accessors": [{"componentType": 5126, "count": 3, "type": "VEC3", "bufferView": 0}],
    "bufferViews": [{"buffer": 0, "byteLength": 36}],
    "buffers": [{"byteLength": 36, "uri": "data:;base64," + base64.b64encode(TRIANGLE).decode()}],
}
LIGHT = {"KHR_lights_punctual": {"lights": [{"type": "point", "intensity": NAN}]}}
# (name, edits as (path, value), a phrase the one line must hold)
CASES = [
    ("nan colour", [(("materials", 0, "pbrMetallicRoughness", "baseColorFactor"), [NAN, 1, 1, 1])], "base_color[0]"),
    ("metallic string", [(("materials", 0, "pbrMetallicRoughness", "metallicFactor"), "x")], "cannot read glTF"),
    ("emission 1e300", [(("materials", 0, "emissiveFactor"), [1e300, 0, 0])], "emissive[0]"),
    ("yfov 0", [(("cameras", 0, "perspective", "yfov"), 0)], "perspective.yfov"),
    ("aspect -2", [(("cameras", 0, "perspective", "aspectRatio"), -2)], "aspectRatio"),
    ("aspect 1e9", [(("cameras", 0, "perspective", "aspectRatio"), 1e9)], "aspectRatio"),
    ("zfar < znear", [(("cameras", 0, "perspective", "zfar"), 0.001)], "near"),
    ("scale 1e300", [(("nodes", 0, "scale"), [1e300, 1, 1])], "nodes[0].scale"),
    ("translation nan", [(("nodes", 1, "translation"), [NAN, 0, 0])], "nodes[1].translation"),
    ("zero quaternion", [(("nodes", 1, "rotation"), [0, 0, 0, 0])], "nodes[1].rotation"),
    ("short matrix", [(("nodes", 0, "matrix"), [1, 0, 0])], "nodes[0].matrix"),
    ("node cycle", [(("nodes", 0, "children"), [0])], "reached twice"),
    ("missing child", [(("nodes", 0, "children"), [7])], "nodes[7]"),
    ("empty scene", [(("scenes", 0, "nodes"), [])], "no triangles"),
    ("hidden by scale 0", [(("nodes", 0, "scale"), [0, 0, 0])], "no triangles"),
    ("missing material", [(("meshes", 0, "primitives", 0, "material"), 9)], "materials[9]"),
    ("count 0", [(("accessors", 0, "count"), 0)], "no triangles"),
    ("count 1e9", [(("accessors", 0, "count"), 10**9)], "run past the end"),
    ("missing buffer file", [(("buffers", 0, "uri"), "missing.bin")], "missing.bin"),
    ("broken data uri", [(("buffers", 0, "uri"), "data:x;base64,%%%")], "invalid data URI"),
    ("missing texture", [(("materials", 0, "pbrMetallicRoughness", "baseColorTexture"), {"index": 3})], "textures[3]"),
    ("nan light", [(("extensions",), LIGHT), (("nodes", 1, "extensions"), {"KHR_lights_punctual": {"light": 0}})],
     "intensity[0]"),
    ("missing camera", [(("nodes", 1, "camera"), 5)], "cameras[5]"),
    ("ortho xmag 0", [(("cameras", 0), {"type": "orthographic", "orthographic": {"xmag": 0, "ymag": 1, "zfar": 9,
                                                                               "znear": 0}})], "orthographic.xmag"),
    ("ortho ymag nan", [(("cameras", 0), {"type": "orthographic", "orthographic": {"xmag": 1, "ymag": NAN, "zfar": 9,
                                                                                 "znear": 0}})], "orthographic.ymag"),
    ("glTF 1.0", [(("asset", "version"), "1.0")], "glTF version 1.0"),
    ("required extension", [(("extensionsRequired",), ["EXT_meshopt_compression"])], "EXT_meshopt_compression"),
]  # fmt: skip


def _edited(edits) -> dict:
    data = copy.deepcopy(BASE)
    for path, value in edits:
        node = data
        for key in path[:-1]:
            node = node[key]
        node[path[-1]] = value
    return data


def test_the_base_file_renders(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    (tmp_path / "ok.gltf").write_text(json.dumps(BASE), "utf-8")
    assert main(["render", "ok.gltf", "-o", "ok.png", "--size", "16x12"]) == 0


@pytest.mark.parametrize("name, edits, phrase", CASES, ids=[c[0] for c in CASES])
def test_bad_gltf_is_one_line_exit_2_nothing_written(name, edits, phrase, tmp_path, monkeypatch, capsys):
    monkeypatch.chdir(tmp_path)
    (tmp_path / "bad.gltf").write_text(json.dumps(_edited(edits)), "utf-8")
    assert main(["render", "bad.gltf", "-o", "out.png", "--size", "16x12"]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "bad.gltf" in err[0] and phrase in err[0], err
    assert not (tmp_path / "out.png").exists()


@pytest.mark.parametrize(
    "texture, phrase",
    [
        ('{ texture = "bad.png" }', "not an image"),
        ('{ texture = "folder" }', "is a directory"),
        ('{ texture = "missing.png" }', "not found"),
        ('{ texture = "bad.png", image = -1 }', "image"),
        ('{ texture = "bad.png", uv = 5 }', "uv"),
        ('{ texture = "bad.png", transform = { scale = [nan, 1] } }', "scale[0]"),
        ('{ texture = "bad.png", wrap = ["x", "repeat"] }', "wrap[0]"),
        ('"bad.png"', "TextureRef"),
    ],
)
def test_bad_texture_reference_is_one_line(texture, phrase, tmp_path, monkeypatch, capsys):
    monkeypatch.chdir(tmp_path)
    (tmp_path / "bad.png").write_bytes(b"not a png")
    (tmp_path / "folder").mkdir()
    (tmp_path / "t.toml").write_text(
        '[camera]\nposition = [0, 0, 3]\nlook_at = [0, 0, 0]\n[materials.m]\ntype = "gltf"\n'
        f'base_color_texture = {texture}\n[[mesh]]\nshape = "sphere"\nmaterial = "m"\n',
        "utf-8",
    )
    assert main(["render", "t.toml", "-o", "out.png", "--size", "16x12"]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "base_color_texture" in err[0] and phrase in err[0], err
    assert not (tmp_path / "out.png").exists()
