"""glTF transmission against the reference: thin-walled glass spheres of four roughnesses, a glass sphere and a
tinted glass cube with volumes (KHR_materials_volume), each alone before a checker wall and floor under a point and
a directional light with shadows, the GPU (screen-space transmission, transmission.glsl) against the NumPy reference
(which follows the paths through the surfaces: reference/transmission.py) — relative MSE per pixel and on 4 × 4-pixel
block means — and the frame time of each against the same frame with the object opaque (transmission 0: what
the frame copy and its mips cost), medians of 12 interleaved frames of a persistent renderer (docs/assets.md).

    python tools/transmission_spheres.py
"""

from __future__ import annotations

import statistics
import sys
import tempfile
import time

import reflets
from reflets.bench.assets import block_means as blocks
from reflets.bench.transmission import glass_scene
from reflets.metrics import relmse

W, H = 160, 120
CASES = {
    "thin-walled, roughness 0": {"roughness": 0.0},
    "thin-walled, roughness 0.15": {"roughness": 0.15},
    "thin-walled, roughness 0.3": {"roughness": 0.3},
    "thin-walled, roughness 0.5": {"roughness": 0.5},
    "volume sphere (thickness = its diameter)": {"roughness": 0.0, "thickness": 1.2, "attenuation_distance": 2.0,
                                                 "attenuation_color": [0.3, 0.7, 0.95]},
    "volume cube seen face on (thickness = its edge)": {"roughness": 0.0, "thickness": 1.0,
                                                        "attenuation_distance": 1.0,
                                                        "attenuation_color": [0.1, 0.5, 0.9], "shape": "cube"},
}  # fmt: skip


def scene(directory: str, shape: str = "sphere", **glass) -> reflets.Scene:
    return glass_scene(directory, glass, shape, size=(W, H))


def frame_times(scenes: list, frames: int = 12) -> list[float]:
    """Median ms of one frame per scene, frames interleaved."""
    renderers = [reflets.Renderer(s) for s in scenes]
    times = [[] for _ in scenes]
    for r in renderers:
        r.render(spp=1)  # programs compiled, copies made
    for _ in range(frames):
        for k, r in enumerate(renderers):
            start = time.perf_counter()
            r.render(spp=1)
            times[k].append(1e3 * (time.perf_counter() - start))
    return [statistics.median(t) for t in times]


def main() -> None:
    print(f"{'case':50s} {'per pixel':>10s} {'blocks':>8s} {'ms':>7s} {'opaque ms':>9s}")
    with tempfile.TemporaryDirectory() as directory:
        for name, params in CASES.items():
            s = scene(directory, **params)
            image = reflets.render(s, spp=16)
            ref = reflets.reference(s, spp=256, pixel="box", progress=False).image
            opaque = s.model_copy(update={"materials": s.materials | {
                "glass": s.materials["glass"].model_copy(update={"transmission": 0.0})}})  # fmt: skip
            ms, ms_opaque = frame_times([s, opaque])
            print(f"{name:50s} {100 * relmse(image, ref):9.2f}% {100 * relmse(blocks(image), blocks(ref)):7.2f}% "
                  f"{ms:7.1f} {ms_opaque:9.1f}", flush=True)  # fmt: skip


if __name__ == "__main__":
    sys.exit(main())
