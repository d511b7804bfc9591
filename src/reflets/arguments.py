"""Checks of the arguments every entry point shares (the API, the CLI, the persistent renderer, the references):
a scene given as a Scene, a path or a dict; an image size; a sample count — each wrong value one clear error."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from .errors import ArgumentError
from .scene import Scene, load_dict, load_scene
from .scene.model import MAX_IMAGE_SIDE

#: the most samples per pixel one call takes (a progressive Renderer goes further call after call)
MAX_SPP = 1 << 16


def as_scene(scene: Scene | str | Path | dict) -> Scene:
    """Accept a Scene, a path to a TOML file, or a dict in the scene-file structure."""
    if isinstance(scene, Scene):
        return scene
    if isinstance(scene, dict):
        return load_dict(scene)
    return load_scene(scene)


def check_size(size: tuple[int, int] | None) -> tuple[int, int] | None:
    """None, or (width, height) with each side in 1…MAX_IMAGE_SIDE."""
    if size is None:
        return None
    try:
        w, h = (int(v) for v in size)
    except (TypeError, ValueError):
        raise ArgumentError(f"expected (width, height), got {size!r}", field="size") from None
    if not (1 <= w <= MAX_IMAGE_SIDE and 1 <= h <= MAX_IMAGE_SIDE):
        raise ArgumentError(f"{w}x{h} is out of range; each side must be in 1..{MAX_IMAGE_SIDE}", field="size")
    return w, h


def check_spp(spp) -> int | None:
    """None, or a whole number of samples per pixel in 1…MAX_SPP."""
    if spp is None:
        return None
    if isinstance(spp, bool) or not isinstance(spp, int | np.integer):
        raise ArgumentError(f"expected a whole number of samples per pixel, got {spp!r}", field="spp")
    if not 1 <= spp <= MAX_SPP:
        raise ArgumentError(f"{spp} is out of range; samples per pixel must be in 1..{MAX_SPP}", field="spp")
    return int(spp)


def read_json(path: str | Path, field: str, what: str, parse=lambda data: data):
    """``parse`` of a JSON file's content (an event script, strokes, a board, camera intrinsics), or a one-line
    error naming the file and the option: a missing file, invalid JSON, a missing key, a wrong shape."""
    import json

    path = Path(path)
    try:
        return parse(json.loads(path.read_text(encoding="utf-8")))
    except FileNotFoundError:
        raise ArgumentError("file not found", file=path, field=field) from None
    except (ValueError, KeyError, TypeError, IndexError, UnicodeDecodeError) as exc:
        raise ArgumentError(f"not {what} ({exc})", file=path, field=field) from None


def read_json_list(path: str | Path, field: str, what: str) -> list:
    """A JSON file holding a list (an event script, a list of strokes)."""

    def as_list(data):
        if not isinstance(data, list):
            raise TypeError("the file must hold a JSON list")
        return data

    return read_json(path, field, f"a JSON list of {what}", as_list)
