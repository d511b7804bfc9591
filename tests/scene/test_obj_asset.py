"""OBJ files as scenes: parts by material, the MTL statements mapped to glTF materials, bad MTL files refused."""

from __future__ import annotations

import warnings
from pathlib import Path

import numpy as np
import pytest
from PIL import Image

import reflets
from reflets.cli import main
from reflets.errors import RefletsWarning
from reflets.scene.geometry import mesh_data
from reflets.textures import TextureRef, load_texture

FUZE = Path(__file__).parents[1] / "data" / "obj" / "fuze" / "fuze.obj"
QUADS = """mtllib m.mtl
v 0 0 0
v 1 0 0
v 1 1 0
v 0 1 0
v 2 0 0
v 2 1 0
vt 0 0
vt 1 0
vt 1 1
vt 0 1
usemtl left
f 1/1 2/2 3/3 4/4
usemtl right
f 2/1 5/2 6/3 3/4
"""


def load(path, **kw):
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        scene = reflets.load_scene(path, **kw)
    return scene, [str(w.message) for w in caught if issubclass(w.category, RefletsWarning)]


def quads(tmp_path, mtl: str, images: dict[str, np.ndarray] | None = None) -> Path:
    (tmp_path / "q.obj").write_text(QUADS, "utf-8")
    (tmp_path / "m.mtl").write_text(mtl, "utf-8")
    for name, pixels in (images or {}).items():
        Image.fromarray(pixels).save(tmp_path / name)
    return tmp_path / "q.obj"


def test_fuze_renders_as_authored_with_its_texture():
    scene, caught = load(FUZE)
    assert len(scene.mesh) == 1
    material = scene.materials[scene.mesh[0].material]
    assert material.type == "gltf" and material.base_color_texture.texture.name == "fuze_uv.jpg"
    assert material.roughness == pytest.approx(1.0)  # Ns 0
    assert any("Tr 1" in line and "opaque" in line for line in caught)
    data = mesh_data(scene, 0)
    assert np.allclose(np.linalg.norm(data.normals, axis=1), 1.0, atol=1e-5)  # the file's are 2π long
    image = reflets.render(scene, size=(48, 64))
    assert np.isfinite(image).all() and image.max() > 0


def test_parts_follow_usemtl_and_mtl_maps_to_the_gltf_material(tmp_path):
    rgba = np.zeros((4, 4, 4), np.uint8)
    rgba[..., 0], rgba[..., 1], rgba[..., 2], rgba[..., 3] = 10, 200, 90, 255
    path = quads(tmp_path, """
newmtl left
Ka 0.1 0.1 0.1
illum 2
Kd 0.5 0.25 0.125
Ns 98
Ke 0 1 2
d 1
newmtl right
Kd 0.8
Pr 0.3
Pm 1
map_Pr -imfchan g orm.png
map_Pm -imfchan b orm.png
norm -bm 0.5 n.png
map_Ks spec.png
""", {"orm.png": rgba, "n.png": np.dstack([rgba[..., :3], rgba[..., 3]]), "spec.png": rgba})
    scene, caught = load(path)
    assert [m.name for m in scene.mesh] == ["q/left", "q/right"]
    left, right = (scene.materials[m.material] for m in scene.mesh)
    assert left.base_color[:3] == pytest.approx((0.5, 0.25, 0.125)) and left.emissive == pytest.approx((0, 1, 2))
    assert left.roughness == pytest.approx((2 / 100) ** 0.25) and left.metallic == 0
    assert right.base_color[:3] == pytest.approx((0.8, 0.8, 0.8))
    assert (right.roughness, right.metallic) == pytest.approx((0.3, 1.0))
    assert right.metallic_roughness_texture.channels == "1gb1"
    codes = load_texture(right.metallic_roughness_texture, False).codes
    assert tuple(codes[0, 0]) == (255, 200, 90, 255)  # G = roughness from g, B = metallic from b
    assert right.normal_scale == 0.5 and right.normal_texture.texture.name == "n.png"
    assert len(caught) == 1 and "map_Ks" in caught[0] and "m.mtl" in caught[0]  # Ka, illum: silently ignored
    assert [mesh_data(scene, i).n_triangles for i in range(2)] == [2, 2]


def test_map_scale_and_offset_read_the_image_where_the_format_says(tmp_path):
    """-s / -o act on the OBJ's v-up uv: the texel at uv is the image's at (s·u + o_u, 1 − (s·v + o_v))."""
    rng = np.random.default_rng(1)
    pixels = rng.integers(0, 255, (8, 8, 3), dtype=np.uint8)
    path = quads(tmp_path, "newmtl left\nmap_Kd -s 0.5 0.25 -o 0.125 0.5 t.png\nnewmtl right\n", {"t.png": pixels})
    scene, _ = load(path)
    material = scene.materials["q/left"]
    uv = rng.random((50, 2))
    data = load_texture(material.base_color_texture, True)
    expected = data.sample(np.stack([0.5 * uv[:, 0] + 0.125, 1.0 - (0.25 * uv[:, 1] + 0.5)], axis=1))
    assert np.allclose(material.at(uv).base[:, :3], expected[:, :3], atol=1e-6)


def test_grey_bump_is_a_height_map_warned_and_map_d_cuts(tmp_path):
    grey = np.full((4, 4, 3), 128, np.uint8)
    path = quads(tmp_path, "newmtl left\nbump h.png\nmap_d a.png\nnewmtl right\nd 0.5\n",
                 {"h.png": grey, "a.png": grey})  # fmt: skip
    scene, caught = load(path)
    left, right = scene.materials["q/left"], scene.materials["q/right"]
    assert left.normal_texture is None and any("height map" in c for c in caught)
    assert left.alpha_mode == "mask" and left.base_color_texture.channels == "111r"
    assert right.alpha_mode == "blend" and right.base_color[3] == 0.5


def test_scene_toml_takes_an_obj_without_material(tmp_path):
    (tmp_path / "s.toml").write_text(
        f'[camera]\nposition = [0, 0, 0.3]\nlook_at = [0, 0, 0]\n[[light]]\ntype = "point"\nposition = [0, 0, 1]\n'
        f'intensity = [1, 1, 1]\n[[mesh]]\nfile = "{FUZE.as_posix()}"\ntransform = {{ scale = 2 }}\n',
        "utf-8",
    )
    scene, _ = load(tmp_path / "s.toml")
    assert len(scene.mesh) == 1 and scene.materials[scene.mesh[0].material].type == "gltf"
    alone, _ = load(FUZE)
    assert np.allclose(mesh_data(scene, 0).positions, 2 * mesh_data(alone, 0).positions, atol=1e-6)


@pytest.mark.parametrize(
    "mtl, phrase",
    [
        ("Kd 1 1 1\n", "before any newmtl"),
        ("newmtl left\nKd x y z\n", "Kd needs 3"),
        ("newmtl left\nNs nan\n", "Ns needs 1"),
        ("newmtl left\nmap_Kd -s 2 2\n", "names no image"),
        ("newmtl left\nmap_Kd missing.png\n", "missing.png"),
        ("newmtl left\nmap_Kd bad.png\n", "not an image"),
        ("newmtl left\nd -5\n", "d must be in [0, 1]"),
        ("newmtl left\nPr 5\n", "Pr must be in [0, 1]"),
        ("newmtl left\nmap_Pr -imfchan x bad.png\n", "-imfchan x"),
        ("newmtl left\nmap_Kd folder\n", "is a directory"),
    ],
)
def test_bad_mtl_is_one_line_exit_2_nothing_written(mtl, phrase, tmp_path, monkeypatch, capsys):
    monkeypatch.chdir(tmp_path)
    quads(tmp_path, mtl + "newmtl right\n")
    (tmp_path / "bad.png").write_bytes(b"not a png")
    (tmp_path / "folder").mkdir()
    assert main(["render", "q.obj", "-o", "out.png", "--size", "16x12"]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and phrase in err[-1], err
    assert not (tmp_path / "out.png").exists()


def test_missing_library_renders_the_default_material_with_a_warning(tmp_path, monkeypatch, capsys):
    monkeypatch.chdir(tmp_path)
    (tmp_path / "q.obj").write_text(QUADS, "utf-8")
    assert main(["render", "q.obj", "-o", "out.png", "--size", "16x12"]) == 0
    err = capsys.readouterr().err
    assert "m.mtl not found" in err and (tmp_path / "out.png").exists()


def test_texture_channels_swizzle():
    ref = TextureRef(texture=FUZE.with_name("fuze_uv.jpg"), channels="0rb1")
    plain = load_texture(TextureRef(texture=ref.texture), False).codes
    codes = load_texture(ref, False).codes
    assert (codes[..., 0] == 0).all() and (codes[..., 3] == 255).all()
    assert np.array_equal(codes[..., 1], plain[..., 0]) and np.array_equal(codes[..., 2], plain[..., 2])


def test_an_obj_that_is_a_directory_is_one_line(tmp_path, monkeypatch, capsys):
    monkeypatch.chdir(tmp_path)
    (tmp_path / "d.obj").mkdir()
    assert main(["render", "d.obj", "-o", "out.png"]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "d.obj" in err[0] and "not a regular file" in err[0]
    assert not (tmp_path / "out.png").exists()
