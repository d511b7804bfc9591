"""``reflets export-gltf`` writes a glTF material back as it was read: factors, textures (their decoded texels),
samplers, uv sets, texture transforms, alpha modes and extensions — read, exported, read again: equal."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pygltflib
import pytest
from PIL import Image

import reflets
from reflets.brdf.gltf import SLOTS
from reflets.gltf import export_gltf
from reflets.metrics import relmse
from reflets.textures import load_texture

DATA = Path(__file__).parents[1] / "data" / "gltf"


def assert_same_materials(a, b, atol=0.0):
    """Every field of every material equal (emission as factor × strength); each texture's decoded texels equal
    (not its file: the export embeds the bytes) or, re-encoded, within ``atol``."""
    assert len(a.materials) == len(b.materials)
    for (name, ma), mb in zip(a.materials.items(), b.materials.values(), strict=True):
        da, db = ma.model_dump(), mb.model_dump()
        for field, _, srgb, _ in SLOTS:
            ra, rb = da.pop(field), db.pop(field)
            assert (ra is None) == (rb is None), (name, field)
            if ra is None:
                continue
            for key in ("uv", "transform", "wrap", "filter"):
                assert ra[key] == rb[key], (name, field, key)
            ta, tb = load_texture(getattr(ma, field), srgb), load_texture(getattr(mb, field), srgb)
            np.testing.assert_allclose(tb.texels, ta.texels, rtol=0, atol=atol, err_msg=f"{name}.{field}")
        emitted = [np.multiply(d.pop("emissive"), d.pop("emissive_strength")) for d in (da, db)]
        np.testing.assert_allclose(*emitted, rtol=1e-6)  # glTF's factor is at most 1: the rest goes to the strength
        assert da == db, name


@pytest.mark.parametrize("asset", ["SheenTest/SheenTest.gltf", "TextureTransformTest/TextureTransformTest.gltf",
                                   "AlphaBlendModeTest/AlphaBlendModeTest.glb",
                                   "AnisotropyStrengthTest/AnisotropyStrengthTest.glb",
                                   "AttenuationTest/AttenuationTest.glb"])  # fmt: skip
def test_a_gltf_file_read_exported_and_read_again_has_the_same_materials(tmp_path, asset):
    scene = reflets.load_scene(DATA / asset)
    path, _ = export_gltf(scene, tmp_path / "out.glb")
    assert_same_materials(scene, reflets.load_scene(path))


def test_textures_glTF_cannot_hold_as_stored_are_re_encoded_and_the_image_matches(tmp_path):
    """A swizzled grey map, a base colour declared linear, a nearest-filtered mirrored transformed texture,
    emission over 1, a point light: the re-read scene renders the same image."""
    rng = np.random.default_rng(3)
    grey = rng.integers(0, 256, (16, 16), dtype=np.uint8)
    Image.fromarray(grey, "L").save(tmp_path / "rough.png")
    Image.fromarray(rng.integers(0, 256, (8, 8, 3), dtype=np.uint8), "RGB").save(tmp_path / "colour.png")
    transform = {"offset": [0.25, 0.5], "rotation": 0.3, "scale": [2, 3]}
    data = {
        "camera": {"position": [0, 1.2, 2.5], "look_at": [0, 0, 0], "size": [64, 48]},
        "materials": {"m": {"type": "gltf", "metallic": 0.3, "roughness": 0.8, "emissive": [0.0, 2.0, 0.5],
                            "metallic_roughness_texture": {"texture": str(tmp_path / "rough.png"), "channels": "1rr1"},
                            "base_color_texture": {"texture": str(tmp_path / "colour.png"), "srgb": False,
                                                   "filter": "nearest", "wrap": ["mirror", "clamp"],
                                                   "transform": transform},
                            "ior": 1.7, "clearcoat": 0.5, "specular_color": [1.0, 0.5, 0.5]}},
        "mesh": [{"shape": "sphere", "radius": 0.6, "material": "m"}],
        "light": [{"type": "point", "position": [1, 2, 2], "intensity": [4, 3, 2]},
                  {"type": "directional", "direction": [0, -1, -1], "irradiance": [0.5, 0.5, 0.5]}],
    }  # fmt: skip
    scene = reflets.load_dict(data)
    path, notes = export_gltf(scene, tmp_path / "out.glb")
    assert notes == ["m.base_color_texture: re-encoded as sRGB (glTF fixes each slot's encoding; 8-bit rounding)"]
    document = pygltflib.GLTF2.load(str(path))
    assert len(document.images) == 2 and all(i.mimeType == "image/png" for i in document.images)
    assert document.materials[0].extensions["KHR_materials_emissive_strength"]["emissiveStrength"] == 2.0
    assert "KHR_texture_transform" in document.extensionsUsed
    back = reflets.load_scene(path, camera=0)
    assert_same_materials(scene, back, atol=0.0046)  # half an 8-bit sRGB step near white: 0.0045 in linear
    # lights: candela and lux in the file, the same radiometric values read back
    assert [light.intensity if light.type == "point" else light.irradiance for light in back.light] == [
        pytest.approx((4, 3, 2)), pytest.approx((0.5, 0.5, 0.5))]  # fmt: skip
    before = reflets.render(scene, method="forward")
    after = reflets.render(back.model_copy(update={"camera": scene.camera}), method="forward")
    assert relmse(after, before) < 1e-4


def test_a_scratched_gltf_base_and_a_lone_second_set_export_as_reflets_renders_them(tmp_path):
    """A scratched material over a glTF base is written as its base (said); a texture on uv set 1 of a mesh with one
    set gets TEXCOORD_1 = the first set (what reflets reads, with its warning), so the file stays valid."""
    from PIL import Image

    Image.fromarray(np.zeros((4, 4, 3), np.uint8), "RGB").save(tmp_path / "t.png")
    texture = {"texture": str(tmp_path / "t.png"), "uv": 1}
    scene = reflets.load_dict({
        "camera": {"position": [0, 1, 3], "look_at": [0, 0, 0], "size": [32, 24]},
        "materials": {"s": {"type": "scratched", "base": {"type": "gltf", "base_color_texture": texture}}},
        "mesh": [{"shape": "sphere", "radius": 0.5, "material": "s"}],
        "light": [{"type": "point", "position": [0, 2, 2], "intensity": [1, 1, 1]}],
    })  # fmt: skip
    path, notes = export_gltf(scene, tmp_path / "out.glb")
    assert notes[0] == "s: scratched, exported by its base BRDF (the scratch lobes have no glTF form)"
    document = pygltflib.GLTF2.load(str(path))
    assert document.materials[0].pbrMetallicRoughness.baseColorTexture.texCoord == 1
    attributes = document.meshes[0].primitives[0].attributes
    assert attributes.TEXCOORD_1 is not None
    assert document.accessors[attributes.TEXCOORD_1].count == document.accessors[attributes.TEXCOORD_0].count
    back = reflets.load_scene(path)
    assert back.materials["out/s"].base_color_texture.uv == 1
