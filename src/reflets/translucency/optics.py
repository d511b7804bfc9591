"""Optics of a smooth dielectric boundary and of the medium inside it (NumPy, float64).

Conventions: ``eta`` is the relative index η = n_inside / n_outside of the translucent material (1.3 for skin,
1.5 for marble). Fresnel reflectance at an interface uses :func:`reflets.fresnel.fresnel_dielectric`,
whose ``eta`` is n_transmitted / n_incident: ``eta`` for light arriving from outside, ``1/eta`` for light
arriving from inside (total internal reflection beyond the critical angle).

The document (§3.3) swaps the names of the reflectance and transmittance terms; here F_R is reflectance and
F_T = 1 − F_R transmittance, as the note corrects.
"""

from __future__ import annotations

import functools

import numpy as np

from ..fresnel import fresnel_dielectric

__all__ = [
    "fresnel_reflectance",
    "fresnel_transmittance",
    "fresnel_moment",
    "diffuse_normalisation",
    "gauss_legendre",
    "fresnel_moment_fit",
    "diffuse_fresnel_reflectance_fit",
    "henyey_greenstein",
    "sample_henyey_greenstein",
    "beckmann_d",
    "refracted_cos",
]


def fresnel_reflectance(cos_i, eta, *, inside: bool = False):
    """F_R for light arriving at the boundary with cosine ``cos_i`` from outside (default) or inside."""
    eta = np.asarray(eta, dtype=np.float64)
    return fresnel_dielectric(cos_i, 1.0 / eta if inside else eta)


def fresnel_transmittance(cos_i, eta, *, inside: bool = False):
    """F_T = 1 − F_R (0 under total internal reflection)."""
    return 1.0 - fresnel_reflectance(cos_i, eta, inside=inside)


@functools.cache
def gauss_legendre(nodes: int) -> tuple[np.ndarray, np.ndarray]:
    """Gauss–Legendre nodes and weights on [0, 1] (cached: the eigen-solve costs O(n²))."""
    x, w = np.polynomial.legendre.leggauss(nodes)
    return 0.5 * (x + 1.0), 0.5 * w


def fresnel_moment(k: int, eta, *, inside: bool = True, nodes: int = 256):
    """C_k = ∫₀¹ F_R(μ) μ^k dμ by Gauss–Legendre quadrature, exact below the critical angle (F_R = 1) and with
    μ = μ_c + (1 − μ_c) t² above it, which removes F_R's square-root behaviour at μ_c.

    ``inside=True`` (the dipole's boundary condition): light hitting the boundary from inside the medium.
    2 C_1 is the cosine-weighted hemispherical average of the reflectance (F_dr of Jensen et al. 2001).
    """
    scalar = np.ndim(eta) == 0
    eta = np.atleast_1d(np.asarray(eta, dtype=np.float64))
    t, w = gauss_legendre(nodes)
    out = np.empty(eta.shape)
    for i, e in enumerate(eta.ravel()):
        relative = 1.0 / e if inside else e
        mu_c = np.sqrt(1.0 - relative * relative) if relative < 1.0 else 0.0
        mu = mu_c + (1.0 - mu_c) * t * t
        jacobian = 2.0 * (1.0 - mu_c) * t
        out.ravel()[i] = mu_c ** (k + 1) / (k + 1) + np.sum(w * jacobian * fresnel_dielectric(mu, relative) * mu**k)
    return float(out[0]) if scalar else out


@functools.cache
def diffuse_normalisation(eta: float) -> float:
    """c = 1 − 2 C₁ for light arriving from outside: ∫ F_T(θ) cosθ dω / π, d'Eon's normalisation of the
    directional part of S_d (so that a uniformly lit flat sample re-emits F_T(θ_i) R_total)."""
    return 1.0 - 2.0 * fresnel_moment(1, float(eta), inside=False)


def fresnel_moment_fit(k: int, eta):
    """d'Eon & Irving's polynomial fits of 2C_1 and 3C_2, returned as C_k (k = 1 or 2), for light from inside
    a medium of relative index η (the moments of F_R(μ; 1/η)). Agrees with :func:`fresnel_moment` within 0.005
    for η ∈ [1.1, 1.6] (tests/translucency/test_translucency_optics.py)."""
    e = np.asarray(eta, dtype=np.float64)
    if k == 1:
        low = 0.919317 - 3.4793 * e + 6.75335 * e**2 - 7.80989 * e**3 + 4.98554 * e**4 - 1.36881 * e**5
        high = -9.23372 + 22.2272 * e - 20.9292 * e**2 + 10.2291 * e**3 - 2.54396 * e**4 + 0.254913 * e**5
        return np.where(e < 1.0, low, high) / 2.0
    if k == 2:
        low = 0.828421 - 2.62051 * e + 3.36231 * e**2 - 1.95284 * e**3 + 0.236494 * e**4 + 0.145787 * e**5
        high = (
            -1641.1
            + 135.926 / e**3
            - 656.175 / e**2
            + 1376.53 / e
            + 1213.67 * e
            - 568.556 * e**2
            + 164.798 * e**3
            - 27.0181 * e**4
            + 1.91826 * e**5
        )
        return np.where(e < 1.0, low, high) / 3.0
    raise ValueError(f"fits exist for k = 1 and 2, not {k}")


def diffuse_fresnel_reflectance_fit(eta):
    """Jensen et al. 2001's fit of F_dr = 2 C_1 (light from inside, relative index η)."""
    e = np.asarray(eta, dtype=np.float64)
    return -1.440 / e**2 + 0.710 / e + 0.668 + 0.0636 * e


def henyey_greenstein(cos_theta, g):
    """p(θ) = (1/4π)(1 − g²)/(1 + g² − 2g cosθ)^{3/2}: normalised over the sphere, mean cosine g."""
    cos_theta = np.asarray(cos_theta, dtype=np.float64)
    g = np.asarray(g, dtype=np.float64)
    denom = np.maximum(1.0 + g * g - 2.0 * g * cos_theta, 1e-300)
    return (1.0 - g * g) / (4.0 * np.pi * denom**1.5)


def sample_henyey_greenstein(g, u):
    """cosθ of a Henyey–Greenstein sample (inverse CDF; isotropic for |g| < 1e-3)."""
    g = np.asarray(g, dtype=np.float64)
    u = np.asarray(u, dtype=np.float64)
    iso = 1.0 - 2.0 * u
    safe = np.where(np.abs(g) < 1e-3, 0.5, g)
    s = (1.0 - safe * safe) / (1.0 - safe + 2.0 * safe * u)
    hg = (1.0 + safe * safe - s * s) / (2.0 * safe)
    return np.clip(np.where(np.abs(g) < 1e-3, iso, hg), -1.0, 1.0)


def beckmann_d(cos_h, m):
    """Beckmann D(h) = exp(−tan²δ/m²) / (π m² cos⁴δ); ∫ D (n·h) dω = 1 over the hemisphere."""
    c = np.clip(np.asarray(cos_h, dtype=np.float64), 1e-12, 1.0)
    m = np.asarray(m, dtype=np.float64)
    tan2 = (1.0 - c * c) / (c * c)
    return np.where(np.asarray(cos_h) > 0.0, np.exp(-tan2 / (m * m)) / (np.pi * m * m * c**4), 0.0)


def refracted_cos(cos_i, eta):
    """|cos θ_t| of the refracted direction for light entering a medium of relative index η (Snell)."""
    cos_i = np.clip(np.abs(np.asarray(cos_i, dtype=np.float64)), 0.0, 1.0)
    return np.sqrt(np.maximum(0.0, 1.0 - (1.0 - cos_i * cos_i) / (np.asarray(eta, dtype=np.float64) ** 2)))
