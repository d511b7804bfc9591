"""Where a reference's tasks run: in this process, in this machine's other cores, or on a Dask cluster
(reflets.reference.cluster).

A reference is a *job* built once per process from picklable arguments (``build(*args)``: the scene's ray-casting
geometry, its light samplers) and *tasks* it runs (``job.task(task, advance)``: a tile of pixels, a block of
samples), each with its own random stream: the results never depend on where a task ran or in which order the
tasks finished — the caller puts them together by task index. Every place has the same shape:

>>> place = places(workers, cluster)
>>> with place.start(build, args) as session:
...     for index, result in session.run(tasks, sizes, advance):
...         ...

``run`` yields ``(task index, result)`` as tasks complete; leaving the ``with`` block drops the tasks still running
(an early stop, an error, Ctrl-C); ``place.close()`` lets a cluster go.
"""

from __future__ import annotations

import contextlib
import contextvars
import itertools
import multiprocessing
import os
from collections.abc import Callable, Iterator, Sequence
from typing import Any

from ..errors import ArgumentError
from ..resources import as_reference_worker

#: the job a local worker process built when it started
_WORKER_JOB = None


class InProcess:
    """Every task in this process, in order (the progress advanced as each task goes)."""

    label = ""
    processes = 1  # of this machine, for its memory

    def start(self, build: Callable, args: tuple, local=None) -> _InProcessSession:
        """``local``: the job, when the caller has built it already."""
        return _InProcessSession(build(*args) if local is None else local)

    def close(self) -> None:
        pass


class _InProcessSession:
    def __init__(self, job):
        self.job = job

    def __enter__(self) -> _InProcessSession:
        return self

    def __exit__(self, *exc) -> None:
        pass

    def run(self, tasks: Sequence, sizes: Sequence[int], advance: Callable[[int], None]) -> Iterator[tuple[int, Any]]:
        for index, task in enumerate(tasks):
            yield index, self.job.task(task, advance)


class LocalProcesses:
    """``workers`` processes of this machine (forked where the platform can: scripts and notebooks without a
    ``__main__`` guard work; the workers touch no GL), each building the job once — started at the first run of
    more than one task (a run of one task goes in this process, with the caller's job when it has one)."""

    def __init__(self, workers: int):
        self.processes = workers
        self.label = f" ({workers} processes)"

    def start(self, build: Callable, args: tuple, local=None) -> _PoolSession:
        return _PoolSession(self.processes, build, args, local)

    def close(self) -> None:
        pass


def _init_worker(build: Callable, args: tuple) -> None:
    global _WORKER_JOB
    as_reference_worker()
    _WORKER_JOB = build(*args)


def _local_task(item) -> tuple[int, object]:
    index, task = item
    return index, _WORKER_JOB.task(task, _no_progress)


def _no_progress(samples: int) -> None:
    pass


class _PoolSession:
    def __init__(self, workers: int, build: Callable, args: tuple, local):
        self.workers, self.build, self.args, self.local = workers, build, args, local
        self.pool = None

    def __enter__(self) -> _PoolSession:
        return self

    def __exit__(self, *exc) -> None:
        if self.pool is not None:
            self.pool.terminate()  # an early stop, an error or Ctrl-C: the tasks still running are dropped at once
            self.pool.join()

    def run(self, tasks: Sequence, sizes: Sequence[int], advance: Callable[[int], None]) -> Iterator[tuple[int, Any]]:
        if len(tasks) == 1 and self.pool is None:  # no pool for one task
            self.local = self.build(*self.args) if self.local is None else self.local
            yield 0, self.local.task(tasks[0], advance)
            return
        if self.pool is None:
            method = "fork" if "fork" in multiprocessing.get_all_start_methods() else "spawn"
            processes = min(self.workers, len(tasks))  # no process without a task
            self.pool = multiprocessing.get_context(method).Pool(processes, initializer=_init_worker,
                                                                 initargs=(self.build, self.args))  # fmt: skip
        for index, result in self.pool.imap_unordered(_local_task, enumerate(tasks)):
            advance(sizes[index])
            yield index, result


#: the place a ``with using(place)`` block gives every reference that names none (a batch, a benchmark suite)
_DEFAULT = contextvars.ContextVar("reflets_reference_place", default=None)


def places(workers: int | None = None, cluster=None):
    """Where a reference runs: the Dask cluster ``cluster`` (an address, reflets.reference.cluster.connect, or a
    connected Cluster), else ``workers`` processes of this machine (one: this process); neither: the place of the
    enclosing ``using`` block (a context variable: threads started in the block do not see it), else every core
    (``cores()``). Close it after the run (a place the caller opened stays open)."""
    if cluster is not None:
        if workers is not None:
            raise ArgumentError("give either workers (this machine's processes) or a cluster, not both",
                                field="workers")  # fmt: skip
        if not isinstance(cluster, str):
            return _Lent(cluster)
        from .cluster import connect

        return connect(cluster)
    if workers is None:
        if _DEFAULT.get() is not None:
            return _Lent(_DEFAULT.get())
        workers = cores()
    if isinstance(workers, bool) or not isinstance(workers, int) or workers < 1:
        raise ArgumentError(f"workers must be at least 1 (got {workers!r})", field="workers")
    return InProcess() if workers == 1 else LocalProcesses(workers)


def within_memory(place, per_process: int, shared: int):
    """``place`` with no more local processes than the memory budget holds (each needs ``per_process`` bytes
    beside ``shared``): a default of every core must not refuse what one process can do. Other places as they are
    (a lent pool of processes is a count, no process yet: a smaller one stands for it)."""
    if not isinstance(place.place if isinstance(place, _Lent) else place, LocalProcesses):
        return place
    from ..resources import memory_budget

    fitting = max(1, (memory_budget().bytes - shared) // max(per_process, 1))
    if fitting >= place.processes:
        return place
    return InProcess() if fitting == 1 else LocalProcesses(int(fitting))


def cores() -> int:
    """The cores this process may run on (its CPU affinity: a container's or a job scheduler's share)."""
    try:
        return len(os.sched_getaffinity(0)) or 1
    except AttributeError:  # not Linux
        return os.cpu_count() or 1


def default_cluster():
    """The cluster of the enclosing ``using`` block, or None (this machine's processes, or none)."""
    place = _DEFAULT.get()
    return place if place is not None and not isinstance(place, InProcess | LocalProcesses) else None


@contextlib.contextmanager
def using(place):
    """References that name no place in the block run at ``place`` (closed by the caller)."""
    token = _DEFAULT.set(place)
    try:
        yield place
    finally:
        _DEFAULT.reset(token)


class _Lent:
    """A place the caller opened: used, never closed here."""

    def __init__(self, place):
        self.place, self.label, self.processes = place, place.label, place.processes

    def start(self, build: Callable, args: tuple, local=None):
        return self.place.start(build, args, local=local)

    def close(self) -> None:
        pass


def ordered(results: Iterator[tuple[int, object]], first: int = 0) -> Iterator[tuple[int, object]]:
    """The results in task order from ``first`` (those finished ahead of the next one wait), for sums that must be
    added in one order to be the same bit for bit."""
    waiting: dict[int, object] = {}
    expected = itertools.count(first)
    index = next(expected)
    for done, result in results:
        waiting[done] = result
        while index in waiting:
            yield index, waiting.pop(index)
            index = next(expected)
