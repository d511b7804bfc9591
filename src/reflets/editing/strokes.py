"""Scripted editing sessions: a list of strokes (JSON) applied one after the other to a mesh's orientation
field — each stroke warps the current highlight tangents inside its brush (``tools.warp_targets``) and the
solver finds the field that follows (``solver.solve``). Behind ``reflets edit-highlights --strokes``."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from ..errors import ArgumentError
from .analysis import highlight_tangents
from .highlights import _prepared
from .solver import HighlightProblem, solve
from .tools import WARPS, Brush, stencil, warp_targets

STROKE_KEYS = {"tool", "centre", "radius", "stroke"}


def load_strokes(path: str | Path) -> list[dict]:
    """A JSON list of strokes: {"tool": "bend" | "expand", "centre": [x, y, z], "radius": r, "stroke": [x, y, z]}."""
    from ..arguments import read_json_list

    path = Path(path)
    strokes = read_json_list(path, "--strokes", "strokes")
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


class EditSession:
    """A mesh's orientation field being edited stroke by stroke, with undo and redo: what a scripted session
    and the viewer's paint mode drive. The camera and light of the scene it was made from fix h."""

    def __init__(self, scene, index: int, light: int | None = None, k: int = 2, iterations: int = 20):
        self.index, self.k, self.iterations = index, k, iterations
        _, self.mesh, self.inverse, h, u = _prepared(scene, index, light)
        self.problem = HighlightProblem(self.mesh, h, k)
        self.h = h
        self.linear = scene.mesh[index].transform.matrix()[:3, :3]
        self.history = [self.mesh.angles(u)]  # φ after each stroke, the start first
        self.future: list[np.ndarray] = []
        self.energies: list[tuple[float, float]] = []

    @property
    def phi(self) -> np.ndarray:
        return self.history[-1]

    def stroke(self, tool: str, centre, radius: float, direction) -> tuple[float, float]:
        """Apply one stroke (a warp solved for, or the stencil); its tensor energy at the start and the end (zero
        for the stencil, which sets the field directly)."""
        brush = Brush(np.asarray(centre, float), float(radius), np.asarray(direction, float))
        if tool == "stencil":
            self.history.append(stencil(self.mesh, self.phi, self.h, brush))
            self.future.clear()
            self.energies.append((0.0, 0.0))
            return self.energies[-1]
        if tool not in WARPS:
            allowed = ", ".join([*WARPS, "stencil"])
            raise ArgumentError(f"unknown tool {tool!r}; allowed: {allowed}", field="stroke.tool")
        ell, degenerate = highlight_tangents(self.mesh, self.phi, self.h, self.k, w=self.problem.w)
        targets, inside = warp_targets(self.mesh, ell, brush, tool)
        result = solve(self.problem, self.phi, targets * ~degenerate[:, None], inside, iterations=self.iterations)
        self.history.append(result.phi)
        self.future.clear()
        self.energies.append((result.energy[0], result.energy[-1]))
        return self.energies[-1]

    def undo(self) -> bool:
        if len(self.history) < 2:
            return False
        self.future.append(self.history.pop())
        return True

    def redo(self) -> bool:
        if not self.future:
            return False
        self.history.append(self.future.pop())
        return True

    def field(self) -> np.ndarray:
        """u (V, 3) in the mesh's own coordinates and vertex order: what a material's ``orientation`` holds."""
        world = self.mesh.field(self.phi)[self.inverse]
        local = world @ np.linalg.inv(self.linear).T
        return local / np.maximum(np.linalg.norm(local, axis=1, keepdims=True), 1e-300)


def apply_strokes(
    scene, index: int, strokes: list[dict], light: int | None = None, k: int = 2, iterations: int = 20
) -> dict[str, np.ndarray]:
    """The orientation field after the strokes (``u`` (V, 3) in the mesh's own coordinates and order, what a
    material's ``orientation`` file holds) and each stroke's energy at its start and end (``energy`` (S, 2))."""
    session = EditSession(scene, index, light, k, iterations)
    for stroke in strokes:
        session.stroke(stroke["tool"], stroke["centre"], stroke["radius"], stroke["stroke"])
    return {"u": session.field(), "energy": np.asarray(session.energies).reshape(-1, 2)}
