"""The image of a technique's frames, made on the GPU: supersampled samples box-filtered, frames summed, then
the mean — so the image stays a texture until someone asks for an array.

Why: a window or a texture consumer shows the image without reading it back, and ``render()`` reads one W × H
image once, not every frame at s² its size. One frame at one sample per pixel (the real-time case) is the drawn
target itself: no pass at all. Frames add in float32 (a thousand frames round by ~10⁻⁴ relative at worst, far
below the Monte Carlo noise left at that count).
"""

from __future__ import annotations

import moderngl

from .context import context_store
from .programs import ProgramSpec, get_program, set_uniforms
from .targets import HDRTarget

FULLSCREEN = "reflets/gpu/shaders/fullscreen.vert"
FRAME_SUM_PROGRAM = ProgramSpec("frame_sum", vertex=FULLSCREEN, fragment="reflets/gpu/shaders/frame_sum.frag")
COPY_PROGRAM = ProgramSpec("copy_image", vertex=FULLSCREEN, fragment="reflets/gpu/shaders/copy_image.frag")
#: the texture units a pass here reads its images from: above every unit the passes use (a target still bound at
#: unit 0 or 1 while a later pass draws into it would be a feedback loop for any sampler left at its default)
UNIT = 62
#: frames summed before the block goes to the total (see FrameSum)
BLOCK = 1024


class FrameSum:
    """The running sum of a technique's frames at the image size, and their mean (:meth:`image`).

    Frames add into a block of at most :data:`BLOCK` frames, and full blocks into the total: a float32 sum then
    rounds by ~(BLOCK + n / BLOCK) · 6·10⁻⁸ relative at worst after n frames (10⁻⁴ after a million), where one
    running sum would drift by n · 6·10⁻⁸ and stop moving near 2²⁴ frames."""

    def __init__(self, ctx):
        self.ctx = ctx
        self._block: HDRTarget | None = None
        self._total: HDRTarget | None = None  # the full blocks (None: none yet)
        self._mean: HDRTarget | None = None
        self._direct: HDRTarget | None = None  # one frame at one sample: the drawn target is the image
        self._in_block = 0
        self._mean_of = 0  # the frames ``_mean`` holds the mean of (0: none since the last add)

    def add(self, target: HDRTarget, side: int, first: bool, alone: bool = False) -> None:
        """Add a frame drawn in ``target`` (``side`` × ``side`` samples per pixel); ``first`` starts the sum.
        ``alone``: no frame will follow before the image is read (the target is then used as it is when
        ``side`` is 1)."""
        self._direct, self._mean_of = None, 0
        if alone and first and side == 1:
            self._direct = target
            return
        width, height = target.size[0] // side, target.size[1] // side
        if not first and (self._block is None or self._block.size != (width, height)):
            raise RuntimeError("a frame added to a sum of another size: start it again (first=True)")
        if first:
            self._block = self._sized(self._block, width, height)
            self._release_total()
            self._block.use(clear=(0.0, 0.0, 0.0, 1.0))
            self._in_block = 0
        elif self._in_block == BLOCK:  # a full block goes to the total
            if self._total is None:
                self._total = self._sized(None, width, height)
                self._total.use(clear=(0.0, 0.0, 0.0, 1.0))
            self._accumulate(self._total, self._block.color, 1, 1.0, add=True)
            self._block.use(clear=(0.0, 0.0, 0.0, 1.0))
            self._in_block = 0
        self._accumulate(self._block, target.color, side, 1.0 / (side * side), add=True)
        self._in_block += 1

    def image(self, frames: int) -> HDRTarget:
        """The mean of the ``frames`` frames added since the first (a target: ``.color`` is the texture, ``.read()``
        the array)."""
        if self._direct is not None:
            return self._direct
        if self._block is None:
            raise RuntimeError("no frame was added")
        if frames == 1:
            return self._block
        if self._mean_of != frames:
            self._mean = self._sized(self._mean, *self._block.size)
            self._accumulate(self._mean, self._block.color, 1, 1.0 / frames, add=False)
            if self._total is not None:
                self._accumulate(self._mean, self._total.color, 1, 1.0 / frames, add=True)
            self._mean_of = frames
        return self._mean

    def _accumulate(self, into: HDRTarget, texture, side: int, scale: float, add: bool) -> None:
        """``into`` = (``into`` +, with ``add``) ``scale`` × the box sums of ``texture``'s side × side blocks."""
        ctx = self.ctx
        into.bind()
        ctx.disable(ctx.DEPTH_TEST | ctx.CULL_FACE)
        ctx.scissor = None
        if add:
            ctx.enable(ctx.BLEND)
            ctx.blend_func = moderngl.ONE, moderngl.ONE
        else:
            ctx.disable(ctx.BLEND)
        texture.use(UNIT)
        fullscreen_pass(ctx, FRAME_SUM_PROGRAM, {"u_frame": UNIT, "u_side": side, "u_scale": scale})
        ctx.disable(ctx.BLEND)

    def _sized(self, target: HDRTarget | None, width: int, height: int) -> HDRTarget:
        if target is None or target.size != (width, height):
            if target is not None:
                target.release()
            target = HDRTarget(self.ctx, width, height, depth=False)
        return target

    def _release_total(self) -> None:
        if self._total is not None:
            self._total.release()
            self._total = None

    def release(self) -> None:
        for target in (self._block, self._mean):
            if target is not None:
                target.release()
        self._release_total()
        self._block = self._mean = self._direct = None
        self._in_block = self._mean_of = 0


def fullscreen_pass(ctx, spec: ProgramSpec, uniforms: dict) -> None:
    """One full-screen triangle of a program into the bound framebuffer (its attribute-less vertex array made
    once per context and program)."""
    program = get_program(ctx, spec)
    arrays = context_store(ctx, "fullscreen arrays")
    if program.glo not in arrays:
        arrays[program.glo] = ctx.vertex_array(program, [])
    set_uniforms(program, uniforms)
    arrays[program.glo].render(moderngl.TRIANGLES, vertices=3)


def copy_image(ctx, framebuffer, size: tuple[int, int], colour, depth) -> None:
    """Colour and depth textures into ``framebuffer`` (the same size), drawn on the GPU: a blit of depth is a
    CPU copy on llvmpipe, which first waits for all that was drawn. The
    depth texture is read as numbers (its comparison turned off)."""
    framebuffer.use()
    ctx.viewport = (0, 0, *size)
    ctx.disable(ctx.BLEND | ctx.CULL_FACE)
    ctx.enable(ctx.DEPTH_TEST)
    ctx.depth_func = "1"  # always: the copy's depth replaces what was there
    framebuffer.depth_mask = True
    depth.compare_func = ""
    colour.use(UNIT)
    depth.use(UNIT + 1)
    fullscreen_pass(ctx, COPY_PROGRAM, {"u_colour": UNIT, "u_depth": UNIT + 1})
    ctx.depth_func = "<"
    ctx.disable(ctx.DEPTH_TEST)
