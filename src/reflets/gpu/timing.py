"""Frame timing: GPU timer queries where they mean something, ``finish()`` + wall clock everywhere.

On Mesa's llvmpipe a GL_TIME_ELAPSED query returns nonsense (≈1 ns), so :class:`FrameTimer` reports
``gpu_ms = None`` there and benchmarks use the wall clock around a ``ctx.finish()``.
"""

from __future__ import annotations

import statistics
import time
from contextlib import contextmanager
from dataclasses import dataclass, field

from .context import is_software


@dataclass
class FrameTimer:
    """Collects per-frame GPU and wall-clock times (milliseconds)."""

    ctx: object
    gpu_ms: list[float] = field(default_factory=list)
    wall_ms: list[float] = field(default_factory=list)
    _query: object = field(default=None, repr=False)

    @contextmanager
    def frame(self):
        query = None
        if not is_software(self.ctx):  # one query, reused: moderngl's Query has no release()
            if self._query is None:
                self._query = self.ctx.query(time=True)
            query = self._query
        self.ctx.finish()
        start = time.perf_counter()
        if query is not None:
            with query:
                yield
        else:
            yield
        self.ctx.finish()
        self.wall_ms.append((time.perf_counter() - start) * 1e3)
        if query is not None:
            self.gpu_ms.append(query.elapsed / 1e6)

    def summary(self) -> dict[str, float | None]:
        """Medians (robust to the noise of shared machines) and the frame count."""
        return {
            "frames": len(self.wall_ms),
            "wall_ms_median": statistics.median(self.wall_ms) if self.wall_ms else None,
            "gpu_ms_median": statistics.median(self.gpu_ms) if self.gpu_ms else None,
        }
