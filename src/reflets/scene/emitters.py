"""Points on area lights: the midpoint rule's samples of a polygon and its emitting normal (the forward pass's
area samples, the soft shadows' sample views, the area-light methods' records)."""

from __future__ import annotations

import numpy as np


def area_light_samples(polygon: np.ndarray, n: int) -> tuple[np.ndarray, np.ndarray]:
    """Midpoint-rule sample points and their areas for a planar convex polygon.

    A parallelogram (4 vertices with p0 + p2 = p1 + p3) uses the n×n grid at (k + ½)/n of eq 2.8; any
    other polygon is fanned into triangles, each split into n² congruent sub-triangles sampled at their
    centroids (the same midpoint rule, exact for linear integrands, O(1/n²) error).
    """
    p = np.asarray(polygon, dtype=np.float64)
    if len(p) == 4 and np.allclose(p[0] + p[2], p[1] + p[3], atol=1e-9 * np.ptp(p)):
        e1, e2 = p[1] - p[0], p[3] - p[0]
        t = (np.arange(n) + 0.5) / n
        u, v = np.meshgrid(t, t, indexing="xy")
        pts = p[0] + u.reshape(-1, 1) * e1 + v.reshape(-1, 1) * e2
        area = np.linalg.norm(np.cross(e1, e2)) / (n * n)
        return pts, np.full(len(pts), area)
    points, areas = [], []
    i, j = np.meshgrid(np.arange(n), np.arange(n), indexing="ij")
    up = (i + j) <= n - 1  # upward sub-triangles have corners (i,j), (i+1,j), (i,j+1)
    down = (i + j) <= n - 2  # downward ones (i+1,j), (i,j+1), (i+1,j+1)
    bary_up = np.stack([i[up] + 1 / 3, j[up] + 1 / 3], axis=1) / n
    bary_down = np.stack([i[down] + 2 / 3, j[down] + 2 / 3], axis=1) / n
    bary = np.concatenate([bary_up, bary_down])
    for k in range(1, len(p) - 1):
        a, b, c = p[0], p[k], p[k + 1]
        points.append(a + bary[:, :1] * (b - a) + bary[:, 1:] * (c - a))
        areas.append(np.full(len(bary), 0.5 * np.linalg.norm(np.cross(b - a, c - a)) / (n * n)))
    return np.concatenate(points), np.concatenate(areas)


def polygon_normal(p: np.ndarray) -> np.ndarray:
    """Unit normal of a planar polygon by Newell's method (counter-clockwise = towards the viewer)."""
    n = np.sum(np.cross(p, np.roll(p, -1, axis=0)), axis=0)
    return n / np.linalg.norm(n)
