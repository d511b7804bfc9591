"""Scripted editing sessions: a list of strokes (JSON) applied one after the other to a mesh's orientation
field — each stroke warps the current highlight tangents inside its brush (``tools.warp_targets``) and the
solver finds the field that follows (``solver.solve``). Behind ``reflets edit-highlights --strokes``."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np

from ..errors import ArgumentError
from .analysis import highlight_tangents
from .highlights import _prepared
from .solver import HighlightProblem, solve
from .tools import WARPS, Brush, warp_targets

STROKE_KEYS = {"tool", "centre", "radius", "stroke"}


def load_strokes(path: str | Path) -> list[dict]:
    """A JSON list of strokes: {"tool": "bend" | "expand", "centre": [x, y, z], "radius": r, "stroke": [x, y, z]}."""
    path = Path(path)
    try:
        strokes = json.loads(path.read_text(encoding="utf-8"))
    except FileNotFoundError:
        raise ArgumentError("file not found", file=path, field="--strokes") from None
    except (json.JSONDecodeError, UnicodeDecodeError) as exc:
        raise ArgumentError(f"not a JSON list of strokes: {exc}", file=path, field="--strokes") from None
    if not isinstance(strokes, list):
        raise ArgumentError("must be a JSON list of strokes", file=path, field="--strokes")
    for k, stroke in enumerate(strokes):
        if not isinstance(stroke, dict) or set(stroke) != STROKE_KEYS:
            raise ArgumentError(f"stroke {k} needs exactly {sorted(STROKE_KEYS)}", file=path, field=f"strokes[{k}]")
        if stroke["tool"] not in WARPS:
            allowed = ", ".join(WARPS)
            raise ArgumentError(
                f"unknown tool {stroke['tool']!r}; allowed: {allowed}", file=path, field=f"strokes[{k}]"
            )
        if not float(stroke["radius"]) > 0:
            raise ArgumentError("radius must be positive", file=path, field=f"strokes[{k}].radius")
    return strokes


def apply_strokes(
    scene, index: int, strokes: list[dict], light: int | None = None, k: int = 2, iterations: int = 20
) -> dict[str, np.ndarray]:
    """The orientation field after the strokes (``u`` (V, 3) in the mesh's own coordinates and order, what a
    material's ``orientation`` file holds) and each stroke's energy at its start and end (``energy`` (S, 2))."""
    data, mesh, inverse, h, u = _prepared(scene, index, light)
    problem = HighlightProblem(mesh, h, k)
    phi = mesh.angles(u)
    energies = []
    for stroke in strokes:
        ell, degenerate = highlight_tangents(mesh, phi, h, k, w=problem.w)
        brush = Brush(np.asarray(stroke["centre"], float), float(stroke["radius"]), np.asarray(stroke["stroke"], float))
        targets, inside = warp_targets(mesh, ell, brush, stroke["tool"])
        result = solve(problem, phi, targets * ~degenerate[:, None], inside, iterations=iterations)
        phi = result.phi
        energies.append((result.energy[0], result.energy[-1]))
    world = mesh.field(phi)[inverse]
    linear = scene.mesh[index].transform.matrix()[:3, :3]
    local = world @ np.linalg.inv(linear).T
    local /= np.maximum(np.linalg.norm(local, axis=1, keepdims=True), 1e-300)
    return {"u": local, "energy": np.asarray(energies).reshape(-1, 2)}
