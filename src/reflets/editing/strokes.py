"""Scripted editing sessions: a list of strokes (JSON) applied one after the other to a mesh's orientation
field — each stroke warps the current highlight tangents inside its brush (``tools.warp_targets``) and the
solver finds the field that follows (``solver.solve``). Behind ``reflets edit-highlights --strokes``."""

from __future__ import annotations

from pathlib import Path
from typing import Annotated

import numpy as np
from pydantic import BaseModel, ConfigDict, Field, Strict, ValidationInfo, field_validator

from ..errors import ArgumentError
from ..quantities import JsonNumber as Number
from ..quantities import Positive
from .analysis import highlight_tangents
from .highlights import _prepared
from .solver import HighlightProblem, check_iterations, solve
from .tools import TOOLS, WARPS, Brush, BrushError, stencil, warp_targets

#: the most strokes one file holds: each is a solve of its own (a scripted session, not a bulk job)
MAX_STROKES = 256

#: a point or a direction: three numbers
Vector = Annotated[list[Number], Field(min_length=3, max_length=3)]


class Stroke(BaseModel):
    """One stroke of a scripted session, what a paint drag in the viewer makes: exactly these four keys."""

    model_config = ConfigDict(extra="forbid")

    tool: Annotated[str, Strict()]
    centre: Vector
    radius: Annotated[Positive, Strict()]
    stroke: Vector

    @field_validator("tool")
    @classmethod
    def _known_tool(cls, tool: str) -> str:
        if tool not in TOOLS:
            raise ValueError(f"unknown tool {tool!r}; allowed: {', '.join(TOOLS)}")
        return tool

    @field_validator("stroke")
    @classmethod
    def _has_direction(cls, stroke: list[float], info: ValidationInfo) -> list[float]:
        """A warp moves the highlight along the stroke: the zero vector has no direction (the stencil needs none)."""
        if info.data.get("tool") in WARPS and not any(stroke):
            raise ValueError(f"the zero vector has no direction; a {info.data['tool']} stroke needs one")
        return stroke


class Session(BaseModel):
    """A strokes file's content, a JSON list of 1…MAX_STROKES strokes applied in turn, under the name its errors
    give it (``strokes[3].centre[1]``)."""

    strokes: Annotated[list[Stroke], Field(min_length=1, max_length=MAX_STROKES)]


def load_strokes(path: str | Path, field: str = "--strokes") -> list[dict]:
    """A JSON list of strokes: {"tool": "bend" | "expand" | "stencil", "centre": [x, y, z], "radius": r,
    "stroke": [x, y, z]}, each checked (:class:`Stroke`) before any scene is loaded."""
    from .. import jsonio
    from ..arguments import validated

    content = jsonio.read(path, field=field, what=f"a JSON list of 1..{MAX_STROKES} strokes")
    session = validated(Session, {"strokes": content}, file=path, field=field)
    return [stroke.model_dump() for stroke in session.strokes]


def _listed(vector):
    """A point or direction as a list (what a strokes file holds), from the array or tuple an API caller gives."""
    return vector.tolist() if isinstance(vector, np.ndarray) else list(vector) if isinstance(vector, tuple) else vector


class EditSession:
    """A mesh's orientation field being edited stroke by stroke, with undo and redo: what a scripted session
    and the viewer's paint mode drive. The camera and light of the scene it was made from fix h."""

    def __init__(self, scene, index: int, light: int | None = None, k: int = 2, iterations: int = 20):
        self.index, self.k, self.iterations = index, k, check_iterations(iterations)
        _, self.mesh, self.inverse, h, u = _prepared(scene, index, light, editing=True)
        self.problem = HighlightProblem(self.mesh, h, k)
        self.h = h
        self.linear = scene.mesh[index].transform.matrix()[:3, :3]
        self.history = [self.mesh.angles(u)]  # φ after each stroke, the start first
        self.future: list[np.ndarray] = []
        self.energies: list[tuple[float, float]] = []

    @property
    def phi(self) -> np.ndarray:
        return self.history[-1]

    def brush(self, tool: str, centre, radius: float, direction) -> tuple[str, Brush]:
        """A stroke's tool and brush, checked as a strokes file's entry is (:class:`Stroke`) and placed on the mesh
        (its centre on the surface; a warp's stroke not along the normal): or one ArgumentError."""
        from ..arguments import validated

        values = {"tool": tool, "centre": _listed(centre), "radius": radius, "stroke": _listed(direction)}
        checked = validated(Stroke, values, field="stroke")
        brush = Brush(np.asarray(checked.centre), checked.radius, np.asarray(checked.stroke))
        try:
            brush.frame(self.mesh, oriented=checked.tool in WARPS)
        except BrushError as exc:
            raise ArgumentError(str(exc), field="stroke") from None
        return checked.tool, brush

    def stroke(self, tool: str, centre, radius: float, direction) -> tuple[float, float]:
        """Apply one stroke (a warp solved for, or the stencil); its tensor energy at the start and the end (zero
        for the stencil, which sets the field directly). A bad stroke is one ArgumentError (:meth:`brush`)."""
        return self.apply_brush(*self.brush(tool, centre, radius, direction))

    def apply_brush(self, tool: str, brush: Brush) -> tuple[float, float]:
        """:meth:`stroke` with the brush :meth:`brush` placed (a scripted session places them all first)."""
        if tool == "stencil":
            phi, energies = stencil(self.mesh, self.phi, self.h, brush), (0.0, 0.0)
        else:
            ell, degenerate = highlight_tangents(self.mesh, self.phi, self.h, self.k, w=self.problem.w)
            targets, inside = warp_targets(self.mesh, ell, brush, tool)
            result = solve(self.problem, self.phi, targets * ~degenerate[:, None], inside, iterations=self.iterations)
            phi, energies = result.phi, (result.energy[0], result.energy[-1])
        self.history.append(phi)
        self.future.clear()
        self.energies.append(energies)
        return energies

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
    scene,
    index: int,
    strokes: list[dict],
    light: int | None = None,
    k: int = 2,
    iterations: int = 20,
    file: str | Path | None = None,
) -> dict[str, np.ndarray]:
    """The orientation field after the strokes (``u`` (V, 3) in the mesh's own coordinates and order, what a
    material's ``orientation`` file holds) and each stroke's energy at its start and end (``energy`` (S, 2)).
    A stroke the mesh refuses (its brush off the surface, its stroke along the normal) is named by its place in
    the list and the ``file`` it came from."""
    session = EditSession(scene, index, light, k, iterations)

    def named(place: int, step, *args):
        try:
            return step(*args)
        except ArgumentError as exc:
            field = "--strokes" if file else "strokes"
            raise ArgumentError(f"strokes[{place}]: {exc.message}", file=file, field=field) from None

    brushes = [named(place, session.brush, s["tool"], s["centre"], s["radius"], s["stroke"])
               for place, s in enumerate(strokes)]  # every brush placed before the first solve  # fmt: skip
    for place, (tool, brush) in enumerate(brushes):
        named(place, session.apply_brush, tool, brush)
    return {"u": session.field(), "energy": np.asarray(session.energies).reshape(-1, 2)}
