"""The technique interface and registry behind ``--method``.

A technique declares its parameters (a pydantic model, so a bad value is a clear error), prepares GPU
resources for one scene in ``prepare`` and draws frames in ``render``. Techniques are found by name
(``register_technique``), like Mitsuba plugins.
"""

from __future__ import annotations

from typing import Any, ClassVar

import numpy as np
from pydantic import BaseModel, ConfigDict, ValidationError

from ..errors import ArgumentError
from ..gpu.targets import TargetCache
from ..scene.model import Scene

TECHNIQUES: dict[str, type[Technique]] = {}


class TechniqueParams(BaseModel):
    model_config = ConfigDict(extra="forbid")


class Technique:
    """Base class: ``Technique(ctx, **params)``, then ``prepare(scene)`` once and ``render(...)`` per frame."""

    name: ClassVar[str]
    summary: ClassVar[str] = ""
    Params: ClassVar[type[TechniqueParams]] = TechniqueParams

    def __init__(self, ctx, **params: Any):
        self.ctx = ctx
        try:
            self.params = self.Params(**params)
        except ValidationError as exc:
            err = exc.errors(include_url=False)[0]
            field = ".".join(str(p) for p in err["loc"] if not ("-" in str(p) or "[" in str(p)))
            allowed = ", ".join(self.Params.model_fields) or "none"
            hint = ""
            if err["type"] == "extra_forbidden":
                from ..scene.loaders import did_you_mean

                hint = did_you_mean(str(err["loc"][-1]), self.Params.model_fields)
            msg = err["msg"].removeprefix("Value error, ")
            raise ArgumentError(f"{msg}{hint} (parameters of '{self.name}': {allowed})", field=field) from None
        self.scene: Scene | None = None
        self._targets = TargetCache()  # the frame target, kept while the size stays

    def prepare(self, scene: Scene) -> None:
        raise NotImplementedError

    #: where the technique's pass goes in a frame that ``auto`` composes (lower first; the BRDF pass is 2, a pass
    #: that reflects the others last)
    auto_order: ClassVar[int] = 2
    #: does one pass take one light (its own light view), so that ``auto`` runs one pass per light?
    one_light_per_pass: ClassVar[bool] = False

    #: does the image converge over frames (Monte Carlo)? A persistent renderer then accumulates frames across
    #: calls while nothing changes
    progressive: ClassVar[bool] = False

    def render(self, *, size: tuple[int, int] | None = None, seed: int = 0, spp: int | None = None) -> np.ndarray:
        total, n_frames = self.accumulate(size=size, seed=seed, spp=spp)
        return self.resolve(total, n_frames)

    def accumulate(
        self, *, size: tuple[int, int] | None = None, seed: int = 0, spp: int | None = None, first_frame: int = 0
    ) -> tuple[np.ndarray, int]:
        """The sum of the frames of ``spp`` samples (:func:`add_frame`), frame indices from ``first_frame``, and
        their count."""
        raise NotImplementedError

    def resolve(self, total: np.ndarray, n_frames: int) -> np.ndarray:
        """The float32 image of an accumulated sum (``total`` itself for one float32 frame)."""
        return (total if n_frames == 1 else total / n_frames).astype(np.float32, copy=False)

    def set_camera(self, camera) -> bool:
        """Take a new camera without preparing again; False when the technique must prepare again."""
        return False

    @property
    def default_spp(self) -> int:
        """Samples per pixel when the caller gives none (1: one sample at each pixel centre)."""
        return 1

    def release(self) -> None:
        """Free GPU resources (the context itself stays)."""
        self._targets.release()


def register_technique(cls: type[Technique]) -> type[Technique]:
    """Class decorator: make a technique selectable by ``cls.name``. Duplicate names are errors."""
    if cls.name in TECHNIQUES:
        raise ValueError(f"technique '{cls.name}' is registered twice")
    TECHNIQUES[cls.name] = cls
    return cls


def get_technique(name: str) -> type[Technique]:
    if name not in TECHNIQUES:
        from ..scene.loaders import did_you_mean

        hint = did_you_mean(str(name), TECHNIQUES)
        raise ArgumentError(f"unknown method '{name}'{hint}; allowed: {', '.join(sorted(TECHNIQUES))}", field="method")
    return TECHNIQUES[name]


def add_frame(total: np.ndarray | None, image: np.ndarray) -> np.ndarray:
    """A running sum of frames: the first frame as it is (float32: a one-frame image is not copied twice over,
    4 ms of a 1280×720 frame), float64 from the second on (thousands of frames add without rounding)."""
    return image if total is None else np.add(total, image, dtype=np.float64)
