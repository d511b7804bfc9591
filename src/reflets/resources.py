"""Work estimated before it is allocated (issue 21): what a parameter that multiplies memory will need, checked
against what this machine has available before anything is allocated.

A parameter that multiplies memory (Fermat's ``subdivide``, an image size × its supersampling, a table's size)
is turned into an estimate of the bytes it allocates — an honest upper bound from the real arrays, the formula
in the docstring of the function that computes it — and :func:`check` refuses it, by name, when the estimate
is more than :func:`available_memory`: one line, exit status 2 from the CLI (a :class:`~reflets.errors.ResourceError`)::

    reflets: error: subdivide: 400 needs about 50.4 GB (240,197,376 reflected vertices) but 24.1 GB is
    available (MemAvailable); lower it (≤ 276 fits)

The available memory is the least of ``MemAvailable`` (/proc/meminfo), the cgroup's memory limit less its usage
(v2 ``memory.max``, v1 ``memory.limit_in_bytes``; reclaimable page cache not counted as used) and the address
space ``RLIMIT_AS`` leaves; ``REFLETS_MEMORY_LIMIT`` (bytes, or with a unit: ``512MB``, ``2GiB``) replaces it —
for tests, and for users who know better (swap, or memory that is about to be freed). Sizes are printed in
decimal units (1 GB = 10⁹ bytes).
"""

from __future__ import annotations

import math
import os
import re
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path

from .errors import ArgumentError, ResourceError

#: the environment variable that replaces the measured available memory (bytes, or a number with a unit)
ENV_VAR = "REFLETS_MEMORY_LIMIT"

_UNITS = {
    "": 1, "k": 10**3, "m": 10**6, "g": 10**9, "t": 10**12,
    "ki": 2**10, "mi": 2**20, "gi": 2**30, "ti": 2**40,
}  # fmt: skip
_SIZE = re.compile(r"\s*(\d+(?:\.\d*)?|\.\d+)(?:[eE]([+-]?\d+))?\s*([kmgt]i?)?b?\s*", re.IGNORECASE)
#: a cgroup limit at or above this is "no limit" (v1 writes 2⁶³ rounded down to a page)
_NO_LIMIT = 1 << 60


@dataclass(frozen=True)
class Budget:
    """The memory a new allocation may take: ``bytes``, and ``source``, where that number comes from."""

    bytes: int
    source: str


def parse_bytes(text: str) -> int:
    """A size in bytes: ``8000000000``, ``1e9``, ``512MB``, ``512 M``, ``1.5GiB``, ``64kib`` (k, M, G, T: powers
    of 1000; Ki, Mi, Gi, Ti: of 1024; the trailing B optional, case ignored). Not a positive size: an
    ArgumentError naming REFLETS_MEMORY_LIMIT."""
    m = _SIZE.fullmatch(str(text))
    value = None
    if m:
        number, exponent, unit = m.groups()
        try:
            value = float(number) * 10.0 ** int(exponent or 0) * _UNITS[(unit or "").lower()]
        except OverflowError:
            value = None
    if value is None or not 1 <= value < 2**63:
        raise ArgumentError(f"{text!r} is not a positive number of bytes (e.g. 8000000000, 512MB, 2GiB)", field=ENV_VAR)
    return int(value)


def memory_budget() -> Budget:
    """The memory available to this process now (see the module docstring), and where the number comes from."""
    override = os.environ.get(ENV_VAR)
    if override is not None and override.strip():
        return Budget(parse_bytes(override), ENV_VAR)
    candidates = [c for c in (_meminfo(), _cgroup(), _address_space()) if c is not None]
    if not candidates:  # not Linux: physical memory, or no limit at all
        try:
            return Budget(os.sysconf("SC_PHYS_PAGES") * os.sysconf("SC_PAGE_SIZE"), "physical memory")
        except (AttributeError, ValueError, OSError):
            return Budget(1 << 62, "unknown")
    return min(candidates, key=lambda b: b.bytes)


def available_memory() -> int:
    """Bytes a new allocation may take now: the least of MemAvailable, the cgroup's limit less its usage and
    RLIMIT_AS less the address space in use; ``REFLETS_MEMORY_LIMIT`` replaces it when set."""
    return memory_budget().bytes


def format_bytes(n: float) -> str:
    """``50.4 GB``, ``512 MB``, ``900 kB``, ``12 B`` (decimal units)."""
    for unit, size in (("TB", 1e12), ("GB", 1e9), ("MB", 1e6), ("kB", 1e3)):
        if n >= size:
            value = n / size
            return f"{value:.1f} {unit}" if value < 100 else f"{value:.0f} {unit}"
    return f"{int(n)} B"


def largest_fitting(estimate: Callable[[int], float], lo: int, hi: int, budget: int) -> int | None:
    """The largest integer v in lo…hi with ``estimate(v) ≤ budget`` (``estimate`` non-decreasing), or None
    when not even ``lo`` fits: a bisection, ~log₂(hi − lo) estimates."""
    if estimate(lo) > budget:
        return None
    while lo < hi:
        mid = (lo + hi + 1) // 2
        if estimate(mid) <= budget:
            lo = mid
        else:
            hi = mid - 1
    return lo


def fitting_size(width: int, height: int, bytes_per_pixel: float, budget: int) -> str | None:
    """``WxH``: the largest image of the shape of width × height whose width · height · ``bytes_per_pixel`` fits
    in ``budget`` (None when not even 1×1 does)."""
    scale = math.sqrt(budget / (width * height * bytes_per_pixel))
    w, h = int(width * scale), int(height * scale)
    return f"{w}x{h}" if w >= 1 and h >= 1 else None


def check(
    field: str,
    estimate: float,
    *,
    value: object = None,
    what: str = "",
    fits: Callable[[int], object] | None = None,
    advice: str = "lower it",
    file: str | Path | None = None,
) -> None:
    """Refuse ``field`` (= ``value``) when its ``estimate`` in bytes is more than the available memory: a
    ResourceError, one line naming the field, the estimate (``what``: how it was counted), the limit and its
    source, and ``fits(budget)``, the largest value that fits, where given (None: nothing does)."""
    budget = memory_budget()
    if estimate <= budget.bytes:
        return
    shown = "" if value is None else f"{value} "
    how = f" ({what})" if what else ""
    hint = f"; {advice}"
    if fits is not None:
        best = fits(budget.bytes)
        hint += f" (≤ {best} fits)" if best is not None else " (not even the smallest value fits)"
    raise ResourceError(
        f"{shown}needs about {format_bytes(estimate)}{how} but {format_bytes(budget.bytes)} is available "
        f"({budget.source}){hint}",
        field=field,
        file=file,
    )


# ---------------------------------------------------------------------------------------------- the sources
def _meminfo() -> Budget | None:
    available = _proc_kb("/proc/meminfo", "MemAvailable")
    return None if available is None else Budget(available, "MemAvailable")


def _read_int(path: Path) -> int | None:
    try:
        text = path.read_text().strip()
    except OSError:
        return None
    if text == "max":
        return None
    try:
        return int(text)
    except ValueError:
        return None


def _stat(path: Path, key: str) -> int:
    try:
        for line in path.read_text().splitlines():
            name, _, number = line.partition(" ")
            if name == key:
                return int(number)
    except (OSError, ValueError):
        pass
    return 0


def _cgroup() -> Budget | None:
    """The tightest cgroup memory limit less usage over this process's cgroup and its ancestors (v2 and v1)."""
    try:
        lines = Path("/proc/self/cgroup").read_text().splitlines()
    except OSError:
        return None
    best: Budget | None = None
    for line in lines:
        parts = line.split(":", 2)
        if len(parts) != 3:
            continue
        hierarchy, controllers, path = parts
        if hierarchy == "0" and controllers == "":
            root, files = Path("/sys/fs/cgroup"), ("memory.max", "memory.current", "inactive_file")
        elif "memory" in controllers.split(","):
            root = Path("/sys/fs/cgroup/memory")
            files = ("memory.limit_in_bytes", "memory.usage_in_bytes", "total_inactive_file")
        else:
            continue
        folder = root / path.lstrip("/")
        for d in [folder, *folder.parents]:
            if not d.is_relative_to(root):
                break
            limit = _read_int(d / files[0])
            if limit is None or limit >= _NO_LIMIT:
                continue
            used = (_read_int(d / files[1]) or 0) - _stat(d / "memory.stat", files[2])
            headroom = max(limit - max(used, 0), 0)
            if best is None or headroom < best.bytes:
                best = Budget(headroom, f"cgroup {files[0]}")
    return best


def _address_space() -> Budget | None:
    try:
        import resource

        soft, _ = resource.getrlimit(resource.RLIMIT_AS)
    except (ImportError, OSError, ValueError):
        return None
    if soft == resource.RLIM_INFINITY or soft < 0:
        return None
    size = _proc_kb("/proc/self/status", "VmSize") or 0
    return Budget(max(soft - size, 0), "RLIMIT_AS")


def _proc_kb(path: str, key: str) -> int | None:
    """Bytes of a ``Key: N kB`` line of a /proc file (None where it cannot be read)."""
    try:
        for line in Path(path).read_text().splitlines():
            if line.startswith(key + ":"):
                return int(line.split()[1]) * 1024
    except (OSError, ValueError, IndexError):
        pass
    return None


def as_reference_worker() -> None:
    """Set up a process that runs a reference's tasks (a local worker, a Dask worker) as one core's worth of work:

    - one BLAS thread: OpenBLAS's own threads (one per core, spinning on the references' small products) would
      take the other workers' cores;
    - glibc's malloc keeps freed memory for the next tile: Dask's nanny starts workers with
      ``MALLOC_TRIM_THRESHOLD_=65536``, which also turns off glibc's growing mmap threshold, so every array of a
      tile came from a fresh mmap and its pages were faulted in again. Arrays under 32 MB come from the heap
      again, kept.
    (`reflets bench reference-scale` before both: far smaller speed-ups in 2 processes, a slowdown on a 2-worker
    Dask cluster; docs/reference-scale.md.)"""
    from threadpoolctl import threadpool_limits

    threadpool_limits(1)
    try:
        import ctypes

        libc = ctypes.CDLL("libc.so.6")
    except OSError:
        return  # not glibc
    m_trim_threshold, m_mmap_threshold = -1, -3
    libc.mallopt(m_mmap_threshold, 32 << 20)  # glibc's largest
    libc.mallopt(m_trim_threshold, 256 << 20)
