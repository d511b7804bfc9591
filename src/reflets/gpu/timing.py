"""Frame timing that never stalls the frame: the CPU time of submission, and GPU timer queries read frames later.

A frame is timed two ways, neither of which waits for the GPU:

- ``cpu_ms``: the wall clock of the Python and driver work that submits the frame's passes (on llvmpipe that
  includes the vertex stage and the triangle set-up, which Mesa runs on the submitting thread; the fragments run on
  its own threads, after — but a draw that samples a texture still being drawn waits for it there);
- ``image_ms``: forming the frame's image after its passes (adding it to the frame sum: on llvmpipe that read of
  the frame waits for its fragments, which a GPU does not);
- ``pass_gpu_ms`` (each pass) and ``gpu_ms`` (their sum, per frame): a GL_TIME_ELAPSED query around each pass,
  read :data:`LAG` frames later, when the GPU has long finished it (moderngl has no "result available?" call: the
  lag is what keeps the read from waiting).

On Mesa's llvmpipe a time query returns nonsense (a constant, whatever was drawn), so there are no ``gpu_ms`` there.
Benchmarks that want a whole frame's time on llvmpipe use :meth:`FrameTimer.measuring`: a ``finish()`` before
and after each frame (``wall_ms``) — never in an interactive loop.
"""

from __future__ import annotations

import time
from collections import deque
from contextlib import contextmanager

from .context import is_software

#: frames between a frame and the read of its queries (at the start of frame n, frame n − LAG's): the GPU has
#: long finished it (it can still wait if the GPU is further behind: moderngl cannot ask whether it is ready)
LAG = 2
#: frame times kept (a viewer runs for hours: the lists are bounded)
HISTORY = 10_000


class _Frame:
    """A frame being timed: when it began, and when its passes were all submitted."""

    def __init__(self, start: float):
        self.start = start
        self.submitted_at: float | None = None

    def submitted(self) -> None:
        self.submitted_at = time.perf_counter()


class FrameTimer:
    """Per-frame ``cpu_ms`` and (real GPU) ``gpu_ms``, and the last read frame's ``pass_gpu_ms`` by pass name."""

    def __init__(self, ctx):
        self.ctx = ctx
        self.gpu_timers = not is_software(ctx)  # do time queries mean anything here?
        self.sync = False  # a finish() around each frame (benchmarks on llvmpipe: ``measuring``)
        self.cpu_ms: deque[float] = deque(maxlen=HISTORY)
        self.gpu_ms: deque[float] = deque(maxlen=HISTORY)
        self.wall_ms: deque[float] = deque(maxlen=HISTORY)
        self.image_ms: deque[float] = deque(maxlen=HISTORY)
        self.pass_gpu_ms: dict[str, float] = {}
        self.pass_history: deque[dict[str, float]] = deque(maxlen=HISTORY)  # pass_gpu_ms of each frame read
        self._free: list = []  # queries to reuse (moderngl's Query has no release())
        self._pending: deque[list[tuple[str, object]]] = deque()
        self._current: list[tuple[str, object]] | None = None

    @contextmanager
    def frame(self):
        """One frame: its submission timed on the CPU, its passes (``timed_pass``) by queries. The handle's
        ``submitted()`` ends ``cpu_ms`` there (what follows — forming the image — goes to ``image_ms``)."""
        if self.sync:
            self.ctx.finish()
        self._read(keep=LAG - 1)
        self._current = []
        handle = _Frame(time.perf_counter())
        try:
            yield handle
        finally:
            end = time.perf_counter()
            submitted = handle.submitted_at or end
            self.cpu_ms.append(1e3 * (submitted - handle.start))
            self.image_ms.append(1e3 * (end - submitted))
            if self.sync:
                self.ctx.finish()
                self.wall_ms.append(1e3 * (time.perf_counter() - handle.start))
            if self._current:
                self._pending.append(self._current)
            self._current = None

    @contextmanager
    def timed_pass(self, name: str):
        """A pass of the current frame, timed by a GPU query (nothing outside a frame or on llvmpipe)."""
        if not self.gpu_timers or self._current is None:
            yield
            return
        query = self._free.pop() if self._free else self.ctx.query(time=True)
        try:
            with query:
                yield
        finally:
            self._current.append((name, query))  # read (then reused) with its frame, even after an error

    def _read(self, keep: int) -> None:
        """Read the queries of all but the last ``keep`` frames (their passes summed by name)."""
        while len(self._pending) > keep:
            passes: dict[str, float] = {}
            for name, query in self._pending.popleft():
                passes[name] = passes.get(name, 0.0) + query.elapsed / 1e6
                self._free.append(query)
            self.pass_gpu_ms = passes
            self.pass_history.append(passes)
            self.gpu_ms.append(sum(passes.values()))

    def flush(self) -> None:
        """Read every pending query (waits for the GPU: after a benchmark's frames, not in a frame loop)."""
        self._read(keep=0)

    @contextmanager
    def measuring(self):
        """Time the frames drawn inside, for a benchmark: the lists restart; on a GPU the queries alone (read at
        the end), on llvmpipe a ``finish()`` around each frame. ``frame_times()`` then gives one time per frame."""
        self.flush()
        for times in (self.cpu_ms, self.gpu_ms, self.wall_ms, self.image_ms, self.pass_history):
            times.clear()
        self.sync = not self.gpu_timers
        try:
            yield self
        finally:
            self.flush()
            self.sync = False

    def frame_times(self) -> list[float]:
        """Each frame's time in ms: the GPU's where its queries mean something, else the synchronised wall clock
        (else the submission alone)."""
        return list(self.gpu_ms or self.wall_ms or self.cpu_ms)
