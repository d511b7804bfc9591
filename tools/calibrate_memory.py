"""Estimated against measured memory for estimates of reflets.resources (docs/inputs-and-outputs.md, calibration):
Fermat's ``subdivide``, the scratch table's size, a frame's bytes per sample and an image write's bytes per pixel.
Each measurement runs in a fresh process and reads its own peak resident memory (VmHWM): the growth over the same
run at subdivide = 1, a table's or a write's growth over the process before it, and the growth of a render between
two sizes over the samples it adds.

    python tools/calibrate_memory.py                 # the defaults below (about 20 s here)
    python tools/calibrate_memory.py --subdivide 10 20 40 60 80 --tables 512 1024
"""

from __future__ import annotations

import argparse
import subprocess
import sys

TEAPOT = "src/reflets/data/scenes/40_reflect_teapot_sphere.toml"
PLANE = "src/reflets/data/scenes/01_plane_point.toml"

_PEAK = "int([l for l in open('/proc/self/status') if l.startswith('VmHWM')][0].split()[1]) * 1024"
_SUBDIVIDE = f"""
import sys, reflets
from reflets.renderer import Renderer
with Renderer(reflets.load_scene({TEAPOT!r}), method="fermat", size=(64, 48), subdivide=int(sys.argv[1])) as r:
    r.render()
print({_PEAK})
"""
_TABLE = f"""
import sys
from reflets.scratches.table import build_table
before = {_PEAK}
build_table("vgroove:0.5", ior=None, size=int(sys.argv[1]), rays=200)
print({_PEAK} - before)
"""


_FRAME = f"""
import sys, reflets
reflets.render({PLANE!r}, method="forward", size=(int(sys.argv[1]), int(sys.argv[1])))
print({_PEAK})
"""
_WRITE = f"""
import sys, numpy as np
from reflets.imageio import write_image
write_image(sys.argv[1], np.zeros((2, 2, 3), np.float32))  # the format's libraries imported first
image = np.random.default_rng(0).random((2048, 2048, 3), dtype=np.float32)  # noise: the least compressible
before = {_PEAK}
write_image(sys.argv[1], image)
print({_PEAK} - before)
"""


def _run(code: str, *args) -> int:
    out = subprocess.run([sys.executable, "-c", code, *map(str, args)], capture_output=True, text=True, check=True)
    return int(out.stdout.split()[-1])


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--subdivide", type=int, nargs="*", default=[10, 20, 40])
    parser.add_argument("--tables", type=int, nargs="*", default=[512, 1024])
    parser.add_argument("--frames", type=int, nargs=2, default=[1024, 2048], help="two square render sizes")
    parser.add_argument("--writes", nargs="*", default=[".png", ".hdr", ".exr", ".npy"])
    args = parser.parse_args()

    import reflets
    from reflets.reflections.technique import subdivision_bytes
    from reflets.scene.geometry import mesh_data
    from reflets.scratches.table import table_bytes

    scene = reflets.load_scene(TEAPOT)
    reflected = [mesh_data(scene, i) for i in (1, 2)]  # the teapot and the sphere seen in the mirror
    base = _run(_SUBDIVIDE, 1)
    print(f"subdivide = 1: peak {base / 1e6:.0f} MB")
    print("| subdivide | estimate (MB) | measured growth (MB) | estimate / measured |")
    print("|---|---|---|---|")
    for k in args.subdivide:
        estimate = subdivision_bytes([(m.n_triangles, m.n_vertices, k) for m in reflected], 1)
        growth = _run(_SUBDIVIDE, k) - base
        print(f"| {k} | {estimate / 1e6:.1f} | {growth / 1e6:.1f} | {estimate / growth:.2f} |")
    print("\n| table size (rays 200) | estimate (MB) | measured growth (MB) |")
    print("|---|---|---|")
    for size in args.tables:
        print(f"| {size} | {table_bytes(size, 200, 1, 'numpy') / 1e6:.0f} | {_run(_TABLE, size) / 1e6:.0f} |")

    import tempfile

    from reflets.imageio import WRITE_BYTES_PER_PIXEL
    from reflets.techniques.base import FRAME_BYTES_PER_SAMPLE

    small, large = args.frames
    per_sample = (_run(_FRAME, large) - _run(_FRAME, small)) / (large * large - small * small)
    print(f"\nframe ({small}² → {large}², forward, 1 spp): {per_sample:.1f} B per sample "
          f"(estimate {FRAME_BYTES_PER_SAMPLE})")  # fmt: skip
    print("\n| write (2048² noise) | estimate (B/px) | measured (B/px) |")
    print("|---|---|---|")
    with tempfile.TemporaryDirectory() as folder:
        for ext in args.writes:
            grown = _run(_WRITE, f"{folder}/out{ext}") / 2048**2
            print(f"| {ext} | {WRITE_BYTES_PER_PIXEL[ext]} | {grown:.1f} |")


if __name__ == "__main__":
    main()
