"""Highlight-curve analysis (001, §4.2): the tangent ℓ of the potential highlight curve through each vertex,
from the orientation field's angle φ, its gradient and the surface's Weingarten map (eq 4.10, the rotation eq
4.7 omits restored):

  ℓ = [b, −t] · ( ∇φ (v·h) + W ū (n·h) ),  ū = (cos φ, sin φ), v = n × u,

which is n × ∇(h·u) with h fixed: the highlight is the zero set of h·u. ``D_d u = (∇φ·d) v + (uᵀ W d) n``
(W the Hessian of the height over the tangent plane, so that D_d n = −W d) gives it in one line.

- ∇φ_i by regression over the 1-ring (eq 4.13) of the neighbours' angles, parallel-transported into i's frame,
  with k = 2 for centrally symmetric BRDFs (u unoriented: φ mod π) and k = 1 otherwise. The residual is the
  wrapped angle difference wrap(k (φ_j − φ_i)) / k rather than the document's sin(k (φ_j − φ_i)): its first
  order, and exact for linear fields (the acceptance's check) where sin is not.
- W_i by a least-squares jet z = a·x + ½ xᵀ W x over the 2-ring (the linear term absorbs a normal's error;
  the ½ is the note's "mind the factor").
"""

from __future__ import annotations

import numpy as np

from .surface import SurfaceMesh

#: h·n above this: a critical point, on every highlight whatever u (§4.2.1)
CRITICAL_COSINE = 0.9995


def wrap(angle: np.ndarray) -> np.ndarray:
    """Angles into (−π, π]."""
    return np.angle(np.exp(1j * np.asarray(angle)))


def gradient_weights(mesh: SurfaceMesh) -> np.ndarray:
    """(E, 2): ∂∇φ_i/∂φ_j for each 1-ring edge (i, j) of eq 4.13's regression, (Σ_j x_j x_jᵀ)⁻¹ x_ij: ∇φ is
    linear in the transported angle differences, so these weights are all the regression there is."""
    i = mesh.edges[:, 0]
    x, _ = mesh.local(mesh.edges)
    ata = np.zeros((len(mesh.positions), 2, 2))
    np.add.at(ata, i, x[:, :, None] * x[:, None, :])
    ata += 1e-12 * np.trace(ata, axis1=1, axis2=2)[:, None, None] * np.eye(2) + 1e-300 * np.eye(2)
    return np.einsum("eab,eb->ea", np.linalg.inv(ata)[i], x)


def phi_gradient(
    mesh: SurfaceMesh, phi: np.ndarray, k: int = 2, weights: np.ndarray | None = None, edges=None
) -> np.ndarray:
    """∇φ per vertex in its (t, b) frame, (V, 2): the least-squares slope of the transported angle differences
    over the 1-ring (eq 4.13; ``weights`` from ``gradient_weights``, computed when not given; ``edges``: only
    the vertices of those edges' first column, zero elsewhere)."""
    weights = gradient_weights(mesh) if weights is None else weights
    sel = slice(None) if edges is None else edges
    i, j = mesh.edges[sel, 0], mesh.edges[sel, 1]
    y = wrap(k * (phi[j] + mesh.transport[sel] - phi[i])) / k
    grad = np.zeros((len(phi), 2))
    np.add.at(grad, i, weights[sel] * y[:, None])
    return grad


def highlight_g(phi: np.ndarray, grad: np.ndarray, w: np.ndarray, h_tb: np.ndarray, h_n: np.ndarray) -> np.ndarray:
    """g = ∇φ (v·h) + W ū (n·h) (rows alike in every argument; h_tb = h in the (t, b) frame): ℓ is g turned by
    90° in the tangent plane (eq 4.10)."""
    u2 = np.stack([np.cos(phi), np.sin(phi)], axis=1)
    v2 = np.stack([-np.sin(phi), np.cos(phi)], axis=1)
    a = np.einsum("ij,ij->i", v2, h_tb)
    return grad * a[:, None] + np.einsum("vab,vb->va", w, u2) * h_n[:, None]


def laplacian_step(
    mesh: SurfaceMesh, phi: np.ndarray, where: np.ndarray, weight: float, k: int = 2, edges=None
) -> np.ndarray:
    """One damped Laplacian step on the angles at ``where`` (neighbours transported, k-fold wrapped; ``edges``:
    the 1-ring edges those vertices need, all by default)."""
    sel = slice(None) if edges is None else edges
    i, j = mesh.edges[sel, 0], mesh.edges[sel, 1]
    delta = wrap(k * (phi[j] + mesh.transport[sel] - phi[i])) / k
    mean = np.bincount(i, delta, len(phi)) / np.maximum(np.bincount(i, minlength=len(phi)), 1)
    return np.where(where, phi + weight * mean, phi)


def weingarten(mesh: SurfaceMesh) -> np.ndarray:
    """The Weingarten map W per vertex in its (t, b) frame, (V, 2, 2) symmetric: the Hessian of the height of the
    2-ring over the tangent plane (z = a·x + ½ xᵀ W x fitted by least squares)."""
    i = mesh.ring2[:, 0]
    x, z = mesh.local(mesh.ring2)
    scale = np.sqrt(np.maximum(np.bincount(i, x[:, 0] ** 2 + x[:, 1] ** 2, len(mesh.positions)), 1e-300))
    s = scale[i]  # per-vertex scaling keeps the normal equations well conditioned on any mesh size
    xs, ys = x[:, 0] / s, x[:, 1] / s
    rows = np.stack([xs, ys, 0.5 * xs * xs, xs * ys, 0.5 * ys * ys], axis=1)
    ata = np.zeros((len(mesh.positions), 5, 5))
    aty = np.zeros((len(mesh.positions), 5))
    np.add.at(ata, i, rows[:, :, None] * rows[:, None, :])
    np.add.at(aty, i, rows * (z / s)[:, None])
    coef = _solve(ata, aty) / scale[:, None]  # back to world units: the second-order terms scale by 1/s
    w = np.empty((len(mesh.positions), 2, 2))
    w[:, 0, 0], w[:, 0, 1], w[:, 1, 1] = coef[:, 2], coef[:, 3], coef[:, 4]
    w[:, 1, 0] = w[:, 0, 1]
    return w


def half_vectors(mesh: SurfaceMesh, eye, light_position=None, light_direction=None) -> np.ndarray:
    """Unit half vectors h per vertex between the eye and a point light (its position) or a directional light
    (``light_direction``, where the light travels)."""
    to_eye = _unit(np.asarray(eye, np.float64) - mesh.positions)
    if light_position is not None:
        to_light = _unit(np.asarray(light_position, np.float64) - mesh.positions)
    else:
        to_light = np.broadcast_to(-_unit(np.asarray(light_direction, np.float64)[None]), to_eye.shape)
    return _unit(to_eye + to_light)


def highlight_tangents(
    mesh: SurfaceMesh, phi: np.ndarray, h: np.ndarray, k: int = 2, w: np.ndarray | None = None
) -> tuple[np.ndarray, np.ndarray]:
    """ℓ per vertex (V, 3), unnormalised (eq 4.10), and the degenerate vertices (V,) bool: ℓ = 0 (a highlight
    region) or a critical point (h·n > ``CRITICAL_COSINE``)."""
    w = weingarten(mesh) if w is None else w
    h_tb = np.stack([np.einsum("ij,ij->i", h, mesh.t), np.einsum("ij,ij->i", h, mesh.b)], axis=1)
    hn = np.einsum("ij,ij->i", h, mesh.normals)
    g = highlight_g(phi, phi_gradient(mesh, phi, k), w, h_tb, hn)
    ell = g[:, :1] * mesh.b - g[:, 1:] * mesh.t
    size = np.linalg.norm(ell, axis=1)
    degenerate = (hn > CRITICAL_COSINE) | (size <= 1e-12 * max(float(size.max(initial=0.0)), 1e-300))
    return ell, degenerate


def _solve(ata: np.ndarray, aty: np.ndarray) -> np.ndarray:
    """Batched least squares from normal equations (a tiny ridge where a neighbourhood is degenerate)."""
    ridge = 1e-12 * np.trace(ata, axis1=1, axis2=2)[:, None, None] * np.eye(ata.shape[1])
    return np.linalg.solve(ata + ridge + 1e-300 * np.eye(ata.shape[1]), aty[..., None])[..., 0]


def _unit(v: np.ndarray) -> np.ndarray:
    return v / np.maximum(np.linalg.norm(v, axis=-1, keepdims=True), 1e-300)
