"""References on a cluster, through Dask distributed (why Dask and not Ray: docs/reference-scale.md).

Start a scheduler and workers (``dask scheduler`` on one machine, ``dask worker tcp://HOST:8786`` on each of the
others, after ``pip install reflets`` there), then ``reflets reference SCENE --cluster tcp://HOST:8786``. A
reference's tasks (reflets.reference.parallel) go to the workers; nothing is assumed shared between the machines
but the scheduler's address:

- **the scene travels by content**: its description, and every file it reads (meshes, textures, maps, measured
  BRDFs) keyed by SHA-256, put on the cluster once per run and sent to each worker that runs a task (its
  dependency). A worker keeps on its disk the files it lacked (``cache_dir("cluster")``), then lays them out as
  on this machine (relative references inside a glTF hold) under a folder named by the scene's content key;
- **versions are checked first**: every worker runs the same reflets, NumPy, Python (major.minor) and Dask as this
  process (the random streams and the sums bit for bit), or the run stops before any task, in one line;
- **a lost worker's tasks run again** elsewhere (Dask reschedules the tasks of a worker that dies); each task draws
  from its own random stream and the results are put together by task index, so the image is the same.
"""

from __future__ import annotations

import asyncio
import contextlib
import hashlib
import os
import shutil
import sys
import threading
import uuid
from collections.abc import Callable, Iterator, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from ..cache import cache_dir, content_key
from ..errors import ArgumentError, RefletsError
from ..resources import as_reference_worker

#: seconds to reach the scheduler, then for a first worker to be there
CONNECT_TIMEOUT_S = 10.0
WORKER_TIMEOUT_S = 30.0
#: the packages whose versions must match between this process and every worker (Mitsuba is optional: a worker
#: without it refuses the Mitsuba bridge's windows in one line, and a worker needs only `pip install reflets`)
MATCHED = ("reflets", "numpy", "scipy", "embreex", "trimesh", "distributed", "cloudpickle")


def engine_version() -> str | None:
    """The cluster engine's version (``reflets info``), None when it is not installed."""
    from importlib import metadata

    try:
        return metadata.version("distributed")
    except metadata.PackageNotFoundError:
        return None


def versions() -> dict[str, str]:
    """This process's versions of what the results depend on (run on each worker too)."""
    from importlib import metadata

    found = {"python": ".".join(map(str, sys.version_info[:2]))}
    for name in MATCHED:
        try:
            found[name] = metadata.version(name)
        except metadata.PackageNotFoundError:
            found[name] = "not installed"
    return found


def check_versions(address: str, here: dict[str, str], workers: dict[str, dict[str, str]]) -> None:
    """One line naming the first worker whose versions differ from this process's."""
    for worker, theirs in sorted(workers.items()):
        wrong = [f"{name} {theirs.get(name)} (here {mine})" for name, mine in here.items() if theirs.get(name) != mine]
        if wrong:
            raise ArgumentError(f"worker {worker} runs {', '.join(wrong)}: install the same versions on every "
                                "machine", field=f"--cluster {address}".strip())  # fmt: skip


def check_address(address) -> None:
    """A scheduler's address, ``tcp://HOST:PORT`` (checked before any work: a typo fails at once)."""
    from distributed.comm import parse_address

    if not isinstance(address, str) or not address.strip():
        raise ArgumentError("an address is needed, like tcp://HOST:8786", field="--cluster")
    try:
        scheme, location = parse_address(address)
        host, _, port = location.rpartition(":")
        if scheme != "tcp" or not host or not port.isdigit() or not 0 < int(port) < 65536:
            raise ValueError(location)
    except ValueError:
        raise ArgumentError("not a scheduler address; expected tcp://HOST:PORT (a Dask scheduler's, as `dask "
                            "scheduler` prints it; tcp only)", field=f"--cluster {address}") from None  # fmt: skip


def connect(address: str) -> Cluster:
    """A Dask scheduler at ``address`` (``tcp://HOST:PORT``) with at least one worker whose versions match:
    or one line, exit 2 — a malformed address, a scheduler that does not answer within CONNECT_TIMEOUT_S, no
    worker within WORKER_TIMEOUT_S, a worker without reflets or with other versions."""
    import distributed

    check_address(address)
    where = f"--cluster {address}"
    try:
        client = distributed.Client(address, timeout=CONNECT_TIMEOUT_S, set_as_default=False)
    except (OSError, TimeoutError) as exc:
        raise ArgumentError(f"no Dask scheduler answered within {CONNECT_TIMEOUT_S:g} s ({type(exc).__name__}): "
                            "is `dask scheduler` running there, and the port open?", field=where) from None  # fmt: skip
    try:
        client.wait_for_workers(1, timeout=WORKER_TIMEOUT_S)
    except (OSError, TimeoutError):
        client.close()
        raise ArgumentError(f"the scheduler has no worker (none joined within {WORKER_TIMEOUT_S:g} s): start "
                            "`dask worker ADDRESS` on the machines", field=where) from None  # fmt: skip
    try:
        theirs = client.run(versions)
    except Exception as exc:  # noqa: BLE001 — a worker that cannot even import reflets: said in one line
        client.close()
        raise ArgumentError(f"a worker could not run reflets ({type(exc).__name__}: {exc}): `pip install "
                            f"reflets=={versions()['reflets']}` on every machine", field=where) from None  # fmt: skip
    try:
        check_versions(address, versions(), theirs)
    except ArgumentError:
        client.close()
        raise
    return Cluster(address, client, len(theirs))


class Cluster:
    """A connected Dask cluster; ``start(build, args)`` as reflets.reference.parallel's places."""

    def __init__(self, address: str, client, workers: int):
        self.address, self.client, self.workers = address, client, workers
        self.label = f" ({workers} workers at {address})"

    processes = 1  # of this machine, for its memory

    def start(self, build: Callable, args: tuple, local=None) -> _ClusterSession:
        """The tasks of ``build(*args)``'s job on the workers (``local``, a job built here, is not used)."""
        session = _ClusterSession(self, build)
        session.args = tuple(session.ship(a) for a in args)
        return session

    def close(self) -> None:
        self.client.close()


class _ClusterSession:
    def __init__(self, cluster: Cluster, build: Callable):
        self.cluster, self.build, self.args = cluster, build, ()
        self.token = uuid.uuid4().hex
        self.runs = 0
        self.pending: set = set()
        self.files: dict = {}  # SHA-256 → the file's bytes scattered on the cluster (a dependency of every task)

    def __enter__(self) -> _ClusterSession:
        return self

    def __exit__(self, *exc) -> None:
        try:  # an early stop, an error or Ctrl-C: nothing left running
            self.cluster.client.cancel(list(self.pending) + list(self.files.values()))
        except Exception:  # noqa: BLE001 — a lost connection: nothing to cancel, and the first error is the one to say
            pass

    def ship(self, value):
        """A scene made ready to travel: its files' contents put on the cluster once, a dependency of every task
        (Dask brings them to whichever worker runs one — a new machine, a worker that joined later —, which keeps
        on its disk those it lacked); other values as they are."""
        from ..scene.model import Scene

        if not isinstance(value, Scene):
            return value
        shipped, contents = ShippedScene.packed(value)
        new = sorted(set(contents) - set(self.files))
        if new:
            with self._said():
                futures = self.cluster.client.scatter([contents[d] for d in new], hash=False)
            self.files.update(zip(new, futures, strict=True))
        return shipped

    def run(self, tasks: Sequence, sizes: Sequence[int], advance: Callable[[int], None]) -> Iterator[tuple[int, Any]]:
        from distributed import as_completed
        from distributed.scheduler import KilledWorker

        client, here = self.cluster.client, versions()
        self.runs += 1  # a session's runs (adaptive rounds) never share a task's key
        with self._said():
            futures = [client.submit(_cluster_task, self.token, self.build, self.args, task, here, self.files,
                                     pure=False, key=f"reflets-{self.token}-{self.runs}-{index}")
                       for index, task in enumerate(tasks)]  # fmt: skip
        self.pending.update(futures)
        index_of = {future.key: index for index, future in enumerate(futures)}
        completed = as_completed(futures, loop=client.loop)
        del futures  # a result is held by nothing here once it has been yielded: the workers release it
        for future in completed:
            index = index_of[future.key]
            try:
                with self._said():
                    result = future.result()
            except KilledWorker:
                raise RefletsError(f"task {index} lost every worker it ran on: the workers' memory, or their logs, "
                                   "say why", field=f"--cluster {self.cluster.address}") from None  # fmt: skip
            self.pending.discard(future)  # its result is released on the workers once yielded
            advance(sizes[index])
            yield index, result

    @contextlib.contextmanager
    def _said(self):
        """The cluster's own failures (a lost connection, a scheduler gone, cancelled tasks) in one line."""
        from distributed.client import FutureCancelledError
        from distributed.comm import CommClosedError

        try:
            yield
        except (CommClosedError, FutureCancelledError, OSError, asyncio.CancelledError) as exc:
            raise RefletsError(f"the cluster stopped answering ({type(exc).__name__}: {exc})",
                               field=f"--cluster {self.cluster.address}") from None  # fmt: skip


# ----------------------------------------------------------------------------------------- on a worker
_JOBS: dict[str, object] = {}
_JOBS_LOCK = threading.Lock()  # a worker with several threads builds a run's job once


def _cluster_task(token: str, build: Callable, args: tuple, task, expected: dict[str, str], files: dict[str, bytes]):
    """A task on a worker: the run's job built on its first task there (this worker's versions checked against
    the driver's — a worker that joined after the start was never asked —, the files it lacked kept on its disk,
    the scene laid out from them)."""
    with _JOBS_LOCK:
        if token not in _JOBS:
            as_reference_worker()
            mine = versions()
            if mine != expected:
                from distributed import get_worker

                check_versions("", expected, {get_worker().address: mine})
            _keep_files({d: data for d, data in files.items() if not (_files_dir() / d).is_file()})
            while len(_JOBS) >= 2:  # a batch of scenes: the last two kept
                _JOBS.pop(next(iter(_JOBS)))
            _JOBS[token] = build(*(a.scene() if isinstance(a, ShippedScene) else a for a in args))
        job = _JOBS[token]
    return job.task(task, _no_progress)


def _no_progress(samples: int) -> None:
    pass


def _files_dir() -> Path:
    return cache_dir("cluster") / "files"


def _keep_files(contents: dict[str, bytes]) -> None:
    folder = _files_dir()
    folder.mkdir(parents=True, exist_ok=True)
    for digest, data in contents.items():
        if hashlib.sha256(data).hexdigest() != digest:
            raise RefletsError(f"a file sent to this worker does not match its digest {digest}")
        writing = folder / f"{digest}.{uuid.uuid4().hex}.writing"  # workers of one machine share the folder
        writing.write_bytes(data)
        os.replace(writing, folder / digest)


@dataclass(frozen=True)
class ShippedScene:
    """A scene as it travels: its description (file paths absolute, as on the machine it left) and the SHA-256 of
    each file it reads."""

    description: dict
    files: dict[str, str]  # absolute path → SHA-256 of its content
    key: str

    @classmethod
    def packed(cls, scene) -> tuple[ShippedScene, dict[str, bytes]]:
        """The scene as it travels, and its files' contents by SHA-256 (each file read once)."""
        description = _map_paths(scene.model_dump(), lambda p: scene.resolve(p).resolve())
        contents = {str(path): path.read_bytes() for path in sorted(scene.input_files())}
        files = {path: hashlib.sha256(data).hexdigest() for path, data in contents.items()}
        shipped = cls(description, files, content_key({"scene": repr(description), "files": files}))
        return shipped, {files[path]: data for path, data in contents.items()}

    def scene(self):
        """The scene on this machine: its files laid out under a folder of its own, from the files kept."""
        from ..scene.model import Scene

        root = cache_dir("cluster") / "scenes" / self.key
        if not root.is_dir():
            building = root.with_name(f"{self.key}.{uuid.uuid4().hex}.building")
            for path, digest in self.files.items():
                kept = _files_dir() / digest
                if not kept.is_file():
                    raise RefletsError(f"the file {path} (SHA-256 {digest}) was not sent to this worker")
                target = _under(building, Path(path))
                target.parent.mkdir(parents=True, exist_ok=True)
                try:
                    os.link(kept, target)
                except OSError:
                    shutil.copyfile(kept, target)
            building.mkdir(parents=True, exist_ok=True)
            try:
                os.rename(building, root)
            except OSError:  # another worker of this machine laid it out first
                shutil.rmtree(building, ignore_errors=True)
        return Scene.model_validate(_map_paths(self.description, lambda p: _under(root, p)))


def _under(root: Path, path: Path) -> Path:
    return root / Path(path).relative_to(Path(path).anchor)


def _map_paths(value, change: Callable[[Path], Path]):
    """``value`` (a scene's model_dump) with every Path changed."""
    if isinstance(value, Path):
        return change(value)
    if isinstance(value, dict):
        return {k: _map_paths(v, change) for k, v in value.items()}
    if isinstance(value, list | tuple):
        return type(value)(_map_paths(v, change) for v in value)
    return value
