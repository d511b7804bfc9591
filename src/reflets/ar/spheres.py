"""The sphere decomposition of an object (004 §5.2), whose spheres cast the soft shadows on the real ground:
Lloyd's k-means on area-weighted surface samples — each sample to its nearest centre, a centre the mean of its
samples, its radius their mean distance — until no assignment changes (at most 1,000 iterations)."""

from __future__ import annotations

import numpy as np


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
    for _ in range(1, count):  # k-means++: far points first
        d2 = np.min(((samples[:, None] - np.array(centres)[None]) ** 2).sum(-1), axis=1)
        centres.append(samples[rng.choice(len(samples), p=d2 / d2.sum())])
    centres = np.array(centres)
    assign = None
    for _ in range(iterations):
        new = np.argmin(((samples[:, None] - centres[None]) ** 2).sum(-1), axis=1)
        if assign is not None and np.array_equal(new, assign):
            break
        assign = new
        for k in range(count):
            members = samples[assign == k]
            if len(members):
                centres[k] = members.mean(axis=0)
    radii = np.array(
        [np.linalg.norm(samples[assign == k] - centres[k], axis=1).mean() if np.any(assign == k) else 0.0
         for k in range(count)]
    )  # fmt: skip
    return centres, radii
