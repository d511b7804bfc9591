"""One cache for everything reflets computes once and uses again: fitted LTC tables, scratch tables and α maps
(in memory and on disk), and the content keys of stored references.

- ``cache_dir(kind)``: ``$XDG_CACHE_HOME/reflets/<kind>`` (default ``~/.cache``);
- ``content_key(data)``: a digest of a JSON-able description (what a result depends on, code hashes included),
  ``file_stamp`` / ``file_digest`` for the files it reads, ``source_hash`` for the source files it runs;
- ``Cache(kind, load, save)``: memory first (least recently used out past a byte budget: a long session that
  edits materials does not grow without bound), then the disk (a broken or stale file is recomputed, a
  read-only disk only costs the recomputation), then ``make`` — stored in both;
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

from .errors import RefletsError

#: default memory budget of one cache (bytes)
MEMORY_BUDGET = 256 << 20


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


class Cache:
    """Memory (bounded LRU) + disk cache of one kind of result, stored as ``<key>.npz``."""

    def __init__(
        self,
        kind: str,
        load: Callable[[Path], object],
        save: Callable[[object, Path], None],
        memory_budget: int = MEMORY_BUDGET,
    ):
        self.kind, self._load, self._save, self.memory_budget = kind, load, save, memory_budget
        self._memory: OrderedDict[str, tuple[object, int]] = OrderedDict()
        self._bytes = 0
        self._lock = threading.RLock()  # renders from several threads share a cache; ``make`` runs outside it

    def get(self, key: str, make: Callable[[], object]):
        """The result under ``key``: from memory, else from disk, else ``make()`` (then stored in both)."""
        with self._lock:
            if key in self._memory:
                self._memory.move_to_end(key)
                return self._memory[key][0]
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
        self._remember(key, value)
        return value

    def peek(self, key: str):
        """The result under ``key`` if it is in memory, else None (nothing loaded, nothing made)."""
        with self._lock:
            entry = self._memory.get(key)
        return None if entry is None else entry[0]

    def clear_memory(self) -> None:
        with self._lock:
            self._memory.clear()
            self._bytes = 0

    @property
    def memory_bytes(self) -> int:
        return self._bytes

    def __len__(self) -> int:
        return len(self._memory)

    def _remember(self, key: str, value) -> None:
        size = size_of(value)
        with self._lock:
            if key in self._memory:  # another thread made it meanwhile
                self._bytes -= self._memory.pop(key)[1]
            self._memory[key] = (value, size)
            self._bytes += size
            while self._bytes > self.memory_budget and len(self._memory) > 1:
                _, (_, dropped) = self._memory.popitem(last=False)
                self._bytes -= dropped

    def _store(self, path: Path, value) -> None:
        try:
            path.parent.mkdir(parents=True, exist_ok=True)
            tmp = path.with_name(f"{path.stem}.{os.getpid()}.{threading.get_ident()}.tmp.npz")
            self._save(value, tmp)
            tmp.replace(path)
        except OSError:
            pass  # a read-only cache only costs the recomputation next time
