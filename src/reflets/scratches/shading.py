"""NumPy twin of the ``scratches`` technique's per-pixel estimator (scratches/shaders/scratches.frag).

For shading points given by their view direction ``wo`` (local frame: x = tangent u, y = bitangent, z = normal)
and α vector, the reflected radiance of the layered SV-BRDF (eq 3.4) is

    L = w_b · L_base + Σ_k (α_k / max(ᾱ, 1)) · L_k,   w_b = max(0, 1 − ᾱ),   ᾱ = Σ_k α_k (α_k < 1e-6 culled),

- L_base: the base BRDF lit as by the forward pass (point / directional lights exactly, the environment as the
  forward pass's grid of distant lights);
- L_k = ∫ ρ_s(φ_o, φ) cos φ L_in(−θ_o, φ) dφ on layer k's reflection half-cone (frame u_k = R(Θ_k) u,
  v_k = n × u_k, cone angles (θ, φ) = (asin ω·u_k, atan2(ω·v_k, ω·n))), ρ_s = F_γ(θ_o) ρ_m + (1 − F_γ) ρ_s(0)
  read at the nearest bin (eq 3.2), for
  * the environment: importance sampling φ ~ ρ_m(φ_o, ·) cos φ / Z by exact inversion of the row's CDF (eq 3.5
    with the Fresnel weight ρ_s/ρ_m; the exact bin pdf is used so lossy rows stay unbiased); the layer of each
    of the S samples is chosen ∝ α_k with stratified numbers (i + ξ)/S — the budget split ∝ α_k — and weighted
    by ᾱ / max(ᾱ, 1);
  * point and directional lights thickened (eq 3.7, §3.7): radiance E · c · f_H(h) around the light with
    f_H(h) = (1 − (h/H)²)², h = the distance in the (θ, φ) chart, c = 3 / (π H² cos θ_ℓ) (so ∫ E c f_H dω → E as
    H → 0 and ∫ L_k dθ_o → ρ_s(φ_o, φ_ℓ) cos φ_ℓ E / cos θ_ℓ, the δ-light answer); the cone crosses the support on
    [φ_ℓ ± sqrt(H² − (θ_ℓ + θ_o)²)] ∩ (−π/2, π/2), sampled uniformly (stratified); culled when H ≤ |θ_ℓ + θ_o|.

``mode``: "expected" (deterministic quadrature of the same integrals: what the estimators converge to),
"estimate" (the GPU's estimator with NumPy random numbers) or "uniform" (φ uniform on the half-cone, for the
unbiasedness test).
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from .material import ALPHA_CULL
from .table import ScratchTable
from .tracer2d import bin_of

HALF_PI = 0.5 * np.pi


@dataclass
class Lights:
    """Lighting of shading points in their local frame.

    ``directional``: list of (unit direction towards the light (3,) or (P, 3), irradiance E (3,) or (P, 3)) — a
    point light is one with E = I / r²; ``env``: callable local directions (..., 3) → radiance (..., 3), or
    None; ``env_grid``: (directions (G, 3) or (P, G, 3), radiance × solid angle (G, 3)) for the base, as the
    forward pass."""

    directional: list = field(default_factory=list)
    env: object = None
    env_grid: tuple | None = None


def layer_weights(alpha: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(culled α (P, K), per-layer weight α_k / max(ᾱ, 1) (P, K), base weight max(0, 1 − ᾱ) (P,))."""
    a = np.asarray(alpha, dtype=np.float64)
    a = np.where(a >= ALPHA_CULL, a, 0.0)
    total = a.sum(axis=-1)
    return a, a / np.maximum(total, 1.0)[..., None], np.maximum(0.0, 1.0 - total)


def cone(w: np.ndarray, angle: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(θ, φ) of local directions in the frame of a layer rotated by ``angle`` (broadcast)."""
    c, s = np.cos(angle), np.sin(angle)
    wu = c * w[..., 0] + s * w[..., 1]
    wv = -s * w[..., 0] + c * w[..., 1]
    return np.arcsin(np.clip(wu, -1.0, 1.0)), np.arctan2(wv, w[..., 2])


def from_cone(theta, phi, angle) -> np.ndarray:
    """Local direction of cone angles (θ, φ) in the layer frame (u_k = (c, s, 0), v_k = (−s, c, 0))."""
    theta, phi, angle = np.broadcast_arrays(np.asarray(theta, float), np.asarray(phi, float), np.asarray(angle, float))
    c, s = np.cos(angle), np.sin(angle)
    st, ct = np.sin(theta), np.cos(theta)
    sv, cv = ct * np.sin(phi), ct * np.cos(phi)
    return np.stack([st * c - sv * s, st * s + sv * c, cv], axis=-1)


def rho_s_cells(table: ScratchTable, theta_o, b, j) -> np.ndarray:
    """ρ_s at bins (b, j) for elevations θ_o (broadcast), RGB (..., 3); the Fresnel weight as in the table."""
    x = np.clip(2.0 * np.abs(np.asarray(theta_o, float)) / np.pi, 0.0, 1.0)
    g, s0 = table.gamma[b, j], table.rho_s0[b, j]
    if table.gamma.ndim == 2:  # one channel: add the channel axis
        g, s0 = g[..., None], s0[..., None]
    x = np.asarray(x)[..., None]
    with np.errstate(divide="ignore"):
        F = np.where(x > 0, np.power(np.maximum(x, 1e-300), g), np.where(g > 0, 0.0, 1.0))
    rho = F * table.rho_m[b, j][..., None] + (1.0 - F) * s0
    return np.broadcast_to(rho, rho.shape[:-1] + (3,))


def _invert(table: ScratchTable, b: np.ndarray, u: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(φ, bin) with CDF_b(φ) = u: the GPU's binary search (max k with cdf[k] ≤ u), then linear in the bin."""
    M = table.size
    c = table.cdf[b]
    k = np.sum(c[..., 1:-1] <= u[..., None], axis=-1)
    lo = np.take_along_axis(c, k[..., None], -1)[..., 0]
    hi = np.take_along_axis(c, k[..., None] + 1, -1)[..., 0]
    frac = np.where(hi > lo, (u - lo) / np.where(hi > lo, hi - lo, 1.0), 0.5)
    return -HALF_PI + (k + np.clip(frac, 0.0, 1.0)) * np.pi / M, k


def env_layer(table, angle, wo, env, mode="expected", u=None, quadrature=8) -> np.ndarray:
    """L_k for the environment, shading points (P,) of one layer: exact quadrature, one sample per point with
    numbers ``u`` (mode "estimate": importance sampled; "uniform": φ uniform), (P, 3)."""
    theta_o, phi_o = cone(wo, angle)
    b = bin_of(phi_o, table.size)
    M = table.size
    if mode == "expected":
        q = quadrature
        phi = -HALF_PI + (np.arange(M * q) + 0.5) * np.pi / (M * q)  # (Q,)
        j = np.repeat(np.arange(M), q)
        w = from_cone(-theta_o[:, None], phi[None, :], angle)
        rho = rho_s_cells(table, theta_o[:, None], b[:, None], j[None, :])
        return np.sum(rho * np.cos(phi)[None, :, None] * env(w), axis=1) * np.pi / (M * q)
    if mode == "uniform":
        phi = -HALF_PI + u * np.pi
        j = bin_of(phi, M)
        rho = rho_s_cells(table, theta_o, b, j)
        return rho * (np.cos(phi) * np.pi)[:, None] * env(from_cone(-theta_o, phi, angle))
    phi, j = _invert(table, b, u)
    pdf = table.pdf[b, j].astype(np.float64)
    rho = rho_s_cells(table, theta_o, b, j)
    weight = np.where(pdf > 0, np.cos(phi) / np.where(pdf > 0, pdf, 1.0), 0.0)
    return rho * weight[:, None] * env(from_cone(-theta_o, phi, angle))


def light_layer(table, angle, wo, wl, E, thickness, mode="expected", u=None, samples=4, quadrature=64):
    """L_k for one thickened light (direction ``wl`` (P, 3) local, irradiance E (P, 3)), (P, 3)."""
    H = float(thickness)
    theta_o, phi_o = cone(wo, angle)
    theta_l, phi_l = cone(wl, angle)
    b = bin_of(phi_o, table.size)
    delta = theta_l + theta_o
    half = np.sqrt(np.maximum(H * H - delta * delta, 0.0))
    lo = np.maximum(phi_l - half, -HALF_PI)
    hi = np.minimum(phi_l + half, HALF_PI)
    live = (np.abs(delta) < H) & (hi > lo)
    norm = 3.0 / (np.pi * H * H * np.maximum(np.cos(theta_l), np.sin(H)))
    n = quadrature if mode == "expected" else samples
    offset = (np.arange(n) + 0.5)[None, :] if mode == "expected" else np.arange(n)[None, :] + u[:, None]
    phi = lo[:, None] + offset / n * (hi - lo)[:, None]  # (P, n)
    h2 = delta[:, None] ** 2 + (phi - phi_l[:, None]) ** 2
    f = np.maximum(0.0, 1.0 - h2 / (H * H)) ** 2
    rho = rho_s_cells(table, theta_o[:, None], b[:, None], bin_of(phi, table.size))
    acc = np.sum(rho * (np.cos(phi) * f)[..., None], axis=1) * ((hi - lo) / n * norm)[:, None]
    return np.where(live[:, None], acc * np.asarray(E, float), 0.0)


def shade(
    table: ScratchTable,
    angles,
    alpha,
    wo,
    lights: Lights,
    *,
    base=None,
    thickness: float = np.radians(2.0),
    mode: str = "expected",
    samples: int = 8,
    light_samples: int = 4,
    rng: np.random.Generator | None = None,
) -> np.ndarray:
    """Reflected radiance (P, 3) of P shading points (module docstring); ``base`` a material (None: black)."""
    wo = np.atleast_2d(np.asarray(wo, dtype=np.float64))
    P = wo.shape[0]
    angles = np.atleast_1d(np.asarray(angles, dtype=np.float64))
    a, wk, wb = layer_weights(np.broadcast_to(np.asarray(alpha, float), (P, angles.size)))
    total = a.sum(axis=1)
    out = np.zeros((P, 3))
    rng = rng or np.random.default_rng(0)
    up = wo[:, 2] > 0
    if base is not None:
        for wl, E in lights.directional:
            wl = np.broadcast_to(np.asarray(wl, float), (P, 3))
            cos = np.maximum(wl[:, 2], 0.0)
            out += wb[:, None] * base.eval(wo, wl) * (np.asarray(E, float) * cos[:, None])
        if lights.env_grid is not None:
            dirs, power = lights.env_grid
            dirs = np.broadcast_to(np.asarray(dirs, float), (P, *np.shape(dirs)[-2:]))
            for g in range(dirs.shape[1]):
                cos = np.maximum(dirs[:, g, 2], 0.0)
                out += wb[:, None] * base.eval(wo, dirs[:, g]) * (power[g] * cos[:, None])
    for wl, E in lights.directional:
        wl = np.broadcast_to(np.asarray(wl, float), (P, 3))
        E = np.broadcast_to(np.asarray(E, float), (P, 3))
        for k, angle in enumerate(angles):
            u = rng.random(P) if mode != "expected" else None
            val = light_layer(table, angle, wo, wl, E, thickness, mode, u, light_samples)
            out += wk[:, k, None] * val
    if lights.env is not None and samples > 0:
        if mode == "expected":
            for k, angle in enumerate(angles):
                out += wk[:, k, None] * env_layer(table, angle, wo, lights.env, "expected")
        else:
            cum = np.cumsum(a, axis=1)
            last = np.where(a > 0, np.arange(angles.size), -1).max(axis=1)
            xi = rng.random(P)
            acc = np.zeros((P, 3))
            for i in range(samples):
                target = (i + xi) / samples * total
                k = np.minimum(np.sum(cum <= target[:, None], axis=1), np.maximum(last, 0))
                u = rng.random(P)
                for layer in np.unique(k):
                    sel = k == layer
                    acc[sel] += env_layer(table, angles[layer], wo[sel], lights.env, mode, u[sel])
            out += acc * (total / np.maximum(total, 1.0) / samples)[:, None]
    return np.where(up[:, None], out, 0.0)
