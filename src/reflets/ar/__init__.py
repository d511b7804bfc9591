"""Augmented reality (004): marker boards, camera intrinsics, tracking by ArUco markers and PnP, synthetic views
with known poses (the test data: real photographs are not available offline)."""

from __future__ import annotations

import json
from collections.abc import Callable
from pathlib import Path

from ..errors import ArgumentError


def read_json(path: str | Path, field: str, what: str, parse: Callable[[dict], object]):
    """``parse`` of a JSON file's content, or a one-line error naming the file and the option (a missing file,
    invalid JSON, a missing key, a wrong shape)."""
    path = Path(path)
    try:
        return parse(json.loads(path.read_text(encoding="utf-8")))
    except FileNotFoundError:
        raise ArgumentError("file not found", file=path, field=field) from None
    except (ValueError, KeyError, TypeError, IndexError) as exc:
        raise ArgumentError(f"not {what} ({exc})", file=path, field=field) from None


def write_json(path: str | Path, data: dict) -> Path:
    path = Path(path)
    path.write_text(json.dumps(data, indent=1), encoding="utf-8")
    return path
