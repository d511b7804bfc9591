"""Sample rings of the multiple-scattering integral (document §6): radii r_max f_β(j/K) and the weights of the
exact integral of the bilinear interpolant over the annular-sector cells.

Cells are [ρ_j, ρ_{j+1}] × [θ_a, θ_{a+1}] in the plane through the shaded point orthogonal to the light; the
integrand is bilinear in (ρ, θ) between the four corner values, and ∫∫ c ρ dρ dθ over a cell gives each inner
corner Δθ Δρ (ρ_j/2 + Δρ/6)/2 and each outer corner Δθ Δρ (ρ_j/2 + Δρ/3)/2 (Δρ = ρ_{j+1} − ρ_j). Summed over
the cells around a node, the integral is Σ_j W_j Σ_a c_{j,a}: one weight per ring. This is the document's
bilinear cell integration written in polar coordinates, where the corrected factor of its eq. (θ₂ − θ₁)/72 ·
r_vᵀ(l₁M₂ + l₂M₁)c_v is exact by construction (tests/translucency/test_translucency_gpu.py integrates
bilinear functions and the profiles with it). The corner values use the true distance to the entry point (the
document's "true geometry"), the cell areas the plane's.

f_β(x) = β √x (1 − x)/(1 − β) + x (eˣ − 1)/(e − 1) concentrates rings near the centre where R_d varies most;
β minimises ∫|g''| with g = R_d ∘ (r_max f_β) (the document's criterion; monotonic for β ≲ 0.68).
"""

from __future__ import annotations

import numpy as np

from .optics import gauss_legendre

BETA_MAX = 0.68


def f_beta(x, beta: float):
    x = np.asarray(x, dtype=np.float64)
    return beta * np.sqrt(x) * (1.0 - x) / (1.0 - beta) + x * np.expm1(x) / (np.e - 1.0)


def ring_radii(r_max: float, rings: int, beta: float) -> np.ndarray:
    """ρ_0 = 0 … ρ_K = r_max."""
    return r_max * f_beta(np.linspace(0.0, 1.0, rings + 1), beta)


def ring_weights(radii: np.ndarray, angles: int) -> np.ndarray:
    """W_j such that Σ_j W_j Σ_a c(ρ_j, θ_a) = ∫ of the bilinear interpolant over the disc of radius ρ_K; the
    centre (ρ_0 = 0) counts as ``angles`` copies of one value."""
    rho = np.asarray(radii, dtype=np.float64)
    d_theta = 2.0 * np.pi / angles
    w = np.zeros_like(rho)
    d = np.diff(rho)
    w[:-1] += d_theta * d * (rho[:-1] / 2.0 + d / 6.0)  # as the inner corner of two angular cells
    w[1:] += d_theta * d * (rho[:-1] / 2.0 + d / 3.0)  # as the outer corner
    return w


def fit_beta(rd, r_max: float, samples: int = 2001) -> float:
    """β ∈ [0, BETA_MAX] minimising ∫₀¹ |g''(x)| dx, g(x) = rd(r_max f_β(x)) (finite differences)."""
    x = np.linspace(1e-4, 1.0, samples)
    h = x[1] - x[0]

    def roughness(beta: float) -> float:
        g = rd(r_max * f_beta(x, beta))
        return float(np.sum(np.abs(np.diff(g, 2))) / h)

    from scipy import optimize  # imported when used (start-up time)

    result = optimize.minimize_scalar(roughness, bounds=(0.0, BETA_MAX), method="bounded", options={"xatol": 1e-3})
    return float(result.x)


def product_weights(radii: np.ndarray, angles: int, rd, order: int = 32, first_cell: bool = True) -> np.ndarray:
    """Product integration: W_j = Δθ ∫ R_d(ρ) ρ hat_j(ρ) dρ per channel (hat_j the piecewise-linear basis of node
    j), so that Σ_j W_j Σ_a e(ρ_j, θ_a) integrates R_d exactly and interpolates only the smooth factor e
    (transmitted flux density × R_d(true)/R_d(plane)). ``rd(r)`` → (..., 3). Exact for a uniformly lit plane,
    where the bilinear rule overestimates the convex profile (+2…5 % at 12 rings, skin1). ``first_cell =
    False`` leaves out the disc ρ < ρ₁ (the shader integrates it per direction, see translucent.frag)."""
    rho = np.asarray(radii, dtype=np.float64)
    t, w = gauss_legendre(order)
    d_theta = 2.0 * np.pi / angles
    out = np.zeros((len(rho), 3))
    for j in range(0 if first_cell else 1, len(rho) - 1):
        r = rho[j] + (rho[j + 1] - rho[j]) * t
        f = rd(r) * (r * w * (rho[j + 1] - rho[j]))[:, None]
        out[j] += d_theta * np.sum(f * (1.0 - t)[:, None], axis=0)
        out[j + 1] += d_theta * np.sum(f * t[:, None], axis=0)
    return out
