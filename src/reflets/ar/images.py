"""Camera images read by the ar commands (``ar track``, ``ar calibrate``, ``ar composite``, the image lists of
``ar run``): each one's size is read from its header and checked before it is decoded — a decompression bomb (a
few kilobytes of PNG that decode to gigabytes) is refused by name, not allocated — and a file Pillow cannot decode
(a directory, an empty file, a truncated PNG, text named .png) is one line naming it."""

from __future__ import annotations

import re
import struct
import warnings
import zlib
from collections.abc import Iterator, Sequence
from contextlib import contextmanager
from pathlib import Path

import numpy as np

from ..errors import ArgumentError
from ..scene.model import MAX_IMAGE_SIDE

#: the most pixels a frame may have, each side at most MAX_IMAGE_SIDE: 50 million (a 45-megapixel camera's
#: photographs fit, 8K video is 33 million) — under Pillow's own decompression-bomb limit (89 million), so that
#: this check, with its message, is the one a large image meets
MAX_FRAME_PIXELS = 50_000_000

#: what Pillow raises on a file it cannot decode: not an image or truncated (OSError, UnidentifiedImageError
#: among them), a broken chunk (SyntaxError, struct.error, zlib.error), a bad header value (ValueError, EOFError)
_DECODE_ERRORS = (OSError, ValueError, SyntaxError, EOFError, struct.error, zlib.error)


#: what a frame may be, as the errors say it
FRAME_LIMITS = f"a frame is at most {MAX_IMAGE_SIDE} pixels a side and {MAX_FRAME_PIXELS:,} in all"


def fits_a_frame(width: int, height: int) -> bool:
    """Whether an image of width × height is within MAX_IMAGE_SIDE a side and MAX_FRAME_PIXELS."""
    return 1 <= width <= MAX_IMAGE_SIDE and 1 <= height <= MAX_IMAGE_SIDE and width * height <= MAX_FRAME_PIXELS


def check_frame_size(width: int, height: int, **where) -> None:
    """A frame (or the intrinsics' size) that :func:`fits_a_frame` (``where``: the error's file or field)."""
    if not fits_a_frame(width, height):
        raise ArgumentError(f"is {width}x{height} pixels; {FRAME_LIMITS}", **where)


def check_intrinsics_size(width: int, height: int, size: tuple[int, int], **where) -> None:
    """A frame must be the size the intrinsics were calibrated at (``where``: the error's file or field)."""
    if (width, height) != tuple(size):
        raise ArgumentError(f"is {width}x{height}, the intrinsics are for {size[0]}x{size[1]}", **where)


def _one_line(exc: BaseException) -> str:
    return " ".join(str(exc).split()) or type(exc).__name__


@contextmanager
def _opened(path: Path) -> Iterator:
    """The Pillow image at ``path`` with only its header read, its size checked (nothing decoded yet)."""
    from PIL import Image

    if path.is_dir():
        raise ArgumentError("is a directory, expected an image", file=path)
    if not path.exists():
        raise ArgumentError("file not found", file=path)
    if not path.is_file():
        raise ArgumentError("is not a regular file, expected an image", file=path)
    if path.stat().st_size == 0:
        raise ArgumentError("is empty, expected an image", file=path)
    try:
        with warnings.catch_warnings():  # Pillow's bomb warning: what MAX_FRAME_PIXELS refuses below, with its name
            warnings.simplefilter("ignore", Image.DecompressionBombWarning)
            image = Image.open(path)
    except Image.DecompressionBombError as exc:
        count = re.search(r"\((\d+) pixels\)", str(exc))
        pixels = f"{int(count.group(1)):,} pixels" if count else "more pixels than Pillow opens"
        raise ArgumentError(f"is {pixels} (a decompression bomb?); {FRAME_LIMITS}", file=path) from None
    except Image.UnidentifiedImageError:
        raise ArgumentError("is not an image Pillow can read (PNG, JPEG, TIFF, BMP...)", file=path) from None
    except _DECODE_ERRORS as exc:
        raise ArgumentError(f"cannot read the image ({_one_line(exc)})", file=path) from None
    with image:
        check_frame_size(*image.size, file=path)
        yield image


def _pixels(image, mode: str, path: Path) -> np.ndarray:
    """The decoded frame as uint8 in ``mode``: a 16-bit grey image scaled to 8 bits (Pillow's convert would clip
    it at 255), a palette through RGBA (as Pillow asks when it has transparency)."""
    values = np.asarray(image) if image.mode in ("I", "F") else None  # older Pillows open 16-bit PNGs as "I"
    if values is not None and not (image.mode == "I" and values.min() >= 0 and values.max() <= 65535):
        raise ArgumentError(f"is a 32-bit image (Pillow mode {image.mode}); frames are 8 or 16 bits", file=path)
    if image.mode.startswith("I;16") or values is not None:
        grey = np.round(np.asarray(image, np.float64) / 257.0).astype(np.uint8)
        return grey if mode == "L" else np.repeat(grey[..., None], 3, axis=2)
    if image.mode in ("P", "PA"):
        image = image.convert("RGBA")
    return np.asarray(image.convert(mode))


def read_frame(name: str | Path, mode: str = "L") -> np.ndarray:
    """One camera image as a uint8 array (H, W) for ``mode="L"``, (H, W, 3) for ``"RGB"``; any problem is one
    ArgumentError naming the file."""
    path = Path(name)
    with _opened(path) as image:
        try:
            return _pixels(image, mode, path)
        except _DECODE_ERRORS as exc:
            raise ArgumentError(f"cannot decode the image ({_one_line(exc)})", file=path) from None


def frame_sizes(names: Sequence[str | Path]) -> list[tuple[int, int]]:
    """Each image's (width, height), from its header: checked (MAX_FRAME_PIXELS), none decoded."""
    sizes = []
    for name in names:
        with _opened(Path(name)) as image:
            sizes.append(image.size)
    return sizes


def read_frames(names: Sequence[str | Path], mode: str = "L", size: tuple[int, int] | None = None) -> list[np.ndarray]:
    """Camera images as uint8 arrays (:func:`read_frame`); ``size`` (width, height): what each must be (the
    intrinsics'). Every header is checked, and the memory all of them take, before the first is decoded."""
    from ..resources import check

    sizes = frame_sizes(names)
    if size is not None:
        for name, (width, height) in zip(names, sizes, strict=True):
            check_intrinsics_size(width, height, size, file=name)
    if sizes:
        channels = 1 if mode == "L" else 3
        # the frames, and the largest one's decoding: Pillow's image and its converted copy, RGBA at most
        estimate = sum(w * h for w, h in sizes) * channels + 8 * max(w * h for w, h in sizes)
        check("images", estimate, value=f"{len(sizes)} images", what=f"{channels} byte(s) a pixel each")
    return [read_frame(name, mode) for name in names]
