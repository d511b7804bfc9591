"""HDR render targets and readback: float32 RGBA colour + 32-bit float depth, read back with row 0 = top."""

from __future__ import annotations

import moderngl
import numpy as np

from ..errors import ArgumentError
from .depth import CLEAR, float_depth_texture


class HDRTarget:
    """An offscreen float32 framebuffer of a given size, owned by one context (``depth=False``: colour alone)."""

    def __init__(self, ctx, width: int, height: int, depth: bool = True):
        self.ctx = ctx
        self.size = (int(width), int(height))
        self.color = ctx.texture(self.size, 4, dtype="f4")
        # reversed-Z: camera passes draw in it (gpu.depth)
        self.depth = float_depth_texture(ctx, self.size) if depth else None
        try:
            self.fbo = ctx.framebuffer(color_attachments=[self.color], depth_attachment=self.depth)
        except moderngl.Error as exc:  # the driver could not allocate it (llvmpipe: at most 1 GB per texture)
            release_objects(ctx, [t for t in (self.color, self.depth) if t is not None])
            raise ArgumentError(
                f"this GL driver cannot make a {width}x{height} float32 target ({exc}); lower the size or the spp",
                field="size",
            ) from None

    def use(self, clear: tuple[float, float, float, float] = (0.0, 0.0, 0.0, 0.0)) -> None:
        self.fbo.use()
        self.ctx.viewport = (0, 0, *self.size)
        self.fbo.clear(*clear, depth=CLEAR)  # (ignored without a depth attachment)

    def bind(self) -> None:
        """Draw into this target without clearing it (a composed frame's later passes)."""
        self.fbo.use()
        self.ctx.viewport = (0, 0, *self.size)

    def read(self, components: int = 3) -> np.ndarray:
        """Colour as float32 (H, W, components); OpenGL's bottom-up rows are flipped so row 0 is the top."""
        w, h = self.size
        # the driver drops the channels (4× cheaper than NumPy's strided copy of 4-channel rows, llvmpipe 640×480)
        data = np.frombuffer(self.fbo.read(components=components, dtype="f4"), dtype=np.float32)
        return np.ascontiguousarray(data.reshape(h, w, components)[::-1])

    def release(self) -> None:
        release_objects(self.ctx, [t for t in (self.fbo, self.color, self.depth) if t is not None])


class GLObjects:
    """The GL objects one component made, released together (``own`` returns what it is given)."""

    def __init__(self, ctx):
        self.ctx = ctx
        self.objects: list = []

    def own(self, obj):
        self.objects.append(obj)
        return obj

    def release(self) -> None:
        release_objects(self.ctx, self.objects)
        self.objects = []


def release_objects(ctx, objects: list) -> None:
    """Release GL objects, the default framebuffer bound first: moderngl restores the last bound framebuffer
    when it creates the next one, and a deleted one there raises GL_INVALID_OPERATION."""
    if objects:
        ctx.detect_framebuffer(0).use()
    for obj in objects:
        obj.release()


class TargetCache:
    """One technique's frame target, kept between frames of the same size: a frame loop creates no GL object."""

    def __init__(self):
        self.target: HDRTarget | None = None

    def get(self, ctx, width: int, height: int, check=None) -> HDRTarget:
        """The target at this size; ``check()`` runs first when one must be made (a size or memory check: not on
        every frame of a loop)."""
        if self.target is None or self.target.size != (int(width), int(height)):
            if check is not None:
                check()
            self.release()
            self.target = HDRTarget(ctx, width, height)
        return self.target

    def release(self) -> None:
        if self.target is not None:
            self.target.release()
            self.target = None
