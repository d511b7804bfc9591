"""The volumetric reference in 1 and 2 processes: the same image and standard error bit for bit, and the speed-up
(issue 31's first step; `reflets bench reference-scale` is to measure it properly). About 20 s here.

    python tools/volumetric_workers.py
"""

from __future__ import annotations

import time

import numpy as np

import reflets
from reflets.reference.volumetric import render_volumetric

SCENE = {
    "camera": {"position": [0, 0.5, 3], "look_at": [0, 0, 0], "fov_y": 35, "size": [64, 48]},
    "materials": {"skin": {"type": "translucent", "preset": "skin1", "eta": 1.0, "mm_per_unit": 25.0}},
    "mesh": [{"shape": "sphere", "radius": 1.0, "material": "skin"}],
    "light": [{"type": "point", "position": [2, 3, 2], "intensity": [20, 20, 20]}],
}


def main() -> None:
    scene = reflets.load_dict(SCENE)
    seconds, results = {1: [], 2: []}, {}
    for workers in (1, 2, 1, 2):  # interleaved: both see the same machine load
        start = time.perf_counter()
        results[workers] = render_volumetric(scene, spp=32, seed=1, workers=workers, progress=False)
        seconds[workers].append(time.perf_counter() - start)
    same = all(np.array_equal(getattr(results[1], k), getattr(results[2], k)) for k in ("image", "stderr"))
    one, two = min(seconds[1]), min(seconds[2])
    print(f"64×48 translucent sphere, 32 spp: 1 process {one:.2f} s, 2 processes {two:.2f} s "
          f"({one / two:.2f}×, best of 2 each); image and standard error identical: {same}")  # fmt: skip


if __name__ == "__main__":
    main()
