"""The viewer's display pass: an HDR frame — the renderer's texture as it is, or an array uploaded — drawn to the
window, tone mapped on the GPU exactly as ``reflets.imageio.tonemap`` does on the CPU (so a window screenshot
equals a rendered PNG)."""

from __future__ import annotations

import moderngl
import numpy as np

from ..gpu import GLObjects, ProgramSpec, get_program, set_uniforms

DISPLAY_PROGRAM = ProgramSpec(
    "display", vertex="reflets/gpu/shaders/fullscreen.vert", fragment="reflets/viewer/shaders/display.frag"
)


class Display:
    """Draws HDR frames into the current framebuffer of ``ctx``: textures (``draw_texture``) or arrays (``draw``)."""

    def __init__(self, ctx):
        self.ctx = ctx
        self._gl = GLObjects(ctx)
        self.program = get_program(ctx, DISPLAY_PROGRAM)
        self.vao = self._gl.own(ctx.vertex_array(self.program, []))
        self.texture = None

    def draw(self, image: np.ndarray, exposure: float = 0.0, tonemap: str = "srgb") -> None:
        """An HDR array (row 0 at the top), uploaded then drawn (the reference, error and highlight views)."""
        h, w = image.shape[:2]
        if self.texture is None or self.texture.size != (w, h):
            if self.texture is not None:
                self.texture.release()
            self.texture = self.ctx.texture((w, h), 3, dtype="f4")
            self.texture.filter = (moderngl.NEAREST, moderngl.NEAREST)
        self.texture.write(np.ascontiguousarray(image, np.float32).tobytes())
        self._draw(self.texture, exposure, tonemap, top_first=True)

    def draw_texture(self, texture, exposure: float = 0.0, tonemap: str = "srgb") -> None:
        """A frame still on the GPU (``Renderer.render_texture``: OpenGL's rows), drawn without a read-back."""
        texture.filter = (moderngl.NEAREST, moderngl.NEAREST)
        self._draw(texture, exposure, tonemap, top_first=False)

    def _draw(self, texture, exposure: float, tonemap: str, top_first: bool) -> None:
        texture.use(0)
        self.ctx.enable_only(moderngl.NOTHING)  # no blending or depth test left by a pass
        set_uniforms(self.program, {"u_image": 0, "u_exposure": float(exposure), "u_aces": int(tonemap == "aces"),
                                    "u_top_first": int(top_first)})  # fmt: skip
        self.vao.render(moderngl.TRIANGLES, vertices=3)

    def release(self) -> None:
        if self.texture is not None:
            self.texture.release()
            self.texture = None
        self._gl.release()
