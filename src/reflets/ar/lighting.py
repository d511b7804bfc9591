"""The document's diffuse lighting from a cube map's coarsest mips (004 §4.2): the irradiance is the sum over
the six faces of the face's mean radiance L̄_F times W_F(n) = ∫_F max(0, n·ω) dω, the clamped-cosine solid
angle of the face. Σ_F W_F(n) = π for every n (the clamped cosine's integral over the sphere).

- ``face_weights_exact``: W_F by Lambert's polygon formula on the face square clipped to the hemisphere of n;
- ``face_weights_fit``: the document's cheap fit max(0.75 + cos θ, 0)² / 1.75 (cos θ = n·a_F) — which does *not*
  sum to π [erratum noted in the digest: a constant environment comes out a few percent off, with a ripple];
- ``face_weights_normalised``: the fit rescaled so that its sum is π.
"""

from __future__ import annotations

import numpy as np

from ..validation import polygon_irradiance

#: the cube's face axes, in the order +x, −x, +y, −y, +z, −z
AXES = np.array([[1, 0, 0], [-1, 0, 0], [0, 1, 0], [0, -1, 0], [0, 0, 1], [0, 0, -1]], np.float64)


def _face_square(axis: np.ndarray) -> np.ndarray:
    """The face of the unit cube (at distance 1) along ``axis``: its four corners, counter-clockwise seen from
    the centre."""
    a = np.argmax(np.abs(axis))
    u = np.eye(3)[(a + 1) % 3]
    v = np.cross(axis, u)
    return np.array([axis - u - v, axis + u - v, axis + u + v, axis - u + v])


def _clip(polygon: np.ndarray, n: np.ndarray) -> np.ndarray:
    """The part of a convex planar polygon with n·x ≥ 0 (Sutherland–Hodgman, one plane through the origin)."""
    out = []
    d = polygon @ n
    for k in range(len(polygon)):
        a, b, da, db = polygon[k], polygon[(k + 1) % len(polygon)], d[k], d[(k + 1) % len(polygon)]
        if da >= 0:
            out.append(a)
        if (da >= 0) != (db >= 0):
            out.append(a + (b - a) * (da / (da - db)))
    return np.array(out)


def _lambert(polygon: np.ndarray, n: np.ndarray) -> float:
    """∫ max(0, n·ω) dω over the solid angle of a polygon clipped to the hemisphere of n (Lambert's formula,
    ``validation.polygon_irradiance``)."""
    if len(polygon) < 3:
        return 0.0
    return float(polygon_irradiance(np.zeros((1, 3)), n[None], polygon, tolerance=1e-9)[0])


def face_weights_exact(normals: np.ndarray) -> np.ndarray:
    """W_F(n) for each normal (N, 3) and face (N, 6), exact."""
    normals = np.atleast_2d(np.asarray(normals, np.float64))
    squares = [_face_square(axis) for axis in AXES]
    return np.array([[_lambert(_clip(square, n), n) for square in squares] for n in normals])


def face_weights_fit(normals: np.ndarray) -> np.ndarray:
    """The document's fit of W_F (its sum is not π)."""
    cos = np.atleast_2d(np.asarray(normals, np.float64)) @ AXES.T
    return np.maximum(0.75 + cos, 0.0) ** 2 / 1.75


def face_weights_normalised(normals: np.ndarray) -> np.ndarray:
    """The fit rescaled per normal to sum to π."""
    w = face_weights_fit(normals)
    return w * (np.pi / w.sum(axis=1, keepdims=True))
