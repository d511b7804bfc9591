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


def validated(model, data, *, file: str | Path | None = None, field: str | None = None):
    """``model.model_validate(data)`` (a pydantic model of an input file: a board, camera intrinsics, strokes, an
    event script), or its first error as one ArgumentError naming the file, the option that gave it and the place
    in the file (``markers.3[2]``: key, then list index)."""
    from pydantic import ValidationError

    try:
        return model.model_validate(data)
    except ValidationError as exc:
        err = exc.errors(include_url=False)[0]
        place = "".join(f"[{p}]" if isinstance(p, int) else f".{p}" for p in err["loc"]).lstrip(".")
        msg = err["msg"].removeprefix("Value error, ").removeprefix("Assertion failed, ")
        got = repr(err.get("input"))
        got = got if len(got) <= 60 else got[:57] + "..."
        text = f"{msg[0].lower()}{msg[1:]}" if err["type"] in ("value_error", "assertion_error") else (
            f"{msg[0].lower()}{msg[1:]} (got {got})")  # fmt: skip
        raise ArgumentError(f"{place}: {text}" if place else text, file=file, field=field) from None


def read_model(model, path: str | Path, *, field: str, what: str):
    """A JSON input file read strictly (reflets.jsonio.read) and validated by ``model`` (:func:`validated`)."""
    from . import jsonio

    return validated(model, jsonio.read(path, field=field, what=what), file=path, field=field)
