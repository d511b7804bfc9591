"""Tests for reflets.imageio: format round trips, RGBE decoding, sRGB/ACES encoding, atomic writes, errors."""

from __future__ import annotations

import os
import re
import struct
import subprocess
import sys

import numpy as np
import pytest

from reflets import outputs
from reflets.errors import ArgumentError, ImageError, OutputError
from reflets.imageio import (
    IMAGE_READ_EXTENSIONS,
    IMAGE_WRITE_EXTENSIONS,
    linear_to_srgb,
    read_image,
    srgb_to_linear,
    tonemap,
    write_image,
)
from reflets.outputs import check_output_path


def _png_bytes_of(path):
    from PIL import Image

    with Image.open(path) as im:
        assert im.mode == "RGB"
        return np.asarray(im)


def _gray(values):
    """A (1, N, 3) grey image from a list of linear values."""
    v = np.asarray(values, dtype=np.float32)
    return np.repeat(v[None, :, None], 3, axis=2)


# ------------------------------------------------------------------------------------------- round trips


def test_exr_round_trip_is_bit_exact_for_large_and_tiny_values(tmp_path):
    rng = np.random.default_rng(20240601)
    image = rng.uniform(0.0, 1e4, size=(19, 23, 3)).astype(np.float32)
    image[:5] = (10.0 ** rng.uniform(-38, -3, size=(5, 23, 3))).astype(np.float32)  # tiny, incl. subnormal
    image[5, 0] = np.float32(1e-44)
    path = tmp_path / "hdr.exr"

    write_image(path, image)
    back = read_image(path)

    assert back.dtype == np.float32 and back.shape == image.shape
    np.testing.assert_array_equal(back.view(np.uint32), image.view(np.uint32))


def test_exr_is_written_with_zip_compression_and_rgb_channels(tmp_path):
    import OpenEXR

    path = tmp_path / "c.exr"
    write_image(path, np.ones((4, 5, 3), np.float32))

    exr = OpenEXR.File(str(path), separate_channels=True)
    assert exr.header()["compression"] == OpenEXR.ZIP_COMPRESSION
    assert sorted(exr.channels()) == ["B", "G", "R"]
    assert all(ch.pixels.dtype == np.float32 for ch in exr.channels().values())


def test_exr_single_channel_luminance_file_is_replicated_to_rgb(tmp_path):
    import OpenEXR

    rng = np.random.default_rng(5)
    y = rng.uniform(0.0, 100.0, size=(6, 7)).astype(np.float16)
    path = tmp_path / "lum.exr"
    OpenEXR.File({"compression": OpenEXR.ZIP_COMPRESSION, "type": OpenEXR.scanlineimage}, {"Y": y}).write(str(path))

    back = read_image(path)

    assert back.shape == (6, 7, 3) and back.dtype == np.float32
    for c in range(3):
        np.testing.assert_array_equal(back[:, :, c], y.astype(np.float32))


def test_npy_round_trip_is_exact(tmp_path):
    rng = np.random.default_rng(11)
    image = rng.uniform(-5.0, 5e3, size=(8, 9, 3)).astype(np.float32)
    path = tmp_path / "img.npy"

    write_image(path, image)

    np.testing.assert_array_equal(read_image(path), image)
    assert np.load(path).dtype == np.float32


def test_npy_reader_accepts_grayscale_and_drops_alpha(tmp_path):
    rng = np.random.default_rng(12)
    gray = rng.random((4, 5))
    rgba = rng.random((4, 5, 4))
    np.save(tmp_path / "gray.npy", gray)
    np.save(tmp_path / "rgba.npy", rgba)

    np.testing.assert_allclose(read_image(tmp_path / "gray.npy"), np.repeat(gray[:, :, None], 3, 2), rtol=1e-6)
    np.testing.assert_allclose(read_image(tmp_path / "rgba.npy"), rgba[:, :, :3], rtol=1e-6)


def test_npy_reader_rejects_an_array_that_is_not_an_image(tmp_path):
    np.save(tmp_path / "vec.npy", np.zeros(10))

    with pytest.raises(ImageError, match=r"vec\.npy: array shape \(10,\) is not allowed"):
        read_image(tmp_path / "vec.npy")


@pytest.mark.parametrize("width", [300, 5], ids=["rle-width", "flat-narrow-width"])
def test_hdr_round_trip_is_within_rgbe_precision(tmp_path, width):
    rng = np.random.default_rng(31)
    # Per-pixel magnitudes over seven decades; channels within a factor 2 of the pixel peak, so each channel
    # keeps at least 7 bits of mantissa in the shared-exponent encoding.
    magnitude = 10.0 ** rng.uniform(-3, 4, size=(13, width, 1))
    image = (magnitude * rng.uniform(0.5, 1.0, size=(13, width, 3))).astype(np.float32)
    path = tmp_path / "rt.hdr"

    write_image(path, image)
    back = read_image(path)

    assert back.shape == image.shape and back.dtype == np.float32
    np.testing.assert_allclose(back, image, rtol=0.01, atol=0)
    # Whatever the channel ratio, the absolute error is at most half a mantissa step of the pixel peak.
    peak = image.max(axis=2, keepdims=True)
    assert np.all(np.abs(back - image) <= peak / 256.0 * 1.0001)


def test_hdr_writer_stores_zero_and_negative_values_as_black(tmp_path):
    image = _gray([0.0, -3.0, 1.0]).repeat(4, axis=0)
    path = tmp_path / "z.hdr"

    write_image(path, image)

    np.testing.assert_array_equal(read_image(path)[:, :2], 0.0)


def _rgbe_value(m: int, e: int) -> float:
    """Radiance's decoding of one mantissa byte: centre of the quantisation bin, exponent bias 128 + 8."""
    return 0.0 if e == 0 else (m + 0.5) * 2.0 ** (e - 136)


def test_hdr_decodes_hand_made_rle_scanlines(tmp_path):
    # Two 8-pixel scanlines, new-style RLE: each scanline is 02 02 <width hi> <width lo>, then the R, G, B
    # and E components of all its pixels, each as packets: count > 128 is a run of (count - 128) copies of
    # the next byte, count <= 128 is that many literal bytes.
    width = 8
    r0, g0, b0, e0 = [128] * 8, [0, 16, 32, 48, 64, 80, 96, 112], [64] * 4 + [1, 2, 3, 4], [129] * 8
    r1, g1, b1, e1 = [200] * 8, [100] * 8, [50] * 8, [130] * 7 + [0]
    line0 = (
        bytes([2, 2, 0, width])
        + bytes([128 + 8, 128])  # R: run of 8
        + bytes([8, *g0])  # G: 8 literals
        + bytes([128 + 4, 64, 4, 1, 2, 3, 4])  # B: run of 4, then 4 literals
        + bytes([128 + 8, 129])  # E: run of 8
    )
    line1 = (
        bytes([2, 2, 0, width])
        + bytes([128 + 3, 200, 128 + 5, 200])  # R: two runs
        + bytes([128 + 8, 100])
        + bytes([2, 50, 50, 128 + 6, 50])  # B: 2 literals then a run of 6
        + bytes([128 + 7, 130, 1, 0])  # E: run of 7, then one literal 0 (black pixel)
    )
    header = b"#?RADIANCE\n# hand made\nFORMAT=32-bit_rle_rgbe\n\n-Y 2 +X 8\n"
    path = tmp_path / "rle.hdr"
    path.write_bytes(header + line0 + line1)

    image = read_image(path)

    expected = np.array(
        [
            [[_rgbe_value(r, e), _rgbe_value(g, e), _rgbe_value(b, e)] for r, g, b, e in zip(*rows, strict=True)]
            for rows in ((r0, g0, b0, e0), (r1, g1, b1, e1))
        ],
        dtype=np.float32,
    )
    assert image.shape == (2, 8, 3)
    np.testing.assert_array_equal(image, expected)
    assert image[0, 0, 0] == pytest.approx(128.5 / 128.0)  # (128 + 0.5) * 2**(129 - 136)
    np.testing.assert_array_equal(image[1, 7], 0.0)


def test_hdr_decodes_flat_scanlines_bottom_up_and_divides_out_exposure(tmp_path):
    pixels = [(128, 64, 32, 129), (255, 0, 0, 128), (0, 0, 0, 0)]  # 3 wide: too narrow for RLE, so flat
    top, bottom = b"".join(struct.pack("4B", *p) for p in pixels), bytes([128, 128, 128, 131]) * 3
    header = b"#?RGBE\nEXPOSURE=2.0\nFORMAT=32-bit_rle_rgbe\n\n+Y 2 +X 3\n"  # +Y: first scanline is the bottom
    path = tmp_path / "flat.pic"
    path.write_bytes(header + bottom + top)

    image = read_image(path)

    assert image.shape == (2, 3, 3)
    np.testing.assert_array_equal(image[0, 0], np.float32([128.5, 64.5, 32.5]) / 128 / 2)
    np.testing.assert_array_equal(image[0, 1], np.float32([255.5, 0.5, 0.5]) / 256 / 2)
    np.testing.assert_array_equal(image[0, 2], 0.0)
    np.testing.assert_array_equal(image[1], np.full((3, 3), 128.5 / 32 / 2, np.float32))


def test_hdr_truncated_pixel_data_raises_image_error(tmp_path):
    path = tmp_path / "cut.hdr"
    write_image(path, np.ones((10, 40, 3), np.float32))
    data = path.read_bytes()
    path.write_bytes(data[: len(data) - 100])

    with pytest.raises(ImageError, match=r"cut\.hdr: corrupt or truncated Radiance pixel data"):
        read_image(path)


def test_hdr_rejects_unsupported_format_header(tmp_path):
    path = tmp_path / "xyz.hdr"
    path.write_bytes(b"#?RADIANCE\nFORMAT=32-bit_rle_xyze\n\n-Y 1 +X 1\n\x80\x80\x80\x80")

    with pytest.raises(ImageError, match=r"FORMAT=32-bit_rle_xyze; allowed: 32-bit_rle_rgbe"):
        read_image(path)


# ------------------------------------------------------------------------------------------ 8-bit output


def test_png_srgb_encoding_of_known_values(tmp_path):
    path = tmp_path / "known.png"

    write_image(path, _gray([0.0, 1.0, 0.5, 2.0, -1.0, 0.0031308]))

    # 0.5 linear -> 1.055 * 0.5**(1/2.4) - 0.055 = 0.7354 -> 187.5 -> 188; out-of-range values are clamped.
    np.testing.assert_array_equal(_png_bytes_of(path)[0, :, 0], [0, 255, 188, 255, 0, 10])


def test_png_exposure_plus_one_doubles_linear_values(tmp_path):
    path = tmp_path / "exposed.png"

    write_image(path, _gray([0.25, 0.5, 0.0]), exposure=1.0)

    np.testing.assert_array_equal(_png_bytes_of(path)[0, :, 0], [188, 255, 0])
    np.testing.assert_array_equal(tonemap(_gray([0.25]), exposure=1.0), tonemap(_gray([0.5])))


def test_aces_tonemap_is_monotonic_and_below_white_for_moderate_values():
    x = np.linspace(0.0, 4.0, 401)
    aces = tonemap(_gray(x), mode="aces")[0, :, 0].astype(int)
    srgb = tonemap(_gray(x), mode="srgb")[0, :, 0].astype(int)

    assert aces[0] == 0
    assert np.all(np.diff(aces) >= 0) and aces[-1] > aces[len(x) // 4]
    assert aces.max() < 255  # highlights are compressed, not clipped ...
    assert srgb[x >= 1.0].min() == 255  # ... unlike the plain sRGB clamp


def test_aces_mode_in_write_image_matches_tonemap(tmp_path):
    rng = np.random.default_rng(8)
    image = rng.uniform(0.0, 20.0, size=(6, 7, 3)).astype(np.float32)
    path = tmp_path / "aces.png"

    write_image(path, image, tonemap="aces", exposure=-0.5)

    np.testing.assert_array_equal(_png_bytes_of(path), tonemap(image, exposure=-0.5, mode="aces"))


def test_png_reader_decodes_srgb_to_linear(tmp_path):
    from PIL import Image

    path = tmp_path / "in.png"
    Image.fromarray(np.array([[[0, 188, 255]]], dtype=np.uint8)).save(path)

    image = read_image(path)

    assert image.dtype == np.float32 and image.shape == (1, 1, 3)
    np.testing.assert_allclose(image[0, 0], [0.0, srgb_to_linear(188 / 255), 1.0], rtol=1e-6)
    assert image[0, 0, 1] == pytest.approx(0.5, abs=0.004)


def test_srgb_helpers_are_exact_piecewise_inverses():
    x = np.linspace(0.0, 1.0, 1001)

    np.testing.assert_allclose(srgb_to_linear(linear_to_srgb(x)), x, atol=1e-12)
    assert linear_to_srgb(0.002) == pytest.approx(12.92 * 0.002)
    assert srgb_to_linear(0.04) == pytest.approx(0.04 / 12.92)
    assert linear_to_srgb(1.0) == pytest.approx(1.0)
    # The two pieces meet at the breakpoint (the curve is continuous to ~1e-7).
    assert 12.92 * 0.0031308 == pytest.approx(1.055 * 0.0031308 ** (1 / 2.4) - 0.055, abs=1e-7)


def test_tonemap_rejects_unknown_mode_and_bad_exposure():
    with pytest.raises(ArgumentError, match=r"tonemap: unknown tone-mapping mode 'filmic'; allowed: srgb, aces"):
        tonemap(_gray([0.5]), mode="filmic")
    with pytest.raises(ArgumentError, match=r"exposure: exposure must be a finite number of stops"):
        tonemap(_gray([0.5]), exposure=float("nan"))


def test_grayscale_input_is_replicated_on_write(tmp_path):
    gray = np.random.default_rng(2).random((3, 4)).astype(np.float32)
    path = tmp_path / "g.npy"

    write_image(path, gray)

    np.testing.assert_array_equal(read_image(path), np.repeat(gray[:, :, None], 3, axis=2))


# ---------------------------------------------------------------------------------- validation, atomicity


def test_write_to_missing_directory_raises_output_error_and_creates_nothing(tmp_path):
    target = tmp_path / "missing" / "out.exr"

    with pytest.raises(OutputError, match=r"out\.exr: directory '.*missing' does not exist"):
        write_image(target, np.zeros((2, 2, 3), np.float32))

    assert not (tmp_path / "missing").exists()
    assert list(tmp_path.iterdir()) == []


def test_nan_image_is_rejected_and_existing_file_keeps_its_old_bytes(tmp_path):
    path = tmp_path / "keep.png"
    write_image(path, _gray([0.1, 0.2]))
    before = path.read_bytes()
    bad = _gray([0.1, np.nan])

    with pytest.raises(ArgumentError, match=r"keep\.png: image: image has 3 non-finite value\(s\)"):
        write_image(path, bad)

    assert path.read_bytes() == before
    assert [p.name for p in tmp_path.iterdir()] == ["keep.png"]


def test_infinite_values_are_rejected(tmp_path):
    with pytest.raises(ArgumentError, match=r"non-finite"):
        write_image(tmp_path / "inf.exr", _gray([np.inf]))
    assert list(tmp_path.iterdir()) == []


def test_failed_replace_keeps_existing_file_and_removes_temporary(tmp_path, monkeypatch):
    path = tmp_path / "old.npy"
    write_image(path, _gray([1.0]))
    before = path.read_bytes()

    def failing_replace(src, dst):
        raise OSError(28, "No space left on device")

    monkeypatch.setattr(outputs.os, "replace", failing_replace)
    with pytest.raises(OutputError, match=r"old\.npy: cannot write file \(No space left on device\)"):
        write_image(path, _gray([2.0]))

    assert path.read_bytes() == before
    assert [p.name for p in tmp_path.iterdir()] == ["old.npy"]


def test_unknown_extension_error_lists_allowed_ones(tmp_path):
    allowed = r"allowed: \.exr, \.hdr, \.npy, \.png"
    with pytest.raises(OutputError, match=r"out\.bmp: unsupported output extension '\.bmp'; " + allowed):
        write_image(tmp_path / "out.bmp", _gray([0.5]))
    with pytest.raises(ImageError, match=r"in\.tga: unsupported image extension '\.tga'; allowed: \.exr, "):
        read_image(tmp_path / "in.tga")
    assert list(tmp_path.iterdir()) == []
    assert set(IMAGE_WRITE_EXTENSIONS) <= set(IMAGE_READ_EXTENSIONS)


def test_bad_image_shape_raises_argument_error(tmp_path):
    with pytest.raises(ArgumentError, match=r"image shape \(2, 2, 4\) is not allowed; expected \(H, W, 3\)"):
        write_image(tmp_path / "x.exr", np.zeros((2, 2, 4), np.float32))


def test_writing_onto_a_directory_raises_output_error(tmp_path):
    (tmp_path / "dir.png").mkdir()

    with pytest.raises(OutputError, match=r"dir\.png: is a directory"):
        write_image(tmp_path / "dir.png", _gray([0.5]))


@pytest.mark.skipif(not hasattr(os, "geteuid") or os.geteuid() == 0, reason="root ignores permissions")
def test_unwritable_directory_raises_output_error(tmp_path):
    locked = tmp_path / "locked"
    locked.mkdir()
    locked.chmod(0o500)
    try:
        with pytest.raises(OutputError, match=r"is not writable"):
            write_image(locked / "x.exr", _gray([0.5]))
    finally:
        locked.chmod(0o700)


def test_check_output_path_validates_without_creating_anything(tmp_path):
    assert check_output_path(tmp_path / "render.EXR", IMAGE_WRITE_EXTENSIONS) == tmp_path / "render.EXR"
    assert check_output_path(tmp_path / "a.json", allowed=(".json",)) == tmp_path / "a.json"
    with pytest.raises(OutputError, match=r"allowed: \.json"):
        check_output_path(tmp_path / "a.png", allowed=("json",))
    with pytest.raises(OutputError, match=r"does not exist"):
        check_output_path(tmp_path / "no" / "a.png", IMAGE_WRITE_EXTENSIONS)
    assert list(tmp_path.iterdir()) == []


# ---------------------------------------------------------------------------------------- reading errors


def test_missing_file_raises_image_error(tmp_path):
    with pytest.raises(ImageError, match=r"absent\.exr: image file does not exist"):
        read_image(tmp_path / "absent.exr")


@pytest.mark.parametrize("name", ["bad.exr", "bad.hdr", "bad.npy", "bad.png", "bad.jpg"])
def test_corrupt_file_raises_image_error(tmp_path, name):
    path = tmp_path / name
    path.write_bytes(b"this is not an image at all")

    with pytest.raises(ImageError, match=re.escape(name) + ": "):
        read_image(path)


def test_truncated_exr_raises_image_error(tmp_path):
    path = tmp_path / "cut.exr"
    write_image(path, np.random.default_rng(4).random((32, 32, 3)).astype(np.float32))
    data = path.read_bytes()
    path.write_bytes(data[: len(data) // 2])

    with pytest.raises(ImageError, match=r"cut\.exr: cannot read OpenEXR data"):
        read_image(path)


def test_importing_the_module_does_not_load_heavy_packages():
    code = (
        "import sys, reflets.imageio, reflets.metrics; "
        "print(','.join(m for m in ('OpenEXR', 'PIL', 'flip_evaluator', 'matplotlib') if m in sys.modules))"
    )
    src = os.path.join(os.path.dirname(os.path.dirname(os.path.abspath(__file__))), "src")
    env = {**os.environ, "PYTHONPATH": src + os.pathsep + os.environ.get("PYTHONPATH", "")}
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, env=env, check=True)
    assert out.stdout.strip() == ""
