"""The viewer's reference: the NumPy ground truth of the current scene and view, computed in a background
thread in chunks (its progress is the fraction of chunks done; the running mean is usable before the end) and
cached by content (memory and disk, ``$XDG_CACHE_HOME/reflets/viewer``): coming back to a view costs nothing."""

from __future__ import annotations

import threading

import numpy as np

from ..cache import Cache, content_key
from ..scene import scene_toml

#: samples per pixel of one chunk (a chunk is one call of the reference, with its own seed)
CHUNK_SPP = 4
REFERENCES = Cache("viewer", lambda path: np.load(path)["image"], lambda image, path: np.savez(path, image=image))


def reference_key(scene, size, spp: int) -> str:
    """What a reference image depends on: the scene (files by absolute path), the image size, the spp."""
    return content_key({"scene": scene_toml(scene), "size": list(size), "spp": spp, "chunk": CHUNK_SPP})


class ReferenceJob:
    """One reference computation: ``progress`` in [0, 1], ``image`` (the mean of the chunks done so far, None
    before the first), ``done``; ``cancel()`` stops it after the current chunk."""

    def __init__(self, scene, size: tuple[int, int], spp: int = 64):
        self.key = reference_key(scene, size, spp)
        self.spp, self.size = spp, tuple(size)
        self.image: np.ndarray | None = None
        self.progress = 0.0
        self.error: str | None = None
        self._cancel = threading.Event()
        cached = REFERENCES.peek(self.key)  # memory now; the disk is read on the thread
        if cached is not None:
            self.image, self.progress = cached, 1.0
            self._thread = None
            return
        self._thread = threading.Thread(target=self._run, args=(scene,), daemon=True)
        self._thread.start()

    @property
    def done(self) -> bool:
        return self.progress >= 1.0

    def cancel(self) -> None:
        self._cancel.set()

    def wait(self, timeout: float | None = None) -> bool:
        if self._thread is not None:
            self._thread.join(timeout)
        return self.done

    def _run(self, scene) -> None:
        from ..reference import reference

        chunks = max(1, -(-self.spp // CHUNK_SPP))

        def compute() -> np.ndarray:
            total = None
            for k in range(chunks):
                if self._cancel.is_set():
                    raise _Cancelled
                part = reference(scene, spp=CHUNK_SPP, seed=k, size=self.size, progress=False).image
                total = part.astype(np.float64) if total is None else total + part
                self.image = (total / (k + 1)).astype(np.float32)
                self.progress = (k + 1) / chunks * 0.999  # 1.0 once stored
            return self.image

        try:
            self.image = REFERENCES.get(self.key, compute)
            self.progress = 1.0
        except _Cancelled:
            pass
        except Exception as exc:  # shown in the overlay; the viewer goes on
            self.error = f"{type(exc).__name__}: {exc}"


class _Cancelled(Exception):
    pass
