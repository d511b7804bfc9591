"""`reflets bench reference`: throughput of the ground-truth renderers (samples per second).

Each scene is rendered by the NumPy reference (shadows on and off) and, when the ``reference`` extra is
installed, by Mitsuba 3 (``scalar_rgb``) at the same size and spp, in the same run, so the ratio between
engines is meaningful on a noisy machine. Throughput = pixels × spp / wall-clock seconds (median of runs).
"""

from __future__ import annotations

import statistics

from ..demo import scene_path
from ..scene import load_scene

SCENES = ["10_ref_plane_quad.toml", "11_ref_ggx_sphere_quad.toml", "12_ref_sphere_env.toml"]


def _mitsuba_available() -> bool:
    try:
        import mitsuba  # noqa: F401
    except ImportError:
        return False
    return True


def bench_reference(quick: bool, out_dir) -> tuple[dict, str]:
    from ..reference import reference

    size, spp, runs = ((48, 32), 16, 1) if quick else ((128, 96), 64, 3)
    engines = [("numpy", True), ("numpy", False)] + ([("mitsuba", True)] if _mitsuba_available() else [])
    rows = []
    for name in SCENES:
        scene = load_scene(scene_path(name))
        for engine, visibility in engines:
            rates = []
            for run in range(runs):
                result = reference(  # one process: the throughput of one core (reference-scale: of several)
                    scene, spp=spp, seed=run, engine=engine, visibility=visibility, size=size, progress=False,
                    workers=1,
                )
                rates.append(result.samples_per_second)
            rows.append(
                {
                    "scene": name,
                    "engine": engine,
                    "visibility": visibility,
                    "size": list(size),
                    "spp": spp,
                    "runs": runs,
                    "samples_per_second_median": statistics.median(rates),
                    "samples_per_second": rates,
                }
            )
    lines = [
        "# Reference renderer throughput",
        "",
        f"{size[0]}×{size[1]} pixels, {spp} spp, median of {runs} run(s); samples = pixels × spp.",
        "",
        "| scene | engine | shadows | M samples/s |",
        "|---|---|---|---|",
    ]
    for r in rows:
        lines.append(
            f"| {r['scene']} | {r['engine']} | {'on' if r['visibility'] else 'off'} | "
            f"{r['samples_per_second_median'] / 1e6:.3f} |"
        )
    if not _mitsuba_available():
        lines += ["", "Mitsuba 3 is not installed here (`pip install 'reflets[reference]'`): no Mitsuba rows."]
    return {"rows": rows}, "\n".join(lines) + "\n"
