"""The public Python API: load a scene, render it with a technique, compare images."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np

from .arguments import check_spp
from .scene import Scene


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
    method : technique name (``reflets.techniques.TECHNIQUES``); default: the scene's ``method`` or "auto"
    size : (width, height) overriding the camera's size
    seed : seed of every random choice of the technique (same seed, same image)
    spp : samples per pixel; default: the technique's own (1 for deterministic techniques, where spp = s²
        gives s×s anti-aliasing; one frame of ``samples`` for ``mc``)
    params : technique parameters (e.g. ``area_samples=16`` for "forward")
    """
    from .gpu.context import get_context, turn
    from .renderer import Renderer

    spp = check_spp(spp)
    with turn(get_context()), Renderer(scene, method=method, size=size, **params) as renderer:
        return renderer.render(seed=seed, spp=spp)


def compare(test: np.ndarray | str | Path, reference: np.ndarray | str | Path) -> dict[str, float]:
    """Error metrics of ``test`` against ``reference`` (arrays or image files): rmse, relmse, psnr,
    max_abs, flip."""
    from .imageio import read_image
    from .metrics import compare as _compare

    a = test if isinstance(test, np.ndarray) else read_image(test)
    b = reference if isinstance(reference, np.ndarray) else read_image(reference)
    return _compare(a, b)
