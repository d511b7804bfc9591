"""`reflets bench reference-scale`: references on every core and on a cluster — wall time, speed-up, per-task
overhead, driver throughput, and what those say about 100 machines.

Two references, each made in one process, in 2 (and, on a larger machine, every core's) local processes, on a
Dask cluster of 2 workers started here on 127.0.0.1 (the engine's own local start: the same code path as a real
cluster, scenes shipped, tasks serialised) and, with ``--cluster ADDRESS``, on that cluster:

- a translucent reference (the volumetric engine: blocks of samples over every pixel, their sums added in order);
- an area-light reference (the numpy engine: tiles of pixels).

Every run's image is compared with the one-process image, bit for bit. The per-task overhead and the driver's
throughput come from tasks that do nothing (reflets.reference.parallel's path, arguments included); with the
references' measured task time they bound a cluster's speed-up: a driver that hands out R tasks a second keeps at
most R × t workers busy with tasks of t seconds, and a reference of n tasks at most n workers.
"""

from __future__ import annotations

import logging
import statistics
import time

import numpy as np

from ..reference.parallel import InProcess, LocalProcesses, places
from ..reference.parallel import cores as parallel_cores

#: machines × cores of the stated projection
PROJECTED_WORKERS = 100 * 16


class _EmptyJob:
    """A job whose tasks do nothing: what remains of a task's time is the place's overhead."""

    def task(self, task, advance):
        return task


def _translucent_scene(size):
    import reflets

    return reflets.load_dict({
        "camera": {"position": [0, 0.5, 3], "look_at": [0, 0, 0], "fov_y": 35, "size": list(size)},
        "materials": {"skin": {"type": "translucent", "preset": "skin1", "eta": 1.0, "mm_per_unit": 25.0}},
        "mesh": [{"shape": "sphere", "radius": 1.0, "material": "skin"}],
        "light": [{"type": "point", "position": [2, 3, 2], "intensity": [20, 20, 20]}],
    })  # fmt: skip


def _references(quick: bool) -> list[dict]:
    from ..demo import scene_path
    from ..reference.volumetric import task_plan
    from ..scene import load_scene

    translucent_size, translucent_spp = ((32, 24), 16) if quick else ((64, 48), 32)
    area_size, area_spp = ((64, 48), 64) if quick else ((192, 144), 256)
    translucent = _translucent_scene(translucent_size)
    from ..reference.volumetric import _VolumetricJob

    blocks, pixel_tiles = task_plan(translucent_spp, len(_VolumetricJob(translucent, None, None).pix))
    from ..reference.montecarlo import RAYS_PER_CHUNK

    tiles = -(-area_size[0] * area_size[1] // max(1, RAYS_PER_CHUNK // area_spp))
    return [
        {"name": "translucent (volumetric engine)", "scene": translucent, "engine": "volumetric",
         "size": translucent_size, "spp": translucent_spp, "tasks": len(blocks) * len(pixel_tiles)},
        {"name": "area light (numpy engine)", "scene": load_scene(scene_path("11_ref_ggx_sphere_quad.toml")),
         "engine": "numpy", "size": area_size, "spp": area_spp, "tasks": tiles},
    ]  # fmt: skip


def _overhead(place, tasks: int) -> dict:
    """Per-task overhead and driver throughput of ``place`` (tasks that do nothing)."""
    with place.start(_EmptyJob, ()) as session:
        list(session.run(list(range(8)), [1] * 8, lambda k: None))  # the workers started, the job built
        start = time.perf_counter()
        done = sum(1 for _ in session.run(list(range(tasks)), [1] * tasks, lambda k: None))
        seconds = time.perf_counter() - start
    return {"tasks": done, "seconds": seconds, "overhead_ms": seconds / done * 1e3, "tasks_per_s": done / seconds}


def bench_reference_scale(quick: bool, out_dir) -> tuple[dict, str]:
    from distributed import LocalCluster

    from ..reference import reference
    from ..reference.cluster import connect, engine_version
    from ..reference.parallel import default_cluster

    runs = 1 if quick else 3
    cores = parallel_cores()
    counts = sorted({1, 2, cores})
    start = time.perf_counter()
    local = LocalCluster(n_workers=2, threads_per_worker=1, processes=True, host="127.0.0.1",
                         dashboard_address=None, silence_logs=logging.ERROR)  # fmt: skip
    cluster_start_s = time.perf_counter() - start
    given = default_cluster()  # `reflets bench --cluster`
    dask_local = None
    try:
        dask_local = connect(local.scheduler_address)
        places_run = [(f"{n} process{'es' if n > 1 else ''}", n, places(n)) for n in counts]
        places_run.append(("Dask, 2 local workers", 2, dask_local))
        if given is not None:
            places_run.append((f"Dask at {given.address}", given.workers, places(cluster=given)))
        rows = []
        for ref in _references(quick):
            base = None
            for label, workers, place in places_run:
                times, image = [], None
                for _ in range(runs):
                    t0 = time.perf_counter()
                    result = reference(ref["scene"], spp=ref["spp"], size=ref["size"], engine=ref["engine"],
                                       progress=False, **_where(place))  # fmt: skip
                    times.append(time.perf_counter() - t0)
                    image = result
                seconds = statistics.median(times)
                if base is None:
                    base = (seconds, image)
                rows.append({
                    "reference": ref["name"], "size": list(ref["size"]), "spp": ref["spp"], "tasks": ref["tasks"],
                    "place": label, "workers": workers, "seconds": seconds, "all_seconds": times,
                    "speedup": base[0] / seconds,
                    "identical": bool(np.array_equal(image.image, base[1].image)
                                      and np.array_equal(image.stderr, base[1].stderr)),
                })  # fmt: skip
        overheads = {label: _overhead(place, 100 if quick else 400) for label, _, place in places_run
                     if not isinstance(place, InProcess)}  # fmt: skip
    finally:
        if dask_local is not None:
            dask_local.close()
        local.close()
    results = {"cluster_engine": f"dask.distributed {engine_version()}", "cores": cores,
               "local_cluster_start_s": cluster_start_s, "rows": rows, "overhead": overheads,
               "projection": _projection(rows, overheads["Dask, 2 local workers"])}  # fmt: skip
    return results, _markdown(results, runs)


def _where(place) -> dict:
    if isinstance(place, InProcess):
        return {"workers": 1}
    if isinstance(place, LocalProcesses):
        return {"workers": place.processes}
    return {"cluster": place}


def _projection(rows: list[dict], dask: dict) -> list[dict]:
    """Each reference on PROJECTED_WORKERS workers: at most its task count busy, and at most what the driver hands
    out (tasks / s × a task's seconds)."""
    out = []
    for row in rows:
        if row["place"] != "1 process":
            continue
        task_s = row["seconds"] / row["tasks"]
        driver_bound = dask["tasks_per_s"] * task_s
        out.append({"reference": row["reference"], "task_seconds": task_s, "tasks": row["tasks"],
                    "driver_bound_workers": driver_bound,
                    "speedup_bound": min(PROJECTED_WORKERS, row["tasks"], driver_bound),
                    "task_seconds_for_all": PROJECTED_WORKERS / dask["tasks_per_s"]})  # fmt: skip
    return out


def _markdown(results: dict, runs: int) -> str:
    lines = [
        "# References on every core and on a cluster",
        "",
        f"Cluster engine: {results['cluster_engine']}; {results['cores']} cores here; a local Dask cluster of 2 "
        f"workers started in {results['local_cluster_start_s']:.2f} s. Wall time: median of {runs} run(s).",
        "",
        "| reference | size | spp | tasks | where | wall s | speed-up | image = 1 process |",
        "|---|---|---|---|---|---|---|---|",
    ]
    for r in results["rows"]:
        same = "bit for bit" if r["identical"] else "NO"
        lines.append(f"| {r['reference']} | {r['size'][0]}×{r['size'][1]} | {r['spp']} | {r['tasks']} | {r['place']} "
                     f"| {r['seconds']:.2f} | {r['speedup']:.2f}× | {same} |")  # fmt: skip
    lines += ["", "| where | empty tasks | per-task overhead | driver throughput |", "|---|---|---|---|"]
    for label, o in results["overhead"].items():
        lines.append(f"| {label} | {o['tasks']} | {o['overhead_ms']:.2f} ms | {o['tasks_per_s']:.0f} tasks/s |")
    lines += ["", f"Projection to 100 machines × 16 cores ({PROJECTED_WORKERS} workers), from the Dask driver's "
              "throughput here and each reference's task time in one process:", "",
              "| reference | task s | tasks | workers the driver keeps busy | speed-up bound | task s to keep "
              f"{PROJECTED_WORKERS} busy |", "|---|---|---|---|---|---|"]  # fmt: skip
    for p in results["projection"]:
        lines.append(f"| {p['reference']} | {p['task_seconds']:.3f} | {p['tasks']} | {p['driver_bound_workers']:.0f} "
                     f"| {p['speedup_bound']:.0f}× | {p['task_seconds_for_all']:.1f} |")  # fmt: skip
    lines += ["", "A reference keeps at most as many workers busy as it has tasks, and the driver at most "
              "(tasks / s) × (a task's seconds): larger references have more tasks (tiles: pixels × spp / "
              "131,072 rays; blocks of samples: ≥ 8), and a driver far from the workers pays the network's round "
              "trip per task on top of the overhead above."]  # fmt: skip
    return "\n".join(lines) + "\n"
