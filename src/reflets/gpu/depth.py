"""Reversed-Z depth for every pass seen from the scene camera: float depth, [0, 1] clip range, infinite far plane.

A standard OpenGL projection spends its depth precision near the near plane: with a 24-bit buffer and the near
plane derived from the scene's extent, a 100 km ground plane pushed the near plane past a sphere 0.5 m from the
camera (it vanished), and two planes 1 mm apart 100 m away z-fought. Reversed-Z (Reed, "Depth Precision
Visualized", 2015; what Unreal, Unity's HDRP and Filament use) maps the near plane to depth 1 and infinity to
0: depth = near / distance. A float32 depth buffer's exponent then follows 1 / distance, so the relative
precision is about 2⁻²⁴ at every distance and the near plane can be tiny. It needs ``glClipControl`` (OpenGL
4.5, or ARB_clip_control) for a [0, 1] clip range — with [-1, 1], the ½ z + ½ mapping would round the small
depths away — and a ``GL_DEPTH_COMPONENT32F`` attachment; moderngl offers neither, so both go through the
context's own GL loader.

Passes from the lights (shadow maps, occlusion atlases) keep the standard convention: :func:`camera_depth`
switches the clip range for the duration of a camera pass and puts it back.
"""

from __future__ import annotations

import contextlib
import ctypes

from ..errors import GLUnavailableError
from .context import context_store

#: depth a camera target is cleared to (reversed: the far end) and the tests that keep the nearer surface
CLEAR = 0.0
NEARER = ">"
NEARER_OR_EQUAL = ">="

_GL_LOWER_LEFT = 0x8CA1
_GL_NEGATIVE_ONE_TO_ONE = 0x935E
_GL_ZERO_TO_ONE = 0x935F
_GL_TEXTURE_2D = 0x0DE1
_GL_TEXTURE_BINDING_2D = 0x8069
_GL_DEPTH_COMPONENT = 0x1902
_GL_DEPTH_COMPONENT32F = 0x8CAC
_GL_FLOAT = 0x1406

_SIGNATURES = {
    "glClipControl": (ctypes.c_uint, ctypes.c_uint),
    "glBindTexture": (ctypes.c_uint, ctypes.c_uint),
    "glGetIntegerv": (ctypes.c_uint, ctypes.POINTER(ctypes.c_int)),
    "glTexImage2D": (ctypes.c_uint, ctypes.c_int, ctypes.c_int, ctypes.c_int, ctypes.c_int, ctypes.c_int,
                     ctypes.c_uint, ctypes.c_uint, ctypes.c_void_p),
    "glTexParameteri": (ctypes.c_uint, ctypes.c_uint, ctypes.c_int),
}  # fmt: skip


def _gl(ctx, name: str):
    """A GL entry point of ``ctx`` (through the loader moderngl's context was made with), cached per context."""
    functions = context_store(ctx, "gl-functions")
    if name not in functions:
        address = ctx.mglo._context.load_opengl_function(name)
        if not address:
            raise GLUnavailableError(f"the OpenGL driver has no {name}; reflets needs OpenGL 4.5 or ARB_clip_control")
        functions[name] = ctypes.CFUNCTYPE(None, *_SIGNATURES[name])(address)
    return functions[name]


def float_depth_texture(ctx, size: tuple[int, int]):
    """A depth texture with 32-bit float storage (moderngl's are 24-bit fixed point): moderngl makes it, so it
    attaches, reads and releases as any of its depth textures; its storage is then specified again as
    ``GL_DEPTH_COMPONENT32F``."""
    texture = ctx.depth_texture(size)
    bound = ctypes.c_int(0)
    _gl(ctx, "glGetIntegerv")(_GL_TEXTURE_BINDING_2D, ctypes.byref(bound))
    _gl(ctx, "glBindTexture")(_GL_TEXTURE_2D, texture.glo)
    _gl(ctx, "glTexImage2D")(
        _GL_TEXTURE_2D, 0, _GL_DEPTH_COMPONENT32F, size[0], size[1], 0, _GL_DEPTH_COMPONENT, _GL_FLOAT, None
    )
    _gl(ctx, "glBindTexture")(_GL_TEXTURE_2D, bound.value)
    return texture


_GL_TEXTURE_WRAP = (0x2802, 0x2803)  # S, T
GL_WRAP_MODES = {"repeat": 0x2901, "clamp": 0x812F, "mirror": 0x8370}


def texture_wrap(ctx, texture, wrap: tuple[str, str]) -> None:
    """Set a texture's wrap modes (s, t) among :data:`GL_WRAP_MODES` — moderngl's ``repeat_x`` / ``repeat_y`` know
    repeat and clamp only, not glTF's mirrored repeat (through the same loader as the depth calls)."""
    bound = ctypes.c_int(0)
    _gl(ctx, "glGetIntegerv")(_GL_TEXTURE_BINDING_2D, ctypes.byref(bound))
    _gl(ctx, "glBindTexture")(_GL_TEXTURE_2D, texture.glo)
    for axis, mode in zip(_GL_TEXTURE_WRAP, wrap, strict=True):
        _gl(ctx, "glTexParameteri")(_GL_TEXTURE_2D, axis, GL_WRAP_MODES[mode])
    _gl(ctx, "glBindTexture")(_GL_TEXTURE_2D, bound.value)


@contextlib.contextmanager
def camera_depth(ctx):
    """Draw the enclosed passes with reversed-Z: clip z in [0, 1], the nearer surface the greater depth."""
    clip_control = _gl(ctx, "glClipControl")
    clip_control(_GL_LOWER_LEFT, _GL_ZERO_TO_ONE)
    ctx.depth_func = NEARER
    try:
        yield
    finally:
        clip_control(_GL_LOWER_LEFT, _GL_NEGATIVE_ONE_TO_ONE)
        ctx.depth_func = "<"
