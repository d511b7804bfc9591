"""Reflection points of vertices on a curved reflector by Fermat's principle (issue 6).

For an eye E and a vertex V the reflection point P = f(u, v) makes the path length
``d(u, v) = |E − f| + |V − f|`` stationary: ``∂d/∂u = −f_u · (unit(E − f) + unit(V − f)) = 0`` (same with v)
is the law of reflection. Two solvers, both vectorised over N pairs with fixed iteration counts and only
per-element arithmetic (no data-dependent loop over elements), so they port line by line to a vertex shader:

* :func:`solve_document` — the document's triangle secant (§3.3): keep a triangle in (u, v), interpolate
  the three gradients linearly to find where it vanishes, replace the farthest vertex.
* :func:`solve_robust` — Newton steps with the analytic Hessian, clamped and with a gradient fallback, in a
  local chart that keeps the iteration away from parameterisation poles, from a tangent-plane guess.

Both report the law-of-reflection residual ``||unit(unit(E − P) + unit(V − P)) × n||``: the sine of the
angle between the half vector and the normal, i.e. half the angular error of the reflected ray. It is
scale-free, independent of the parameterisation (a gradient norm scales with ``|f_u|`` and vanishes at a
pole whatever the point) and, unlike the un-normalised cross product, does not shrink at grazing incidence.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from reflets.scene.surfaces import Chart, IdentityChart, Sphere, Surface, _dot, _unit


@dataclass(frozen=True)
class SolverSettings:
    """Tolerances and trust-region settings of both solvers: the NumPy defaults here, and the ``FERMAT_*``
    ``#define``s of solver.glsl (``glsl_constants``) — one source, so the twins cannot drift apart."""

    tol: float = 1e-5  # NumPy (float64): residual below which a point has converged
    gpu_tol: float = 1e-4  # the GLSL twin's (float32: 1e-5 is at rounding level)
    max_angle: float = 0.5  # robust: initial trust region, radians the normal may turn along a step
    max_step: float = 0.25  # robust: initial trust region in chart units (bounds steps on flat parts)
    guess_angle: float = 0.1  # robust: the tangent-plane guess moves the normal by at most this
    accept: float = 4.0  # robust: a step may multiply |∇d|² by at most this
    min_edge: float = 0.02  # document: the initial triangle's smallest edge
    min_size: float = 1e-10  # document: stop when the triangle is smaller


SETTINGS = SolverSettings()
#: SURFACE_KIND codes of solver.glsl (``SURFACE_SPHERE``…) and SOLVER codes (``SOLVER_ROBUST``…)
SURFACE_KINDS = {"sphere": 1, "torus": 2, "cylinder": 3, "plane": 4, "sampled": 5}
SOLVERS = {"robust": 0, "document": 1}


def glsl_constants() -> tuple[tuple[str, str], ...]:
    """The ``#define``s solver.glsl reads: FERMAT_* settings, SURFACE_* kinds, SOLVER_* codes."""
    from ..gpu.programs import shared_constants

    fermat = {
        **{k: getattr(SETTINGS, k) for k in ("max_angle", "max_step", "guess_angle", "accept", "min_edge", "min_size")}
    }
    return shared_constants(FERMAT={"tol": SETTINGS.gpu_tol, **fermat}, SURFACE=SURFACE_KINDS, SOLVER=SOLVERS)


SQRT3_2 = 0.5 * math.sqrt(3.0)


# --------------------------------------------------------------------------------------------- path length
def _pairs(E, V) -> tuple[np.ndarray, np.ndarray]:
    """E and V as two (N, 3) float64 arrays (broadcast against each other)."""
    E, V = np.broadcast_arrays(np.asarray(E, dtype=np.float64), np.asarray(V, dtype=np.float64))
    return np.atleast_2d(E).reshape(-1, 3), np.atleast_2d(V).reshape(-1, 3)


def _derivatives(f, fu, fv, fuu, fuv, fvv, E, V) -> tuple[np.ndarray, np.ndarray]:
    """Gradient (N, 2) and Hessian (N, 2, 2) of d from f and its derivatives.

    With ``a = E − f``, ``â = a/|a|`` (same for b = V − f) and ``∂â/∂x_j = −(I − ââᵀ) f_j / |a|``:
    ``H_ij = −f_ij · (â + b̂) + f_iᵀ [(I − ââᵀ)/|a| + (I − b̂b̂ᵀ)/|b|] f_j``.
    """
    a, b = E - f, V - f
    la, lb = np.linalg.norm(a, axis=-1), np.linalg.norm(b, axis=-1)
    ah, bh = a / la[..., None], b / lb[..., None]
    h = ah + bh
    g = -np.stack([_dot(fu, h), _dot(fv, h)], axis=-1)

    def k(x, y):
        xy = _dot(x, y)
        return (xy - _dot(x, ah) * _dot(y, ah)) / la + (xy - _dot(x, bh) * _dot(y, bh)) / lb

    h00 = -_dot(fuu, h) + k(fu, fu)
    h01 = -_dot(fuv, h) + k(fu, fv)
    h11 = -_dot(fvv, h) + k(fv, fv)
    H = np.stack([np.stack([h00, h01], -1), np.stack([h01, h11], -1)], -2)
    return g, H


def path_length(surface: Surface, u, v, E, V) -> np.ndarray:
    """``|E − f(u, v)| + |V − f(u, v)|``, (N,)."""
    E, V = _pairs(E, V)
    f = surface.evaluate(np.ravel(u), np.ravel(v), 0)[0]
    return np.linalg.norm(E - f, axis=-1) + np.linalg.norm(V - f, axis=-1)


def gradient(surface: Surface, u, v, E, V) -> np.ndarray:
    """``(∂d/∂u, ∂d/∂v)`` = ``−(f_u, f_v) · (unit(E − f) + unit(V − f))``, (N, 2)."""
    E, V = _pairs(E, V)
    f, fu, fv = surface.evaluate(np.ravel(u), np.ravel(v), 1)
    h = _unit(E - f) + _unit(V - f)
    return -np.stack([_dot(fu, h), _dot(fv, h)], axis=-1)


def hessian(surface: Surface, u, v, E, V) -> np.ndarray:
    """Analytic Hessian of d in (u, v), (N, 2, 2), from f's first and second derivatives."""
    E, V = _pairs(E, V)
    return _derivatives(*surface.evaluate(np.ravel(u), np.ravel(v), 2), E, V)[1]


def reflection_residual(P, n, E, V) -> np.ndarray:
    """``||unit(unit(E − P) + unit(V − P)) × n||``: sine of the half-vector / normal angle, (N,)."""
    h = _unit(_unit(np.asarray(E) - P) + _unit(np.asarray(V) - P))
    return np.linalg.norm(np.cross(h, n), axis=-1)


def planar_reflection(P0, n, E, V) -> np.ndarray:
    """Closed-form reflection point on the plane (P0, n): ``P = E + t (V' − E)`` with V' the mirror of V.

    ``V' = V − 2((V − P0)·n) n``, ``t = ((P0 − E)·n) / ((V' − E)·n)``; n need not be unit, nor oriented.
    """
    P0, n = np.asarray(P0, dtype=np.float64), _unit(np.asarray(n, dtype=np.float64))
    E, V = np.asarray(E, dtype=np.float64), np.asarray(V, dtype=np.float64)
    Vm = V - 2.0 * _dot(V - P0, n)[..., None] * n
    den = _dot(Vm - E, n)
    t = _dot(P0 - E, n) / np.where(np.abs(den) > 1e-300, den, 1e-300)
    return E + t[..., None] * (Vm - E)


# ------------------------------------------------------------------------------------------------- results
@dataclass
class ReflectionResult:
    """Per-pair output of a solver (all arrays have N rows).

    ``residual`` is :func:`reflection_residual` at the returned point; ``converged`` is ``residual < tol``;
    ``valid`` adds that (u, v) is in the reflector's domain and that P faces both E and V
    (``n·(E − P) > 0`` and ``n·(V − P) > 0``). ``iterations`` counts the iterations used: for the document's
    solver the secant updates done before it stopped, for the robust one the first count after which the
    residual was below ``tol`` (the budget if never). ``history[:, k]``, when asked for, is the residual
    after k iterations (column 0: the initial guess), shape (N, iterations + 1), for convergence plots.
    """

    u: np.ndarray
    v: np.ndarray
    position: np.ndarray
    normal: np.ndarray
    iterations: np.ndarray
    residual: np.ndarray
    converged: np.ndarray
    valid: np.ndarray
    history: np.ndarray | None = None


def _residual_at(surface: Surface, chart: Chart, s, t, E, V) -> np.ndarray:
    u, v = chart.to_uv(s, t)
    return reflection_residual(surface.position(u, v), surface.normal(u, v), E, V)


def _result(surface: Surface, chart: Chart, s, t, E, V, iterations, tol, history) -> ReflectionResult:
    u, v = chart.to_uv(s, t)
    P, n = surface.position(u, v), surface.normal(u, v)
    with np.errstate(invalid="ignore"):
        res = reflection_residual(P, n, E, V)
    res = np.where(np.isfinite(res), res, np.inf)
    converged = res < tol
    facing = (_dot(n, E - P) > 0) & (_dot(n, V - P) > 0)
    return ReflectionResult(
        u=u,
        v=v,
        position=P,
        normal=n,
        iterations=iterations,
        residual=res,
        converged=converged,
        valid=converged & facing & surface.contains(u, v),
        history=history,
    )


def _start(surface: Surface, E, V, local_chart: bool, unwrap: bool = True) -> tuple[Chart, np.ndarray]:
    """The document's A = [V, O] ∩ S and B = [E, O] ∩ S, in a chart around them; and O."""
    O = surface.interior_point(E, V)
    a, b = surface.segment_hit(V, O), surface.segment_hit(E, O)
    return (surface.chart(a, b) if local_chart else IdentityChart(surface, a, b, unwrap=unwrap)), O


# ---------------------------------------------------------------------------------------- document solver
def third_point(a: np.ndarray, b: np.ndarray, min_edge: float = SETTINGS.min_edge) -> tuple[np.ndarray, np.ndarray]:
    """B (possibly moved) and C making an equilateral triangle on AB in (u, v), (N, 2) each.

    ``C = (A + B)/2 + (√3/2) R₉₀ (B − A)``: the least flat triangle on AB, on the left of A → B. When
    ``|AB| < min_edge`` (eye and vertex seen from O in the same direction) B is first moved to
    ``A + min_edge · unit(B − A)`` (or along +u), since a triangle on a point would make eq. 3.2 singular.
    """
    e = b - a
    length = np.linalg.norm(e, axis=-1, keepdims=True)
    direction = np.where(length > 0, e / np.where(length > 0, length, 1.0), [1.0, 0.0])
    b = np.where(length < min_edge, a + min_edge * direction, b)
    e = b - a
    c = 0.5 * (a + b) + SQRT3_2 * np.stack([-e[:, 1], e[:, 0]], axis=-1)
    return b, c


def _grad(chart: Chart, x: np.ndarray, E, V) -> np.ndarray:
    f, fu, fv = chart.evaluate(x[:, 0], x[:, 1], 1)
    h = _unit(E - f) + _unit(V - f)
    return -np.stack([_dot(fu, h), _dot(fv, h)], axis=-1)


def _cross2(p: np.ndarray, q: np.ndarray) -> np.ndarray:
    return p[:, 0] * q[:, 1] - p[:, 1] * q[:, 0]


def _solve_barycentric(GA, GB, GC, singular: str) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(α, β) of eq. 3.2 and where they are usable.

    ``singular='stop'``: Cramer's rule, unusable when ``|det| ≤ 1e-12 |G_B − G_A| |G_C − G_A|``.
    ``'least_squares'``: ``(MᵀM + λI)⁻¹ Mᵀ (−G_A)`` with ``λ = 1e-12 ||M||²_F``, equal to Cramer's rule for
    a regular system and the minimum-norm solution of a singular one (flat triangle, or a gradient component
    that vanishes at all three vertices, as on a symmetry line).
    """
    d1, d2 = GB - GA, GC - GA
    if singular == "stop":
        det = _cross2(d1, d2)
        ok = np.isfinite(det) & (np.abs(det) > 1e-12 * np.linalg.norm(d1, axis=-1) * np.linalg.norm(d2, axis=-1))
        det = np.where(ok, det, 1.0)
        return _cross2(-GA, d2) / det, _cross2(d1, -GA) / det, ok
    if singular != "least_squares":
        raise ValueError(f"singular must be 'stop' or 'least_squares', got {singular!r}")
    m00, m01, m11 = _dot(d1, d1), _dot(d1, d2), _dot(d2, d2)
    lam = 1e-12 * (m00 + m11) + 1e-300
    m00, m11 = m00 + lam, m11 + lam
    r0, r1 = -_dot(d1, GA), -_dot(d2, GA)
    det = m00 * m11 - m01 * m01
    with np.errstate(invalid="ignore", divide="ignore"):
        alpha, beta = (m11 * r0 - m01 * r1) / det, (m00 * r1 - m01 * r0) / det
    return alpha, beta, np.isfinite(alpha) & np.isfinite(beta) & (m00 + m11 > 1e-300)


def solve_document(
    surface: Surface,
    E,
    V,
    iterations: int = 5,
    tol: float = SETTINGS.tol,
    min_size: float = SETTINGS.min_size,
    local_chart: bool = False,
    unwrap: bool = True,
    singular: str = "stop",
    history: bool = False,
) -> ReflectionResult:
    """The document's triangle secant, faithfully; returns the last point P computed.

    Each iteration solves ``[G_B − G_A, G_C − G_A] (α, β)ᵀ = −G_A``, sets ``P = (1 − α − β)A + αB + βC``
    (extrapolating when α, β leave [0, 1]; non-periodic coordinates clamped to the domain) and replaces the
    vertex farthest from P in (u, v): one new gradient per iteration. A pair stops (keeps its last P) when
    the system is singular (flat triangle or parallel gradient differences) or the triangle's longest edge
    is below ``min_size``. By default it iterates in the global parameterisation, as the document does, with
    B's periodic coordinate moved to the image nearest A (``unwrap=False`` keeps the raw seam jump);
    ``local_chart=True`` uses the surface's local chart instead (the note's "chart centred between A and B").
    """
    E, V = _pairs(E, V)
    chart, _ = _start(surface, E, V, local_chart, unwrap)
    A = np.stack(chart.a, axis=-1)
    B, C = third_point(A, np.stack(chart.b, axis=-1))
    C = np.stack(chart.clamp(C[:, 0], C[:, 1]), axis=-1)
    GA, GB, GC = _grad(chart, A, E, V), _grad(chart, B, E, V), _grad(chart, C, E, V)
    # Until the first update, the estimate is the vertex with the smallest gradient.
    norms = np.stack([np.linalg.norm(G, axis=-1) for G in (GA, GB, GC)], axis=-1)
    x = np.choose(np.argmin(norms, axis=-1)[:, None], [A, B, C])
    active = np.ones(len(E), bool)
    used = np.zeros(len(E), np.int64)
    hist = [_residual_at(surface, chart, x[:, 0], x[:, 1], E, V)] if history else None
    for _ in range(iterations):
        alpha, beta, ok = _solve_barycentric(GA, GB, GC, singular)
        P = A + alpha[:, None] * (B - A) + beta[:, None] * (C - A)
        P = np.stack(chart.clamp(P[:, 0], P[:, 1]), axis=-1)
        step = active & ok & np.all(np.isfinite(P), axis=-1)
        P = np.where(step[:, None], P, x)
        GP = _grad(chart, P, E, V)
        far = np.argmax(np.stack([np.linalg.norm(X - P, axis=-1) for X in (A, B, C)], axis=-1), axis=-1)
        for k, (X, G) in enumerate(((A, GA), (B, GB), (C, GC))):
            sel = (step & (far == k))[:, None]
            X[...] = np.where(sel, P, X)
            G[...] = np.where(sel, GP, G)
        x = P
        used += step
        size = np.max(np.stack([np.linalg.norm(p - q, axis=-1) for p, q in ((A, B), (B, C), (C, A))], -1), -1)
        active = step & (size > min_size)
        if history:
            hist.append(_residual_at(surface, chart, x[:, 0], x[:, 1], E, V))
    hist = np.stack(hist, axis=-1) if history else None
    return _result(surface, chart, x[:, 0], x[:, 1], E, V, used, tol, hist)


# ------------------------------------------------------------------------------------------ robust solver
def _clamp_length(step: np.ndarray, max_length) -> np.ndarray:
    """Scale each row of ``step`` down to length ``max_length`` (a scalar or one per row) if longer."""
    length = np.linalg.norm(step, axis=-1)
    return step * np.minimum(1.0, max_length / np.maximum(length, 1e-300))[..., None]


def initial_guess(
    surface: Surface, chart: Chart, O: np.ndarray, E, V, mode: str = "bisector", max_angle: float = SETTINGS.guess_angle
) -> np.ndarray:
    """Starting chart coordinates (N, 2).

    * ``midpoint``: the midpoint M of A and B in the chart — on a sphere chart the point of the arc AB
      bisecting the angle AOB, but in a global lat-long chart possibly far off the arc (A and B on either
      side of a pole average to a point 90° away).
    * ``bisector``: where the ray from O along the bisector of OA and OB meets the surface (one more
      :meth:`Surface.segment_hit`, from ``O + 2 max(|OA|, |OB|) · unit(bisector)``): the same point as
      ``midpoint`` on a sphere chart, and on the arc between A and B whatever the parameterisation.
    * ``tangent_plane`` (what :func:`solve_robust` uses): from the bisector point X, the closed-form mirror
      point Q in the tangent plane at X (:func:`planar_reflection`), pulled back to first order,
      ``δ = (JᵀJ)⁻¹ Jᵀ (Q − X)`` with ``J = [f_u, f_v]``, scaled down so that the normal turns by at most
      ``max_angle`` along it. Exact on a plane; unlimited, it overshoots towards grazing points on convex
      reflectors (0.4 rad was worse than 0.1 on the sphere, ellipsoid and cylinder, 0.05–0.2 were equal).
    """
    if mode not in ("midpoint", "bisector", "tangent_plane"):
        raise ValueError(f"guess must be 'midpoint', 'bisector' or 'tangent_plane', got {mode!r}")
    M = 0.5 * (np.stack(chart.a, axis=-1) + np.stack(chart.b, axis=-1))
    if mode == "midpoint":
        return M
    oa = chart.evaluate(*chart.a, 0)[0] - O
    ob = chart.evaluate(*chart.b, 0)[0] - O
    la, lb = np.linalg.norm(oa, axis=-1), np.linalg.norm(ob, axis=-1)
    w = _unit(oa) + _unit(ob)
    w = np.where(np.linalg.norm(w, axis=-1, keepdims=True) > 1e-6, w, oa)
    X = np.stack(chart.from_uv(*surface.segment_hit(O + 2.0 * np.maximum(la, lb)[:, None] * _unit(w), O)), -1)
    if mode == "bisector":
        return X
    f, fu, fv, fuu, fuv, fvv = chart.evaluate(X[:, 0], X[:, 1], 2)
    n = np.cross(fu, fv)
    with np.errstate(invalid="ignore", divide="ignore"):
        d = planar_reflection(f, n, E, V) - f
        g00, g01, g11 = _dot(fu, fu), _dot(fu, fv), _dot(fv, fv)
        det = g00 * g11 - g01 * g01
        r0, r1 = _dot(fu, d), _dot(fv, d)
        delta = np.stack([g11 * r0 - g01 * r1, g00 * r1 - g01 * r0], axis=-1) / det[:, None]
    usable = np.all(np.isfinite(delta), axis=-1) & (det > 1e-12 * g00 * g11)
    delta = np.where(usable[:, None], delta, 0.0)
    turn = _turn(delta, fu, fv, fuu, fuv, fvv)
    delta = delta * np.minimum(1.0, max_angle / np.maximum(turn, 1e-300))[:, None]
    return np.stack(chart.clamp(*(X + delta).T), axis=-1)


def _newton_step(g: np.ndarray, H: np.ndarray) -> np.ndarray:
    """``−H⁻¹ g``, or ``−g / ||H||_F`` where H is singular or not finite (``|det H| ≤ 1e-10 ||H||²_F``)."""
    det = H[:, 0, 0] * H[:, 1, 1] - H[:, 0, 1] * H[:, 1, 0]
    fro2 = np.sum(H * H, axis=(1, 2))
    ok = np.isfinite(det) & (np.abs(det) > 1e-10 * fro2)
    det = np.where(ok, det, 1.0)
    newton = np.stack([H[:, 1, 1] * g[:, 0] - H[:, 0, 1] * g[:, 1], H[:, 0, 0] * g[:, 1] - H[:, 1, 0] * g[:, 0]], -1)
    step = np.where(ok[:, None], -newton / det[:, None], -g / np.maximum(np.sqrt(fro2), 1e-300)[:, None])
    return np.where(np.isfinite(step), step, 0.0)


def _turn(step: np.ndarray, fu, fv, fuu, fuv, fvv) -> np.ndarray:
    """Angle the normal turns along ``step`` (normal curvature × 3D length), to first order, (N,)."""
    s0, s1 = step[:, :1], step[:, 1:]
    length = np.linalg.norm(fu * s0 + fv * s1, axis=-1)
    bend = np.abs(_dot(_unit(np.cross(fu, fv)), fuu * s0 * s0 + 2.0 * fuv * s0 * s1 + fvv * s1 * s1))
    return bend / np.maximum(length, 1e-300)


def solve_robust(
    surface: Surface,
    E,
    V,
    iterations: int = 8,
    tol: float = SETTINGS.tol,
    max_angle: float = SETTINGS.max_angle,
    max_step: float = SETTINGS.max_step,
    guess: str = "tangent_plane",
    local_chart: bool = True,
    trust_region: bool = True,
    accept_ratio: float = SETTINGS.accept,
    history: bool = False,
) -> ReflectionResult:
    """Newton on ∇d = 0 with the analytic Hessian, in the surface's local chart, inside a trust region.

    Newton is applied to the gradient (root finding), not to d (minimisation): reflection points on concave
    or saddle-shaped reflectors are maxima or saddles of d. Safeguards, all per element and branch-free:

    * where H is singular or not finite the step is a gradient step (:func:`_newton_step`);
    * the step is scaled down so that the normal turns by at most an angle (initially ``max_angle`` rad, the
      scale over which the quadratic model of d is trustworthy on a curved mirror, whatever the
      parameterisation) and moves by at most a chart length (initially ``max_step``; it bounds steps on flat
      parts, where the turn is 0);
    * with ``trust_region``, the candidate is rejected if it multiplies ``|∇d|²`` by more than
      ``accept_ratio`` (a non-monotone test: the strict one, 1, left more pairs on the torus stuck at
      non-zero local minima of ``|∇d|²``; 4 was best of 1, 2, 4, 16 there, and all were equal on the sphere,
      ellipsoid and cylinder). On acceptance both limits double (up to 2 × their initial values); on
      rejection the pair stays put and the limits drop to a quarter of the rejected step's. Without it every
      limited step is taken;
    * non-periodic coordinates are clamped to the domain.

    One evaluation of f with first and second derivatives per iteration, plus one for the guess.
    """
    E, V = _pairs(E, V)
    chart, O = _start(surface, E, V, local_chart)
    x = initial_guess(surface, chart, O, E, V, guess)
    n_pairs = len(E)
    used = np.full(n_pairs, iterations, np.int64)
    ev = chart.evaluate(x[:, 0], x[:, 1], 2)
    g, H = _derivatives(*ev, E, V)
    merit = np.where(np.all(np.isfinite(g), -1), np.sum(g * g, -1), np.inf)
    angle, radius = np.full(n_pairs, float(max_angle)), np.full(n_pairs, float(max_step))
    hist = [_residual_at(surface, chart, x[:, 0], x[:, 1], E, V)] if history else []
    for k in range(1, iterations + 1):
        step = _newton_step(g, H)
        turn = _turn(step, *ev[1:])
        length = np.linalg.norm(step, axis=-1)
        scale = np.minimum(1.0, np.minimum(angle / np.maximum(turn, 1e-300), radius / np.maximum(length, 1e-300)))
        step, turn, length = step * scale[:, None], turn * scale, length * scale
        xc = np.stack(chart.clamp(*(x + step).T), axis=-1)
        evc = chart.evaluate(xc[:, 0], xc[:, 1], 2)
        gc, Hc = _derivatives(*evc, E, V)
        mc = np.where(np.all(np.isfinite(gc), -1), np.sum(gc * gc, -1), np.inf)
        accept = (mc < accept_ratio * merit) | ~np.isfinite(merit) if trust_region else np.ones(n_pairs, bool)
        x = np.where(accept[:, None], xc, x)
        g, H = np.where(accept[:, None], gc, g), np.where(accept[:, None, None], Hc, H)
        ev = [np.where(accept[:, None], a, b) for a, b in zip(evc, ev, strict=True)]
        merit = np.where(accept, mc, merit)
        if trust_region:
            angle = np.where(accept, np.minimum(2.0 * angle, 2.0 * max_angle), 0.25 * np.maximum(turn, 1e-12))
            radius = np.where(accept, np.minimum(2.0 * radius, 2.0 * max_step), 0.25 * np.maximum(length, 1e-12))
        res = _residual_at(surface, chart, x[:, 0], x[:, 1], E, V)
        used = np.where((used == iterations) & (res < tol), np.minimum(used, k), used)
        if history:
            hist.append(res)
    hist = np.stack(hist, axis=-1) if history else None
    return _result(surface, chart, x[:, 0], x[:, 1], E, V, used, tol, hist)


# ------------------------------------------------------------------------------------------- benchmarking
def convergence_statistics(
    surface: Surface, solver: Callable[..., ReflectionResult], E, V, iterations_list, tol: float = 1e-5, **kwargs
) -> np.ndarray:
    """Fraction of pairs converged (residual < tol) after each iteration count of ``iterations_list``."""
    return np.array(
        [solver(surface, E, V, iterations=int(k), tol=tol, **kwargs).converged.mean() for k in iterations_list]
    )


def sphere_reflection(sphere: Sphere, E, V, steps: int = 60) -> np.ndarray:
    """Reference reflection point on a sphere: bisection on the arc AB in the plane (E, V, centre).

    A (towards V) and B (towards E) bracket the reflection (Ofek); the tangential component of the half
    vector changes sign between them. Returns (N, 3) points; used to filter random pairs.
    """
    E, V = _pairs(E, V)
    c, r = sphere.center, sphere.radius
    e1 = _unit(V - c)
    w = (E - c) - _dot(E - c, e1)[:, None] * e1
    axis = np.eye(3)[np.argmin(np.abs(e1), axis=-1)]
    e2 = _unit(np.where(np.linalg.norm(w, axis=-1, keepdims=True) > 1e-12, w, np.cross(e1, axis)))
    theta_b = np.arctan2(_dot(E - c, e2), _dot(E - c, e1))

    def tangential(theta):
        n = np.cos(theta)[:, None] * e1 + np.sin(theta)[:, None] * e2
        t = -np.sin(theta)[:, None] * e1 + np.cos(theta)[:, None] * e2
        P = c + r * n
        return _dot(_unit(E - P) + _unit(V - P), t)

    lo, hi = np.zeros_like(theta_b), theta_b
    f_lo = tangential(lo)
    for _ in range(steps):
        mid = 0.5 * (lo + hi)
        f_mid = tangential(mid)
        same = np.signbit(f_mid) == np.signbit(f_lo)
        lo, hi, f_lo = np.where(same, mid, lo), np.where(same, hi, mid), np.where(same, f_mid, f_lo)
    theta = 0.5 * (lo + hi)
    return c + r * (np.cos(theta)[:, None] * e1 + np.sin(theta)[:, None] * e2)


def _random_directions(rng: np.random.Generator, n: int) -> np.ndarray:
    return _unit(rng.standard_normal((n, 3)))


def random_valid_pairs(
    surface: Surface | None = None,
    n: int = 1000,
    rng: np.random.Generator | int | None = 0,
    distance: tuple[float, float] = (1.5, 10.0),
    occlusion_steps: int = 256,
) -> tuple[np.ndarray, np.ndarray]:
    """Seeded random eye / vertex pairs (E, V), each (n, 3), that have a valid reflection on ``surface``.

    Sphere (the default, unit at the origin): E and V in uniform directions at distances uniform in
    ``distance`` radii; pairs whose segment EV crosses the sphere are rejected, and so are those whose
    reference reflection (:func:`sphere_reflection`) does not face both. Other surfaces (which must be
    implicit, for the occlusion test): a uniform (u, v) gives P, E lies in a uniform direction of the front
    hemisphere, V along the mirrored direction, both at ``distance`` × the surface's size from P; pairs with
    E or V inside, or with P hidden from E or V (sign change of ``implicit`` on the segment, sampled at
    ``occlusion_steps`` points), are rejected — P is then a valid reflection, not necessarily the only one.
    """
    surface = Sphere() if surface is None else surface
    rng = np.random.default_rng(rng)
    lo, hi = distance
    out_e, out_v, count = [], [], 0
    while count < n:
        m = 2 * (n - count) + 16
        if isinstance(surface, Sphere):
            c, r = surface.center, surface.radius
            E = c + r * rng.uniform(lo, hi, (m, 1)) * _random_directions(rng, m)
            V = c + r * rng.uniform(lo, hi, (m, 1)) * _random_directions(rng, m)
            d = V - E
            t = np.clip(_dot(c - E, d) / _dot(d, d), 0.0, 1.0)
            keep = np.linalg.norm(E + t[:, None] * d - c, axis=-1) > r
            P = sphere_reflection(surface, E, V)
            nrm = (P - c) / r
            keep &= (_dot(nrm, E - P) > 0) & (_dot(nrm, V - P) > 0)
        else:
            u, v = rng.uniform(0.0, 1.0, m), rng.uniform(0.0, 1.0, m)
            P, nrm = surface.position(u, v), surface.normal(u, v)
            size = _surface_size(surface)
            de = _random_directions(rng, m)
            de = np.where(_dot(de, nrm)[:, None] < 0, -de, de)
            dv = 2 * _dot(de, nrm)[:, None] * nrm - de
            E = P + size * rng.uniform(lo, hi, (m, 1)) * de
            V = P + size * rng.uniform(lo, hi, (m, 1)) * dv
            keep = np.all(np.isfinite(nrm), axis=-1) & (surface.implicit(E) > 0) & (surface.implicit(V) > 0)
            ts = np.linspace(0.0, 1.0, occlusion_steps + 1)[1:]
            for X in (E, V):
                for chunk in np.array_split(ts, max(1, occlusion_steps // 32)):
                    samples = P[:, None, :] + chunk[:, None] * (X - P)[:, None, :]
                    keep &= np.all(surface.implicit(samples) > 0, axis=-1)
        out_e.append(E[keep])
        out_v.append(V[keep])
        count += int(keep.sum())
    return np.concatenate(out_e)[:n], np.concatenate(out_v)[:n]


def _surface_size(surface: Surface) -> float:
    """Half the diagonal of the bounding box of a 33 × 33 sampling: the scale of the random distances."""
    g = np.linspace(0.0, 1.0, 33)
    pts = surface.position(*np.meshgrid(g, g)).reshape(-1, 3)
    return 0.5 * float(np.linalg.norm(np.ptp(pts, axis=0)))
