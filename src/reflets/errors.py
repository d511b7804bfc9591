"""User-facing error types.

Every mistake a user can make (a bad scene file, a missing mesh, an unwritable output path, no OpenGL)
raises a subclass of :class:`RefletsError`. Its ``str()`` is one line naming the file, the field and what
is allowed, so the CLI can print it and exit with status 2 without a traceback. Programming errors stay
ordinary Python exceptions.
"""

from __future__ import annotations

import zipfile
from pathlib import Path


class RefletsError(Exception):
    """Base of all errors caused by user input or the environment (one-line message)."""

    def __init__(self, message: str, *, file: str | Path | None = None, field: str | None = None):
        self.message = message
        self.file = str(file) if file is not None else None
        self.field = field
        super().__init__(self._format())

    def _format(self) -> str:
        where = ": ".join(p for p in (self.file, self.field) if p)
        return f"{where}: {self.message}" if where else self.message


class RefletsWarning(UserWarning):
    """The scene renders, but part of it is ignored, approximated or unlit (the CLI prints one line)."""


class SceneError(RefletsError):
    """The scene (file or dict) is invalid: bad TOML, unknown key, wrong value, missing mesh file."""


class ImageError(RefletsError):
    """An image file cannot be read or written, or has an unsupported format."""


class OutputError(RefletsError):
    """An output path cannot be written (missing directory, no permission, unknown extension)."""


class GLUnavailableError(RefletsError):
    """No OpenGL context can be created (no EGL, no driver, version too old)."""


class ContextThreadError(RefletsError):
    """A renderer (or other GL object) used from a thread other than the one its GL context is current on."""


class ShaderError(RefletsError):
    """A GLSL program failed to compile or link; the message maps driver lines back to source files."""


class ArgumentError(RefletsError):
    """A command-line or API argument is out of range (image size, method name, sample count)."""


class ResourceError(ArgumentError):
    """A parameter whose estimated memory is more than this machine has available (reflets.resources): refused,
    by name, before anything is allocated."""


#: what reading a damaged or empty .npy / .npz raises (NumPy names none of these as its own): to be caught where a
#: file enters and turned into one line naming it
ARRAY_READ_ERRORS = (OSError, ValueError, EOFError, zipfile.BadZipFile)
