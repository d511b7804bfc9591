"""PNGs of every colour type and bit depth are read at full precision, and written at 16 bits on request.

The files are built byte by byte here (zlib + the PNG chunk layout), so the reader is checked against the PNG
specification rather than against the library that reads them.
"""

from __future__ import annotations

import struct
import zlib

import numpy as np
import pytest

from reflets.cli import main
from reflets.errors import ArgumentError
from reflets.imageio import linear_to_srgb, read_image, srgb_to_linear, write_image
from reflets.metrics import compare

GREY, RGB, PALETTE, GREY_ALPHA, RGBA = 0, 2, 3, 4, 6
PLANES = {GREY: 1, RGB: 3, PALETTE: 1, GREY_ALPHA: 2, RGBA: 4}


def _chunk(kind: bytes, body: bytes) -> bytes:
    return struct.pack(">I", len(body)) + kind + body + struct.pack(">I", zlib.crc32(kind + body) & 0xFFFFFFFF)


def png_bytes(codes: np.ndarray, colour_type: int, bit_depth: int, *, extra: bytes = b"", sub_filter=True) -> bytes:
    """A PNG of ``codes`` (H, W, planes) integers. Rows alternate filter 0 (none) and 1 (sub) when ``sub_filter``,
    so that the reader's unfiltering is exercised as well."""
    height, width, planes = codes.shape
    assert planes == PLANES[colour_type]
    dtype = ">u2" if bit_depth == 16 else ">u1"
    raw = codes.astype(dtype).reshape(height, -1).view(np.uint8).reshape(height, -1)
    bpp = planes * (2 if bit_depth == 16 else 1)
    lines = []
    for y, row in enumerate(raw):
        if sub_filter and y % 2:
            left = np.concatenate([np.zeros(bpp, np.uint8), row[:-bpp]])
            lines.append(b"\x01" + (row - left).astype(np.uint8).tobytes())
        else:
            lines.append(b"\x00" + row.tobytes())
    ihdr = struct.pack(">IIBBBBB", width, height, bit_depth, colour_type, 0, 0, 0)
    return (
        b"\x89PNG\r\n\x1a\n"
        + _chunk(b"IHDR", ihdr)
        + extra
        + _chunk(b"IDAT", zlib.compress(b"".join(lines)))
        + _chunk(b"IEND", b"")
    )


def _codes16(shape, seed=0) -> np.ndarray:
    return np.random.default_rng(seed).integers(0, 65536, size=shape, dtype=np.int64)


def _as_codes16(linear: np.ndarray) -> np.ndarray:
    return np.round(linear_to_srgb(linear.astype(np.float64)) * 65535.0).astype(np.int64)


@pytest.mark.parametrize(
    ("colour_type", "colour"),
    [(RGB, slice(0, 3)), (RGBA, slice(0, 3)), (GREY, [0, 0, 0]), (GREY_ALPHA, [0, 0, 0])],
    ids=["rgb", "rgba", "grey", "grey+alpha"],
)
def test_16_bit_pngs_keep_every_code(tmp_path, colour_type, colour):
    codes = _codes16((7, 9, PLANES[colour_type]))
    path = tmp_path / "in.png"
    path.write_bytes(png_bytes(codes, colour_type, 16))
    image = read_image(path)
    assert image.shape == (7, 9, 3) and image.dtype == np.float32
    np.testing.assert_array_equal(_as_codes16(image), codes[:, :, colour])  # alpha dropped, colour exact


def test_references_two_hundred_codes_apart_are_told_apart(tmp_path):
    """The issue's case: RGB references that differ by 200 / 65535 compared as identical (rmse 0) at 8 bits."""
    codes = np.full((8, 8, 3), 30000, dtype=np.int64)
    (tmp_path / "a.png").write_bytes(png_bytes(codes, RGB, 16))
    (tmp_path / "b.png").write_bytes(png_bytes(codes + 200, RGB, 16))
    a, b = read_image(tmp_path / "a.png"), read_image(tmp_path / "b.png")
    expected = srgb_to_linear(30200 / 65535) - srgb_to_linear(30000 / 65535)
    assert compare(b, a)["rmse"] == pytest.approx(expected, rel=1e-4)


def test_palette_png_with_transparency_is_exact(tmp_path):
    palette = np.array([[0, 0, 0], [255, 128, 1], [17, 34, 51], [250, 251, 252]], dtype=np.uint8)
    indices = np.random.default_rng(3).integers(0, 4, size=(5, 6, 1))
    extra = _chunk(b"PLTE", palette.tobytes()) + _chunk(b"tRNS", bytes([255, 0, 128, 255]))
    path = tmp_path / "palette.png"
    path.write_bytes(png_bytes(indices, PALETTE, 8, extra=extra, sub_filter=False))
    codes = np.round(linear_to_srgb(read_image(path).astype(np.float64)) * 255.0)
    np.testing.assert_array_equal(codes, palette[indices[:, :, 0]])


@pytest.mark.parametrize("bit_depth", [1, 2, 4, 8])
def test_low_bit_depth_grey_spans_the_full_range(tmp_path, bit_depth):
    top = 2**bit_depth - 1
    width = 8 // bit_depth * 2  # whole bytes per row
    values = np.arange(width) % (top + 1)
    packed = np.packbits(np.unpackbits(values.astype(np.uint8)[:, None], axis=1)[:, 8 - bit_depth :].ravel())
    ihdr = struct.pack(">IIBBBBB", width, 1, bit_depth, GREY, 0, 0, 0)
    data = b"\x89PNG\r\n\x1a\n" + _chunk(b"IHDR", ihdr) + _chunk(b"IDAT", zlib.compress(b"\x00" + packed.tobytes()))
    path = tmp_path / "grey.png"
    path.write_bytes(data + _chunk(b"IEND", b""))
    image = read_image(path)
    np.testing.assert_allclose(image[0, :, 1], srgb_to_linear(values / top), atol=1e-6)


def test_gamma_one_png_is_linear_data_and_srgb_chunk_wins(tmp_path):
    codes = np.array([[[0, 16384, 65535]]], dtype=np.int64)
    gamma_one = _chunk(b"gAMA", struct.pack(">I", 100000))
    (tmp_path / "linear.png").write_bytes(png_bytes(codes, RGB, 16, extra=gamma_one))
    np.testing.assert_allclose(read_image(tmp_path / "linear.png")[0, 0], codes[0, 0] / 65535.0, rtol=1e-6)
    with_srgb = gamma_one + _chunk(b"sRGB", b"\x00")  # sRGB overrides gAMA (PNG specification, 11.3.3.5)
    (tmp_path / "srgb.png").write_bytes(png_bytes(codes, RGB, 16, extra=with_srgb))
    np.testing.assert_allclose(read_image(tmp_path / "srgb.png")[0, 0], srgb_to_linear(codes[0, 0] / 65535.0))


def test_16_bit_write_round_trip_is_exact_to_one_code(tmp_path):
    linear = np.random.default_rng(5).random((33, 47, 3)).astype(np.float32) * 1.2  # some values clip at 1
    path = write_image(tmp_path / "out.png", linear, bit_depth=16)
    expected = _as_codes16(np.clip(linear, 0.0, 1.0))
    assert np.abs(_as_codes16(read_image(path)) - expected).max() <= 1
    eight = read_image(write_image(tmp_path / "out8.png", linear))
    assert np.abs(_as_codes16(eight) - expected).max() > 100  # what 16 bits are for


def test_cli_render_writes_16_bit_png(ctx, capsys, tmp_path, minimal_toml):
    exr, png = tmp_path / "r.exr", tmp_path / "r.png"
    for out, extra in ((exr, []), (png, ["--bit-depth", "16"])):
        assert main(["render", str(minimal_toml), "--size", "64x48", "-o", str(out), *extra]) == 0
    with open(png, "rb") as fh:
        assert fh.read(26)[24:26] == bytes([16, RGB])  # IHDR: 16 bits, truecolour
    expected = _as_codes16(np.clip(read_image(exr), 0.0, 1.0))
    assert np.abs(_as_codes16(read_image(png)) - expected).max() <= 1


@pytest.mark.parametrize("depth", [12, 0, True, "16"])
def test_bad_bit_depth_is_refused_before_writing(tmp_path, depth):
    with pytest.raises(ArgumentError, match=r"x\.png: bit_depth: PNG bit depth must be one of 8, 16"):
        write_image(tmp_path / "x.png", np.zeros((2, 2, 3)), bit_depth=depth)
    assert not list(tmp_path.iterdir())


def test_cli_refuses_bit_depth_outside_choices(capsys, tmp_path, minimal_toml):
    with pytest.raises(SystemExit) as info:
        main(["render", str(minimal_toml), "-o", str(tmp_path / "x.png"), "--bit-depth", "12"])
    assert info.value.code == 2 and "--bit-depth" in capsys.readouterr().err
