"""Augmented reality (004): marker boards, camera intrinsics, tracking by ArUco markers and PnP, synthetic views
with known poses (the test data: real photographs are not available offline)."""

from __future__ import annotations

import json
from pathlib import Path


def write_json(path: str | Path, data: dict) -> Path:
    path = Path(path)
    path.write_text(json.dumps(data, indent=1), encoding="utf-8")
    return path
