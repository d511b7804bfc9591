"""reflets.cache: memory within the byte budget every cache shares (REFLETS_CACHE_MB), disk entries re-used,
broken ones recomputed."""

from __future__ import annotations

import numpy as np
import pytest

from reflets.cache import Cache, cache_budget, clear_memory, content_key
from reflets.errors import ArgumentError


@pytest.fixture(autouse=True)
def _budget_to_themselves():
    """Each test's caches alone in the shared budget (each cache of the process keeps its latest entry in it)."""
    clear_memory()


def _cache(kind: str = "test") -> Cache:
    def save(value, path):
        np.savez(path, a=value)

    def load(path):
        with np.load(path) as data:
            return data["a"]

    return Cache(kind, load, save)


def _kb8(k: int):
    """A result of 8 kB."""
    return lambda: np.full(1000, k, np.float64)


def test_memory_stays_within_its_budget_least_recently_used_out(tmp_path, monkeypatch):
    monkeypatch.setenv("XDG_CACHE_HOME", str(tmp_path))
    monkeypatch.setenv("REFLETS_CACHE_MB", "0.024")  # 3 × 8 kB, shared with every other cache of the process
    cache = _cache()
    for k in range(40):  # a long session editing a parameter: 40 different results of 8 kB
        cache.get(content_key({"k": k}), lambda k=k: np.full(1000, k, np.float64))
    assert cache.memory_bytes <= 3 * 8000 and len(cache) == 3
    made = []
    value = cache.get(content_key({"k": 0}), lambda: made.append(1) or np.zeros(1000))
    assert not made and value[0] == 0  # evicted from memory, read back from disk, not recomputed


def test_a_broken_disk_entry_is_recomputed(tmp_path, monkeypatch):
    monkeypatch.setenv("XDG_CACHE_HOME", str(tmp_path))
    key = content_key({"broken": True})
    path = tmp_path / "reflets" / "test" / f"{key}.npz"
    path.parent.mkdir(parents=True)
    path.write_bytes(b"not an npz")
    assert _cache().get(key, lambda: np.arange(3.0))[2] == 2.0
    with np.load(path) as data:  # and stored again, whole
        assert data["a"][2] == 2.0


def test_a_read_only_cache_only_costs_the_recomputation(tmp_path, monkeypatch):
    (tmp_path / "ro").mkdir(mode=0o500)
    monkeypatch.setenv("XDG_CACHE_HOME", str(tmp_path / "ro" / "sub"))
    assert _cache().get("k", lambda: np.ones(2)).sum() == 2.0


def test_caches_share_one_budget_and_evict_each_others_least_recently_used(tmp_path, monkeypatch):
    monkeypatch.setenv("XDG_CACHE_HOME", str(tmp_path))
    monkeypatch.setenv("REFLETS_CACHE_MB", "0.024")  # room for three results of 8 kB, in all caches together
    tables, maps = _cache("tables"), _cache("maps")
    tables.get("t0", _kb8(0)), maps.get("m1", _kb8(1)), tables.get("t2", _kb8(2))
    maps.get("m3", _kb8(3))  # a map makes way: out goes the least recently used of either cache, a table
    assert tables.peek("t0") is None and tables.peek("t2")[0] == 2
    maps.get("m1", _kb8(-1))  # used again: now the most recent
    tables.get("t4", _kb8(4)), tables.get("t5", _kb8(5))  # out go t2, then m3 (m1, made earlier, was used later)
    assert maps.peek("m3") is None and maps.peek("m1")[0] == 1 and len(tables) == 2 and len(maps) == 1
    assert tables.memory_bytes + maps.memory_bytes == 3 * 8000


def test_reflets_cache_mb_sets_the_budget_and_is_validated(tmp_path, monkeypatch):
    monkeypatch.setenv("XDG_CACHE_HOME", str(tmp_path))
    monkeypatch.delenv("REFLETS_CACHE_MB", raising=False)
    assert cache_budget() == 256 * 10**6
    monkeypatch.setenv("REFLETS_CACHE_MB", " 1.5 ")
    assert cache_budget() == 1_500_000
    monkeypatch.setenv("REFLETS_CACHE_MB", "0")  # no memory caching: made once, then read from the disk
    cache, made = _cache(), []
    for _ in range(2):
        assert cache.get("k", lambda: made.append(1) or np.ones(3)).sum() == 3.0
    assert made == [1] and len(cache) == 0 and cache.peek("k") is None
    for bad in ("-1", "lots", "nan", "inf", "1e400"):
        monkeypatch.setenv("REFLETS_CACHE_MB", bad)
        with pytest.raises(ArgumentError, match="REFLETS_CACHE_MB") as caught:
            cache.get("other", lambda: pytest.fail("computed before the budget was checked"))
        assert "\n" not in str(caught.value) and "non-negative number" in str(caught.value)


def test_a_memo_keeps_the_most_recently_used_values():
    from reflets.cache import Memo

    memo, made = Memo(size=2), []

    def make(value):
        made.append(value)
        return value

    assert memo.get("a", lambda: make(1)) == 1
    assert memo.get("b", lambda: make(2)) == 2
    assert memo.get("a", lambda: make(-1)) == 1  # remembered, and now the most recent
    assert memo.get("c", lambda: make(3)) == 3  # "b", the least recently used, goes
    assert len(memo) == 2 and memo.get("b", lambda: make(4)) == 4
    assert made == [1, 2, 3, 4]


def test_each_cache_keeps_its_latest_entry_past_the_budget(tmp_path, monkeypatch):
    """A scratch table and its α maps, the maps alone over the budget: both stay (the render that asked uses both;
    either pushing the other out would read it again at every frame) — older entries still go."""
    monkeypatch.setenv("XDG_CACHE_HOME", str(tmp_path))
    monkeypatch.setenv("REFLETS_CACHE_MB", "0.016")  # room for two results of 8 kB
    tables, maps = _cache("tables"), _cache("maps")
    tables.get("t0", _kb8(0)), maps.get("m", lambda: np.zeros(3000))  # the maps: 24 kB
    assert tables.peek("t0") is not None and maps.peek("m") is not None
    tables.get("t1", _kb8(1))
    assert tables.peek("t0") is None and tables.peek("t1") is not None and maps.peek("m") is not None
