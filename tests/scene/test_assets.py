"""glTF files as scenes: what is read (nodes, Draco, cameras, lights, materials, textures) and what is warned."""

from __future__ import annotations

import warnings
from pathlib import Path

import numpy as np
import pytest

import reflets
from reflets.errors import ArgumentError, RefletsWarning, SceneError
from reflets.gltf_file import read_gltf
from reflets.imageio import linear_to_srgb
from reflets.scene.geometry import mesh_data

ASSETS = Path(__file__).parents[1] / "data" / "gltf"
FILES = sorted(p for p in ASSETS.glob("*/*.gl*"))


def load(path, **kw):
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        scene = reflets.load_scene(path, **kw)
    return scene, [str(w.message) for w in caught if issubclass(w.category, RefletsWarning)]


@pytest.mark.parametrize("path", FILES, ids=lambda p: p.stem)
def test_every_test_asset_loads_with_a_camera_a_light_and_its_materials(path):
    scene, _ = load(path)
    assert scene.mesh and scene.light
    assert all(m.material in scene.materials for m in scene.mesh)
    points = np.concatenate([mesh_data(scene, i).positions for i in range(len(scene.mesh))])
    assert np.ptp(points, axis=0).max() > 0  # not collapsed (Draco decoded, accessors read)


def test_draco_box_is_decoded_to_a_unit_cube():
    scene, _ = load(ASSETS / "Box" / "Box.gltf")
    data = mesh_data(scene, 0)
    assert data.n_triangles == 12
    # the Box's root node turns y up from z up; its extent is 1 along every axis either way
    assert np.allclose(np.ptp(data.positions, axis=0), 1.0, atol=1e-6)


def test_node_transforms_match_trimesh_scene_graph():
    """OrientationTest's 13 nodes (rotations and matrices): every part's world vertices equal those trimesh's
    independent scene graph gives (same vertex order)."""
    import trimesh

    path = ASSETS / "OrientationTest" / "OrientationTest.glb"
    scene, _ = load(path)
    loaded = trimesh.load(str(path), process=False)
    expected = []
    for node in loaded.graph.nodes_geometry:
        matrix, name = loaded.graph[node]
        geom = loaded.geometry[name]
        expected.append(np.sort(np.round(trimesh.transform_points(geom.vertices, matrix), 4), axis=0))
    ours = [np.sort(np.round(mesh_data(scene, i).positions.astype(float), 4), axis=0) for i in range(len(scene.mesh))]
    assert len(ours) == len(expected) == 13
    unmatched = [e for e in expected if not any(o.shape == e.shape and np.allclose(o, e, atol=2e-4) for o in ours)]
    assert not unmatched, f"{len(unmatched)} of 13 parts placed differently from trimesh's graph"


def test_both_cameras_perspective_and_orthographic():
    scene, said = load(ASSETS / "Cameras" / "Cameras.gltf")
    assert scene.camera.fov_y == pytest.approx(np.degrees(0.7)) and not scene.camera.orthographic
    assert not said
    ortho, _ = load(ASSETS / "Cameras" / "Cameras.gltf", camera=1)
    assert ortho.camera.orthographic and ortho.camera.ortho_height == pytest.approx(2.0)  # 2 × ymag
    assert ortho.camera.position == pytest.approx((0.5, 0.5, 3.0)) and ortho.camera.size == (480, 480)
    with pytest.raises(ArgumentError, match="no camera '5'"):
        reflets.load_scene(ASSETS / "Cameras" / "Cameras.gltf", camera="5")


def test_emissive_strength_and_unsupported_extensions(tmp_path):
    import pygltflib

    scene, _ = load(ASSETS / "EmissiveStrengthTest" / "EmissiveStrengthTest.glb")
    assert max(m.emissive_strength for m in scene.materials.values()) == pytest.approx(16.0)
    document = pygltflib.GLTF2.load(str(ASSETS / "AnisotropyStrengthTest" / "AnisotropyStrengthTest.glb"))
    for material in document.materials:
        material.extensions["KHR_materials_iridescence"] = {"iridescenceFactor": 1.0}
    document.save_binary(str(tmp_path / "iridescent.glb"))
    _, said = load(tmp_path / "iridescent.glb")
    assert said == ["iridescent.glb: KHR_materials_iridescence not supported, the base metallic-roughness material is "
                    "rendered (materials 'materials[0]', 'materials[1]', 'materials[2]' and 47 more)"]  # fmt: skip
    scene, said = load(ASSETS / "AnisotropyStrengthTest" / "AnisotropyStrengthTest.glb")
    assert said == [] and max(m.anisotropy_strength for m in scene.materials.values()) == pytest.approx(1.0)


def test_sheen_read_with_its_textures_and_no_warning():
    """KHR_materials_sheen (tools/make_sheen_test.py): factors, the colour texture decoded as sRGB colour, the
    roughness texture read in A; the clear coat beside it; nothing said about either."""
    scene, said = load(ASSETS / "SheenTest" / "SheenTest.gltf")
    assert not said, said
    velvet = scene.materials["SheenTest/velvet"]
    assert velvet.sheen_color == pytest.approx((1.0, 0.3, 0.4)) and velvet.sheen_roughness == pytest.approx(0.3)
    textured = scene.materials["SheenTest/textured sheen"]
    assert textured.sheen_color_texture is not None and textured.sheen_roughness_texture is not None
    from PIL import Image

    image = np.asarray(Image.open(ASSETS / "SheenTest" / "sheen.png"))  # mesh uv (u, v): image (row 64 (1 − v), u)
    points = textured.at(np.array([[0.1, 0.5], [0.9, 0.02]]))
    assert points.sheen[0] == pytest.approx(_linear(image[32, 6, :3]), abs=2e-3)  # RGB, sRGB-decoded
    assert points.sheen_roughness[1] == pytest.approx(image[62, 57, 3] / 255.0, abs=0.02)  # A, linear
    coated = scene.materials["SheenTest/coated sheen"]
    assert coated.sheened and coated.clearcoat == pytest.approx(0.5)


def test_ior_and_unlit_read_and_checked(tmp_path):
    """KHR_materials_ior becomes ``ior``, KHR_materials_unlit ``unlit`` (no warning); an ior between 0 and 1 is one
    line naming the material."""
    import json
    import shutil

    for name in ("SheenTest.bin", "sheen.png"):
        shutil.copy(ASSETS / "SheenTest" / name, tmp_path / name)
    document = json.loads((ASSETS / "SheenTest" / "SheenTest.gltf").read_text("utf-8"))
    document["materials"][0]["extensions"]["KHR_materials_ior"] = {"ior": 1.33}
    document["materials"][3]["extensions"] = {"KHR_materials_unlit": {}}
    (tmp_path / "a.gltf").write_text(json.dumps(document), "utf-8")
    scene, said = load(tmp_path / "a.gltf")
    assert not said and scene.materials["a/velvet"].ior == pytest.approx(1.33)
    assert scene.materials["a/felt"].ior == 1.5 and scene.materials["a/felt"].unlit
    assert not scene.materials["a/velvet"].unlit
    document["materials"][0]["extensions"]["KHR_materials_ior"] = {"ior": 0.5}
    (tmp_path / "b.gltf").write_text(json.dumps(document), "utf-8")
    with pytest.raises(SceneError, match="ior"):
        load(tmp_path / "b.gltf")


def test_spot_light_read_with_its_cone(tmp_path):
    """KHR_lights_punctual spot: a point light with a cone along its node's −z, the angles in degrees, no warning;
    an inner angle not below the outer one is one line."""
    import json
    import shutil

    for name in ("SheenTest.bin", "sheen.png"):
        shutil.copy(ASSETS / "SheenTest" / name, tmp_path / name)
    document = json.loads((ASSETS / "SheenTest" / "SheenTest.gltf").read_text("utf-8"))
    document["extensionsUsed"].append("KHR_lights_punctual")
    document["extensions"] = {"KHR_lights_punctual": {"lights": [
        {"type": "spot", "intensity": 683.0, "spot": {"innerConeAngle": 0.2, "outerConeAngle": 0.5}}]}}  # fmt: skip
    document["nodes"].append({"translation": [0, 2, 0], "rotation": [-0.7071068, 0, 0, 0.7071068],  # −z → −y
                              "extensions": {"KHR_lights_punctual": {"light": 0}}})  # fmt: skip
    document["scenes"][0]["nodes"].append(len(document["nodes"]) - 1)
    (tmp_path / "spot.gltf").write_text(json.dumps(document), "utf-8")
    scene, said = load(tmp_path / "spot.gltf")
    assert not said, said
    (light,) = [light for light in scene.light if light.type == "point"]
    assert light.intensity == pytest.approx((1.0, 1.0, 1.0)) and light.position == pytest.approx((0, 2, 0))
    assert light.spot.inner_deg == pytest.approx(np.degrees(0.2)) and light.spot.outer_deg == pytest.approx(
        np.degrees(0.5))  # fmt: skip
    assert np.allclose(light.spot.direction, (0, -1, 0), atol=1e-6)
    document["materials"][1]["extensions"]["KHR_materials_sheen"]["sheenColorTexture"] = {"index": "0"}
    (tmp_path / "index.gltf").write_text(json.dumps(document), "utf-8")
    with pytest.raises(SceneError, match="sheenColorTexture.index: must be a texture index"):
        load(tmp_path / "index.gltf")  # a string index: one line (an extension's textureInfo is raw JSON)
    document["materials"][1]["extensions"]["KHR_materials_sheen"]["sheenColorTexture"] = {"index": 0}
    document["extensions"]["KHR_lights_punctual"]["lights"][0]["spot"] = {"innerConeAngle": 0.6,
                                                                          "outerConeAngle": 0.5}  # fmt: skip
    (tmp_path / "bad.gltf").write_text(json.dumps(document), "utf-8")
    with pytest.raises(SceneError, match="inner_deg"):
        load(tmp_path / "bad.gltf")


def _linear(codes):
    from reflets.imageio import srgb_to_linear

    return srgb_to_linear(np.asarray(codes, np.float64) / 255.0)


def test_texture_transform_read():
    scene, _ = load(ASSETS / "TextureTransformTest" / "TextureTransformTest.gltf")
    transforms = [m.base_color_texture.transform for m in scene.materials.values() if m.base_color_texture]
    assert any(t is not None and t.rotation != 0 for t in transforms)
    assert any(t is not None and tuple(t.offset) != (0.0, 0.0) for t in transforms)


def test_uv_orientation_reads_the_image_top_left_at_gltf_uv_origin():
    """TextureCoordinateTest: the base colour the material reads at each vertex equals the texel of the image at
    the vertex's glTF uv (u right, v down from the top-left), decoded independently with Pillow and trimesh."""
    import io

    import trimesh
    from PIL import Image

    path = ASSETS / "TextureCoordinateTest" / "TextureCoordinateTest.glb"
    scene, _ = load(path)
    loaded = trimesh.load(str(path), process=False)
    checked = 0
    for i, mesh in enumerate(scene.mesh):
        material = scene.materials[mesh.material]
        if material.base_color_texture is None:
            continue
        data = mesh_data(scene, i)
        gltf_uv = np.stack([data.uvs[:, 0], 1.0 - data.uvs[:, 1]], axis=1)  # back to glTF's v down
        inside = np.all((gltf_uv > 0.02) & (gltf_uv < 0.98), axis=1)
        doc = read_gltf(path)
        image = np.asarray(Image.open(io.BytesIO(doc.image_bytes(0))).convert("RGB"), np.float64) / 255.0
        h, w = image.shape[:2]
        texel = image[(gltf_uv[inside, 1] * h).astype(int), (gltf_uv[inside, 0] * w).astype(int)]
        srgb = linear_to_srgb(material.at(data.uvs[inside]).base)
        assert np.abs(srgb - texel).max() < 0.2, mesh.name
        checked += inside.sum()
    assert checked > 0 and len(loaded.geometry) >= 1


def test_toml_file_mesh_without_material_takes_the_files_materials(tmp_path):
    path = tmp_path / "scene.toml"
    box = (ASSETS / "TextureCoordinateTest" / "TextureCoordinateTest.glb").as_posix()
    path.write_text(
        f"""
[camera]
position = [0, 0, 3]
look_at = [0, 0, 0]
[[mesh]]
file = "{box}"
transform = {{ translate = [1, 0, 0] }}
[[light]]
type = "point"
position = [0, 0, 3]
intensity = [1, 1, 1]
""",
        encoding="utf-8",
    )
    scene = reflets.load_scene(path)
    whole, _ = load(ASSETS / "TextureCoordinateTest" / "TextureCoordinateTest.glb")
    assert len(scene.mesh) == len(whole.mesh) > 1
    assert all(m.material.startswith("TextureCoordinateTest/") for m in scene.mesh)
    moved = mesh_data(scene, 0).positions - mesh_data(whole, 0).positions
    assert np.allclose(moved, [1.0, 0.0, 0.0], atol=1e-6)  # the mesh's transform on top of the file's


def test_ply_without_material_is_an_error(tmp_path):
    path = tmp_path / "scene.toml"
    path.write_text('[camera]\nposition = [0, 0, 3]\nlook_at = [0, 0, 0]\n[[mesh]]\nfile = "x.ply"\n', "utf-8")
    with pytest.raises(SceneError, match=r"mesh\[0\].material: required"):
        reflets.load_scene(path)


def test_damaged_gltf_is_one_line_error(tmp_path):
    bad = tmp_path / "bad.glb"
    bad.write_bytes(b"glTF" + b"\0" * 20)
    with pytest.raises(SceneError, match="bad.glb"):
        reflets.load_scene(bad)
    text = tmp_path / "bad.gltf"
    text.write_text('{"asset": {"version": "2.0"}, "meshes": [{"primitives": [{"attributes": {"POSITION": 3}}]}], '
                    '"nodes": [{"mesh": 0}], "scenes": [{"nodes": [0]}]}', "utf-8")  # fmt: skip
    with pytest.raises(SceneError, match=r"accessors\[3\] does not exist"):
        reflets.load_scene(text)


def test_cli_renders_a_gltf_file_with_no_other_argument(tmp_path, monkeypatch, capsys):
    from reflets.cli import main

    monkeypatch.chdir(tmp_path)
    assert main(["render", str(ASSETS / "Box" / "Box.gltf"), "-o", "box.png", "--size", "32x24"]) == 0
    assert (tmp_path / "box.png").is_file()
    assert main(["render", str(ASSETS / "Box" / "Box.gltf"), "-o", "b.png", "--camera", "2"]) == 2
    assert "no camera '2'" in capsys.readouterr().err
    assert not (tmp_path / "b.png").exists()


def test_textured_materials_take_ltc_per_fragment_under_area_lights_in_auto(ctx):
    """LTC reads a textured glTF material per fragment: auto keeps it; the analytic and biased methods' integrals
    read constant factors (an explicit --method says it ignores the textures), and an anisotropic lobe (isotropic
    in LTC) takes forward's midpoint rule."""
    from reflets.diagnostics import scene_warnings
    from reflets.renderer.compose import Auto
    from reflets.scene.model import QuadLight

    scene, _ = load(ASSETS / "TextureCoordinateTest" / "TextureCoordinateTest.glb")
    quad = QuadLight(type="quad", corners=((-1, 2, -1), (1, 2, -1), (-1, 2, 1)), radiance=(5, 5, 5), two_sided=True)
    scene = scene.model_copy(update={"light": [quad]})
    assert Auto(ctx)._area_method(scene) == "ltc"
    assert not any("ignored" in line for line in scene_warnings(scene, "ltc"))
    assert any("textures are ignored" in line for line in scene_warnings(scene, "biased"))
    brushed = {k: m.model_copy(update={"anisotropy_strength": 0.5}) for k, m in scene.materials.items()}
    brushed_scene = scene.model_copy(update={"materials": brushed})
    assert Auto(ctx)._area_method(brushed_scene) == "forward"
    assert any("anisotropy is ignored" in line for line in scene_warnings(brushed_scene, "ltc"))


def test_gltf_with_a_material_is_one_mesh_read_by_reflets_reader(tmp_path):
    """With a material, the whole file is one mesh — read by reflets' reader, so Draco data is decoded."""
    path = tmp_path / "scene.toml"
    box = (ASSETS / "Box" / "Box.gltf").as_posix()
    path.write_text(f'[camera]\nposition = [0, 0, 3]\nlook_at = [0, 0, 0]\n[materials.grey]\ntype = "lambert"\n'
                    f'albedo = [0.5, 0.5, 0.5]\n[[mesh]]\nfile = "{box}"\nmaterial = "grey"\n', "utf-8")  # fmt: skip
    scene = reflets.load_scene(path)
    assert len(scene.mesh) == 1
    assert np.allclose(np.ptp(mesh_data(scene, 0).positions, axis=0), 1.0, atol=1e-6)
