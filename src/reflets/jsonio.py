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

__all__ = ["dumps", "finite_or_none", "write"]


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
    from .imageio import atomic_write

    path = Path(path)
    atomic_write(path, dumps(obj, **kw).encode("utf-8"))
    return path
