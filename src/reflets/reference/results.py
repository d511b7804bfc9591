"""The volumetric reference's result, apart from its engine: the reference store reads it back without importing
the path tracer (and the path tracer's checkpoints use the store's fingerprints)."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np


@dataclass
class VolumetricImage:
    """Mean radiance per pixel and its standard error (float32 (H, W, 3)), with the object mask."""

    image: np.ndarray
    stderr: np.ndarray
    mask: np.ndarray
    spp: int
