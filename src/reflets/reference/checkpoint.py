"""A long reference's partial sums on disk: written as its blocks of samples complete, read back to go on after a
kill or a crash — and the run that goes on ends in the image an uninterrupted run gives, bit for bit.

A reference split into blocks (each with its own random stream, their sums added in block order) is fully
described by the blocks done so far: ``next_block`` and the per-pixel Σ and Σ² of blocks ``0 … next_block − 1``.
The file also holds a key of everything the sums depend on (the scene as validated, its files' contents, the
engine's parameters, the blocks); a file of another reference is refused, never mixed in.
"""

from __future__ import annotations

import os
import time
from pathlib import Path

import numpy as np

from ..errors import ARRAY_READ_ERRORS, ArgumentError

#: seconds between two writes of the partial sums as blocks complete (a kill, a crash or an error writes them at
#: once, and a finished run's sums are written before the caller writes its images)
SAVE_EVERY_S = 10.0


def reference_key(scene, **params) -> str:
    """A digest of what a reference's sums depend on, bit for bit: the scene and its files' contents
    (``store.fingerprint``: the reference algorithm's version included), the engine's parameters (its sampling's
    version among them) and NumPy's version (its random streams and vectorised functions)."""
    from .store import fingerprint

    return fingerprint(scene, numpy=np.__version__, **params)[0]


class PartialSums:
    """The checkpoint file of one reference (``path``, an ``.npz``), for the reference of ``key``."""

    def __init__(self, path: str | Path, key: str):
        self.path = Path(path)
        self.key = key
        self._saved_at = time.monotonic()

    def load(self) -> tuple[int, np.ndarray | float, np.ndarray | float]:
        """(next block, Σ, Σ²) of the file; (0, 0, 0) when there is none. A file that is not such a checkpoint,
        or is another reference's, is refused (one line naming it)."""
        if not self.path.exists():
            return 0, 0.0, 0.0
        try:
            with np.load(self.path, allow_pickle=False) as data:
                key, next_block = str(data["key"]), int(data["next_block"])
                total, total2 = np.array(data["total"]), np.array(data["total2"])
        except (*ARRAY_READ_ERRORS, KeyError) as exc:
            raise ArgumentError(f"not a reflets checkpoint ({exc})", file=self.path, field="--resume") from None
        if key != self.key:
            raise ArgumentError(
                "holds the partial sums of another reference (scene, files, spp, seed or size differ): delete it, "
                "or run that reference", file=self.path, field="--resume"
            )
        return next_block, total, total2

    def save(self, next_block: int, total, total2, force: bool = False) -> None:
        """Write the sums of blocks 0 … next_block − 1 (atomically: a kill mid-write leaves the previous file),
        at most every SAVE_EVERY_S seconds unless ``force``."""
        if not force and time.monotonic() - self._saved_at < SAVE_EVERY_S:
            return
        with open(self._writing, "wb") as stream:
            np.savez(stream, key=self.key, next_block=next_block, total=np.asarray(total, np.float64),
                     total2=np.asarray(total2, np.float64))  # fmt: skip
            stream.flush()
            os.fsync(stream.fileno())  # on disk before it replaces the previous one
        os.replace(self._writing, self.path)
        self._saved_at = time.monotonic()

    def remove(self) -> None:
        """The reference is complete and its images written: its partial sums go."""
        self.path.unlink(missing_ok=True)
        self._writing.unlink(missing_ok=True)

    @property
    def _writing(self) -> Path:
        return self.path.with_name(self.path.name + ".writing")
