"""Augmented reality (004): marker boards, camera intrinsics, tracking by ArUco markers and PnP, synthetic views
with known poses (the test data: real photographs are not available offline)."""

from __future__ import annotations

from pathlib import Path

from .. import jsonio


def write_json(path: str | Path, data: dict) -> Path:
    return jsonio.write(path, data, indent=1)
