"""OpenGL plumbing only: the context, programs with #include, HDR targets, readback, timers."""

from . import depth
from .context import get_context, gl_info, is_software
from .programs import ProgramSpec, get_program, set_uniforms
from .targets import GLObjects, HDRTarget, TargetCache, release_objects
from .timing import FrameTimer

__all__ = [
    "depth",
    "get_context",
    "gl_info",
    "is_software",
    "ProgramSpec",
    "get_program",
    "set_uniforms",
    "HDRTarget",
    "TargetCache",
    "GLObjects",
    "release_objects",
    "FrameTimer",
]
