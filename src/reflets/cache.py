"""One cache for everything reflets computes once and uses again: fitted LTC tables, scratch tables and α maps
(in memory and on disk), and the content keys of stored references.

- ``cache_dir(kind)``: ``$XDG_CACHE_HOME/reflets/<kind>`` (default ``~/.cache``);
- ``content_key(data)``: a digest of a JSON-able description (what a result depends on, code hashes included),
  ``file_stamp`` / ``file_digest`` for the files it reads, ``source_hash`` for the source files it runs;
- ``Cache(kind, load, save)``: memory first, then the disk (a broken or stale file is recomputed, a read-only
  disk only costs the recomputation), then ``make`` — stored in both. Every cache of the process shares one
  memory budget (``REFLETS_CACHE_MB``, default 256 MB; 0: nothing kept in memory), the least recently used
  entry of any of them out past it (each keeps its latest): a long session that edits materials (each variant
  its tables and α maps) does not grow without bound, nor by one budget per kind of result;
- ``Memo(size)``: small values (a number, a word) by key, in memory only, the least recently used out past
  ``size`` entries.
"""

from __future__ import annotations

import hashlib
import json
import os
import threading
import zipfile
from collections import OrderedDict
from collections.abc import Callable
from pathlib import Path

import numpy as np

from .errors import ArgumentError, RefletsError

#: the environment variable setting the memory every cache of the process shares, in MB (10⁶ bytes; 0: none)
ENV_VAR = "REFLETS_CACHE_MB"
#: that memory when the variable is not set (MB)
DEFAULT_MB = 256


def cache_dir(kind: str) -> Path:
    base = os.environ.get("XDG_CACHE_HOME") or str(Path.home() / ".cache")
    return Path(base) / "reflets" / kind


def content_key(data: dict, length: int = 32) -> str:
    return hashlib.sha256(json.dumps(data, sort_keys=True, default=str).encode()).hexdigest()[:length]


def file_stamp(path: str | Path) -> list[int] | None:
    """[size, modification time in ns] of a file, or None when it cannot be read."""
    try:
        st = Path(path).expanduser().stat()
    except OSError:
        return None
    return [st.st_size, st.st_mtime_ns]


def file_digest(path: str | Path) -> str:
    """SHA-256 of a file's content (a moved or renamed file keeps its key)."""
    return hashlib.sha256(Path(path).read_bytes()).hexdigest()


def source_hash(*paths: Path) -> str:
    """Digest of source files a cached result depends on (a changed fitter or tracer recomputes)."""
    h = hashlib.sha256()
    for path in paths:
        h.update(Path(path).read_bytes())
    return h.hexdigest()[:16]


def size_of(value) -> int:
    """Bytes held by a cached value: its arrays (directly, in a dict, or as attributes)."""
    if isinstance(value, np.ndarray):
        return int(value.nbytes)
    if isinstance(value, dict):
        return sum(size_of(v) for v in value.values())
    if hasattr(value, "__dict__"):
        return sum(size_of(v) for v in vars(value).values())
    return 0


class Memo:
    """Small values remembered by key in memory, at most ``size`` of them (least recently used out); renderers on
    several threads share one (``make`` runs outside the lock: two threads may both make a value)."""

    def __init__(self, size: int = 1024):
        self.size = size
        self._values: OrderedDict[object, object] = OrderedDict()
        self._lock = threading.Lock()

    def get(self, key, make: Callable[[], object]):
        with self._lock:
            if key in self._values:
                self._values.move_to_end(key)
                return self._values[key]
        value = make()
        with self._lock:
            self._values[key] = value
            while len(self._values) > self.size:
                self._values.popitem(last=False)
        return value

    def __len__(self) -> int:
        return len(self._values)


def cache_budget() -> int:
    """Bytes every cache of the process may hold together: ``REFLETS_CACHE_MB`` × 10⁶ (read at each miss: a test
    or a session may change it), else DEFAULT_MB. Not a non-negative number: an ArgumentError naming it."""
    text = os.environ.get(ENV_VAR, "").strip()
    if not text:
        return DEFAULT_MB * 10**6
    try:
        mb = float(text)
    except ValueError:
        mb = -1.0
    if not 0 <= mb < 2**43:  # NaN and inf fail too
        raise ArgumentError(f"{text!r} is not a non-negative number of MB (e.g. 256; 0 keeps nothing in memory)",
                            field=ENV_VAR)  # fmt: skip
    return int(mb * 10**6)


class _Shared:
    """The memory every Cache of the process shares: its entries, least recently used first ((cache, key) →
    bytes; caches hash by identity), their total, and the lock renders on several threads take (``make`` runs
    outside it)."""

    def __init__(self):
        self.entries: OrderedDict[tuple[Cache, str], int] = OrderedDict()
        self.bytes = 0
        self.lock = threading.RLock()


_SHARED = _Shared()


def clear_memory() -> None:
    """Drop every cache's entries from memory (what is on disk stays): the whole budget free again."""
    with _SHARED.lock:
        for cache, key in list(_SHARED.entries):
            cache._forget(key)


class Cache:
    """Memory + disk cache of one kind of result, stored as ``<key>.npz``; its memory within the budget every
    cache of the process shares (:func:`cache_budget`)."""

    def __init__(self, kind: str, load: Callable[[Path], object], save: Callable[[object, Path], None]):
        self.kind, self._load, self._save = kind, load, save
        self._memory: dict[str, tuple[object, int]] = {}
        self._bytes = 0
        self._latest: str | None = None  # the key last asked for: kept when another cache needs room

    def get(self, key: str, make: Callable[[], object]):
        """The result under ``key``: from memory, else from disk, else ``make()`` (then stored in both)."""
        with _SHARED.lock:
            if key in self._memory:
                _SHARED.entries.move_to_end((self, key))
                self._latest = key
                return self._memory[key][0]
        budget = cache_budget()  # a bad REFLETS_CACHE_MB is said before anything is loaded or computed
        path = cache_dir(self.kind) / f"{key}.npz"
        value = None
        if path.is_file():
            try:
                value = self._load(path)
            except (OSError, ValueError, KeyError, zipfile.BadZipFile, RefletsError):
                value = None  # a broken or stale entry is recomputed
        if value is None:
            value = make()
            self._store(path, value)
        self._remember(key, value, budget)
        return value

    def peek(self, key: str):
        """The result under ``key`` if it is in memory, else None (nothing loaded, nothing made)."""
        with _SHARED.lock:
            entry = self._memory.get(key)
        return None if entry is None else entry[0]

    def clear_memory(self) -> None:
        with _SHARED.lock:
            for key in list(self._memory):
                self._forget(key)

    @property
    def memory_bytes(self) -> int:
        return self._bytes

    def __len__(self) -> int:
        return len(self._memory)

    def _remember(self, key: str, value, budget: int) -> None:
        """Keep ``value`` in memory, and drop the least recently used entries of every cache past the budget —
        except each cache's latest (the render that asked for a table and its α maps uses both at once: one
        alone over the budget must not push the other out, to be read again at every frame); budget 0: none."""
        size = size_of(value)
        with _SHARED.lock:
            if key in self._memory:  # another thread made it meanwhile
                self._forget(key)
            if budget > 0:
                self._memory[key] = (value, size)
                self._bytes += size
                _SHARED.entries[(self, key)] = size
                _SHARED.bytes += size
                self._latest = key
            for cache, oldest in list(_SHARED.entries):  # least recently used first
                if _SHARED.bytes <= budget:
                    break
                if budget == 0 or oldest != cache._latest:
                    cache._forget(oldest)

    def _forget(self, key: str) -> None:
        """Drop ``key`` from memory (the shared lock held)."""
        size = self._memory.pop(key)[1]
        self._bytes -= size
        del _SHARED.entries[(self, key)]
        _SHARED.bytes -= size

    def _store(self, path: Path, value) -> None:
        try:
            path.parent.mkdir(parents=True, exist_ok=True)
            tmp = path.with_name(f"{path.stem}.{os.getpid()}.{threading.get_ident()}.tmp.npz")
            self._save(value, tmp)
            tmp.replace(path)
        except OSError:
            pass  # a read-only cache only costs the recomputation next time
