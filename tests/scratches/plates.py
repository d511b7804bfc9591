"""A small scratched material and a smooth sky shared by the tests that render scratched plates (the scratches
pass, and Fermat reflections of a scratched plate)."""

from __future__ import annotations

from pathlib import Path

import numpy as np

#: three layers of V-grooves over a Lambertian base, a small table: fast to trace, every term present
MATERIAL = {
    "type": "scratched",
    "profile": "vgroove:0.4",
    "table_size": 32,
    "rays": 2000,
    "count": 3,
    "spread": 120,
    "coverage": 0.3,
    "seed": 2,
    "base": {"type": "lambert", "albedo": [0.4, 0.3, 0.2]},
}


def write_smooth_sky(path: Path) -> Path:
    """A 32 × 16 sky without a sun (a comparison then measures the estimator, not a sun's variance)."""
    h, w = 16, 32
    v = (np.arange(h) + 0.5) / h
    u = (np.arange(w) + 0.5) / w
    env = np.stack(
        np.broadcast_arrays(
            0.6 + 0.4 * np.cos(2 * np.pi * u)[None, :], 0.4 + 0.6 * v[:, None], 0.8 - 0.5 * v[:, None] + 0 * u
        ),
        axis=-1,
    ).astype(np.float32)
    np.save(path, env)
    return path
