"""Where a command writes, under one rule: an output is checked before any work — its extension, its folder
(which must exist: nothing creates folders), not a directory, not one of the work's own input files, and not an
existing file unless the user said ``--overwrite`` — and written atomically (a temporary sibling renamed over
it), so that a failure or a kill never leaves half a file and never destroys what was there.

Commands check every output they will write, with :func:`check_output`, before the first byte of any of them;
API functions that write (``write_image``, ``export_gltf``) check what they can see themselves.
"""

from __future__ import annotations

import contextlib
import os
import secrets
import stat
from collections.abc import Iterable
from pathlib import Path

from .errors import OutputError

__all__ = ["atomic_write", "check_not_input", "check_output", "check_output_path"]


def check_output(path: str | Path, allowed: Iterable[str], *, inputs: Iterable[str | Path] = (),
                 overwrite: bool = False, field: str | None = None) -> Path:  # fmt: skip
    """The whole rule for one output file of a command (see the module docstring); returns it as a Path.

    ``inputs``: the files the work reads (an output naming one of them is refused even with ``overwrite``);
    ``field``: the option that named the output, for the message (``--image``, ``--diff``)."""
    p = check_output_path(path, allowed, field=field)
    check_not_input(p, inputs, field=field)
    if p.exists() and not overwrite:
        raise OutputError("exists already; give --overwrite to replace it (nothing was written)", file=p,
                          field=field)  # fmt: skip
    return p


def check_output_path(path: str | Path, allowed: Iterable[str], *, field: str | None = None) -> Path:
    """Check that ``path`` could be written, without creating anything: its extension (case-insensitive) is one
    of ``allowed``, it is not a directory, its parent directory exists and is writable.

    Meant to run before an expensive render, so that a typo in the output path fails in milliseconds, not after
    minutes of work. Raises an OutputError naming the path and what is allowed."""
    p = Path(path)
    allowed = (allowed,) if isinstance(allowed, str) else allowed
    allowed = tuple(a.lower() if a.startswith(".") else f".{a.lower()}" for a in allowed)
    ext = p.suffix.lower()
    if ext not in allowed:
        raise OutputError(f"unsupported output extension {ext or '(none)'!r}; allowed: {', '.join(allowed)}",
                          file=p, field=field)  # fmt: skip
    if p.is_dir():
        raise OutputError("is a directory; give a file name", file=p, field=field)
    parent = p.parent
    if not parent.exists():
        raise OutputError(f"directory '{parent}' does not exist; create it first", file=p, field=field)
    if not parent.is_dir():
        raise OutputError(f"'{parent}' is not a directory", file=p, field=field)
    if not os.access(parent, os.W_OK | os.X_OK):
        raise OutputError(f"directory '{parent}' is not writable", file=p, field=field)
    return p


def _same_file(a: Path, b: Path) -> bool:
    """The same file: one path (links resolved), or two names of one file (a hard link). A link that loops
    resolves to nothing (RuntimeError on Python 3.11): no file, not an input."""
    with contextlib.suppress(OSError, RuntimeError):
        if a.resolve() == b.resolve():
            return True
        return a.exists() and b.exists() and os.path.samefile(a, b)
    return False


def check_not_input(path: str | Path, inputs: Iterable[str | Path], *, field: str | None = None) -> None:
    """Refuse an output that would replace one of the files the work reads (the scene, its meshes, textures,
    maps, a board, an image): an OutputError naming it, before anything is written."""
    target = Path(path)
    for item in inputs:
        if item is not None and _same_file(target, Path(item)):
            raise OutputError(f"is one of the inputs ({item}); give the output another name", file=path,
                              field=field)  # fmt: skip


def atomic_write(path: Path, payload: bytes) -> None:
    """Write ``payload`` to a temporary sibling of ``path``, then rename it over ``path``.

    The temporary file lives in the same directory so that :func:`os.replace` is a same-filesystem rename,
    which is atomic on POSIX and Windows. It is created with mode 0o666 so that the umask applies as for any
    new file; a file it replaces keeps its permissions.
    """
    tmp = path.with_name(f".{path.name}.{secrets.token_hex(6)}.tmp")
    try:
        fd = os.open(tmp, os.O_WRONLY | os.O_CREAT | os.O_EXCL | getattr(os, "O_BINARY", 0), 0o666)
    except OSError as exc:
        reason = exc.strerror or exc
        raise OutputError(f"cannot create a file in '{path.parent}' ({reason})", file=path) from exc
    try:
        with os.fdopen(fd, "wb") as fh:
            fh.write(payload)
            fh.flush()
            os.fsync(fh.fileno())
        with contextlib.suppress(FileNotFoundError):
            os.chmod(tmp, stat.S_IMODE(os.stat(path).st_mode))
        os.replace(tmp, path)
    except BaseException as exc:
        with contextlib.suppress(OSError):
            os.unlink(tmp)
        if isinstance(exc, OSError):
            raise OutputError(f"cannot write file ({exc.strerror or exc})", file=path) from exc
        raise

