"""The document's diffuse lighting from a cube map's coarsest mips (004 §4.2): the irradiance is the sum over
the six faces of the face's mean radiance L̄_F times W_F(n) = ∫_F max(0, n·ω) dω, the clamped-cosine solid
angle of the face. Σ_F W_F(n) = π for every n (the clamped cosine's integral over the sphere).

- ``face_weights_exact``: W_F by Lambert's polygon formula on the face square clipped to the hemisphere of n
  (vectorised over normals);
- ``face_weights_fit``: the document's cheap fit max(0.75 + cos θ, 0)² / 1.75 (cos θ = n·a_F) — which does *not*
  sum to π [erratum noted in the digest: a constant environment comes out a few percent off, with a ripple];
- ``face_weights_normalised``: the fit rescaled so that its sum is π.
"""

from __future__ import annotations

import numpy as np

#: the cube's face axes, in the order +x, −x, +y, −y, +z, −z
AXES = np.array([[1, 0, 0], [-1, 0, 0], [0, 1, 0], [0, -1, 0], [0, 0, 1], [0, 0, -1]], np.float64)


def _face_square(axis: np.ndarray) -> np.ndarray:
    """The face of the unit cube (at distance 1) along ``axis``: its four corners, counter-clockwise seen from
    the centre."""
    a = np.argmax(np.abs(axis))
    u = np.eye(3)[(a + 1) % 3]
    v = np.cross(axis, u)
    return np.array([axis - u - v, axis + u - v, axis + u + v, axis - u + v])


def _clipped_squares(square: np.ndarray, normals: np.ndarray) -> np.ndarray:
    """The face square clipped to each normal's hemisphere (Sutherland–Hodgman, one plane through the origin),
    vectorised over normals: (N, 8, 3) vertices, each polygon padded by repeating its last vertex (an empty one:
    all zeros), so that padding adds only zero-length edges."""
    d = normals @ square.T  # (N, 4)
    a, b = square, np.roll(square, -1, axis=0)
    da, db = d, np.roll(d, -1, axis=1)
    keep = da >= 0
    crosses = keep != (db >= 0)
    with np.errstate(divide="ignore", invalid="ignore"):
        s = np.where(crosses, da / (da - db), 0.0)
    crossing = a[None] + (b - a)[None] * s[..., None]  # (N, 4, 3)
    candidates = np.stack([np.broadcast_to(a, crossing.shape), crossing], axis=2).reshape(len(normals), 8, 3)
    valid = np.stack([keep, crosses], axis=2).reshape(len(normals), 8)
    order = np.argsort(~valid, axis=1, kind="stable")  # the valid vertices first, in order
    vertices = np.take_along_axis(candidates, order[..., None], axis=1)
    count = valid.sum(axis=1)
    last = np.take_along_axis(vertices, np.maximum(count - 1, 0)[:, None, None], axis=1)
    pad = np.arange(8)[None, :] >= count[:, None]
    return np.where(pad[..., None], last, vertices) * (count >= 3)[:, None, None]


def _lambert(polygons: np.ndarray, normals: np.ndarray) -> np.ndarray:
    """∫ n·ω dω over each polygon (N, V, 3), all above n's horizon (Lambert's formula, as
    ``validation.polygon_irradiance``; zero-length edges add nothing)."""
    length = np.linalg.norm(polygons, axis=-1, keepdims=True)
    u = polygons / np.maximum(length, 1e-300)
    v = np.roll(u, -1, axis=1)
    theta = np.arccos(np.clip(np.sum(u * v, axis=-1), -1.0, 1.0))
    gamma = np.cross(u, v)
    gamma /= np.maximum(np.linalg.norm(gamma, axis=-1, keepdims=True), 1e-300)
    return 0.5 * np.abs(np.sum(theta * np.einsum("nvk,nk->nv", gamma, normals), axis=1))


def face_weights_exact(normals: np.ndarray) -> np.ndarray:
    """W_F(n) for each normal (N, 3) and face (N, 6), exact."""
    normals = np.atleast_2d(np.asarray(normals, np.float64))
    normals = normals / np.linalg.norm(normals, axis=1, keepdims=True)
    return np.stack([_lambert(_clipped_squares(_face_square(axis), normals), normals) for axis in AXES], axis=1)


def face_weights_fit(normals: np.ndarray) -> np.ndarray:
    """The document's fit of W_F (its sum is not π)."""
    cos = np.atleast_2d(np.asarray(normals, np.float64)) @ AXES.T
    return np.maximum(0.75 + cos, 0.0) ** 2 / 1.75


def face_weights_normalised(normals: np.ndarray) -> np.ndarray:
    """The fit rescaled per normal to sum to π."""
    w = face_weights_fit(normals)
    return w * (np.pi / w.sum(axis=1, keepdims=True))
