"""Two uv sets (glTF's TEXCOORD_1): a texture on the second set reads it in the GPU passes, the shadow maps'
cut-outs, the NumPy reference and the export."""

from __future__ import annotations

import json
import warnings

import numpy as np
import pygltflib
from PIL import Image

import reflets
from reflets.errors import RefletsWarning
from reflets.gltf import export_gltf
from reflets.metrics import relmse


def _with_second_set(src, dst, swap_sets: bool):
    """``src`` (an export of one textured plane) with TEXCOORD_1 = its uv turned by 90° and scaled by 2; the base
    colour on set 1 — or, ``swap_sets``, the same coordinates as set 0 (the image both must give)."""
    doc = pygltflib.GLTF2.load(str(src))
    blob = bytearray(doc.binary_blob())
    attributes = doc.meshes[0].primitives[0].attributes
    accessor = doc.accessors[attributes.TEXCOORD_0]
    view = doc.bufferViews[accessor.bufferView]
    uv = np.frombuffer(bytes(blob[view.byteOffset : view.byteOffset + view.byteLength]), np.float32).reshape(-1, 2)
    second = np.ascontiguousarray(np.stack([2.0 * uv[:, 1], 2.0 * (1.0 - uv[:, 0])], axis=1), np.float32)
    while len(blob) % 4:
        blob.append(0)
    doc.bufferViews.append(pygltflib.BufferView(buffer=0, byteOffset=len(blob), byteLength=second.nbytes))
    blob.extend(second.tobytes())
    doc.accessors.append(pygltflib.Accessor(bufferView=len(doc.bufferViews) - 1, componentType=pygltflib.FLOAT,
                                            count=len(second), type=pygltflib.VEC2))  # fmt: skip
    doc.buffers[0].byteLength = len(blob)
    if swap_sets:
        attributes.TEXCOORD_0 = len(doc.accessors) - 1
    else:
        attributes.TEXCOORD_1 = len(doc.accessors) - 1
        doc.materials[0].pbrMetallicRoughness.baseColorTexture.texCoord = 1
    doc.set_binary_blob(bytes(blob))
    doc.save_binary(str(dst))
    return dst


def test_a_texture_on_the_second_uv_set_reads_it_everywhere(tmp_path):
    rng = np.random.default_rng(5)
    codes = rng.integers(0, 256, (8, 8, 4), dtype=np.uint8)
    codes[..., 3] = np.where(codes[..., 3] > 100, 255, 0)  # a cut-out: holes in the shadow too
    Image.fromarray(codes, "RGBA").save(tmp_path / "tiles.png")
    data = {
        "camera": {"position": [0, 2.0, 1.6], "look_at": [0, 0, 0], "size": [96, 72]},
        "materials": {"card": {"type": "gltf", "metallic": 0.0, "roughness": 0.6, "alpha_mode": "mask",
                               "base_color_texture": {"texture": str(tmp_path / "tiles.png"), "filter": "nearest"}}},
        "mesh": [{"shape": "plane", "size": [1.6, 1.6], "material": "card"}],
        "light": [{"type": "point", "position": [0.5, 2, 1], "intensity": [3, 3, 3]}],
    }  # fmt: skip
    plain, _ = export_gltf(reflets.load_dict(data), tmp_path / "plain.glb")
    second = reflets.load_scene(_with_second_set(plain, tmp_path / "second.glb", swap_sets=False))
    swapped = reflets.load_scene(_with_second_set(plain, tmp_path / "swapped.glb", swap_sets=True))
    assert second.materials["second/card"].base_color_texture.uv == 1
    floor = {"shape": "plane", "size": [4, 4], "material": "floor", "transform": {"translate": [0, -0.3, 0]}}

    def on_floor(scene):  # a floor under the card: its shadow shows the holes of the uv set read
        d = scene.model_dump(mode="json", exclude_none=True)
        return reflets.load_dict(
            {
                **d,
                "camera": data["camera"],
                "light": data["light"],
                "mesh": [*d["mesh"], floor],
                "materials": {**d["materials"], "floor": {"type": "lambert", "albedo": [0.5] * 3}},
            }
        )

    scenes = [on_floor(second), on_floor(swapped)]
    gpu = [reflets.render(s, method="forward") for s in scenes]
    np.testing.assert_array_equal(gpu[0], gpu[1])
    first_set = reflets.render(on_floor(reflets.load_scene(plain)), method="forward")
    assert relmse(first_set, gpu[0]) > 0.05  # the sets differ: reading the first would be seen
    ref = [reflets.reference(s, spp=4, progress=False, seed=1).image for s in scenes]
    np.testing.assert_array_equal(ref[0], ref[1])
    assert relmse(gpu[0], ref[0]) < 0.02
    back, _ = export_gltf(second, tmp_path / "back.glb")
    again = reflets.load_scene(back)
    assert again.materials["back/second/card"].base_color_texture.uv == 1
    assert pygltflib.GLTF2.load(str(back)).meshes[0].primitives[0].attributes.TEXCOORD_1 is not None


def test_a_second_set_on_a_mesh_with_one_is_one_warning_and_reads_the_first(tmp_path):
    halves = np.zeros((4, 4, 3), np.uint8)
    halves[:, :2] = (255, 0, 0)
    halves[:, 2:] = (0, 0, 255)
    Image.fromarray(halves, "RGB").save(tmp_path / "t.png")
    data = {
        "camera": {"position": [0, 1, 3], "look_at": [0, 0, 0], "size": [32, 24]},
        "materials": {"m": {"type": "gltf", "base_color_texture": {"texture": str(tmp_path / "t.png"), "uv": 1}}},
        "mesh": [{"shape": "sphere", "radius": 0.5, "material": "m"}],
        "light": [{"type": "point", "position": [0, 2, 2], "intensity": [1, 1, 1]}],
    }
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        scene = reflets.load_dict(data)
    lines = [str(w.message) for w in caught if issubclass(w.category, RefletsWarning)]
    assert lines == ["mesh[0] has one uv set: materials.m.base_color_texture reads uv set 1, the first is read"]
    first = json.loads(json.dumps(data))
    first["materials"]["m"]["base_color_texture"]["uv"] = 0
    np.testing.assert_array_equal(reflets.render(scene, method="forward"), reflets.render(first, method="forward"))
