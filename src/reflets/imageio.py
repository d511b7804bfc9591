"""Reading and writing images, and tone mapping them for display.

Conventions shared by the whole library: an image is a ``float32`` NumPy array of shape ``(H, W, 3)``
holding linear (scene-referred) RGB radiance, row 0 being the top row. HDR formats (``.exr``, ``.hdr``,
``.npy``) store those values unchanged; 8-bit formats (``.png``, ``.jpg``) are display-referred and are
converted through the exact piecewise sRGB transfer function on the way in and out.

Writes are atomic: the bytes are encoded in memory, written to a temporary file in the destination directory
and moved into place with :func:`os.replace`, so a failure never leaves a half-written file behind and never
destroys a file that was already there.

OpenEXR and Pillow are imported inside the functions that need them, so importing this module stays cheap.
"""

from __future__ import annotations

import io
import math
from collections.abc import Iterable
from pathlib import Path

import numpy as np

from reflets.errors import ArgumentError, ImageError, OutputError
from reflets.outputs import atomic_write, check_output_path

__all__ = [
    "IMAGE_READ_EXTENSIONS",
    "IMAGE_WRITE_EXTENSIONS",
    "PNG_BIT_DEPTHS",
    "TONEMAP_MODES",
    "linear_to_srgb",
    "read_image",
    "srgb_to_linear",
    "tonemap",
    "write_image",
]

#: Extensions :func:`read_image` understands (compared case-insensitively).
IMAGE_READ_EXTENSIONS: tuple[str, ...] = (".exr", ".hdr", ".pic", ".npy", ".png", ".jpg", ".jpeg")
#: Extensions :func:`write_image` can produce (compared case-insensitively).
IMAGE_WRITE_EXTENSIONS: tuple[str, ...] = (".exr", ".hdr", ".npy", ".png")
#: Tone-mapping curves accepted by :func:`tonemap` and :func:`write_image`.
TONEMAP_MODES: tuple[str, ...] = ("srgb", "aces")
#: Bits per channel :func:`write_image` can write to a PNG.
PNG_BIT_DEPTHS: tuple[int, ...] = (8, 16)
#: Bytes per pixel :func:`write_image` allocates beyond the float32 image it is given, by format (measured on
#: 2048² noise, the least compressible: PNG 111 (8 and 16 bits: the float64 tone-mapping temporaries), HDR 88.9,
#: EXR 16.0, NPY 3.8), rounded up: what reflets.resources checks before a render it will write
WRITE_BYTES_PER_PIXEL: dict[str, int] = {".png": 112, ".hdr": 90, ".exr": 16, ".npy": 4}

#: exposure in stops, either way: beyond it 2**exposure over/underflows float32 for any sensible image
MAX_EXPOSURE = 64.0
# Radiance's own writer stores colours below this as (0, 0, 0, 0); it also keeps the exponent byte far from
# the values that would make a flat scanline look like a run-length-encoded one.
_RGBE_MIN = 1e-32
# Largest value the RGBE exponent byte can hold (2**127 would need exponent byte 256).
_RGBE_MAX = 1e38


# --------------------------------------------------------------------------------------------------- sRGB


def srgb_to_linear(values: np.ndarray | float) -> np.ndarray:
    """Decode sRGB-encoded values in [0, 1] to linear light with the exact piecewise IEC 61966-2-1 curve.

    The piecewise form (linear toe below 0.04045) is used rather than a pure 2.2 gamma so that 8-bit files
    round-trip exactly through :func:`linear_to_srgb`. Returns ``float64``.
    """
    x = np.asarray(values, dtype=np.float64)
    return np.where(x <= 0.04045, x / 12.92, ((np.maximum(x, 0.04045) + 0.055) / 1.055) ** 2.4)


def linear_to_srgb(values: np.ndarray | float) -> np.ndarray:
    """Encode linear values with the exact piecewise sRGB OETF (inverse of :func:`srgb_to_linear`).

    Values are not clamped; :func:`tonemap` clamps before quantising. Returns ``float64``.
    """
    x = np.asarray(values, dtype=np.float64)
    return np.where(x <= 0.0031308, 12.92 * x, 1.055 * np.maximum(x, 0.0031308) ** (1.0 / 2.4) - 0.055)


def _aces_narkowicz(x: np.ndarray) -> np.ndarray:
    """ACES filmic curve fitted by K. Narkowicz ("ACES Filmic Tone Mapping Curve", blog post, 2016).

    The fit is pre-exposed (1.0 maps to about 0.8), so it is applied as published, without the 0.6 factor
    that would reproduce the original ACES RRT+ODT exposure.
    """
    return (x * (2.51 * x + 0.03)) / (x * (2.43 * x + 0.59) + 0.14)


def tonemap(image: np.ndarray, exposure: float = 0.0, mode: str = "srgb") -> np.ndarray:
    """Map linear radiance to 8-bit sRGB for display.

    Parameters
    ----------
    image : array (H, W, 3) or (H, W)
        Linear radiance; must be finite (a NaN would otherwise silently become an arbitrary byte).
    exposure : float
        Stops of exposure: values are multiplied by ``2**exposure`` before the curve, in [-64, 64].
    mode : {"srgb", "aces"}
        ``"srgb"`` clamps to [0, 1] then applies the sRGB OETF (what a plain viewer shows);
        ``"aces"`` first compresses highlights with Narkowicz's ACES fit, so bright HDR content keeps detail.

    Returns
    -------
    ndarray of uint8, shape (H, W, 3)
    """
    return _tonemap_checked(_as_rgb(image), _check_exposure(exposure), _check_tonemap(mode))


def _tonemap_checked(rgb: np.ndarray, stops: float, curve: str, bit_depth: int = 8) -> np.ndarray:
    """uint8 or uint16 sRGB codes (``bit_depth`` 8 or 16)."""
    # The upper clamp keeps the rational ACES fit away from inf/inf; both curves saturate long before 1e6.
    x = np.clip(rgb.astype(np.float64) * 2.0**stops, 0.0, 1e6)
    if curve == "aces":
        x = _aces_narkowicz(x)
    encoded = linear_to_srgb(np.clip(x, 0.0, 1.0))
    levels, dtype = (65535.0, np.uint16) if bit_depth == 16 else (255.0, np.uint8)
    return np.round(np.clip(encoded, 0.0, 1.0) * levels).astype(dtype)


# --------------------------------------------------------------------------------------------- validation


def _check_exposure(exposure: float, file: str | Path | None = None) -> float:
    try:
        stops = float(exposure)
    except (TypeError, ValueError):
        stops = math.nan
    if not math.isfinite(stops) or abs(stops) > MAX_EXPOSURE:
        raise ArgumentError(
            f"exposure must be a finite number of stops in [-{MAX_EXPOSURE:g}, {MAX_EXPOSURE:g}], got {exposure!r}",
            file=file,
            field="exposure",
        )
    return stops


def _check_bit_depth(bit_depth: int, file: str | Path | None = None) -> int:
    if isinstance(bit_depth, bool) or bit_depth not in PNG_BIT_DEPTHS:
        raise ArgumentError(
            f"PNG bit depth must be one of {', '.join(map(str, PNG_BIT_DEPTHS))}, got {bit_depth!r}",
            file=file,
            field="bit_depth",
        )
    return int(bit_depth)


def _check_tonemap(mode: str, file: str | Path | None = None) -> str:
    name = mode.lower() if isinstance(mode, str) else mode
    if name not in TONEMAP_MODES:
        raise ArgumentError(
            f"unknown tone-mapping mode {mode!r}; allowed: {', '.join(TONEMAP_MODES)}",
            file=file,
            field="tonemap",
        )
    return name


def _as_rgb(image: np.ndarray, file: str | Path | None = None) -> np.ndarray:
    """Validate an image to be written or displayed; return it as contiguous float32 (H, W, 3)."""
    arr = np.asarray(image)
    if arr.dtype.kind not in "fiu":
        raise ArgumentError(f"image dtype {arr.dtype} is not a real number type", file=file, field="image")
    if arr.ndim == 2:
        arr = np.repeat(arr[:, :, None], 3, axis=2)
    if arr.ndim != 3 or arr.shape[2] != 3 or arr.shape[0] == 0 or arr.shape[1] == 0:
        raise ArgumentError(
            f"image shape {tuple(np.shape(image))} is not allowed; expected (H, W, 3) or (H, W), H, W >= 1",
            file=file,
            field="image",
        )
    rgb = np.ascontiguousarray(arr, dtype=np.float32)
    bad = int(rgb.size - np.count_nonzero(np.isfinite(rgb)))
    if bad:
        raise ArgumentError(
            f"image has {bad} non-finite value(s) (NaN/inf or beyond float32); only finite ones are allowed",
            file=file,
            field="image",
        )
    return rgb


def _extension(path: Path) -> str:
    return path.suffix.lower()


def _allowed_text(allowed: Iterable[str]) -> str:
    return ", ".join(allowed)


# ------------------------------------------------------------------------------------------------ reading


def read_image(path: str | Path) -> np.ndarray:
    """Read an image file as linear float32 RGB of shape (H, W, 3), row 0 at the top.

    The format is chosen by extension (see :data:`IMAGE_READ_EXTENSIONS`):

    * ``.exr``: channels R, G, B of the first part (half, float or uint → float32); a single-channel ``Y``
      (luminance) file is replicated to three channels.
    * ``.hdr`` / ``.pic``: Radiance RGBE, decoded by a small NumPy reader (flat and new-style run-length
      scanlines; ``EXPOSURE=`` header values are divided out, as the format specifies).
    * ``.npy``: an array of shape (H, W), (H, W, 3) or (H, W, 4) (alpha is dropped).
    * ``.png`` / ``.jpg``: 1- to 16-bit grey, grey + alpha, palette, RGB, RGBA, decoded to linear at full
      precision (sRGB, or the power law of a gAMA chunk far from 1/2.2); alpha is dropped, not composited.

    Raises
    ------
    ImageError
        The file is missing, unreadable, corrupt, has an unsupported layout, or an unknown extension.
    """
    p = Path(path)
    ext = _extension(p)
    if ext not in IMAGE_READ_EXTENSIONS:
        raise ImageError(
            f"unsupported image extension {ext or '(none)'!r}; allowed: {_allowed_text(IMAGE_READ_EXTENSIONS)}",
            file=p,
        )
    if not p.exists():
        raise ImageError("image file does not exist", file=p)
    if not p.is_file():
        raise ImageError("is not a regular file", file=p)
    if ext == ".exr":
        rgb = _read_exr(p)
    elif ext in (".hdr", ".pic"):
        rgb = _read_rgbe(p)
    elif ext == ".npy":
        rgb = _read_npy(p)
    else:
        rgb = _read_ldr(p)
    return np.ascontiguousarray(rgb, dtype=np.float32)


def _read_exr(path: Path) -> np.ndarray:
    import OpenEXR

    try:
        channels = OpenEXR.File(str(path), separate_channels=True).channels()
        planes = {name: np.asarray(ch.pixels) for name, ch in channels.items()}
    except Exception as exc:  # the bindings raise RuntimeError or ValueError for damaged files
        raise ImageError(f"cannot read OpenEXR data ({exc})", file=path) from exc
    if all(c in planes for c in "RGB"):
        names = ("R", "G", "B")
    elif "Y" in planes:
        names = ("Y", "Y", "Y")
    else:
        raise ImageError(f"OpenEXR channels {sorted(planes)} are not supported; need R, G, B or a single Y", file=path)
    shapes = {planes[n].shape for n in names}
    if len(shapes) != 1 or len(next(iter(shapes))) != 2:
        raise ImageError(f"OpenEXR channels have differing or subsampled shapes {sorted(shapes)}", file=path)
    return np.stack([planes[n].astype(np.float32) for n in names], axis=2)


def _read_npy(path: Path) -> np.ndarray:
    try:
        arr = np.load(path, allow_pickle=False)
    except Exception as exc:  # ValueError, OSError, EOFError, UnpicklingError depending on the damage
        raise ImageError(f"cannot read NumPy array ({exc})", file=path) from exc
    if not isinstance(arr, np.ndarray) or arr.dtype.kind not in "fiu":
        raise ImageError(f"NumPy data of dtype {getattr(arr, 'dtype', '?')} is not a real-valued image", file=path)
    if arr.ndim == 2:
        arr = arr[:, :, None]
    if arr.ndim != 3 or arr.shape[2] not in (1, 3, 4) or 0 in arr.shape:
        raise ImageError(f"array shape {arr.shape} is not allowed; expected (H, W), (H, W, 3) or (H, W, 4)", file=path)
    if arr.shape[2] == 1:
        arr = np.repeat(arr, 3, axis=2)
    return arr[:, :, :3].astype(np.float32)


def _read_ldr(path: Path) -> np.ndarray:
    """PNG and JPEG: display-referred codes → linear. Pillow opens every file (its chunks, ``gAMA`` / ``sRGB`` /
    ``iCCP`` among them, and its decompression-bomb check); 16-bit PNGs are decoded by pypng, because Pillow keeps
    only grey ones at 16 bits (``convert("RGB")`` drops the low byte of RGB / RGBA / grey + alpha ones)."""
    from PIL import Image

    try:
        data = path.read_bytes()
    except OSError as exc:
        raise ImageError(f"cannot read file ({exc.strerror or exc})", file=path) from exc
    try:
        with Image.open(io.BytesIO(data)) as im:
            gamma = im.info.get("gamma") if "srgb" not in im.info and "icc_profile" not in im.info else None
            if data.startswith(_PNG_SIGNATURE) and data[12:16] == b"IHDR" and data[24] == 16:  # IHDR bit depth
                encoded = _read_png16(data)
            else:  # a palette with transparency goes through RGBA, as Pillow asks; alpha is dropped after
                full = im.convert("RGBA") if im.mode in ("P", "PA") else im.convert("RGB")
                encoded = np.asarray(full, dtype=np.float64)[:, :, :3] / 255.0
    except Exception as exc:  # UnidentifiedImageError, OSError (truncated), DecompressionBombError, png errors...
        raise ImageError(f"cannot decode image ({exc})", file=path) from exc
    return _decode_transfer(np.clip(encoded, 0.0, 1.0), gamma)


_PNG_SIGNATURE = b"\x89PNG\r\n\x1a\n"


def _read_png16(data: bytes) -> np.ndarray:
    """Codes in [0, 1] (H, W, 3) of a 16-bit PNG of any colour type (alpha dropped)."""
    import png

    width, height, rows, info = png.Reader(bytes=data).asDirect()  # palette and tRNS expanded, sBIT honoured
    planes = info["planes"]
    codes = np.vstack([np.asarray(row, dtype=np.uint16) for row in rows]).reshape(height, width, planes)
    colour = codes[:, :, :3] if planes >= 3 else np.repeat(codes[:, :, :1], 3, axis=2)
    return colour.astype(np.float64) / float(2 ** info["bitdepth"] - 1)


def _decode_transfer(encoded: np.ndarray, gamma: float | None) -> np.ndarray:
    """Codes → linear light: sRGB, unless the file carries a gAMA far from sRGB's 1/2.2 (gAMA = 1.0: linear
    data, as some tools write for data images; 1/1.8: an old Mac gamma) — then its power law, as PNG says."""
    if gamma is not None and gamma > 0.0 and abs(gamma - 1.0 / 2.2) > 0.01:
        return encoded ** (1.0 / gamma)
    return srgb_to_linear(encoded)


# --------------------------------------------------------------------------------------- Radiance RGBE


def _read_rgbe(path: Path) -> np.ndarray:
    """Decode a Radiance RGBE file (Greg Ward's format, as described in Graphics Gems II and ``color.c``)."""
    try:
        data = path.read_bytes()
    except OSError as exc:
        raise ImageError(f"cannot read file ({exc.strerror or exc})", file=path) from exc
    if not data.startswith(b"#?"):
        raise ImageError("not a Radiance HDR file (missing '#?' signature)", file=path)

    # Header: text lines up to the first empty line.
    pos, exposure, fmt = 0, 1.0, None
    while True:
        end = data.find(b"\n", pos)
        if end < 0:
            raise ImageError("truncated Radiance header (no empty line before the resolution)", file=path)
        line = data[pos:end].strip()
        pos = end + 1
        if not line:
            break
        if line.startswith(b"FORMAT="):
            fmt = line[len(b"FORMAT=") :].strip()
        elif line.startswith(b"EXPOSURE="):
            try:
                exposure *= float(line[len(b"EXPOSURE=") :])
            except ValueError:
                exposure = math.nan
    if fmt not in (None, b"32-bit_rle_rgbe"):
        raise ImageError(
            f"unsupported Radiance FORMAT={fmt.decode(errors='replace')}; allowed: 32-bit_rle_rgbe", file=path
        )
    if not (math.isfinite(exposure) and exposure > 0.0):
        raise ImageError("Radiance EXPOSURE header must be a positive number", file=path)

    # Resolution line: "-Y H +X W" is the standard top-to-bottom, left-to-right order.
    end = data.find(b"\n", pos)
    if end < 0:
        raise ImageError("truncated Radiance file (no pixel data after the header)", file=path)
    tokens = data[pos:end].split()
    try:
        ysign, height, xsign, width = tokens[0], int(tokens[1]), tokens[2], int(tokens[3])
    except (IndexError, ValueError):
        ysign = xsign = b""
        height = width = 0
    valid = ysign in (b"-Y", b"+Y") and xsign in (b"+X", b"-X") and height >= 1 and width >= 1
    if len(tokens) != 4 or not valid:
        shown = b" ".join(tokens).decode(errors="replace")
        raise ImageError(f"unsupported Radiance resolution line {shown!r}; expected '-Y H +X W'", file=path)
    pos = end + 1

    try:
        rgbe = _decode_rgbe_scanlines(data, pos, height, width)
    except (IndexError, ValueError) as exc:
        raise ImageError(f"corrupt or truncated Radiance pixel data ({exc})", file=path) from exc
    if ysign == b"+Y":
        rgbe = rgbe[::-1]
    if xsign == b"-X":
        rgbe = rgbe[:, ::-1]

    # Radiance decodes to the centre of the quantisation bin: (m + 0.5) * 2**(e - 136); e == 0 means black.
    e = rgbe[:, :, 3].astype(np.int32)
    scale = np.where(e > 0, np.ldexp(1.0, e - 136), 0.0) / exposure
    return (rgbe[:, :, :3] + 0.5) * scale[:, :, None]


def _decode_rgbe_scanlines(data: bytes, pos: int, height: int, width: int) -> np.ndarray:
    """Return (H, W, 4) uint8 RGBE from flat and/or new-style run-length-encoded scanlines."""
    rle_width = 8 <= width <= 0x7FFF  # the only widths for which Radiance ever writes RLE scanlines
    # Reject impossible sizes before allocating: even all-run RLE needs 4 + 4 * 2 * ceil(W / 127) bytes a row.
    min_row = 4 + 8 * -(-width // 127) if rle_width else 4 * width
    if height * min_row > len(data) - pos:
        raise ValueError(f"{len(data) - pos} bytes cannot hold {height} scanlines of width {width}")
    out = np.empty((height, width, 4), dtype=np.uint8)
    for y in range(height):
        head = data[pos : pos + 4]
        if len(head) < 4:
            raise ValueError(f"scanline {y} is missing")
        if rle_width and head[0] == 2 and head[1] == 2 and not head[2] & 0x80:
            if (head[2] << 8 | head[3]) != width:
                raise ValueError(f"scanline {y} declares width {head[2] << 8 | head[3]}, not {width}")
            pos += 4
            row = bytearray(4 * width)  # planar: all R, then all G, B, E
            for c in range(4):
                o, stop = c * width, (c + 1) * width
                while o < stop:
                    count = data[pos]
                    if count > 128:  # run: one byte repeated (count - 128) times
                        count -= 128
                        if o + count > stop:
                            raise ValueError(f"run overruns scanline {y}")
                        row[o : o + count] = bytes((data[pos + 1],)) * count
                        pos += 2
                    else:  # literal: the next `count` bytes
                        chunk = data[pos + 1 : pos + 1 + count]
                        if count == 0 or o + count > stop or len(chunk) != count:
                            raise ValueError(f"bad literal packet in scanline {y}")
                        row[o : o + count] = chunk
                        pos += 1 + count
                    o += count
            out[y] = np.frombuffer(bytes(row), dtype=np.uint8).reshape(4, width).T
        else:  # flat: W pixels of 4 bytes
            chunk = data[pos : pos + 4 * width]
            if len(chunk) != 4 * width:
                raise ValueError(f"scanline {y} is truncated")
            out[y] = np.frombuffer(chunk, dtype=np.uint8).reshape(width, 4)
            pos += 4 * width
    return out


def _encode_rgbe(rgb: np.ndarray) -> bytes:
    """Encode float RGB as a Radiance file (header + scanlines).

    Negative values cannot be represented and are stored as 0. Scanlines use the new-style run-length format
    with literal packets only: valid for every reader, under 1 % larger than flat data, and (unlike flat
    data) never mistaken for an RLE scanline header. Widths outside [8, 32767] are written flat, as Radiance
    does.
    """
    height, width = rgb.shape[:2]
    x = np.clip(rgb.astype(np.float64), 0.0, _RGBE_MAX)
    peak = x.max(axis=2)
    mant, exp = np.frexp(peak)  # peak = mant * 2**exp with mant in [0.5, 1)
    visible = peak >= _RGBE_MIN
    scale = np.divide(mant * 256.0, peak, out=np.zeros_like(peak), where=visible)
    rgbe = np.zeros((height, width, 4), dtype=np.uint8)
    rgbe[:, :, :3] = np.minimum(np.floor(x * scale[:, :, None]), 255.0)
    rgbe[:, :, 3] = np.where(visible, exp + 128, 0)

    header = f"#?RADIANCE\n# written by reflets\nFORMAT=32-bit_rle_rgbe\n\n-Y {height} +X {width}\n".encode()
    if not 8 <= width <= 0x7FFF:
        return header + rgbe.tobytes()
    planar = rgbe.transpose(0, 2, 1)  # (H, 4, W): each channel of a scanline is encoded separately
    full, rest = divmod(width, 128)
    pieces = []
    if full:
        blocks = planar[:, :, : full * 128].reshape(height, 4, full, 128)
        counts = np.full((height, 4, full, 1), 128, dtype=np.uint8)
        pieces.append(np.concatenate([counts, blocks], axis=3).reshape(height, 4, full * 129))
    if rest:
        counts = np.full((height, 4, 1), rest, dtype=np.uint8)
        pieces.append(np.concatenate([counts, planar[:, :, full * 128 :]], axis=2))
    body = np.concatenate(pieces, axis=2).reshape(height, -1)
    starts = np.tile(np.array([2, 2, width >> 8, width & 0xFF], dtype=np.uint8), (height, 1))
    return header + np.concatenate([starts, body], axis=1).tobytes()


# ------------------------------------------------------------------------------------------------ writing


def write_image(
    path: str | Path, image: np.ndarray, *, exposure: float = 0.0, tonemap: str = "srgb", bit_depth: int = 8
) -> Path:
    """Write an image atomically; the format follows the extension (:data:`IMAGE_WRITE_EXTENSIONS`).

    * ``.exr``: float32 R, G, B with lossless ZIP compression (exact round trip).
    * ``.npy``: float32 (H, W, 3) (exact round trip).
    * ``.hdr``: Radiance RGBE (about 1 % relative precision, no negatives).
    * ``.png``: 8- or 16-bit (``bit_depth``) sRGB through the ``tonemap`` curve after ``exposure``. HDR formats
      store linear radiance untouched; ``exposure``, ``tonemap`` and ``bit_depth`` are still validated for
      them so typos are caught.

    Parameters
    ----------
    path : str or Path
    image : array (H, W, 3) or (H, W)
        Linear radiance; must be finite.
    exposure : float
        Stops applied before tone mapping (PNG only).
    tonemap : {"srgb", "aces"}
        Tone-mapping curve (PNG only).
    bit_depth : {8, 16}
        Bits per channel of a PNG; 16 keeps 1/65535 steps (references, smooth gradients), read back exactly by
        :func:`read_image`.

    Returns
    -------
    Path
        The path written.

    Raises
    ------
    OutputError
        Unknown extension, missing or unwritable directory, path is a directory, or the write failed.
    ArgumentError
        The image has a bad shape or non-finite values, or exposure/tonemap are invalid.
    """
    p = check_output_path(path, IMAGE_WRITE_EXTENSIONS)
    rgb = _as_rgb(image, file=p)
    stops = _check_exposure(exposure, file=p)
    curve = _check_tonemap(tonemap, file=p)
    depth = _check_bit_depth(bit_depth, file=p)
    ext = _extension(p)
    if ext == ".exr":
        payload = _encode_exr(rgb, p)
    elif ext == ".npy":
        buf = io.BytesIO()
        np.save(buf, rgb, allow_pickle=False)
        payload = buf.getvalue()
    elif ext == ".hdr":
        payload = _encode_rgbe(rgb)
    else:
        payload = _encode_png(_tonemap_checked(rgb, stops, curve, depth))
    atomic_write(p, payload)
    return p


def _encode_exr(rgb: np.ndarray, path: Path) -> bytes:
    import OpenEXR

    channels = {name: np.ascontiguousarray(rgb[:, :, i]) for i, name in enumerate("RGB")}
    header = {"compression": OpenEXR.ZIP_COMPRESSION, "type": OpenEXR.scanlineimage}
    buf = io.BytesIO()
    try:
        OpenEXR.File(header, channels).write(buf)
    except Exception as exc:  # encoding failures are reported by the bindings as RuntimeError
        raise OutputError(f"cannot encode OpenEXR data ({exc})", file=path) from exc
    return buf.getvalue()


def _encode_png(codes: np.ndarray) -> bytes:
    """uint8 codes through Pillow; uint16 RGB through pypng (Pillow cannot write 16-bit colour PNGs)."""
    buf = io.BytesIO()
    if codes.dtype == np.uint16:
        import png

        height, width = codes.shape[:2]
        rows = codes.reshape(height, width * 3)
        png.Writer(width, height, greyscale=False, bitdepth=16, compression=6).write(buf, rows)
    else:
        from PIL import Image

        Image.fromarray(codes).save(buf, format="PNG")
    return buf.getvalue()


def write_png8(path: str | Path, rgb8: np.ndarray) -> Path:
    """Write an already tone-mapped uint8 (H, W, 3) image (heat maps, thumbnails) atomically as PNG."""
    p = check_output_path(path, (".png",))
    rgb8 = np.asarray(rgb8)
    if rgb8.dtype != np.uint8 or rgb8.ndim != 3 or rgb8.shape[2] != 3:
        raise ArgumentError(f"expected uint8 (H, W, 3), got {rgb8.dtype} {rgb8.shape}", field="image", file=p)
    atomic_write(p, _encode_png(np.ascontiguousarray(rgb8)))
    return p
