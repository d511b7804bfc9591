"""Strict JSON for every ``--json`` output and every results file: non-finite numbers are written as ``null``.

Python's :func:`json.dumps` writes ``NaN``, ``Infinity`` and ``-Infinity`` by default, which is not JSON:
``jq``, ``JSON.parse`` and most other parsers reject the whole document. Yet several values in reflets have
no finite value by design (the PSNR of identical images is ``inf``, z-scores without any Monte Carlo noise
are NaN, a benchmark row without a preparation step has no ``prepare_ms``). :func:`dumps` writes each of
them as ``null`` and then encodes with ``allow_nan=False``, so that no non-finite number can slip through.

NumPy scalars and arrays are turned into plain Python values on the way (``np.float32`` is not JSON
serialisable by itself). Only the standard library and NumPy are imported at module level: any module may use
this one.
"""

from __future__ import annotations

import json
import math
from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np

__all__ = ["dumps", "finite_or_none", "read", "write"]

#: the largest JSON input read (a board, camera intrinsics, strokes, an event script: kilobytes in real use)
MAX_JSON_BYTES = 16_000_000


def finite_or_none(obj: Any) -> Any:
    """``obj`` with every non-finite float (Python or NumPy) replaced by ``None``, recursively.

    Dicts, lists and tuples are rebuilt (tuples become lists, as JSON has no tuples); NumPy arrays become
    nested lists and NumPy scalars plain ``float`` / ``int`` / ``bool``. Anything else is returned as is.
    """
    if isinstance(obj, bool | np.bool_):
        return bool(obj)
    if isinstance(obj, float | np.floating):
        value = float(obj)
        return value if math.isfinite(value) else None
    if isinstance(obj, np.integer):
        return int(obj)
    if isinstance(obj, dict):
        return {_key(k): finite_or_none(v) for k, v in obj.items()}
    if isinstance(obj, list | tuple):
        return [finite_or_none(v) for v in obj]
    if isinstance(obj, np.ndarray):
        return finite_or_none(obj.tolist())
    if isinstance(obj, np.generic):  # other NumPy scalars (complex, str, ...): their Python value
        return obj.item()
    return obj


def _key(key: Any) -> Any:
    return key.item() if isinstance(key, np.generic) else key


def dumps(obj: Any, **kw: Any) -> str:
    """:func:`json.dumps` of ``obj`` as strict JSON: non-finite floats are ``null`` (see the module docstring).

    Keyword arguments (``indent``, ``sort_keys``, ``default``, ...) are passed on; ``allow_nan`` is always
    False. The values a ``default`` function returns are made finite the same way.
    """
    kw.pop("allow_nan", None)
    default: Callable[[Any], Any] | None = kw.pop("default", None)
    if default is not None:
        kw["default"] = lambda o: finite_or_none(default(o))
    return json.dumps(finite_or_none(obj), allow_nan=False, **kw)


def write(path: str | Path, obj: Any, **kw: Any) -> Path:
    """Write :func:`dumps` of ``obj`` (UTF-8) to ``path`` atomically (a failed write leaves what was there);
    returns the path."""
    from .outputs import atomic_write

    path = Path(path)
    atomic_write(path, dumps(obj, **kw).encode("utf-8"))
    return path


def _no_duplicate_keys(pairs: list[tuple[str, Any]]) -> dict:
    keys = [k for k, _ in pairs]
    if len(set(keys)) != len(keys):
        twice = sorted({k for k in keys if keys.count(k) > 1})
        raise ValueError(f"key {twice[0]!r} is given twice (JSON keeps only the last: say it once)")
    return dict(pairs)


def _no_constant(name: str) -> None:
    raise ValueError(f"{name} is not JSON (numbers must be finite)")


def read(path: str | Path, *, field: str | None = None, what: str = "a JSON file") -> Any:
    """A JSON input file's content, strictly: duplicate keys, NaN / Infinity, more than MAX_JSON_BYTES or
    nesting deeper than Python's stack are refused — each as one :class:`~reflets.errors.ArgumentError` naming
    the file and the option (``field``) that gave it, as are a missing file, a directory and bytes that are not
    UTF-8. What the content must be is its reader's check (a pydantic model: ``reflets.arguments.validated``)."""
    from .errors import ArgumentError

    path = Path(path)
    try:
        if path.is_dir():
            raise ArgumentError(f"is a directory, expected {what}", file=path, field=field)
        if path.exists() and not path.is_file():  # a device or a pipe: no size to check, maybe no end
            raise ArgumentError(f"is not a regular file, expected {what}", file=path, field=field)
        size = path.stat().st_size
        if size > MAX_JSON_BYTES:
            raise ArgumentError(f"is {size:,} bytes; {what} is at most {MAX_JSON_BYTES:,}", file=path, field=field)
        text = path.read_text(encoding="utf-8")
    except FileNotFoundError:
        raise ArgumentError("file not found", file=path, field=field) from None
    except UnicodeDecodeError:
        raise ArgumentError(f"not a text file (expected {what}: UTF-8 JSON)", file=path, field=field) from None
    except OSError as exc:
        raise ArgumentError(f"cannot read ({exc.strerror or type(exc).__name__})", file=path, field=field) from None
    try:
        return json.loads(text, object_pairs_hook=_no_duplicate_keys, parse_constant=_no_constant)
    except RecursionError:
        raise ArgumentError(f"values nested too deeply (not {what})", file=path, field=field) from None
    except ValueError as exc:  # json.JSONDecodeError is one
        raise ArgumentError(f"not {what} ({exc})", file=path, field=field) from None
