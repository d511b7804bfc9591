"""Fitting Linearly Transformed Cosines (Heitz, Dupuy, Hill & Neubelt 2016) to any reflets BRDF.

An LTC is the clamped cosine ``D_o(ω) = max(0, ω_z)/π`` seen through a 3×3 matrix M: its density is

    D(ω) = D_o(M⁻¹ω / |M⁻¹ω|) · |det M⁻¹| / |M⁻¹ω|³ = det(M⁻¹) · max(0, (M⁻¹ω)_z) / (π |M⁻¹ω|⁴)   (|ω| = 1),

a probability density on the sphere for every invertible M, unchanged when M is multiplied by a positive
number. Its integral over a polygon P is the clamped cosine's integral over the polygon M⁻¹P, which
Lambert's formula gives in closed form. For a view direction wo = (sinθ, 0, cosθ) and a BRDF f the fitter
finds M such that ``f(wo, ω) cosθ_ω ≈ A · D(ω)`` with the magnitude ``A = ∫ f cos dω`` (the directional
albedo). The lobe of an isotropic BRDF is symmetric about the plane of incidence (xz), so M has the form

    M = [[a, 0, b], [0, c, 0], [d, 0, 1]]      (4 free coefficients; m22 = 1 fixes the scale)

and is optimised as (log a', log c, b, d) with a' = a − b·d = det of the xz block (> 0, so det M > 0: M
keeps orientations and M⁻¹ never flips a vertex to its antipode).

Mixture base (``FitSettings.base_power`` n > 1, odd): D_o = (1 − β) max(0, z)/π + β (n + 1)/(2π) max(0, z)ⁿ,
β ∈ (0, 1) a fifth parameter per cell (optimised as its logit, stored in ``power_weight``). The clamped
cosine seen through M falls off as a power law, ∝ ψ⁻⁴ at an angle ψ from its axis, so a Gaussian-like lobe
(Phong's cos^e ψ ≈ exp(−e ψ²/2), Beckmann, Ward) is fitted no better than L1 0.359: its plateau too low, its
tails too heavy. cosⁿ seen through diag(s, s, 1) is (1 + tan²ψ/s²)^(−(n+3)/2) — a Gaussian as n grows — and
its polygon integral stays closed-form for odd n (Arvo 1995, :func:`polygon_integral`). With n = 31 the
sharp lobes reach L1 ≈ 0.03; GGX's heavy tails keep β < 1 % (the clamped cosine is their shape). The
renderer also cuts the cosⁿ lobe off outside the cone z ≥ :func:`support_cut` (all but ``SUPPORT_MASS`` of
its mass), where it still fades as a power law; the fit ignores that cut (≤ 10⁻⁴ of the lobe).

Fit
---
Per table cell, a fixed set of directions: k×k stratified samples of the BRDF's own importance sampling
(``material.sample``) and ``n_uniform`` points of a spherical Fibonacci lattice (coverage of the whole sphere,
also below the horizon, where the LTC may leak but the lobe is 0), combined by the power heuristic (β = 2;
a lattice point that lands in a sharp peak then weighs almost nothing). The normalised target p is the
Rec. 709 luminance of f·cos divided by its integral; the magnitude is kept per RGB channel (the shape is
shared). The objective is the L1 error Σ w |D − p| (``FitSettings.power``; on the benchmark scene L1 fits
render better than Heitz et al.'s L3: relative MSE 0.12 % / 0.19 % / 0.27 % for L1 / L2 / L3 with GGX
α = 0.3, 0.91 % / 1.20 % / 1.21 % with Phong e = 150, 32² tables), minimised by a vectorised Nelder–Mead
over all roughness cells of one view angle at once (converged cells drop out), sweeping θ from the normal to
grazing. Each row starts from the previous row's solution with b shifted by the change of the lobe's mean
direction (so sharp lobes are not lost between rows); the first row from the best of a scan of isotropic
scalings diag(s, s, 1); a cell still misplacing > 30 % of its lobe is restarted from a scan about the lobe's
mean direction.

Magnitude and error: after the fit, each cell is integrated by a deterministic quadrature over the upper
hemisphere concentrated about the lobe's peak (:func:`hemisphere_quadrature`, 2·32² directions; < 2·10⁻⁴
relative error against 4·10⁶-point lattices except for the sharpest lobes at grazing views). It gives the
magnitude A = ∫ f cos dω (BRDF sampling on a fixed grid was 1–2.5 % off: the horizon cuts the integrand in
the sampler's unit square) and the reported per-cell error, the **L1 distance** ∫ |D − p| dω between the
normalised lobe and the LTC (∈ [0, 2]; twice the fraction of the lobe's energy the LTC puts in the wrong
place, its mass below the horizon included), computed as 2 − 2∫min(D, p). The best L1 an LTC reaches on a Gaussian lobe
(Phong, Beckmann, Ward at small α: a rotationally symmetric Gaussian against the best-scaled LTC) is 0.359;
the fitted tables reach a median of 0.364 there (α < 0.02, θ ≤ 60°) — the LTC's shape, not the
optimiser, limits those families.

Tables
------
A table is a grid over the view angle (axis u = sqrt(1 − cosθ), ``n_theta`` entries, u_i = i/(n − 1); the
last row is fitted at cosθ = ``COS_THETA_MIN``) and, for a family of BRDFs, a roughness axis
r = (sqrt α − sqrt α_min)/(1 − sqrt α_min), α ∈ [``ALPHA_MIN``, 1] (``n_rough`` entries; one for a single
material). Phong and Blinn-Phong lobes use the equivalent roughness α = sqrt(2/(e + 2)) (Walter et al. 2007's
e = 2/α² − 2). :func:`lookup_coordinates` maps (cosθ, r) to texture coordinates; ``ltc.glsl`` mirrors it and
tests/arealights/test_ltc.py checks that they agree.

File format (``.npz``, written by :meth:`LtcTable.save`):

- ``minv`` float32 (n_rough, n_theta, 4): (m02, m11, m20, m22) of a'·M⁻¹ = [[1, 0, −b], [0, a'/c, 0], [−d, 0, a]]
  (m00 = 1 and the zero entries are implied);
- ``magnitude`` float32 (n_rough, n_theta, 3): ∫ f cos dω per RGB channel;
- ``error`` float32 (n_rough, n_theta): the L1 fit error of each cell (above);
- ``power_weight`` float32 (n_rough, n_theta): the mixture weight β of each cell (0 with the clamped cosine;
  format version 2 — version 1 files, without it, are read as clamped-cosine tables);
- ``cos_theta`` float64 (n_theta,), ``alpha`` float64 (n_rough,): the axes' values;
- ``meta``: a JSON string — format version, brdf type and parameters, table size, axis mappings,
  ``base_power`` (1: the clamped cosine), objective, sample counts, fit time, error summary.
"""

from __future__ import annotations

import json
import math
import time
from dataclasses import dataclass, field, replace
from pathlib import Path

import numpy as np

from ..brdf import MATERIALS, Material
from ..errors import ArgumentError
from ..resources import check, largest_fitting

FORMAT_VERSION = 2
#: versions :meth:`LtcTable.load` reads (version 1: the clamped cosine only, no ``power_weight``)
READABLE_VERSIONS = (1, 2)
#: the largest cosine power of a mixture base (the shader unrolls (n − 1)/2 recurrence steps per edge)
MAX_BASE_POWER = 63
#: the mass of the cosⁿ lobe outside its support cone (ltc.glsl's window): the cone is z ≥ SUPPORT_MASS^(1/(n+1))
SUPPORT_MASS = 1e-4
#: a mixture fit whose weights β all stay below this is replaced by the clamped-cosine fit (one-material tables)
MIN_POWER_WEIGHT = 0.01
#: name of the view-angle axis mapping (``ltc.glsl`` implements this one)
THETA_MAPPING = "sqrt(1-cos(theta))"
#: name of the roughness axis mapping
ROUGHNESS_MAPPING = "(sqrt(alpha)-sqrt(alpha_min))/(1-sqrt(alpha_min))"
#: roughness range of the family tables (α of microfacet and Ward models; the equivalent α of Phong lobes)
ALPHA_MIN = 1e-3
#: the grazing row of a table is fitted at this cosθ (a view exactly at the horizon sees no lobe)
COS_THETA_MIN = 1e-2
#: weights of the luminance the lobe's shape is fitted to (Rec. 709)
LUMINANCE = np.array([0.2126, 0.7152, 0.0722])
DEFAULT_SIZE = 64
DEFAULT_INSTANCE_SIZE = 32


# ------------------------------------------------------------------------------ parameterisation (one place)


def theta_coordinate(cos_theta) -> np.ndarray:
    """View-angle axis coordinate u = sqrt(1 − cosθ) ∈ [0, 1] (cosθ clamped to [0, 1])."""
    return np.sqrt(1.0 - np.clip(np.asarray(cos_theta, dtype=np.float64), 0.0, 1.0))


def cos_theta_of(u) -> np.ndarray:
    """Inverse of :func:`theta_coordinate`."""
    u = np.asarray(u, dtype=np.float64)
    return 1.0 - u * u


def roughness_coordinate(alpha, alpha_min: float = ALPHA_MIN) -> np.ndarray:
    """Roughness axis coordinate r ∈ [0, 1] of α (clamped to [alpha_min, 1]); a table's alpha_min is in its
    metadata."""
    s = np.sqrt(np.clip(np.asarray(alpha, dtype=np.float64), alpha_min, 1.0))
    return (s - math.sqrt(alpha_min)) / (1.0 - math.sqrt(alpha_min))


def alpha_of(r, alpha_min: float = ALPHA_MIN) -> np.ndarray:
    """Inverse of :func:`roughness_coordinate`."""
    s = math.sqrt(alpha_min) + np.asarray(r, dtype=np.float64) * (1.0 - math.sqrt(alpha_min))
    return np.clip(s * s, alpha_min, 1.0)


def lookup_coordinates(cos_theta, r, size: tuple[int, int]) -> np.ndarray:
    """Texture coordinates (s, t) ∈ (0, 1)² of a view angle and roughness coordinate in a table of
    ``size`` = (n_theta, n_rough): entry i of an axis of n entries sits at the texel centre (i + ½)/n, so
    bilinear filtering interpolates linearly between the fitted cells. Mirrored by ``ltc_lookup`` in ltc.glsl.
    """
    n_theta, n_rough = size
    u = theta_coordinate(cos_theta)
    u, r = np.broadcast_arrays(u, np.clip(np.asarray(r, dtype=np.float64), 0.0, 1.0))
    return np.stack([(u * (n_theta - 1) + 0.5) / n_theta, (r * (n_rough - 1) + 0.5) / n_rough], axis=-1)


def phong_alpha(exponent) -> np.ndarray:
    """Equivalent roughness of a Phong / Blinn-Phong exponent, α = sqrt(2/(e + 2))."""
    return np.sqrt(2.0 / (np.asarray(exponent, dtype=np.float64) + 2.0))


def phong_exponent(alpha) -> np.ndarray:
    """Inverse of :func:`phong_alpha`: e = 2/α² − 2."""
    a = np.asarray(alpha, dtype=np.float64)
    return 2.0 / (a * a) - 2.0


# ------------------------------------------------------------------------------ families (2-D tables)


@dataclass(frozen=True)
class Family:
    """A BRDF family tabulated over roughness: the material at α, and the α of a member."""

    name: str
    material_type: str
    #: parameters that make the member (besides the roughness one) — the table is fitted with exactly these
    fixed: dict
    #: the parameter carrying the roughness ("alpha", or "exponent" through phong_alpha)
    roughness_parameter: str
    #: smallest α of the table (Phong lobes: the equivalent α of the largest exponent a model accepts, 10⁶)
    alpha_min: float = ALPHA_MIN

    def material(self, alpha: float, params: dict | None = None) -> Material:
        value = min(float(phong_exponent(alpha)), 1e6) if self.roughness_parameter == "exponent" else float(alpha)
        return MATERIALS[self.material_type](**{**self.fixed, **(params or {}), self.roughness_parameter: value})

    def alpha(self, material) -> float:
        """α of a member (the geometric mean sqrt(α_x α_y) for an anisotropic one)."""
        if self.roughness_parameter == "exponent":
            return float(phong_alpha(material.exponent))
        return float(np.sqrt(np.prod(material.alpha_xy)))


_PHONG = {"normalized": True, "kd": (0, 0, 0), "ks": (1, 1, 1)}
FAMILIES: dict[str, Family] = {
    "ggx": Family("ggx", "microfacet", {"distribution": "ggx", "fresnel": "none"}, "alpha"),
    "beckmann": Family("beckmann", "microfacet", {"distribution": "beckmann", "fresnel": "none"}, "alpha"),
    "phong": Family("phong", "phong", _PHONG, "exponent"),
    "blinn_phong": Family("blinn_phong", "blinn_phong", _PHONG, "exponent"),
    "ward": Family("ward", "ward", {"variant": "duer", "kd": (0, 0, 0), "ks": (1, 1, 1)}, "alpha"),
}


# ------------------------------------------------------------------------------ LTC math


def params_to_minv(p: np.ndarray) -> np.ndarray:
    """The stored form (m02, m11, m20, m22) of a'·M⁻¹ = [[1, 0, −b], [0, a'/c, 0], [−d, 0, a' + b d]], for
    M = [[a, 0, b], [0, c, 0], [d, 0, 1]] with optimisation parameters (log a', log c, b, d), a = a' + b d."""
    p = np.asarray(p, dtype=np.float64)
    ap, c, b, d = np.exp(p[..., 0]), np.exp(p[..., 1]), p[..., 2], p[..., 3]
    return np.stack([-b, ap / c, -d, ap + b * d], axis=-1)


def minv_matrix(minv: np.ndarray) -> np.ndarray:
    """3×3 matrices (a multiple of M⁻¹) from stored (m02, m11, m20, m22) entries."""
    minv = np.asarray(minv, dtype=np.float64)
    m = np.zeros(minv.shape[:-1] + (3, 3))
    m[..., 0, 0] = 1.0
    m[..., 0, 2], m[..., 1, 1], m[..., 2, 0], m[..., 2, 2] = minv[..., 0], minv[..., 1], minv[..., 2], minv[..., 3]
    return m


def sigmoid(q) -> np.ndarray:
    """The weight of the cosine power in a mixture, β = 1/(1 + e^−q) ∈ (0, 1), from the fit's free parameter q."""
    return 1.0 / (1.0 + np.exp(-np.asarray(q, dtype=np.float64)))


def ltc_density(minv: np.ndarray, w: np.ndarray, base_power: int = 1, weight=0.0) -> np.ndarray:
    """D(ω) for stored inverse entries ``minv`` (..., 4) at unit directions ``w`` (..., 3), broadcasting; with
    ``base_power`` n > 1 the base is the mixture (1 − β) clamped cosine + β cosⁿ, β = ``weight``."""
    minv = np.asarray(minv, dtype=np.float64)
    m02, m11, m20, m22 = (minv[..., k] for k in range(4))
    vx = w[..., 0] + m02 * w[..., 2]
    vy = m11 * w[..., 1]
    vz = m20 * w[..., 0] + m22 * w[..., 2]
    return _mixture(m11 * (m22 - m02 * m20), vx * vx + vy * vy + vz * vz, vz, base_power, weight)


def _mixture(det, len2, vz, base_power: int, weight):
    """det(M⁻¹) · D_o(v/|v|) / |v|³ for v = M⁻¹ω: the clamped cosine z/π, or with ``base_power`` n > 1 the
    mixture (1 − β) z/π + β (n + 1)/(2π) zⁿ (both densities on the hemisphere; β = ``weight``)."""
    cosine = det * np.maximum(vz, 0.0) / (np.pi * len2 * len2)
    if base_power == 1:
        return cosine
    z = np.maximum(vz, 0.0) / np.sqrt(len2)
    power = det * (0.5 * (base_power + 1) / np.pi) * z**base_power / (len2 * np.sqrt(len2))
    return cosine + weight * (power - cosine)


def _density(p: np.ndarray, wx: np.ndarray, wy: np.ndarray, wz: np.ndarray, base_power: int = 1) -> np.ndarray:
    """D for parameters p (B, K, 4 or 5) at directions with components wx, wy, wz (B, S) → (B, K, S); the fifth
    parameter, with ``base_power`` > 1, is the mixture weight's logit q."""
    ap, c = np.exp(p[..., 0])[..., None], np.exp(p[..., 1])[..., None]
    b, d = p[..., 2][..., None], p[..., 3][..., None]
    wx, wy, wz = wx[:, None], wy[:, None], wz[:, None]
    vx = wx - b * wz
    vy = (ap / c) * wy
    vz = (ap + b * d) * wz - d * wx
    len2 = vx * vx + vy * vy + vz * vz
    if base_power == 1:
        return ((ap * ap / (np.pi * c)) * np.maximum(vz, 0.0)) / (len2 * len2)
    return _mixture(ap * ap / c, len2, vz, base_power, sigmoid(p[..., 4])[..., None])


def _density_from_params(p: np.ndarray, w: np.ndarray, base_power: int = 1) -> np.ndarray:
    """D for parameters p (B, K, 4 or 5) at directions w (B, S, 3) → (B, K, S)."""
    return _density(p, w[..., 0], w[..., 1], w[..., 2], base_power)


# ------------------------------------------------------------------------------ the edge integral's θ/sinθ

#: θ/sinθ as a function of x = cosθ on [0, 1]: (p0 + p1 x + p2 x²)/(1 + q1 x + q2 x²), fitted by
#: :func:`fit_theta_over_sin` (max relative error 5.7e-7); ltc.glsl receives them as defines. For x < 0,
#: θ(x) = π − θ(−x) gives θ/sinθ = π/sqrt(1 − x²) − (θ/sinθ)(−x).
EDGE_P = (1.57079544, 0.90580527, 0.02603201)
EDGE_Q = (1.21323352, 0.2893978)


def theta_over_sin(x) -> np.ndarray:
    """The rational approximation of acos(x)/sqrt(1 − x²) used by ltc.glsl (NumPy twin, any x in [−1, 1))."""
    x = np.asarray(x, dtype=np.float64)
    y = np.abs(x)
    r = (EDGE_P[0] + y * (EDGE_P[1] + y * EDGE_P[2])) / (1.0 + y * (EDGE_Q[0] + y * EDGE_Q[1]))
    return np.where(x >= 0.0, r, np.pi / np.sqrt(np.maximum(1.0 - x * x, 1e-7)) - r)


def support_cut(base_power: int) -> float:
    """cos of the cone about the base's axis holding all but SUPPORT_MASS of the cosⁿ lobe:
    ∫_{z < t} (n + 1)/(2π) zⁿ dω = t^(n+1). 0 for the clamped cosine (no cut)."""
    return 0.0 if base_power == 1 else float(SUPPORT_MASS ** (1.0 / (base_power + 1)))


def power_edge_sum(a: np.ndarray, b: np.ndarray, base_power: int) -> tuple[float, float]:
    """(Σ_{k = 2, 4, …, n − 1} J_k, highest z) of the arc a → b (unit vectors, float64): J_k = ∫ h(s)^k ds along
    the arc, h = its z coordinate, by the recurrence J_k = ((k − 1) C² J_{k−2} − [h^{k−1} h']_a^b)/k, J_0 = θ
    (ltc.glsl's ``ltc_power_sum``; the edge's cosⁿ term is its clamped-cosine term × (1 + the sum / θ))."""
    c = np.cross(a, b)
    sin_theta = float(np.linalg.norm(c))
    if sin_theta < 1e-15:
        return 0.0, max(a[2], b[2])
    cos_theta = float(a @ b)
    j = math.atan2(sin_theta, cos_theta)
    slope_a = (b[2] - cos_theta * a[2]) / sin_theta  # h'(0), h'(θ): the arc's z slope at its ends
    slope_b = (b[2] * cos_theta - a[2]) / sin_theta
    c2 = a[2] * a[2] + slope_a * slope_a
    top = math.sqrt(c2) if slope_a > 0.0 and slope_b < 0.0 else max(a[2], b[2])
    total = 0.0
    for k in range(2, base_power, 2):
        j = ((k - 1) * c2 * j - (b[2] ** (k - 1) * slope_b - a[2] ** (k - 1) * slope_a)) / k
        total += j
    return total, top


def polygon_integral(vertices: np.ndarray, base_power: int = 1, weight: float = 0.0) -> float:
    """∫ D_o dω over a polygon (vertices (m, 3), not necessarily unit) clipped to z ≥ 0, D_o the clamped cosine
    z/π or the mixture (1 − β) z/π + β W (n + 1)/(2π) zⁿ (β = ``weight``, W the support window): the float64
    twin of ``ltc_polygon_integral`` in ltc.glsl (Sutherland–Hodgman clipping, exact angles).

    For odd n Arvo's (1995) recurrence of the axial moments ∫_P zᵏ collapses to (n + 1)/(2π) ∫_P zⁿ =
    (1/2π) Σ_edges Γ_z Σ_{k even < n} J_k, Γ_z the z component of the edge plane's unit normal. W is 0 when the
    polygon lies wholly outside the cone z ≥ :func:`support_cut` (no point of it above the cut, the pole
    outside), else 1."""
    clipped = []
    for k in range(len(vertices)):
        a, b = vertices[k], vertices[(k + 1) % len(vertices)]
        if a[2] >= 0:
            clipped.append(a)
        if (a[2] >= 0) != (b[2] >= 0):
            clipped.append(a + (b - a) * (a[2] / (a[2] - b[2])))
    if len(clipped) < 3:
        return 0.0
    u = np.array(clipped, dtype=np.float64)
    u /= np.linalg.norm(u, axis=1, keepdims=True)
    cosine, excess, top, normals_z = 0.0, 0.0, 0.0, []
    for k in range(len(u)):
        a, b = u[k], u[(k + 1) % len(u)]
        c = np.cross(a, b)
        sin_theta = float(np.linalg.norm(c))
        if sin_theta > 1e-15:
            cosine += math.atan2(sin_theta, float(a @ b)) * c[2] / sin_theta
            normals_z.append(c[2])
        if base_power > 1:
            extra, arc_top = power_edge_sum(a, b, base_power)
            excess += extra * c[2] / max(sin_theta, 1e-15)
            top = max(top, arc_top)
    if base_power == 1 or weight == 0.0:
        return abs(cosine) / (2.0 * np.pi)
    pole_inside = min(normals_z) >= 0.0 or max(normals_z) <= 0.0
    window = weight if pole_inside or top >= support_cut(base_power) else 0.0
    return abs((1.0 - weight) * cosine + window * (cosine + excess)) / (2.0 * np.pi)


def fit_theta_over_sin(samples: int = 20001, rounds: int = 60) -> tuple[np.ndarray, np.ndarray, float]:
    """Fit (EDGE_P, EDGE_Q): least squares on the relative error over x ∈ [0, 1], then Lawson-style
    reweighting towards the minimax solution. Returns (p, q, max relative error)."""
    from scipy.optimize import least_squares

    x = np.linspace(0.0, 1.0, samples)
    target = np.ones_like(x)
    inner = x < 1.0
    target[inner] = np.arccos(x[inner]) / np.sqrt(1.0 - x[inner] ** 2)

    def rel(c):
        return (c[0] + x * (c[1] + x * c[2])) / (1.0 + x * (c[3] + x * c[4])) / target - 1.0

    c = least_squares(rel, np.array([np.pi / 2, 0.0, 0.0, 0.0, 0.0])).x
    weight = np.ones_like(x)
    for _ in range(rounds):
        c = least_squares(lambda c, weight=weight: weight * rel(c), c).x
        e = np.abs(rel(c))
        weight = weight * (e / e.max()) ** 0.3 + 1e-3
        weight /= weight.mean()
    return c[:3], c[3:], float(np.max(np.abs(rel(c))))


def glsl_defines(
    size: tuple[int, int],
    diffuse: bool = True,
    lobe: bool = True,
    uniform_lights: int = 0,
    vertices: int = 0,
    base_power: int = 1,
) -> dict[str, str | int]:
    """The ``#define``s ltc.glsl needs: the table's ``size`` = (n_theta, n_rough), the edge-integral
    coefficients, whether the material has a Lambertian term and a fitted lobe, the capacity of the uniform
    copy of the light records (0: read the light buffer), the vertex count shared by every polygon light
    (0: read each light's) and the table's base power."""
    return {
        "LTC_POWER": _check_base_power(base_power),
        "LTC_CUT": f"{support_cut(base_power):.8g}",
        "LTC_SIZE_THETA": int(size[0]),
        "LTC_SIZE_ROUGH": int(size[1]),
        "LTC_EDGE_P": "vec3({:.8g}, {:.8g}, {:.8g})".format(*EDGE_P),
        "LTC_EDGE_Q": "vec2({:.8g}, {:.8g})".format(*EDGE_Q),
        "LTC_DIFFUSE": int(diffuse),
        "LTC_LOBE": int(lobe),
        "LTC_UNIFORM_LIGHTS": int(uniform_lights),
        "LTC_VERTICES": int(vertices),
    }


# ------------------------------------------------------------------------------ direction sets


def _stratified(k: int, shift: tuple[float, float]) -> tuple[np.ndarray, np.ndarray]:
    t = (np.arange(k) + 0.5) / k
    u1, u2 = np.meshgrid(t, t, indexing="ij")
    u1 = (u1.ravel() + shift[0] / k) % 1.0
    u2 = (u2.ravel() + shift[1] / k) % 1.0
    return np.minimum(u1, np.nextafter(1.0, 0.0)), u2


def _fibonacci_sphere(n: int, shift: float) -> np.ndarray:
    i = np.arange(n) + 0.5
    z = 1.0 - 2.0 * ((i / n + shift / n) % 1.0)
    phi = i * np.pi * (3.0 - math.sqrt(5.0)) + 2.0 * np.pi * shift
    r = np.sqrt(np.maximum(0.0, 1.0 - z * z))
    return np.stack([r * np.cos(phi), r * np.sin(phi), z], axis=-1)


@dataclass
class _Cells:
    """Fixed directions of a batch of cells: w (B, S, 3), weights (B, S), normalised target p (B, S),
    BRDF-sampling magnitude (B, 3), luminance albedo (B,), and the tangent of the lobe's mean direction in the
    xz plane (B,)."""

    w: np.ndarray
    weight: np.ndarray
    p: np.ndarray
    magnitude: np.ndarray
    albedo: np.ndarray
    mean_tan: np.ndarray


def _brdf_samples(material: Material, wo: np.ndarray, k: int, shift: float):
    u1, u2 = _stratified(k, (shift, 0.61803398875 * shift))
    wo_b = np.broadcast_to(wo, (k * k, 3))
    with np.errstate(all="ignore"):
        wi, pdf = material.sample(wo_b, u1, u2)
        f = np.nan_to_num(material.eval(wo_b, wi), nan=0.0, posinf=0.0)
    failed = ~(pdf > 0) | ~np.all(np.isfinite(wi), axis=-1)
    wi = np.where(failed[:, None], [0.0, 0.0, -1.0], wi)
    fcos = np.where(failed[:, None], 0.0, f * np.maximum(wi[:, 2], 0.0)[:, None])
    # the BRDF-sampling estimate of ∫ f cos (midpoint rule in the sampler's unit square)
    magnitude = np.sum(fcos / np.where(failed, 1.0, pdf)[:, None], axis=0) / (k * k)
    return wi, failed, fcos, magnitude


def _wo(cos_theta: float) -> np.ndarray:
    return np.array([math.sqrt(max(0.0, 1.0 - cos_theta * cos_theta)), 0.0, cos_theta])


def _cell_directions(material: Material, cos_theta: float, k: int, n_uniform: int, shift: float):
    wo = _wo(cos_theta)
    wi_b, failed, fcos_b, magnitude = _brdf_samples(material, wo, k, shift)
    wi_u = _fibonacci_sphere(n_uniform, shift)
    w = np.concatenate([wi_b, wi_u])
    wo_all = np.broadcast_to(wo, w.shape)
    with np.errstate(all="ignore"):
        pdf = np.nan_to_num(material.pdf(wo_all, w), nan=0.0, posinf=0.0)
        f_u = np.nan_to_num(material.eval(wo_all[: len(wi_u)], wi_u), nan=0.0, posinf=0.0)
    fcos = np.concatenate([fcos_b, f_u * np.maximum(wi_u[:, 2], 0.0)[:, None]])
    # power heuristic (β = 2): weight N_s p_s / ((N_b p_b)² + (N_u p_u)²) for a direction of strategy s
    nb_pb, nu_pu = k * k * pdf, np.full(len(w), n_uniform / (4.0 * np.pi))
    weight = np.concatenate([nb_pb[: k * k], nu_pu[k * k :]]) / (nb_pb * nb_pb + nu_pu * nu_pu)
    weight[: k * k][failed] = 0.0
    return w, weight, fcos, magnitude


def _cells(materials: list[Material], cos_theta: float, k: int, n_uniform: int, shift: float) -> _Cells:
    out = [_cell_directions(m, cos_theta, k, n_uniform, shift) for m in materials]
    w, weight, fcos, magnitude = (np.stack(a) for a in zip(*out, strict=True))
    lum = fcos @ LUMINANCE
    albedo = np.einsum("bs,bs->b", weight, lum)
    p = lum / np.where(albedo > 0, albedo, 1.0)[:, None]
    mean = np.einsum("bs,bs,bsk->bk", weight, p, w)
    mean_tan = np.clip(mean[:, 0] / np.maximum(mean[:, 2], 1e-3), -1e3, 1e3)
    return _Cells(w, weight, p, magnitude, albedo, mean_tan)


def _lobe_axis_and_width(cells: _Cells) -> tuple[np.ndarray, np.ndarray]:
    """The lobe's peak direction (B, 3) (the fit direction of largest density, moved into the xz plane, the
    plane of symmetry) and the weighted median angle to it (B,). The peak, not the mean direction: at grazing
    views the mean is pulled far from a peak that hugs the horizon."""
    peak = cells.w[np.arange(len(cells.w)), np.argmax(cells.p, axis=1)]
    axis = np.stack([peak[:, 0], np.zeros(len(peak)), np.maximum(peak[:, 2], 1e-4)], axis=-1)
    axis /= np.linalg.norm(axis, axis=-1, keepdims=True)
    angle = np.arccos(np.clip(np.einsum("bsk,bk->bs", cells.w, axis), -1.0, 1.0))
    mass = cells.weight * cells.p
    order = np.argsort(angle, axis=1)
    cdf = np.cumsum(np.take_along_axis(mass, order, axis=1), axis=1)
    half = np.argmax(cdf >= 0.5 * cdf[:, -1:], axis=1)
    width = np.take_along_axis(np.take_along_axis(angle, order, axis=1), half[:, None], axis=1)[:, 0]
    return axis, np.clip(width, 1e-4, 1.0)


def hemisphere_quadrature(axis: np.ndarray, width: np.ndarray, n: int):
    """Directions (B, N, 3) and weights (B, N), N = 2n², of a quadrature over the upper hemisphere for lobes
    symmetric about the xz plane, peaked at ``axis`` (B, 3) (unit, in the xz plane) with angular width
    ``width`` (B,).

    Spherical coordinates about the y axis, ω = (cosφ sinψ, cosψ, sinφ sinψ): the hemisphere z > 0 is the
    rectangle φ ∈ (0, π), ψ ∈ (0, π) — the horizon is φ = 0 and φ = π whatever the lobe, so a peak hugging the
    horizon at a grazing view is no harder than any other — and the lobe peaks at (φ_p, π/2). Each side of
    φ_p is mapped as φ = φ_p ± s·tan(t·atan(span/s)), t ∈ (0, 1) with n Gauss–Legendre nodes, and ψ from π/2
    to the pole likewise (the y < 0 half by symmetry): nodes concentrate within the width s of the peak and
    still reach the horizon, where the integrand (∝ cosθ) vanishes. Against 4·10⁶-point spherical lattices,
    n = 32: < 2·10⁻⁴ relative on the albedo of GGX, Beckmann, Phong and Ward lobes for α ∈ [0.02, 1] and
    cosθ ≥ 0.03; ≤ 2 % for the sharpest lobes at cosθ ≤ 0.01, where the lattice itself is unreliable.
    """
    t, wt = np.polynomial.legendre.leggauss(n)
    t, wt = 0.5 * (t + 1.0), 0.5 * wt
    s = width[:, None]
    phi_p = np.arctan2(axis[:, 2], axis[:, 0])[:, None]
    span_lo, span_hi = np.arctan(phi_p / s), np.arctan((np.pi - phi_p) / s)
    a_lo, a_hi = t * span_lo, t * span_hi
    phi = np.concatenate([phi_p - s * np.tan(a_lo), phi_p + s * np.tan(a_hi)], axis=1)
    w_phi = np.concatenate([wt * s * span_lo / np.cos(a_lo) ** 2, wt * s * span_hi / np.cos(a_hi) ** 2], axis=1)
    span = np.arctan(0.5 * np.pi / s)
    b = t * span
    psi = 0.5 * np.pi - s * np.tan(b)
    w_psi = 2.0 * wt * s * span / np.cos(b) ** 2  # × 2: the half y < 0, by symmetry
    p, q = phi[:, :, None], psi[:, None, :]
    w = np.stack([np.cos(p) * np.sin(q), np.cos(q) * np.ones_like(p), np.sin(p) * np.sin(q)], axis=-1)
    weight = w_phi[:, :, None] * w_psi[:, None, :] * np.sin(q)
    return w.reshape(len(axis), -1, 3), weight.reshape(len(axis), -1)


def _check(materials: list[Material], cos_theta: float, axis, width, params, n: int, base_power: int = 1):
    """Magnitude (B, 3) and L1 error (B,) of fitted cells by :func:`hemisphere_quadrature`. The error is
    computed as ∫|D − p| = ∫D + ∫p − 2∫min(D, p) = 2 − 2∫min(D, p) (both integrate to 1: D exactly, p by its
    normalisation on the same nodes), which needs the quadrature to be accurate only where the lobe is — an
    LTC's mass elsewhere, including below the horizon, counts as error without being integrated."""
    wo = _wo(cos_theta)
    w, weight = hemisphere_quadrature(axis, width, n)
    fcos = (
        np.stack(
            [
                np.nan_to_num(m.eval(np.broadcast_to(wo, wb.shape), wb), nan=0.0)
                for m, wb in zip(materials, w, strict=True)
            ]
        )
        * w[..., 2:3]
    )
    magnitude = np.einsum("bs,bsc->bc", weight, fcos)
    lum = magnitude @ LUMINANCE
    p = (fcos @ LUMINANCE) / np.where(lum > 0, lum, 1.0)[:, None]
    d = _density_from_params(params[:, None, :], w, base_power)[:, 0]
    error = 2.0 - 2.0 * np.einsum("bs,bs->b", weight, np.minimum(d, p))
    return magnitude, np.where(lum > 0, np.clip(error, 0.0, 2.0), 0.0)


# ------------------------------------------------------------------------------ vectorised Nelder–Mead


def nelder_mead(fun, x0: np.ndarray, step: np.ndarray, max_iter: int = 300, ftol: float = 1e-6):
    """Minimise B independent functions at once. ``fun(x, cells)`` maps points x (len(cells), K, n) of the
    cells with indices ``cells`` to values (len(cells), K); ``x0`` (B, n) starts, ``step`` (B, n) the initial
    simplex edges. Standard coefficients (reflection 1, expansion 2, contraction ½, shrink ½). A cell stops
    when its simplex values agree to a relative ``ftol`` (then it is no longer evaluated).
    Returns (x (B, n), f (B,), iterations of the slowest cell)."""
    x0 = np.asarray(x0, dtype=np.float64)
    b, n = x0.shape
    simplex = np.repeat(x0[:, None, :], n + 1, axis=1)
    simplex[:, 1:, :] += np.asarray(step)[:, None, :] * np.eye(n)[None]
    values = fun(simplex, np.arange(b))
    done = np.zeros(b, dtype=bool)
    it = 0
    for it in range(1, max_iter + 1):  # noqa: B007
        order = np.argsort(values, axis=1)
        simplex = np.take_along_axis(simplex, order[..., None], axis=1)
        values = np.take_along_axis(values, order, axis=1)
        done |= values[:, -1] - values[:, 0] <= ftol * np.abs(values[:, 0]) + 1e-300
        act = np.flatnonzero(~done)
        if len(act) == 0:
            break
        sim, val = simplex[act], values[act]
        worst = sim[:, -1]
        centroid = sim[:, :-1].mean(axis=1)
        xr = 2.0 * centroid - worst
        fr = fun(xr[:, None], act)[:, 0]
        expand = fr < val[:, 0]
        accept_r = (fr >= val[:, 0]) & (fr < val[:, -2])
        outside = (fr >= val[:, -2]) & (fr < val[:, -1])
        # second candidate: expansion, outside or inside contraction
        coef = np.where(expand, 2.0, np.where(outside, 0.5, -0.5))
        x2 = centroid + coef[:, None] * (centroid - worst)
        f2 = fun(x2[:, None], act)[:, 0]
        new_x, new_f = worst.copy(), val[:, -1].copy()
        take_e = expand & (f2 < fr)
        take_r = (expand & ~take_e) | accept_r
        take_c = (outside & (f2 <= fr)) | (~expand & ~accept_r & ~outside & (f2 < val[:, -1]))
        new_x[take_r], new_f[take_r] = xr[take_r], fr[take_r]
        new_x[take_e], new_f[take_e] = x2[take_e], f2[take_e]
        new_x[take_c], new_f[take_c] = x2[take_c], f2[take_c]
        sim[:, -1], val[:, -1] = new_x, new_f
        shrink = ~(take_r | take_e | take_c)
        if np.any(shrink):
            rows = act[shrink]
            shrunk = sim[shrink, :1] + 0.5 * (sim[shrink, 1:] - sim[shrink, :1])
            sim[shrink, 1:] = shrunk
            val[shrink, 1:] = fun(shrunk, rows)
        simplex[act], values[act] = sim, val
    i = np.argmin(values, axis=1)
    rows = np.arange(b)
    return simplex[rows, i], values[rows, i], it


# ------------------------------------------------------------------------------ the fitter


@dataclass
class LtcTable:
    """A fitted LTC table (see the module docstring for the arrays and the file format)."""

    minv: np.ndarray
    magnitude: np.ndarray
    error: np.ndarray
    cos_theta: np.ndarray
    alpha: np.ndarray
    meta: dict = field(default_factory=dict)
    #: the mixture weight β of each cell (zeros for a clamped-cosine table)
    power_weight: np.ndarray | None = None

    def __post_init__(self):
        # float32 as in the file and on the GPU, so a table in memory equals the one read back from disk
        self.minv = np.asarray(self.minv, dtype=np.float32)
        self.magnitude = np.asarray(self.magnitude, dtype=np.float32)
        self.error = np.asarray(self.error, dtype=np.float32)
        if self.power_weight is None:
            self.power_weight = np.zeros(self.error.shape)
        self.power_weight = np.asarray(self.power_weight, dtype=np.float32)

    @property
    def base_power(self) -> int:
        """n of the base distribution (1: the clamped cosine; n > 1: the mixture with cosⁿ)."""
        return int(self.meta.get("base_power", 1))

    @property
    def size(self) -> tuple[int, int]:
        """(n_theta, n_rough): the texture's width and height."""
        return int(self.minv.shape[1]), int(self.minv.shape[0])

    def save(self, path: str | Path) -> None:
        import io

        from ..outputs import atomic_write

        path = Path(path)
        if path.suffix.lower() != ".npz":
            raise ArgumentError(f"an LTC table is written as .npz, got '{path.name}'", field="output")
        path.parent.mkdir(parents=True, exist_ok=True)
        with io.BytesIO() as fh:
            np.savez_compressed(
                fh,
                minv=self.minv,
                magnitude=self.magnitude,
                error=self.error,
                power_weight=self.power_weight,
                cos_theta=self.cos_theta,
                alpha=self.alpha,
                meta=np.array(json.dumps(self.meta)),
            )
            atomic_write(path, fh.getvalue())  # a kill mid-write leaves the table there before, or none

    @classmethod
    def load(cls, path) -> LtcTable:
        """Read a table written by :meth:`save` (a path or a file object); checks the format version."""
        with np.load(path, allow_pickle=False) as data:
            meta = json.loads(str(data["meta"]))
            if meta.get("version") not in READABLE_VERSIONS or meta.get("theta_mapping") != THETA_MAPPING:
                raise ArgumentError(
                    f"LTC table {path}: format {meta.get('version')} / {meta.get('theta_mapping')}, this reflets reads "
                    f"{' or '.join(map(str, READABLE_VERSIONS))} / {THETA_MAPPING}; refit it with `reflets fit-ltc`",
                    field="table",
                )
            table = cls(
                minv=data["minv"],
                magnitude=data["magnitude"],
                error=data["error"],
                cos_theta=data["cos_theta"],
                alpha=data["alpha"],
                meta=meta,
                power_weight=data["power_weight"] if "power_weight" in data.files else None,
            )
        shapes = {table.minv.shape[:2], table.magnitude.shape[:2], table.error.shape, table.power_weight.shape}
        if len(shapes) > 1:
            raise ArgumentError(f"LTC table {path}: inconsistent array shapes", field="table")
        return table


@dataclass
class FitSettings:
    """Direction counts and optimiser limits of a fit (stored in the table's metadata)."""

    k: int = 32  #: k×k BRDF samples per cell for the fit
    n_uniform: int = 512  #: spherical Fibonacci directions per cell for the fit
    n_quadrature: int = 32  #: hemisphere quadrature (magnitude and reported error): 2n² directions
    max_iter: int = 400
    ftol: float = 1e-6
    power: int = 1  #: the objective is Σ w |D − p|^power
    #: the base distribution: 1 the clamped cosine (Heitz et al.), odd n > 1 the mixture (1 − β) cos + β cosⁿ
    base_power: int = 1


#: logits q of the mixture weight β the starting scan tries (β ≈ 0.02 and 0.98)
_START_LOGITS = (-4.0, 4.0)


def _isotropic_start(objective, idx: np.ndarray, tilt: np.ndarray, base_power: int = 1) -> np.ndarray:
    """Starting points (len(idx), 4; 5 with a mixture): the best of 60 isotropic widths a' = c ∈ [1e-4, 3]
    about the axis (tilt, 0, 1), d = 0 (with a mixture, for each β of ``_START_LOGITS``)."""
    scales = np.linspace(np.log(1e-4), np.log(3.0), 60)
    logits = _START_LOGITS if base_power > 1 else (0.0,)
    grid = np.zeros((len(idx), len(scales) * len(logits), 4 if base_power == 1 else 5))
    grid[..., 0] = grid[..., 1] = np.tile(scales, len(logits))
    grid[..., 2] = tilt[:, None]
    if base_power > 1:
        grid[..., 4] = np.repeat(logits, len(scales))
    return grid[np.arange(len(idx)), np.argmin(objective(grid, idx), axis=1)]


def _steps(x: np.ndarray) -> np.ndarray:
    """Initial simplex edges: 0.2 in log a' and log c, 0.1 in d, and 0.3 a' in b — the LTC's axis is at
    atan(b) and its width in that plane a'/(1 + b²), so a step of 0.3 a' in b moves the axis by a third of
    the lobe's width, however sharp the lobe and however close to the horizon — and 1 in the mixture's logit."""
    n = len(x)
    steps = [np.full(n, 0.2), np.full(n, 0.2), 0.3 * np.exp(x[:, 0]), np.full(n, 0.1)]
    return np.stack(steps + [np.full(n, 1.0)] * (x.shape[1] - 4), axis=1)


def fit_cells(materials: list[Material], n_theta: int, settings: FitSettings | None = None, progress=None):
    """Fit one row of cells per view angle for each material (a batch of B = len(materials) cells per row).

    Rows run from the normal to grazing views; each starts from the previous row's solution with b shifted
    by the change of the lobe's mean direction, the first from :func:`_isotropic_start`. A cell whose fit
    still misplaces more than 30 % of the lobe (the warm start lost a sharp lobe) is refitted from
    :func:`_isotropic_start` about the lobe's mean direction, keeping the better of the two.

    Returns (minv (B, n_theta, 4), magnitude (B, n_theta, 3), error (B, n_theta), power_weight (B, n_theta):
    the mixture weight β (0 for the clamped cosine), cos_theta (n_theta,), Nelder–Mead iterations)."""
    s = settings or FitSettings()
    n_power = _check_base_power(s.base_power)
    cos_theta = np.maximum(cos_theta_of(np.linspace(0.0, 1.0, n_theta)), COS_THETA_MIN)
    nb = len(materials)
    everything = np.arange(nb)
    minv = np.zeros((nb, n_theta, 4))
    magnitude = np.zeros((nb, n_theta, 3))
    error = np.zeros((nb, n_theta))
    power_weight = np.zeros((nb, n_theta))
    x = None
    previous_tan = None
    iterations = 0
    for i, ct in enumerate(cos_theta):
        cells = _cells(materials, float(ct), s.k, s.n_uniform, shift=0.0)
        live = cells.albedo > 0
        wx, wy, wz = (np.ascontiguousarray(cells.w[..., k]) for k in range(3))

        def objective(p, idx, cells=cells, wx=wx, wy=wy, wz=wz, power=s.power):
            d = _density(p, wx[idx], wy[idx], wz[idx], n_power)
            r = np.abs(d - cells.p[idx, None, :])
            r = r * r * r if power == 3 else r**power
            return np.einsum("bs,bks->bk", cells.weight[idx], r)

        if x is None:
            x = _isotropic_start(objective, everything, np.zeros(nb), n_power)
        else:
            x = x.copy()
            x[:, 2] += cells.mean_tan - previous_tan
        previous_tan = cells.mean_tan
        x_new, f_new, it = nelder_mead(objective, x, _steps(x), s.max_iter, s.ftol)
        iterations += it
        d = _density(x_new[:, None, :], wx, wy, wz, n_power)[:, 0]
        l1 = np.einsum("bs,bs->b", cells.weight, np.abs(d - cells.p))
        lost = np.flatnonzero(live & (l1 > 0.3))
        if len(lost):
            retry = _isotropic_start(objective, lost, cells.mean_tan[lost], n_power)
            x_retry, f_retry, it = nelder_mead(
                lambda p, idx, lost=lost: objective(p, lost[idx]), retry, _steps(retry), s.max_iter, s.ftol
            )
            iterations += it
            better = f_retry < f_new[lost]
            x_new[lost[better]] = x_retry[better]
        x = np.where(live[:, None], x_new, x)
        # magnitude and the reported error by the hemisphere quadrature
        axis, width = _lobe_axis_and_width(cells)
        magnitude[:, i], error[:, i] = _check(materials, float(ct), axis, width, x, s.n_quadrature, n_power)
        minv[:, i] = np.where(live[:, None], params_to_minv(x), [0.0, 1.0, 0.0, 1.0])
        if n_power > 1:
            power_weight[:, i] = np.where(live, sigmoid(x[:, 4]), 0.0)
        if progress is not None:
            progress(i + 1, n_theta)
    return minv, magnitude, error, power_weight, cos_theta, iterations


def _check_base_power(base_power) -> int:
    if not (isinstance(base_power, int) and base_power >= 1 and base_power % 2 == 1 and base_power <= MAX_BASE_POWER):
        raise ArgumentError(
            f"base_power must be an odd integer in [1, {MAX_BASE_POWER}] (the edge integral's recurrence runs over "
            f"the odd powers), got {base_power!r}",
            field="base_power",
        )
    return base_power


def _summary(error: np.ndarray) -> dict:
    return {
        "l1_mean": float(np.mean(error)),
        "l1_median": float(np.median(error)),
        "l1_p95": float(np.percentile(error, 95)),
        "l1_max": float(np.max(error)),
    }


#: bytes a row of fits holds per material and fit direction (k² BRDF samples + n_uniform directions): the
#: directions, weights and densities of every simplex point (measured 4.6 MB per material at the default
#: 32² + 512, size 16, 32 and 64)
FIT_BYTES_PER_DIRECTION = 3200


def fit_bytes(size: int, settings: FitSettings | None = None) -> int:
    """Peak bytes of :func:`fit_family` at ``size`` × ``size`` cells: a row fits all ``size`` roughnesses at once,
    size · (k² + n_uniform) · FIT_BYTES_PER_DIRECTION, plus the tables (size² cells, 12 float64 each)."""
    s = settings or FitSettings()
    return size * (s.k * s.k + s.n_uniform) * FIT_BYTES_PER_DIRECTION + 96 * size * size


def fit_family(name: str, size: int = DEFAULT_SIZE, params: dict | None = None, settings=None, progress=None):
    """2-D table (view angle × roughness) of a family in :data:`FAMILIES`; ``params`` set the family's other
    parameters (e.g. masking = "correlated"); their roughness parameter must not be among them. ``size`` is
    checked against the available memory first (:func:`fit_bytes`)."""
    family = FAMILIES[name]
    params = dict(params or {})
    check(
        "size",
        fit_bytes(size, settings),
        value=size,
        what=f"{size} roughnesses fitted at once per view angle",
        fits=lambda budget: largest_fitting(lambda n: fit_bytes(n, settings), 1, size, budget),
    )
    alpha = alpha_of(np.linspace(0.0, 1.0, size), family.alpha_min)
    materials = [family.material(float(a), params) for a in alpha]
    start = time.perf_counter()
    s = settings or FitSettings()
    minv, magnitude, error, weight, cos_theta, iterations = fit_cells(materials, size, s, progress)
    meta = _meta(name, family.material_type, {**family.fixed, **params}, (size, size), s, start, error, iterations)
    meta["roughness_parameter"] = family.roughness_parameter
    meta["alpha_min"] = family.alpha_min
    return LtcTable(minv, magnitude, error, cos_theta, alpha, meta, weight)


def fit_material(material: Material, n_theta: int = DEFAULT_INSTANCE_SIZE, settings=None, progress=None):
    """1-D table (view angle only) of one material with its exact parameters (with a mixture base that no cell
    uses — β < ``MIN_POWER_WEIGHT`` everywhere — the clamped-cosine fit instead)."""
    start = time.perf_counter()
    s = settings or FitSettings()
    minv, magnitude, error, weight, cos_theta, iterations = fit_cells([material], n_theta, s, progress)
    if s.base_power > 1 and np.max(weight) < MIN_POWER_WEIGHT:
        # no cell uses the cosⁿ lobe (a GGX-like, heavy-tailed lobe): the clamped-cosine fit spares the
        # shader the recurrence
        return fit_material(material, n_theta, replace(s, base_power=1), progress)
    params = material.model_dump(mode="json", exclude={"type"})
    meta = _meta(material.type, material.type, params, (n_theta, 1), s, start, error, iterations)
    return LtcTable(minv, magnitude, error, cos_theta, np.array([np.nan]), meta, weight)


def _meta(brdf, material_type, params, size, s: FitSettings, start, error, iterations) -> dict:
    return {
        "version": FORMAT_VERSION,
        "brdf": brdf,
        "material_type": material_type,
        "params": json.loads(json.dumps(params, default=str)),
        "size": list(size),
        "theta_mapping": THETA_MAPPING,
        "cos_theta_min": COS_THETA_MIN,
        "roughness_mapping": ROUGHNESS_MAPPING if size[1] > 1 else None,
        "alpha_min": ALPHA_MIN,
        "base_power": s.base_power,
        "base": "clamped cosine" if s.base_power == 1 else f"(1 - w) clamped cosine + w cos^{s.base_power}, w per cell",
        "objective": f"L{s.power}: sum over the fit directions of w |D - p|^{s.power}",
        "error_metric": "L1: integral of |D - p| over the sphere = 2 - 2 integral of min(D, p) "
        "(hemisphere_quadrature about the lobe's peak)",
        "magnitude": "integral of f cos per RGB channel, hemisphere_quadrature about the lobe's peak",
        "settings": s.__dict__.copy(),
        "nelder_mead_iterations": int(iterations),
        "fit_seconds": round(time.perf_counter() - start, 2),
        "error_summary": _summary(error),
    }


def fit_ltc(brdf: str, params: dict | None = None, size: int | None = None, settings=None, progress=None) -> LtcTable:
    """Fit the table the ``reflets fit-ltc`` command writes.

    ``brdf`` is a family (ggx, beckmann, phong, blinn_phong, ward) — a 2-D table over roughness unless
    ``params`` fixes the roughness parameter (``alpha`` / ``exponent``), which makes it a single material —
    or any material type (lambert, microfacet, lafortune, ashikhmin_shirley, measured, …), fitted as the one
    material ``params`` describe (a 1-D table over the view angle). ``params["base_power"]`` (odd n, not a
    material parameter) fits the mixture base with cosⁿ.
    """
    params = dict(params or {})
    if "base_power" in params:  # a fitter setting, given like the material's parameters on the command line
        settings = replace(settings or FitSettings(), base_power=_check_base_power(params.pop("base_power")))
    if brdf in FAMILIES:
        family = FAMILIES[brdf]
        if family.roughness_parameter not in params:
            return fit_family(brdf, size or DEFAULT_SIZE, params, settings, progress)
        material = _make(family.material_type, {**family.fixed, **params})
    elif brdf in MATERIALS:
        material = _make(brdf, params)
    else:
        raise ArgumentError(
            f"unknown BRDF '{brdf}'; choose a family ({', '.join(FAMILIES)}) or a material type "
            f"({', '.join(sorted(MATERIALS))})",
            field="--brdf",
        )
    table = fit_material(material, size or DEFAULT_INSTANCE_SIZE, settings, progress)
    table.meta["brdf"] = brdf
    return table


def _make(material_type: str, params: dict) -> Material:
    from pydantic import ValidationError

    try:
        return MATERIALS[material_type](type=material_type, **params)
    except ValidationError as exc:
        first = exc.errors()[0]
        where = ".".join(str(p) for p in first["loc"])
        raise ArgumentError(f"{material_type}: {where}: {first['msg']}", field="--param") from None
