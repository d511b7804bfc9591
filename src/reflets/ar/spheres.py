"""The sphere decomposition of an object (004 §5.2), whose spheres cast the soft shadows on the real ground:
Lloyd's k-means on area-weighted surface samples — each sample to its nearest centre, a centre the mean of its
samples, its radius their mean distance — until no assignment changes (at most 1,000 iterations)."""

from __future__ import annotations

import numpy as np
from scipy.spatial import cKDTree


def surface_samples(positions: np.ndarray, faces: np.ndarray, count: int, seed: int = 0) -> np.ndarray:
    """``count`` points spread uniformly by area over a triangle mesh."""
    rng = np.random.default_rng(seed)
    tri = positions[faces]
    area = 0.5 * np.linalg.norm(np.cross(tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0]), axis=1)
    pick = rng.choice(len(faces), size=count, p=area / area.sum())
    r1, r2 = rng.random(count), rng.random(count)
    s = np.sqrt(r1)
    a, b, c = tri[pick, 0], tri[pick, 1], tri[pick, 2]
    return (1 - s)[:, None] * a + (s * (1 - r2))[:, None] * b + (s * r2)[:, None] * c


def decompose(samples: np.ndarray, count: int, seed: int = 0, iterations: int = 1000) -> tuple[np.ndarray, np.ndarray]:
    """(centres (K, 3), radii (K,)) of ``count`` spheres fitted to surface samples by k-means (k-means++ start)."""
    rng = np.random.default_rng(seed)
    centres = [samples[rng.integers(len(samples))]]
    d2 = ((samples - centres[0]) ** 2).sum(-1)  # each sample's squared distance to its nearest centre so far
    for _ in range(1, count):  # k-means++: far points first
        centres.append(samples[rng.choice(len(samples), p=d2 / d2.sum())])
        d2 = np.minimum(d2, ((samples - centres[-1]) ** 2).sum(-1))
    centres = np.array(centres)
    assign = None
    for _ in range(iterations):
        new = cKDTree(centres).query(samples)[1]  # the nearest centre of each sample
        if assign is not None and np.array_equal(new, assign):
            break
        assign = new
        counts = np.bincount(assign, minlength=count)
        sums = np.stack([np.bincount(assign, samples[:, k], minlength=count) for k in range(3)], axis=1)
        filled = counts > 0
        centres[filled] = sums[filled] / counts[filled, None]
    distance = np.linalg.norm(samples - centres[assign], axis=1)
    counts = np.bincount(assign, minlength=count)
    radii = np.bincount(assign, distance, minlength=count) / np.maximum(counts, 1)
    return centres, radii
