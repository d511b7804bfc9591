"""reflets.cache: memory within its byte budget, disk entries re-used, broken ones recomputed."""

from __future__ import annotations

import numpy as np

from reflets.cache import Cache, content_key


def _cache(budget: int) -> Cache:
    def save(value, path):
        np.savez(path, a=value)

    def load(path):
        with np.load(path) as data:
            return data["a"]

    return Cache("test", load, save, memory_budget=budget)


def test_memory_stays_within_its_budget_least_recently_used_out(tmp_path, monkeypatch):
    monkeypatch.setenv("XDG_CACHE_HOME", str(tmp_path))
    cache = _cache(budget=3 * 8000)
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
    assert _cache(1 << 20).get(key, lambda: np.arange(3.0))[2] == 2.0
    with np.load(path) as data:  # and stored again, whole
        assert data["a"][2] == 2.0


def test_a_read_only_cache_only_costs_the_recomputation(tmp_path, monkeypatch):
    (tmp_path / "ro").mkdir(mode=0o500)
    monkeypatch.setenv("XDG_CACHE_HOME", str(tmp_path / "ro" / "sub"))
    assert _cache(1 << 20).get("k", lambda: np.ones(2)).sum() == 2.0


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
