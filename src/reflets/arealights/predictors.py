"""The area-light document's sampling predictors and cone geometry, in NumPy (float64), errata fixed.

Used by the ``adaptive`` and ``biased`` methods (which evaluate the same formulas in GLSL, or receive their
result as uniforms) and by the tests and docs. Equation numbers are those of Meunier 2007.

Grid-step predictors (§2.4.2). A step Δ is a fraction of the light width w (Δ = 1: one sample; Δ = 1/n:
an n×n grid), d the distance from the shaded point to the *nearest* point of the light, in light widths.

- Lambert (2.9): ``Δ = 0.727 d + 0.055`` for d < 1.3, else 1.
- Phong (2.11): the largest usable exponent for a step s at distance d,
  ``e_max(d, s) = 1.6464 (d − 0.0327)^2.1252 / (s − 0.0017)^2.0990``; its inverse (2.12) is
  ``Δ_phong(d, e) = (1.6464 (d − 0.0327)^2.1252 / e)^(1/2.0990) + 0.0017``. **Erratum**: the document prints
  the exponent 0.4761 and "− 0.0017"; the exact inverse of its own fit has 1/2.0990 = 0.47642 and "+ 0.0017"
  (:func:`phong_max_exponent` ∘ :func:`delta_phong` is the identity; the tests check it). d is clamped to
  ≥ 0.0327 (the fit's zero).
- Blinn-Phong (2.13), printed as ``Δ_blinn(d, e) = (2.6419 (d + 0.1364)^2.0780 / e)^2.4589 + 0.0082``.
  The Phong fit has the shape ``Δ = (a (d + b)^c / e)^(1/p) + q``; the printed outer exponent 2.4589 is
  almost certainly the fit's p (the exponent of (s − q) in the forward fit) copied without inverting it.
  With 2.4589 the base (≈ 0.005 for e = 500, d = 1) is raised to a power > 1, so Δ ≈ 0.0082 → the 0.05
  floor for every glossy case (the method degenerates into a 20×20 brute force), while for a base > 1
  (low exponents, far away) Δ explodes past 1 at once. ``BLINN_FITS["inverted"]`` uses 1/2.4589 = 0.40668,
  which gives steps of the same magnitude as Phong's; the choice was measured against the reference (see
  ``adaptive.py``) and ``inverted`` is the default. ``blinn_max_exponent`` is the forward fit implied by it.
- Safety factors (§2.4.2, "Mise en œuvre"): 95 % of Δ_lambert, 90 % of Δ_phong, 50 % of Δ_blinn; floor
  Δ ≥ 0.05 (at most 20×20 samples); quantised to an exact grid Δ → 1/ceil(1/Δ); optional dithering (2.21)
  ``Δ = max(0.05, Δ − 0.1 ξ)`` with ξ uniform in [0, 1).

Nearest point (2.14–2.20): the document projects x onto the light's (u, v) by ``(x − c1)·e / |e|`` and
clamps to [0, 1]². **Erratum**: the coordinate along an edge e is ``(x − c1)·e / |e|²``; the printed
formula is right only for a unit light. Even fixed, clamping (u, v) separately gives the nearest point
only when the edges are orthogonal (a rectangle); for a skewed parallelogram (or any convex polygon)
:func:`nearest_point` projects onto the plane, keeps the projection if it is inside, and otherwise takes
the nearest point of the boundary edges — exact for every convex polygon; this is what the GLSL uses.

Cone of useful directions (§2.5): the half-angle a(e) with
``t ∫_{−π/2}^{π/2} cos^e x dx = ∫_{−a}^{a} cos^e x dx`` (2.22). With s = sin²x the integral is an
incomplete beta function, ``∫_0^a cos^e x dx = ½ B(sin²a; ½, (e + 1)/2)``, so (2.22) reads
``I_{sin²a}(½, (e + 1)/2) = t``; :func:`cone_half_angle` solves it by Brent's method on a (to 1e-13 rad).
The document's fit (2.23) ``a(e) = 1.8026 e^−0.2868 − 0.2162`` (t = 0.99) is :func:`cone_half_angle_fit`;
the report says it is valid for e ∈ [1, ~300]. Measured (``tests/arealights/test_predictors.py``): for
2 ≤ e ≤ 300 it is within 0.07 rad (≤ 9 %) of the exact angle (at e = 1 it exceeds π/2), then too small —
by 17 % at e = 400, 24 % at e = 500, 60 % at e = 1000 — and negative beyond e ≈ 1.63·10³ (an empty cone).

Cone ∩ light plane (§2.5, eq 2.24): a ray from x along the cone axis r hits the plane at distance d with
angle β between r and the plane normal; while β + α < 90° the intersection is an ellipse. In the plane of
incidence it extends from the hit point c by ``d sin α / cos(β + α)`` (far side) and ``d sin α / cos(β − α)``
(near side); its half-width across is ``h sin α / sqrt(cos(β − α) cos(β + α))`` with h = d cos β the height
of x over the plane. The document's square half-width ``L = d sin α / cos β`` (2.24) is smaller than the far
extent (and than the circle d tan α at β = 0): :func:`cone_ellipse` returns both.
"""

from __future__ import annotations

import math
from typing import Literal

import numpy as np

#: safety factors applied to the predicted steps (§2.4.2)
SAFETY = {"lambert": 0.95, "phong": 0.90, "blinn": 0.50}
#: smallest grid step, in light widths (at most 20×20 samples on a square light)
MIN_STEP = 0.05
#: amplitude of the dithering of eq 2.21
DITHER_AMPLITUDE = 0.1
#: Blinn-Phong fit (2.13): outer exponent, "inverted" (1/2.4589, the default) or as printed (2.4589)
BLINN_FITS = {"inverted": 1.0 / 2.4589, "printed": 2.4589}

PHONG_A, PHONG_B, PHONG_C, PHONG_P, PHONG_Q = 1.6464, -0.0327, 2.1252, 2.0990, 0.0017
BLINN_A, BLINN_B, BLINN_C, BLINN_P, BLINN_Q = 2.6419, 0.1364, 2.0780, 2.4589, 0.0082


# ------------------------------------------------------------------------------------------ grid steps
def delta_lambert(d):
    """Eq 2.9: grid step (light widths) for a Lambertian surface at normalised distance d."""
    d = np.asarray(d, dtype=np.float64)
    return np.where(d < 1.3, 0.727 * d + 0.055, 1.0)


def phong_max_exponent(d, s):
    """Eq 2.11: the largest Phong exponent a grid step s renders without visible artefacts at distance d."""
    d = np.maximum(np.asarray(d, dtype=np.float64), -PHONG_B)
    return PHONG_A * (d + PHONG_B) ** PHONG_C / (np.asarray(s, dtype=np.float64) - PHONG_Q) ** PHONG_P


def delta_phong(d, e):
    """Eq 2.12 (corrected: exponent 1/2.0990, + 0.0017): the grid step for a Phong lobe of exponent e."""
    d = np.maximum(np.asarray(d, dtype=np.float64), -PHONG_B)
    e = np.maximum(np.asarray(e, dtype=np.float64), 1e-12)
    return (PHONG_A * (d + PHONG_B) ** PHONG_C / e) ** (1.0 / PHONG_P) + PHONG_Q


def blinn_max_exponent(d, s):
    """The forward Blinn-Phong fit implied by the inverted reading of eq 2.13:
    ``e_max = 2.6419 (d + 0.1364)^2.0780 / (s − 0.0082)^2.4589``."""
    d = np.asarray(d, dtype=np.float64)
    return BLINN_A * (d + BLINN_B) ** BLINN_C / (np.asarray(s, dtype=np.float64) - BLINN_Q) ** BLINN_P


def delta_blinn(d, e, fit: Literal["inverted", "printed"] = "inverted"):
    """Eq 2.13: the grid step for a Blinn-Phong lobe, outer exponent 1/2.4589 (``inverted``) or 2.4589."""
    d = np.maximum(np.asarray(d, dtype=np.float64), 0.0)
    e = np.maximum(np.asarray(e, dtype=np.float64), 1e-12)
    return (BLINN_A * (d + BLINN_B) ** BLINN_C / e) ** BLINN_FITS[fit] + BLINN_Q


def grid_step(
    d,
    kind: int,
    exponent: float,
    diffuse: bool = True,
    safety: dict[str, float] | None = None,
    xi=None,
    min_step: float = MIN_STEP,
    blinn_fit: Literal["inverted", "printed"] = "inverted",
):
    """The quantised step the ``adaptive`` method uses (the GLSL evaluates the same formulas).

    ``kind`` is the material's lobe kind (0 none, 1 Phong, 2 Blinn-Phong, see ``lobe_info``); the step is the
    smallest of the specular predictor and, when the material has a diffuse part (or no lobe), the Lambert
    one, each times its safety factor; then dithered (``xi`` given), clamped to [min_step, 1] and quantised
    to 1/ceil(1/Δ). Returns Δ (the grid is n×n with n = 1/Δ on a square light).
    """
    safety = {**SAFETY, **(safety or {})}
    d = np.asarray(d, dtype=np.float64)
    step = np.full(d.shape, np.inf)
    if diffuse or kind == 0:
        step = np.minimum(step, safety["lambert"] * delta_lambert(d))
    if kind == 1:
        step = np.minimum(step, safety["phong"] * delta_phong(d, exponent))
    elif kind == 2:
        step = np.minimum(step, safety["blinn"] * delta_blinn(d, exponent, blinn_fit))
    if xi is not None:
        step = np.maximum(min_step, step - DITHER_AMPLITUDE * np.asarray(xi, dtype=np.float64))
    step = np.clip(step, min_step, 1.0)
    return 1.0 / grid_count(step)


def grid_count(step):
    """Samples per light width for a step Δ: ceil(1/Δ) (a tolerance absorbs float rounding of 1/(1/n))."""
    return np.ceil(1.0 / np.asarray(step, dtype=np.float64) - 1e-4).astype(np.int64)


# ---------------------------------------------------------------------------------------- nearest point
def nearest_point_document(x, c1, e1, e2, erratum_fixed: bool = True):
    """Eqs 2.14–2.20: project x onto the light's (u, v), clamp to [0, 1]², return the world point.

    ``erratum_fixed`` divides by the squared edge lengths (right for any rectangle); False reproduces the
    printed formula (right only for a unit light). Either way it is exact only for orthogonal edges.
    """
    x, c1, e1, e2 = (np.asarray(a, dtype=np.float64) for a in (x, c1, e1, e2))
    q = x - c1
    p1, p2 = (2, 2) if erratum_fixed else (1, 1)
    u = np.clip(q @ e1 / np.linalg.norm(e1) ** p1, 0.0, 1.0)
    v = np.clip(q @ e2 / np.linalg.norm(e2) ** p2, 0.0, 1.0)
    return c1 + u[..., None] * e1 + v[..., None] * e2


def _segment_nearest(x, a, b):
    ab = b - a
    t = np.clip(np.sum((x - a) * ab, axis=-1) / np.dot(ab, ab), 0.0, 1.0)
    return a + t[..., None] * ab


def nearest_point(x, polygon):
    """Exact nearest point of a planar convex polygon (vertices counter-clockwise around its normal) to
    points x (..., 3): the projection onto the plane when it falls inside, else the nearest boundary point."""
    x = np.asarray(x, dtype=np.float64)
    p = np.asarray(polygon, dtype=np.float64)
    normal = np.sum(np.cross(p, np.roll(p, -1, axis=0)), axis=0)
    normal /= np.linalg.norm(normal)
    proj = x - ((x - p[0]) @ normal)[..., None] * normal
    inside = np.ones(x.shape[:-1], dtype=bool)
    best = np.full(x.shape, np.nan)
    best_dist = np.full(x.shape[:-1], np.inf)
    for k in range(len(p)):
        a, b = p[k], p[(k + 1) % len(p)]
        inside &= (np.cross(b - a, proj - a) @ normal) >= 0.0
        q = _segment_nearest(x, a, b)
        dist = np.linalg.norm(x - q, axis=-1)
        closer = dist < best_dist
        best = np.where(closer[..., None], q, best)
        best_dist = np.where(closer, dist, best_dist)
    return np.where(inside[..., None], proj, best)


def normalized_distance(x, polygon):
    """d of the predictors: distance from x to the nearest point of the light over its width |c2 − c1|."""
    p = np.asarray(polygon, dtype=np.float64)
    x = np.asarray(x, dtype=np.float64)
    return np.linalg.norm(x - nearest_point(x, p), axis=-1) / np.linalg.norm(p[1] - p[0])


# ---------------------------------------------------------------------------------------- cone (§2.5)
def lobe_fraction(a, e):
    """∫_{−a}^{a} cos^e / ∫_{−π/2}^{π/2} cos^e (the ratio of eq 2.22) = I_{sin²a}(½, (e + 1)/2)."""
    a = np.clip(np.asarray(a, dtype=np.float64), 0.0, np.pi / 2)
    from scipy.special import betainc  # imported when used (start-up time)

    return betainc(0.5, (np.asarray(e, dtype=np.float64) + 1.0) / 2.0, np.sin(a) ** 2)


def cone_half_angle(e: float, t: float = 0.99) -> float:
    """Exact root a ∈ [0, π/2] of eq 2.22 for exponent e ≥ 0 and tolerance t ∈ (0, 1) (radians)."""
    if not (0.0 < t < 1.0):
        raise ValueError(f"tolerance t must be in (0, 1), got {t}")
    if e < 0 or not math.isfinite(e):
        raise ValueError(f"exponent must be finite and ≥ 0, got {e}")
    from scipy.optimize import brentq

    return float(brentq(lambda a: float(lobe_fraction(a, e)) - t, 0.0, np.pi / 2, xtol=1e-13, rtol=1e-13))


def cone_half_angle_fit(e):
    """The document's fit (2.23) for t = 0.99: a(e) = 1.8026 e^−0.2868 − 0.2162 (radians; may be < 0)."""
    return 1.8026 * np.asarray(e, dtype=np.float64) ** -0.2868 - 0.2162


def cone_ellipse(d, alpha, beta) -> dict[str, float]:
    """Extents of cone ∩ plane for a cone of half-angle alpha whose axis hits the plane at distance d with
    angle beta to its normal (radians, beta + alpha < π/2): ``far``/``near`` along the projected axis from
    the hit point, ``across`` (the half-width), and the document's square half-width ``document`` (2.24)."""
    if beta + alpha >= np.pi / 2:
        raise ValueError("beta + alpha ≥ 90°: the intersection is not an ellipse")
    h = d * np.cos(beta)
    return {
        "far": d * np.sin(alpha) / np.cos(beta + alpha),
        "near": d * np.sin(alpha) / np.cos(beta - alpha),
        "across": h * np.sin(alpha) / np.sqrt(np.cos(beta - alpha) * np.cos(beta + alpha)),
        "document": d * np.sin(alpha) / np.cos(beta),
    }
