"""The technique interface and registry behind ``--method``.

A technique declares its parameters (a pydantic model, so a bad value is a clear error), prepares GPU
resources for one scene in ``prepare`` and draws frames in ``render``. Techniques are found by name
(``register_technique``), like Mitsuba plugins.
"""

from __future__ import annotations

import math
from typing import Any, ClassVar

import numpy as np
from pydantic import BaseModel, ConfigDict, ValidationError

from ..errors import ArgumentError
from ..gpu.frames import FrameSum
from ..gpu.targets import HDRTarget, TargetCache
from ..gpu.timing import FrameTimer
from ..resources import check, fitting_size, largest_fitting
from ..scene.model import Scene

TECHNIQUES: dict[str, type[Technique]] = {}


#: bytes per sample of a frame, an upper bound: the float32 RGBA colour and 32-bit depth of the drawn target (20 per
#: sample), the frame sum and its mean on the GPU (16 each per pixel) and the read-back (16, and its RGB copy 12, per
#: pixel): 80 at one sample per pixel. Measured: 44.1 for one frame at one sample, whose image is the drawn target
#: (``python tools/calibrate_memory.py``, llvmpipe, 1024² → 2048²)
FRAME_BYTES_PER_SAMPLE = 80


def check_target_size(ctx, width: int, height: int, s: int, extra_per_sample: int = 0) -> None:
    """The supersampled target must fit the driver's largest framebuffer (else "framebuffer not complete"), and
    its memory — width · height · s² · (FRAME_BYTES_PER_SAMPLE + ``extra_per_sample``: a technique's own images
    at the target size) — the available memory (reflets.resources), before the target is made."""
    limit = int(ctx.info.get("GL_MAX_TEXTURE_SIZE", 16384))
    if max(width, height) * s > limit:
        raise ArgumentError(
            f"{s}×{s} supersampling of {width}x{height} needs a {width * s}x{height * s} target; this GL driver "
            f"allows at most {limit} per side (use fewer spp or a smaller size)",
            field="spp",
        )
    per_sample = FRAME_BYTES_PER_SAMPLE + extra_per_sample
    samples = width * height * s * s
    what = f"{samples:,} samples × {per_sample} B: target, read-back, sums"
    if s > 1:  # the largest s² that fits at this size

        def fits(budget: int) -> str | None:
            side = largest_fitting(lambda k: width * height * k * k * per_sample, 1, s, budget)
            return None if side is None else f"{side * side} spp"

        check("spp", samples * per_sample, value=f"{s * s} spp at {width}x{height}", what=what, fits=fits)
    else:  # the largest size of the same shape that fits
        check(
            "size",
            samples * per_sample,
            value=f"{width}x{height}",
            what=what,
            fits=lambda budget: fitting_size(width, height, per_sample, budget),
        )


def samples_per_pixel_side(spp: int) -> int:
    s = math.isqrt(spp)
    if spp < 1 or s * s != spp:
        raise ArgumentError(
            f"{spp} is not a perfect square; forward anti-aliasing uses s×s samples (1, 4, 9, 16…)",
            field="spp",
        )
    return s


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
        self._frame_sum = FrameSum(ctx)  # the frames' image, on the GPU
        self.timer = FrameTimer(ctx)

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
        """The image of ``spp`` samples per pixel: float32 (H, W, 3), row 0 = top (one read-back)."""
        return self.image(self.accumulate(size=size, seed=seed, spp=spp)).read()

    def accumulate(
        self, *, size: tuple[int, int] | None = None, seed: int = 0, spp: int | None = None, first_frame: int = 0
    ) -> int:
        """Draw the frames of ``spp`` samples, frame indices from ``first_frame``, and add them on the GPU to the
        frames drawn since frame 0 (a progressive caller goes on where it stopped); returns how many it drew.
        Nothing waits for the GPU and nothing is read back: :meth:`image` is the result."""
        if self.scene is None:
            raise RuntimeError("call prepare(scene) before render()")
        ctx = self.ctx
        n_frames, s = self.frames(self.default_spp if spp is None else spp)
        width, height = size or self.scene.camera.size
        view, proj = self.camera_matrices(width, height)
        view_proj = proj @ view
        vp_bytes = view_proj.T.astype(np.float32).tobytes()  # GLSL matrices are column-major
        target = self._targets.get(
            ctx, width * s, height * s, lambda: check_target_size(ctx, width, height, s, self.screen_bytes_per_sample())
        )
        alone = n_frames == 1 and not self.progressive  # nothing adds to it: the drawn target is the image
        for frame in range(first_frame, first_frame + n_frames):
            with self.timer.frame() as timing:
                self._timed_draw(target, view_proj, vp_bytes, frame, seed)
                timing.submitted()
                with self.timer.timed_pass("frame sum"):
                    self._frame_sum.add(target, s, first=frame == 0, alone=alone)
        return n_frames

    def image(self, frames: int) -> HDRTarget:
        """The image of the ``frames`` frames drawn since frame 0, on the GPU: ``.color`` is the texture (W × H
        float32 RGBA, OpenGL's rows: bottom first), ``.read()`` the array (row 0 = top)."""
        return self._frame_sum.image(frames)

    def _timed_draw(self, target, view_proj, vp_bytes, frame: int, seed: int) -> None:
        """One frame's passes, each timed (here the technique's whole frame is one pass)."""
        with self.timer.timed_pass(self.name):
            self._draw(target, view_proj, vp_bytes, frame, seed)

    def _draw(self, target, view_proj, vp_bytes, frame: int, seed: int) -> None:
        raise NotImplementedError

    #: does its changing part (``_draw_dynamic``) read an image it has just drawn itself (``auto`` draws such parts
    #: first: their order among the changing parts does not change the frame)?
    reads_own_images: ClassVar[bool] = False

    @property
    def frame_dependent(self) -> bool:
        """Does a frame's image depend on its index (new samples each frame)? ``auto`` then redraws, in the frames
        after the first from one view, only the passes' :meth:`_draw_dynamic` parts."""
        return self.progressive

    def _draw_static(self, target, view_proj, vp_bytes, frame: int, seed: int) -> None:
        """The part of a frame that is the same in every frame from one view (``_draw_static`` then
        ``_draw_dynamic`` is ``_draw``): all of it here, unless the frames differ."""
        if not self.frame_dependent:
            self._draw(target, view_proj, vp_bytes, frame, seed)

    def _draw_dynamic(self, target, view_proj, vp_bytes, frame: int, seed: int) -> None:
        """The part of a frame that changes from frame to frame (drawn after every pass's static part)."""
        if self.frame_dependent:
            self._draw(target, view_proj, vp_bytes, frame, seed)

    def camera_matrices(self, width: int, height: int) -> tuple[np.ndarray, np.ndarray]:
        raise NotImplementedError

    def frames(self, spp: int) -> tuple[int, int]:
        """(frames to accumulate, supersampling side s) for a requested spp."""
        raise NotImplementedError

    def screen_bytes_per_sample(self) -> int:
        """Bytes per target sample of the technique's own screen images, beyond the frame's."""
        return 0

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
        self._frame_sum.release()


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

