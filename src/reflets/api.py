"""The public Python API: load a scene, render it with a technique, compare images."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np

from .errors import ArgumentError
from .scene import Scene, load_dict, load_scene
from .scene.model import MAX_IMAGE_SIDE


def as_scene(scene: Scene | str | Path | dict) -> Scene:
    """Accept a Scene, a path to a TOML file, or a dict in the scene-file structure."""
    if isinstance(scene, Scene):
        return scene
    if isinstance(scene, dict):
        return load_dict(scene)
    return load_scene(scene)


def check_size(size: tuple[int, int] | None) -> tuple[int, int] | None:
    if size is None:
        return None
    try:
        w, h = (int(v) for v in size)
    except (TypeError, ValueError):
        raise ArgumentError(f"expected (width, height), got {size!r}", field="size") from None
    if not (1 <= w <= MAX_IMAGE_SIDE and 1 <= h <= MAX_IMAGE_SIDE):
        raise ArgumentError(f"{w}x{h} is out of range; each side must be in 1..{MAX_IMAGE_SIDE}", field="size")
    return w, h


def render(
    scene: Scene | str | Path | dict,
    method: str | None = None,
    size: tuple[int, int] | None = None,
    seed: int = 0,
    spp: int | None = None,
    **params: Any,
) -> np.ndarray:
    """Render ``scene`` and return linear HDR radiance, float32 (H, W, 3), row 0 = top.

    Parameters
    ----------
    scene : Scene, path or dict
    method : technique name (``reflets.techniques.TECHNIQUES``); default: the scene's ``method`` or "forward"
    size : (width, height) overriding the camera's size
    seed : seed of every random choice of the technique (same seed, same image)
    spp : samples per pixel; default: the technique's own (1 for deterministic techniques, where spp = s²
        gives s×s anti-aliasing; one frame of ``samples`` for ``mc``)
    params : technique parameters (e.g. ``area_samples=16`` for "forward")
    """
    from .gpu import get_context
    from .techniques import DEFAULT_METHOD, get_technique

    scene = as_scene(scene)
    size = check_size(size)
    technique_cls = get_technique(method or scene.method or DEFAULT_METHOD)
    technique = technique_cls(get_context(), **params)
    try:
        technique.prepare(scene)
        return technique.render(size=size, seed=seed, spp=spp)
    finally:
        technique.release()


def compare(test: np.ndarray | str | Path, reference: np.ndarray | str | Path) -> dict[str, float]:
    """Error metrics of ``test`` against ``reference`` (arrays or image files): rmse, relmse, psnr,
    max_abs, flip."""
    from .imageio import read_image
    from .metrics import compare as _compare

    a = test if isinstance(test, np.ndarray) else read_image(test)
    b = reference if isinstance(reference, np.ndarray) else read_image(reference)
    return _compare(a, b)
