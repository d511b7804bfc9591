"""Peak RSS growth of making 40 scratched-material variants (each its own table and α maps) in one process: what
the shared cache budget (reflets.cache, REFLETS_CACHE_MB) bounds. Cold (the tables computed):

    XDG_CACHE_HOME=$(mktemp -d) .venv/bin/python tools/cache_rss.py 40

run it again with the same XDG_CACHE_HOME for the tables read back from the disk cache; REFLETS_CACHE_MB=64 in
front to see the budget follow. Quoted in docs/inputs-and-outputs.md."""

from __future__ import annotations

import resource
import sys
import time

from reflets.scratches.material import ALPHAS, TABLES, Scratched


def peak_mb() -> float:
    return resource.getrusage(resource.RUSAGE_SELF).ru_maxrss * 1024 / 1e6  # ru_maxrss: KiB on Linux; MB = 10⁶ B


def variant(k: int) -> Scratched:
    return Scratched(profile=f"vgroove:{0.3 + 0.01 * k:.2f}", seed=k, alpha_size=1024)


variant(99).table(), variant(99).alpha_maps()  # code paths warm, then their cache entries dropped
TABLES.clear_memory(), ALPHAS.clear_memory()
start, t0 = peak_mb(), time.perf_counter()
for k in range(int(sys.argv[1]) if len(sys.argv) > 1 else 40):
    m = variant(k)
    m.table(), m.alpha_maps()
held = (TABLES.memory_bytes + ALPHAS.memory_bytes) / 1e6
print(f"peak RSS growth {peak_mb() - start:.0f} MB; cached in memory {held:.0f} MB "
      f"({len(TABLES)} tables, {len(ALPHAS)} α maps); {time.perf_counter() - t0:.1f} s")
