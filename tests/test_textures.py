"""Material textures: decoding by role, the mip chains the GPU gets, the swizzle, what the GPU samples."""

from __future__ import annotations

import numpy as np

from reflets.textures import TextureData, swizzled, texture_bytes

TEXTURE_BYTES = texture_bytes


def _data(srgb: bool, shape=(6, 10)) -> TextureData:
    codes = np.random.default_rng(2).integers(0, 256, (*shape, 4), dtype=np.uint8)
    return TextureData(codes, srgb, key="test")


def test_normal_map_mips_are_float16_box_means_of_unit_normals_down_to_one_texel():
    """Normals keep their precision on the GPU: float16 levels, each the mean of the one above (an odd side's last
    three merge), the last one of a power-of-two image the mean of the whole; level 0's vectors made unit."""
    data = _data(srgb=False)
    levels = data.mip_chain(normal_map=True)
    assert all(level.dtype == np.float16 for level in levels)
    assert [level.shape[:2] for level in levels] == [(6, 10), (3, 5), (1, 2), (1, 1)]
    assert np.allclose(np.linalg.norm(levels[0][..., :3].astype(float) * 2 - 1, axis=-1), 1.0, atol=2e-3)
    square = _data(srgb=False, shape=(4, 8))
    chain = square.mip_chain(normal_map=True)
    assert np.allclose(chain[-1][0, 0], chain[0].astype(float).reshape(-1, 4).mean(axis=0), atol=1e-3)
    assert data.gpu_bytes(normal_map=True) == int(6 * 10 * 8 * 4 / 3)


def test_other_data_mips_are_its_codes_then_rounded_box_means():
    """Roughness, metalness, occlusion: the file's 8-bit codes, the mips their means rounded to a code."""
    data = _data(srgb=False, shape=(4, 8))
    levels = data.mip_chain()
    assert levels[0] is data.codes and all(level.dtype == np.uint8 for level in levels)
    mean = data.codes.reshape(-1, 4).astype(float).mean(axis=0)
    assert np.all(np.abs(levels[-1][0, 0].astype(float) - mean) <= 0.5 + 1e-9)
    assert data.gpu_bytes() == int(4 * 8 * 4 * 4 / 3)


def test_colour_mips_are_srgb_bytes_averaged_in_linear_values():
    data = _data(srgb=True, shape=(2, 2))
    levels = data.mip_chain()
    assert levels[0] is data.codes and levels[1].dtype == np.uint8
    mean = data.texels.reshape(-1, 4).mean(axis=0)
    decoded = TextureData(levels[1], True, key="x").texels[0, 0]
    assert np.allclose(decoded, mean, atol=2.5 / 255)  # not the mean of the sRGB codes
    assert data.gpu_bytes() == int(2 * 2 * 4 * 4 / 3)


def test_swizzle_reads_channels_and_constants():
    codes = np.arange(2 * 4, dtype=np.uint8).reshape(1, 2, 4)
    assert swizzled(codes, None) is codes
    assert swizzled(codes, "1gb0").tolist() == [[[255, 1, 2, 0], [255, 5, 6, 0]]]
    assert swizzled(codes, "aaar").tolist() == [[[3, 3, 3, 0], [7, 7, 7, 4]]]


def test_gpu_samples_a_normal_map_at_float_precision(ctx):
    """A 2 × 2 normal map of x codes 100 and 102: its 1 × 1 mip, as the GPU samples it, is the mean of the unit
    vectors — the float16 chain keeps it; an 8-bit chain rounds it to a code (a normal tilted by 1/510 at every
    mip)."""
    import moderngl

    from reflets.textures import texture_for

    codes = np.array([[[100, 128, 255, 255], [102, 128, 255, 255]], [[102, 128, 255, 255], [100, 128, 255, 255]]],
                     np.uint8)  # fmt: skip
    data = TextureData(codes, False, key="checker", wrap=("clamp", "clamp"))
    texture = texture_for(ctx, data, normal_map=True)
    expected = data.mip_chain(normal_map=True)[1][0, 0, 0] * 255.0
    texture.use(0)
    program = ctx.program(
        vertex_shader="#version 330\nvoid main() { gl_Position = vec4(0.0, 0.0, 0.0, 1.0); gl_PointSize = 1.0; }",
        fragment_shader="#version 330\nuniform sampler2D t; out vec4 c;\n"
        "void main() { c = textureLod(t, vec2(0.5, 0.5), 1.0); }",
    )
    target = ctx.simple_framebuffer((1, 1), components=4, dtype="f4")
    target.use()
    program["t"] = 0
    ctx.vertex_array(program, []).render(mode=moderngl.POINTS, vertices=1)
    value = np.frombuffer(target.read(components=4, dtype="f4"), dtype=np.float32)
    assert abs(value[0] * 255.0 - expected) < 0.05, (value[0] * 255.0, expected)
    assert abs(expected - np.rint(expected)) > 0.2  # between two codes: what an 8-bit chain could not hold


def test_a_gltf_image_in_a_file_it_names_is_read_again_when_that_file_changes(tmp_path, monkeypatch):
    """An image a .gltf names by uri (or holds in its .bin) is cached by the stamps of those files too: an unchanged
    one is neither read nor hashed again (the reference looks textures up per batch), an edited image file is
    decoded again, and an edited .bin makes the document be read again."""
    import os
    import shutil
    from pathlib import Path

    from PIL import Image

    import reflets
    from reflets import textures
    from reflets.gltf_file import read_gltf
    from reflets.scene.geometry import mesh_data
    from reflets.textures import TextureRef, load_texture

    def touch(path: Path) -> None:
        stat = path.stat()
        os.utime(path, ns=(stat.st_atime_ns, stat.st_mtime_ns + 10**9))

    source = Path(__file__).parent / "data" / "gltf" / "SheenTest"
    for name in ("SheenTest.gltf", "SheenTest.bin", "sheen.png"):
        shutil.copy(source / name, tmp_path / name)
    ref = TextureRef(texture=tmp_path / "SheenTest.gltf", image=0)
    first = load_texture(ref, False)
    reads = []
    monkeypatch.setattr(textures, "texture_bytes", lambda r: reads.append(r) or TEXTURE_BYTES(r))
    assert load_texture(ref, False) is first and not reads  # unchanged: the cached texture, nothing read
    Image.fromarray(np.full((4, 4, 4), 77, np.uint8)).save(tmp_path / "sheen.png")
    touch(tmp_path / "sheen.png")
    again = load_texture(ref, False)
    assert again is not first and np.all(again.codes == 77) and len(reads) == 1
    document = read_gltf(tmp_path / "SheenTest.gltf")
    scene = reflets.load_scene(tmp_path / "SheenTest.gltf")
    vertices = mesh_data(scene, 0).positions.copy()
    blob = bytearray((tmp_path / "SheenTest.bin").read_bytes())
    view = document.doc.bufferViews[document.doc.accessors[document.doc.meshes[0].primitives[0].attributes.POSITION]
                                     .bufferView]  # fmt: skip
    positions = np.frombuffer(blob, np.float32, count=3, offset=view.byteOffset or 0)
    blob[view.byteOffset or 0 : (view.byteOffset or 0) + 12] = (positions + 1.0).astype(np.float32).tobytes()
    (tmp_path / "SheenTest.bin").write_bytes(bytes(blob))
    touch(tmp_path / "SheenTest.bin")
    assert read_gltf(tmp_path / "SheenTest.gltf") is not document
    assert not np.array_equal(mesh_data(scene, 0).positions, vertices)  # the mesh built again from the edited .bin
