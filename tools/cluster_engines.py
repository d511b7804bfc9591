"""Ray or Dask distributed for reflets' references on a cluster: what each costs, measured the same way.

Run it with the Python of an environment that has one engine (and nothing else of size):

    python -m venv /tmp/dask && /tmp/dask/bin/pip install "dask[distributed]"
    /tmp/dask/bin/python tools/cluster_engines.py dask
    python -m venv /tmp/ray && /tmp/ray/bin/pip install ray
    /tmp/ray/bin/python tools/cluster_engines.py ray

It prints one JSON line: the engine's version, its installed weight (the environment's site-packages less pip and
setuptools), a local cluster of 2 worker processes on 127.0.0.1 started and stopped, the per-task overhead (1,000
empty tasks submitted at once: wall time / 1,000; and one task at a time, submit then wait: the median round trip),
and its fault handling (four 2-second tasks, one worker process killed after 0.5 s: do all four come back, in how
long). docs/reference-scale.md quotes the numbers of one run on the development machine.
"""

from __future__ import annotations

import json
import os
import signal
import statistics
import sys
import sysconfig
import tempfile
import time
from pathlib import Path


def installed_mb() -> float:
    site = Path(sysconfig.get_paths()["purelib"])
    skip = ("pip", "setuptools", "_distutils_hack", "distutils-precedence.pth")
    total = 0
    for entry in site.iterdir():
        if entry.name.split("-")[0] in skip:
            continue
        files = [entry] if entry.is_file() else [p for p in entry.rglob("*") if p.is_file()]
        total += sum(p.stat().st_size for p in files)
    return total / 1e6


def empty(i: int) -> int:
    return i


def sleeper(args) -> int:
    """Sleeps, and says which process ran it (in a file: the driver kills that process)."""
    seconds, folder = args
    Path(folder, str(os.getpid())).touch()
    time.sleep(seconds)
    return os.getpid()


class Dask:
    def __init__(self):
        import distributed

        self.version = distributed.__version__
        self.cluster = distributed.LocalCluster(n_workers=2, threads_per_worker=1, processes=True,
                                                host="127.0.0.1", dashboard_address=None)  # fmt: skip
        self.client = distributed.Client(self.cluster)

    def map(self, fn, items) -> list:
        return self.client.gather(self.client.map(fn, items, pure=False))

    def one(self, fn, item):
        return self.client.submit(fn, item, pure=False).result()

    def close(self) -> None:
        self.client.close()
        self.cluster.close()


class Ray:
    def __init__(self):
        import ray

        self.ray, self.version = ray, ray.__version__
        ray.init(num_cpus=2, include_dashboard=False, log_to_driver=False, address="local")
        self.remote = {}

    def _task(self, fn):
        if fn not in self.remote:
            self.remote[fn] = self.ray.remote(fn)
        return self.remote[fn]

    def map(self, fn, items) -> list:
        task = self._task(fn)
        return self.ray.get([task.remote(i) for i in items])

    def one(self, fn, item):
        return self.ray.get(self._task(fn).remote(item))

    def close(self) -> None:
        self.ray.shutdown()


def measure(engine: str) -> dict:
    start = time.perf_counter()
    cluster = {"dask": Dask, "ray": Ray}[engine]()
    started = time.perf_counter() - start
    cluster.map(empty, range(20))  # warm: the workers have imported the task's module
    start = time.perf_counter()
    assert cluster.map(empty, range(1000)) == list(range(1000))
    bulk_ms = (time.perf_counter() - start) / 1000 * 1e3
    trips = []
    for i in range(50):
        start = time.perf_counter()
        cluster.one(empty, i)
        trips.append((time.perf_counter() - start) * 1e3)
    with tempfile.TemporaryDirectory() as folder:
        start = time.perf_counter()
        if engine == "dask":
            futures = cluster.client.map(sleeper, [(2.0, folder)] * 4, pure=False)
        else:
            futures = [cluster._task(sleeper).remote((2.0, folder)) for _ in range(4)]
        time.sleep(0.5)
        victim = int(sorted(os.listdir(folder))[0])
        os.kill(victim, signal.SIGKILL)
        try:
            results = cluster.client.gather(futures) if engine == "dask" else cluster.ray.get(futures)
            recovered = len(results) == 4
        except Exception as exc:  # noqa: BLE001 — what the engine raises is what we report
            recovered, results = False, repr(exc)
        fault_s = time.perf_counter() - start
    start = time.perf_counter()
    cluster.close()
    return {
        "engine": engine,
        "version": cluster.version,
        "python": sys.version.split()[0],
        "installed_mb": round(installed_mb(), 1),
        "start_s": round(started, 2),
        "stop_s": round(time.perf_counter() - start, 2),
        "task_overhead_bulk_ms": round(bulk_ms, 3),
        "task_round_trip_ms": round(statistics.median(trips), 2),
        "worker_killed": {"all_tasks_returned": recovered, "seconds": round(fault_s, 2),
                          "ideal_seconds": 4.0},  # fmt: skip
    }


if __name__ == "__main__":
    if len(sys.argv) != 2 or sys.argv[1] not in ("dask", "ray"):
        sys.exit("usage: python tools/cluster_engines.py dask|ray")
    print(json.dumps(measure(sys.argv[1])))
