"""Brute-force 3D reference: rays in 3D against the extruded scratch, the ground truth of the scratch BRDF.

Geometry. World axes (x, y, z) = (**v**, **n**, **u**): **u** is the scratch (extrusion) direction, **n** the
base normal and **v** = **n** × **u** (right-handed). The scratch surface is the extruded, periodic height field
y = h(x) for every z (:class:`~reflets.scratches.profiles.Profile`), infinitely long along z.

Rays. A directional light from ω_i lights the lid plane y = lid uniformly, so rays start at (x0, lid, z0) with
x0 ~ U[0, 1) and z0 ~ U[0, 1) (z0 is irrelevant for an extruded profile but it is a genuine 3D ray) and travel
along D = −ω_i. Each flight is found by conservative Lipschitz marching in 3D on G(p) = p_y − h(p_x): from a
point with G > 0 the next root is at least G / (|D_y| + L |D_x|) away (L = max |h'|), so the ray steps by that
amount (at least ``min_step``) until G < 0, then 50 bisection steps; nothing is shared with the 2D cell walk
but h and h'. At a hit the 3D normal m = (−h'(x), 1, 0)/‖·‖, the Fresnel factor is F(|D·m|) with the full 3D
cosine, and D ← D − 2 (D·m) m. A ray going up through the lid has left.

Mapping to the 2D table (chapter 3, §3.2). A direction ω has cone coordinates
θ = asin(ω·**u**) = asin(ω_z) and φ = atan2(ω·**v**, ω·**n**) = atan2(ω_x, ω_y), i.e.
ω = (cos θ sin φ, cos θ cos φ, sin θ). A reflection on a wall whose normal lies in the xy plane keeps ω_z and
mirrors the projection (ω_x, ω_y) in 2D, so:

- θ_out = −θ_in exactly (the reflection half-cone; checked here on every ray, ``off_cone``);
- φ, the angle of the projection onto the profile plane, follows the 2D mirror path, so the 3D histogram of
  φ_out must equal the 2D ρ_m for every θ;
- the 3D cosine of incidence at each bounce is |D·m| = cos θ · |d₂·m| where d₂ is the normalised projection:
  the 2D tracer's Fresnel argument cos θ · c₂.

Normalisation. For incident direction ω_i the fraction of the incident flux leaving into dθ_o dφ_o is
f(ω_o, ω_i) (ω_o·n) dω_o = f cos θ_o cos φ_o · cos θ_o dθ_o dφ_o; with f = ρ_m δ(θ_i + θ_o)/cos²θ_o this
integrates over θ_o to ρ_m(φ_o, φ_i) cos φ_o dφ_o. So a histogram of φ_out with A rays (or path weights) in
bin b out of N gives ρ(φ_b, φ_i) = A / (N Δφ cos φ_b), the 2D table's formula.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .profiles import Profile
from .tracer2d import FresnelSpec, bin_of, column_weight, stratified_phi

_BISECTIONS = 50


def _h(profile: Profile, x):
    return profile.height(x)


@dataclass
class Trace3D:
    """Histogram of one 3D trace, indexed [φ_out bin, column] for the requested φ_in columns."""

    columns: np.ndarray  # (J,) φ_in bin indices
    size: int
    rays: int
    theta: float  # elevation θ_out = −θ_in of the light
    counts: np.ndarray  # (M, J) Σ c(ψ) (the mirror tally)
    weights: np.ndarray  # (M, J, C) sum of Fresnel path weights
    weights_sq: np.ndarray  # (M, J, C)
    lost: int
    off_cone: float  # max |θ_out + θ_in| over all rays (radians)

    def rho(self, which: str = "fresnel") -> np.ndarray:
        """ρ estimate (M, J[, C]) = tally / (N Δφ cos φ_b)."""
        M = self.size
        phi = -0.5 * np.pi + (np.arange(M) + 0.5) * np.pi / M
        norm = self.rays * (np.pi / M) * np.cos(phi)
        if which == "mirror":
            return self.counts / norm[:, None]
        return self.weights / norm[:, None, None]

    def variance(self) -> np.ndarray:
        """Variance of :meth:`rho` (Fresnel) per bin, (M, J, C), from the sums of squared weights."""
        M = self.size
        phi = -0.5 * np.pi + (np.arange(M) + 0.5) * np.pi / M
        norm = self.rays * (np.pi / M) * np.cos(phi)
        n = self.rays
        mean = self.weights / n
        var_one = np.maximum(self.weights_sq / n - mean * mean, 0.0)
        return var_one * n / (norm[:, None, None] ** 2)


def trace_directions(
    profile: Profile,
    omega_in: np.ndarray,
    x0: np.ndarray,
    z0: np.ndarray,
    *,
    fresnel: FresnelSpec | None = None,
    max_bounces: int = 100,
    min_step: float = 2.5e-4,
    max_steps: int = 20000,
):
    """Trace 3D rays towards −``omega_in`` (n, 3) from (x0, lid, z0). Returns (exit directions (n, 3),
    Fresnel weights (n, C), bounces (n,), lost (n,) bool)."""
    fresnel = fresnel or FresnelSpec()
    n = omega_in.shape[0]
    pos = np.stack([np.asarray(x0, float), np.full(n, profile.lid), np.asarray(z0, float)], axis=1)
    D = -np.asarray(omega_in, dtype=np.float64).copy()
    D /= np.linalg.norm(D, axis=1, keepdims=True)
    w = np.ones((n, fresnel.channels))
    bounces = np.zeros(n, np.int64)
    lost = np.zeros(n, bool)
    L = max(profile.max_slope, 1e-12)
    lid = profile.lid
    active = np.arange(n)
    while active.size:
        p, d = pos[active], D[active]
        t = np.zeros(active.size)
        g = p[:, 1] - _h(profile, p[:, 0])
        state = np.zeros(active.size, np.int8)  # 0 marching, 1 hit, 2 left
        t_prev = np.zeros(active.size)
        lam = np.abs(d[:, 1]) + L * np.abs(d[:, 0])
        live = np.arange(active.size)
        for _ in range(max_steps):
            if live.size == 0:
                break
            step = np.maximum(np.maximum(g[live], 0.0) / lam[live], min_step)
            t_prev[live] = t[live]
            t[live] += step
            q = p[live] + t[live, None] * d[live]
            g[live] = q[:, 1] - _h(profile, q[:, 0])
            left = (q[:, 1] > lid) & (d[live, 1] > 0)
            below = g[live] < 0.0
            state[live[below]] = 1
            state[live[left & ~below]] = 2
            live = live[~(below | (left & ~below))]
        lost[active[state == 0]] = True
        hits = np.nonzero(state == 1)[0]
        # bisection between the last point above the surface and the first below
        lo, hi = t_prev[hits], t[hits]
        ph, dh = p[hits], d[hits]
        for _ in range(_BISECTIONS):
            mid = 0.5 * (lo + hi)
            q = ph + mid[:, None] * dh
            below = q[:, 1] - _h(profile, q[:, 0]) < 0.0
            hi = np.where(below, mid, hi)
            lo = np.where(below, lo, mid)
        q = ph + lo[:, None] * dh
        s = profile.slope(q[:, 0])
        m = np.stack([-s, np.ones_like(s), np.zeros_like(s)], axis=1)
        m /= np.linalg.norm(m, axis=1, keepdims=True)
        dm = np.sum(dh * m, axis=1)
        gi = active[hits]
        if fresnel.model != "none":
            w[gi] *= fresnel(np.abs(dm))
        D[gi] = dh - 2.0 * dm[:, None] * m
        pos[gi] = q
        bounces[gi] += 1
        over = bounces[gi] > max_bounces
        lost[gi[over]] = True
        active = gi[~over]
    return D, w, bounces, lost


def trace3d(
    profile: Profile,
    *,
    theta: float,
    size: int,
    rays: int,
    columns,
    fresnel: FresnelSpec | None = None,
    seed: int = 0,
) -> Trace3D:
    """3D histogram of φ_out for lights at elevation θ_in = −θ and φ_in jittered in each bin of ``columns``."""
    fresnel = fresnel or FresnelSpec()
    rng = np.random.default_rng(seed)
    M, N = int(size), int(rays)
    columns = np.atleast_1d(np.asarray(columns, dtype=np.int64))
    J, C = columns.size, fresnel.channels
    counts = np.zeros((M, J))
    wsum = np.zeros((M, J, C))
    wsq = np.zeros((M, J, C))
    lost = 0
    off = 0.0
    theta_in = -float(theta)
    for k, j in enumerate(columns):
        phi_in = stratified_phi(j, np.arange(N), N, M, rng.random(N))  # as in the 2D tracer
        omega = np.stack(
            [np.cos(theta_in) * np.sin(phi_in), np.cos(theta_in) * np.cos(phi_in), np.full(N, np.sin(theta_in))],
            axis=1,
        )
        D, w, _, bad = trace_directions(profile, omega, rng.random(N), rng.random(N), fresnel=fresnel)
        ok = ~bad
        lost += int(bad.sum())
        theta_out = np.arcsin(np.clip(D[ok, 2], -1.0, 1.0))  # θ = asin(ω·u)
        phi_out = np.arctan2(D[ok, 0], D[ok, 1])  # φ = atan2(ω·v, ω·n)
        if ok.any():
            off = max(off, float(np.abs(theta_out + theta_in).max()))
        b = bin_of(phi_out, M)
        cw = column_weight(phi_in[ok], j, M)  # the same per-ray weight as the 2D tallies
        counts[:, k] = np.bincount(b, weights=cw, minlength=M)
        for ch in range(C):
            wsum[:, k, ch] = np.bincount(b, weights=w[ok, ch] * cw, minlength=M)
            wsq[:, k, ch] = np.bincount(b, weights=(w[ok, ch] * cw) ** 2, minlength=M)
    return Trace3D(columns, M, N, float(theta), counts, wsum, wsq, lost, off)
