"""Fresnel reflectance of a smooth interface seen from the outside (index 1), unpolarised light.

Every function takes ``cos_i`` = cosine between the incident direction and the interface normal (for a
microfacet: wi·h = wo·h), clipped to [0, 1], and broadcasts NumPy-style against its material parameters:
pass ``cos[..., None]`` with an RGB ``eta`` to get (..., 3). The GLSL twins are in ``glsl/fresnel.glsl``.
"""

from __future__ import annotations

import numpy as np

#: complex index of refraction η + i k of gold per linear-RGB channel: the "Au" row of the RGB table shared by
#: Tungsten (ComplexIorData.hpp), Nori and Yocto/GL; the default of a ``fresnel = "conductor"`` microfacet
GOLD_ETA = (0.1431189557, 0.3749570432, 1.4424785571)
GOLD_K = (3.9831604247, 2.3857207478, 1.6032152899)


def fresnel_dielectric(cos_i, eta):
    """Exact reflectance of a dielectric interface with real relative index ``eta`` = η_inside / η_outside.

    F = (r_s² + r_p²) / 2 with r_s = (cosθi − η cosθt)/(cosθi + η cosθt), r_p = (η cosθi − cosθt)/(η cosθi + cosθt)
    and Snell's law sinθt = sinθi / η. For η < 1 (light leaving a denser medium) total internal reflection
    gives F = 1 when sinθi ≥ η. F(1) = ((η − 1)/(η + 1))², F(0) = 1 (for η ≠ 1).
    """
    cos_i = np.clip(np.asarray(cos_i, dtype=np.float64), 0.0, 1.0)
    eta = np.asarray(eta, dtype=np.float64)
    sin2_t = (1.0 - cos_i * cos_i) / (eta * eta)
    cos_t = np.sqrt(np.maximum(0.0, 1.0 - sin2_t))
    rs = (cos_i - eta * cos_t) / np.maximum(cos_i + eta * cos_t, 1e-300)
    rp = (eta * cos_i - cos_t) / np.maximum(eta * cos_i + cos_t, 1e-300)
    return np.where(sin2_t >= 1.0, 1.0, 0.5 * (rs * rs + rp * rp))


def fresnel_conductor(cos_i, eta, k):
    """Exact reflectance of an absorbing interface with complex relative index η + i k (k ≥ 0).

    The real-arithmetic closed form of the complex Fresnel equations (Mitsuba 0.6 ``fresnelConductorExact``,
    pbrt-v3 ``FrConductor``): with t = η² − k² − sin²θ, a² + b² = sqrt(t² + 4η²k²) and a = sqrt((a² + b² + t)/2),
    R_s = (a² + b² + cos²θ − 2a cosθ) / (a² + b² + cos²θ + 2a cosθ),
    R_p = R_s (cos²θ (a² + b²) + sin⁴θ − 2a cosθ sin²θ) / (cos²θ (a² + b²) + sin⁴θ + 2a cosθ sin²θ),
    F = (R_s + R_p)/2. With k = 0 it equals :func:`fresnel_dielectric` (total internal reflection included).
    """
    cos_i = np.clip(np.asarray(cos_i, dtype=np.float64), 0.0, 1.0)
    eta = np.asarray(eta, dtype=np.float64)
    k = np.asarray(k, dtype=np.float64)
    cos2 = cos_i * cos_i
    sin2 = 1.0 - cos2
    temp = (eta * eta - k * k) - sin2
    a2pb2 = np.sqrt(temp * temp + 4.0 * (eta * eta * k * k))
    a = np.sqrt(np.maximum(0.0, 0.5 * (a2pb2 + temp)))
    term1 = a2pb2 + cos2
    term2 = 2.0 * a * cos_i
    rs = (term1 - term2) / np.maximum(term1 + term2, 1e-300)
    term3 = a2pb2 * cos2 + sin2 * sin2
    term4 = term2 * sin2
    rp = rs * (term3 - term4) / np.maximum(term3 + term4, 1e-300)
    return 0.5 * (rs + rp)


def fresnel_schlick(cos_i, f0):
    """Schlick's approximation F0 + (1 − F0)(1 − cosθ)⁵ (F0 = reflectance at normal incidence, in [0, 1])."""
    cos_i = np.clip(np.asarray(cos_i, dtype=np.float64), 0.0, 1.0)
    f0 = np.asarray(f0, dtype=np.float64)
    return f0 + (1.0 - f0) * (1.0 - cos_i) ** 5
