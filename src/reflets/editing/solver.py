"""The orientation-field solver of 001 §4.2.4: find the angles φ of the field on the brush's vertices whose
highlight tangents ℓ (eq 4.10) match targets ℓ*, by Levenberg–Marquardt on the tensor energy of eq 4.5 with an
analytic sparse Jacobian (each ℓ_i depends on φ over i's 1-ring), Laplacian smoothing of φ after each step.

The tensor energy removes ℓ's sign: with L = ℓℓᵀ / |ℓ|² and θ the angle of ℓ in the tangent plane,
‖L − L*‖² = ½ |e^{2iθ} − e^{2iθ*}|², so a vertex contributes the two residuals √(A/2) (cos 2θ − cos 2θ*,
sin 2θ − sin 2θ*) [eq 4.11 squares inside the residual: erratum]. Residual vertices: those with a target, and
the brush's 1-ring neighbours without one (their current ℓ is their target: a stroke does not disturb what
surrounds it); degenerate vertices (critical points, ℓ = 0) have none. The loop stops when the energy falls
below ``tolerance`` × its start [the thesis prints the test reversed: erratum], or after ``iterations``.
"""

from __future__ import annotations

import time
from dataclasses import dataclass, field

import numpy as np
import scipy.sparse as sp
import scipy.sparse.linalg as spla

from ..errors import ArgumentError
from .analysis import CRITICAL_COSINE, gradient_weights, highlight_g, laplacian_step, phi_gradient, weingarten
from .surface import SurfaceMesh

#: weight of the Laplacian smoothing step applied to the free angles after each accepted LM step
SMOOTHING = 0.1
#: the most Levenberg–Marquardt iterations one solve takes: it converges in tens (20 by default); each iteration
#: is a sparse solve over the free vertices (seconds when a whole dense mesh is free)
MAX_ITERATIONS = 1000
#: a target row of norm at most this is no target (its vertex follows its neighbours)
NO_TARGET = 1e-12


def check_iterations(iterations, field: str = "iterations") -> int:
    """A whole number of iterations in 1…MAX_ITERATIONS: checked before a scene is loaded or a solve starts."""
    if isinstance(iterations, bool) or not isinstance(iterations, int | np.integer):
        raise ArgumentError(f"expected a whole number of iterations, got {iterations!r}", field=field)
    if not 1 <= iterations <= MAX_ITERATIONS:
        raise ArgumentError(f"{iterations} is out of range; iterations must be in 1..{MAX_ITERATIONS}", field=field)
    return int(iterations)


@dataclass
class SolveResult:
    """The solved angles, the energy before the first and after each iteration, and per-iteration timings."""

    phi: np.ndarray
    energy: list[float]
    jacobian_ms: list[float] = field(default_factory=list)
    solve_ms: list[float] = field(default_factory=list)


class HighlightProblem:
    """Everything about a mesh, a light and a view that the solver's iterations share (the Weingarten maps, the
    regression weights of ∇φ, the half vectors in each vertex's frame)."""

    def __init__(self, mesh: SurfaceMesh, h: np.ndarray, k: int = 2):
        self.mesh, self.k = mesh, k
        self.w = weingarten(mesh)
        #: ∂∇φ_i / ∂φ_j for each 1-ring edge (i, j)
        self.c = gradient_weights(mesh)
        self.h_tb = np.stack([np.einsum("ij,ij->i", h, mesh.t), np.einsum("ij,ij->i", h, mesh.b)], axis=1)
        self.h_n = np.einsum("ij,ij->i", h, mesh.normals)
        self.critical = self.h_n > CRITICAL_COSINE

    def subset(self, rows: np.ndarray) -> np.ndarray:
        """The 1-ring edges (i, j) with i in ``rows``: what ∇φ and ℓ at those vertices read."""
        inside = np.zeros(len(self.mesh.positions), bool)
        inside[rows] = True
        return np.flatnonzero(inside[self.mesh.edges[:, 0]])

    def gradient(self, phi: np.ndarray, edges: np.ndarray | None = None) -> np.ndarray:
        """∇φ (V, 2), at the vertices of ``edges``' first column when a subset is given (zero elsewhere)."""
        return phi_gradient(self.mesh, phi, self.k, self.c, edges)

    def g(self, phi: np.ndarray, grad: np.ndarray | None = None, rows=slice(None)) -> np.ndarray:
        """``analysis.highlight_g`` at ``rows``."""
        grad = self.gradient(phi) if grad is None else grad
        return highlight_g(phi[rows], grad[rows], self.w[rows], self.h_tb[rows], self.h_n[rows])

    def angles(
        self, phi: np.ndarray, rows=slice(None), edges: np.ndarray | None = None
    ) -> tuple[np.ndarray, np.ndarray]:
        """θ, the angle of ℓ in each vertex's (t, b) frame, and |ℓ|, at ``rows`` (``edges``: their subset)."""
        g = self.g(phi, self.gradient(phi, edges), rows)
        return np.arctan2(g[:, 0], -g[:, 1]), np.linalg.norm(g, axis=1)

    def jacobian(
        self, phi: np.ndarray, rows: np.ndarray, free_index: np.ndarray, edges: np.ndarray
    ) -> tuple[np.ndarray, sp.csr_matrix]:
        """dθ_i/dφ_m for the residual vertices ``rows`` (``edges``: their 1-ring edges) and the free vertices
        (``free_index``: the column of each vertex, −1 if fixed), and θ at ``rows``."""
        mesh, count = self.mesh, len(phi)
        grad = self.gradient(phi, edges)
        g = self.g(phi, grad, rows)
        p = phi[rows]
        u2 = np.stack([np.cos(p), np.sin(p)], axis=1)
        v2 = np.stack([-np.sin(p), np.cos(p)], axis=1)
        h_tb = self.h_tb[rows]
        a = np.einsum("ij,ij->i", v2, h_tb)
        da = -np.einsum("ij,ij->i", u2, h_tb)
        size2 = np.maximum(np.einsum("ij,ij->i", g, g), 1e-300)
        dtheta_dg = np.stack([-g[:, 1], g[:, 0]], axis=1) / size2[:, None]  # θ = angle(g) + 90°
        row_of = np.full(count, -1)
        row_of[rows] = np.arange(len(rows))
        i, j = mesh.edges[edges, 0], mesh.edges[edges, 1]
        c = self.c[edges]
        csum = np.zeros((len(rows), 2))
        np.add.at(csum, row_of[i], c)
        dg_self = -csum * a[:, None] + grad[rows] * da[:, None]
        dg_self += np.einsum("vab,vb->va", self.w[rows], v2) * self.h_n[rows][:, None]
        own = free_index[rows] >= 0
        edge = free_index[j] >= 0
        r_i = row_of[i[edge]]
        entries_r = np.concatenate([np.flatnonzero(own), r_i])
        entries_c = np.concatenate([free_index[rows][own], free_index[j[edge]]])
        values = np.concatenate(
            [
                np.einsum("ij,ij->i", dtheta_dg[own], dg_self[own]),
                np.einsum("ij,ij->i", dtheta_dg[r_i], c[edge]) * a[r_i],
            ]
        )
        n_free = int(free_index.max()) + 1 if (free_index >= 0).any() else 0
        jac = sp.coo_matrix((values, (entries_r, entries_c)), shape=(len(rows), n_free)).tocsr()
        return np.arctan2(g[:, 0], -g[:, 1]), jac


def target_angles(mesh: SurfaceMesh, ell: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """θ* of target tangents (V, 3) in each vertex's frame, and which rows hold a target (non-zero)."""
    theta = np.arctan2(np.einsum("ij,ij->i", ell, mesh.b), np.einsum("ij,ij->i", ell, mesh.t))
    return theta, np.linalg.norm(ell, axis=1) > NO_TARGET


def solve(
    problem: HighlightProblem,
    phi0: np.ndarray,
    targets: np.ndarray,
    free: np.ndarray,
    iterations: int = 20,
    tolerance: float = 1e-8,
    smoothing: float = SMOOTHING,
) -> SolveResult:
    """Angles φ (only ``free`` vertices change) whose ℓ match ``targets`` (V, 3; zero rows: no target)."""
    mesh = problem.mesh
    phi = np.asarray(phi0, np.float64).copy()
    free = np.asarray(free, bool)
    theta_star, has_target = target_angles(mesh, targets)
    near = np.zeros(len(phi), bool)  # the brush and its 1-ring: where ℓ can change
    near[mesh.edges[free[mesh.edges[:, 1]], 0]] = True
    near |= free
    candidates = np.flatnonzero(near)
    current, size = problem.angles(phi, candidates, problem.subset(candidates))
    keep = ~has_target[candidates]  # no target given: keep the ℓ it has
    theta_star = np.where(keep, current, theta_star[candidates])
    use = (has_target[candidates] | keep) & ~problem.critical[candidates] & (size > 1e-12)
    rows, theta_star = candidates[use], theta_star[use]
    edges = problem.subset(rows)  # every iteration reads only the brush and its 1-ring
    free_edges = problem.subset(np.flatnonzero(free))
    weights = np.sqrt(mesh.areas[rows] / 2.0)
    free_index = np.full(len(phi), -1)
    free_index[free] = np.arange(int(free.sum()))
    c_star, s_star = np.cos(2 * theta_star), np.sin(2 * theta_star)

    def residuals(p):
        t, _ = problem.angles(p, rows, edges)
        return np.concatenate([weights * (np.cos(2 * t) - c_star), weights * (np.sin(2 * t) - s_star)])

    r = residuals(phi)
    result = SolveResult(phi, [float(r @ r)])
    damping = 1e-3
    for _ in range(iterations):
        if not free.any() or result.energy[-1] <= tolerance * result.energy[0]:
            break
        start = time.perf_counter()
        theta, dtheta = problem.jacobian(phi, rows, free_index, edges)
        d2 = 2.0 * weights[:, None]
        jac = sp.vstack(
            [sp.diags(-d2[:, 0] * np.sin(2 * theta)) @ dtheta, sp.diags(d2[:, 0] * np.cos(2 * theta)) @ dtheta]
        )
        jtj = (jac.T @ jac).tocsc()
        jtr = jac.T @ r
        result.jacobian_ms.append(1e3 * (time.perf_counter() - start))
        start = time.perf_counter()
        diag = sp.diags(jtj.diagonal() + 1e-12)
        for _ in range(12):  # Levenberg–Marquardt: raise the damping until the step lowers the energy
            step = spla.spsolve((jtj + damping * diag).tocsc(), -jtr)
            trial = phi.copy()
            trial[free] += step
            r_trial = residuals(trial)
            if r_trial @ r_trial < r @ r:
                damping = max(damping / 3.0, 1e-9)
                break
            damping *= 5.0
        else:
            result.solve_ms.append(1e3 * (time.perf_counter() - start))
            break  # no step lowers the energy: a (local) minimum
        phi = laplacian_step(mesh, trial, free, smoothing, problem.k, free_edges) if smoothing > 0 else trial
        r = residuals(phi)
        if r @ r > r_trial @ r_trial * 1.5:  # smoothing that undoes the step: keep the step alone
            phi, r = trial, r_trial
        result.solve_ms.append(1e3 * (time.perf_counter() - start))
        result.energy.append(float(r @ r))
    result.phi = phi
    return result
