"""The 2D profile ray tracer with Fresnel at every bounce (NumPy reference, float64).

Directions in the profile plane are 2D unit vectors (x along **v**, y along **n**) and the cone angle of a
direction ω is φ = atan2(ω_x, ω_y) ∈ (−π/2, π/2) (chapter 3, §3.2). Light arriving *from* φ_in travels along
d = −(sin φ_in, cos φ_in); a ray that leaves the scratch along d is tallied at φ_out = atan2(d_x, d_y). A flat
profile sends φ_in to φ_out = −φ_in (the anti-diagonal).

Algorithm for one ray (the digest's pseudo-code, §3.4):

1. origin on the lid (x0 ~ U[0, 1), y = lid), direction d;
2. walk the polyline cells the ray crosses (the profile is periodic: leaving cell K−1 enters cell 0 of the
   next period, the x coordinate is shifted by one period so positions stay in [0, 1]); in each cell
   - ``polyline`` profiles: exact intersection with the segment;
   - ``quartic``: sign change of g(t) = y(t) − h(x(t)) at the end of the cell, or a graze (g within
     4D (d_x Δt)² of 0 — the most a smooth g can dip below its ends with |h''| ≤ 32 D —, g' < 0 at the
     cell's start and > 0 at its end, and g ≤ 0 at the minimum found by bisection on g') → 40 bisection
     steps on the exact curve (the new origin is the end of the bracket still above the surface);
   - no hit and the ray reaches the lid (d_y > 0) inside the cell → it has left the scratch;
3. at a hit with unit normal m: c₂ = |d·m| and every Fresnel weight is multiplied by F(cos θ · c₂), the 3D
   cosine of incidence for a ray of elevation θ along the scratch (the path itself does not depend on θ);
   d ← d − 2(d·m) m; back to 2.

Rays that bounce more than ``max_bounces`` times or walk more than ``3K + 8`` cells in one flight (a ray below
the lid cannot pass a period's highest point, so a walk is at most about one period) are *lost*; they are
counted, never tallied, and show up as missing energy.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from ..errors import ArgumentError
from ..fresnel import fresnel_conductor, fresnel_dielectric, fresnel_schlick
from .profiles import Profile, quartic_height, quartic_slope

MAX_BOUNCES = 256  # whispering-gallery paths along a concave quartic reach ~70 at 256² × 10⁴
THETAS = (0.0, np.pi / 3.0)  # the elevations of the table's Fresnel tallies ρ_s(0), ρ_s(π/3)
_BISECTIONS = 40
_CHUNK = 1 << 17


# -- Fresnel ------------------------------------------------------------------------------------------------
#: Fresnel models of the scratch walls: the codes of the GPU tracer's FRESNEL_MODEL flag (``FRESNEL_NONE``…)
FRESNEL_MODELS = {"none": 0, "schlick": 1, "dielectric": 2, "lazanyi": 3, "conductor": 4}
#: profile kinds of the GPU tracer's PROFILE_KIND flag: a polyline (exact segment hits) or the quartic (bisection)
PROFILE_KINDS = {"polyline": 0, "quartic": 1}


@dataclass(frozen=True)
class FresnelSpec:
    """Fresnel reflectance of the scratch walls, one value per colour channel.

    ``model``: ``none`` (F = 1, the mirror BRDF ρ_m), ``schlick`` (dielectric, F0 = ((η−1)/(η+1))²),
    ``dielectric`` (exact dielectric), ``lazanyi`` (conductor, Lazányi–Szirmay-Kalos:
    F = [(n−1)² + 4n(1−cos)⁵ + k²] / [(n+1)² + k²]) or ``conductor`` (exact complex Fresnel).
    """

    model: str = "none"
    eta: tuple[float, ...] = (1.0,)
    k: tuple[float, ...] = (0.0,)

    @property
    def channels(self) -> int:
        return len(self.eta)

    @property
    def model_id(self) -> int:
        return FRESNEL_MODELS[self.model]

    def __call__(self, cos_i) -> np.ndarray:
        """F(cos) with a trailing channel axis: (..., C)."""
        c = np.clip(np.asarray(cos_i, dtype=np.float64), 0.0, 1.0)[..., None]
        eta = np.asarray(self.eta, dtype=np.float64)
        k = np.asarray(self.k, dtype=np.float64)
        if self.model == "none":
            return np.ones(c.shape[:-1] + (self.channels,))
        if self.model == "schlick":
            return fresnel_schlick(c, ((eta - 1.0) / (eta + 1.0)) ** 2)
        if self.model == "dielectric":
            return fresnel_dielectric(c, eta)
        if self.model == "lazanyi":
            m = (1.0 - c) ** 5
            return ((eta - 1.0) ** 2 + 4.0 * eta * m + k * k) / ((eta + 1.0) ** 2 + k * k)
        return fresnel_conductor(c, eta, k)

    def describe(self) -> dict:
        return {"model": self.model, "eta": list(self.eta), "k": list(self.k)}


def make_fresnel(ior=None, conductor=None, model: str = "auto") -> FresnelSpec:
    """Fresnel of the walls: ``conductor=(eta, k)`` (scalars or RGB triples) wins over ``ior`` (real index,
    scalar or RGB); neither → F = 1. ``model``: ``auto`` (Schlick for dielectrics, Lazányi for conductors, as
    in the document), ``exact`` (exact dielectric / complex Fresnel), or a :class:`FresnelSpec` model name."""
    if conductor is not None:
        try:
            eta, k = conductor
        except (TypeError, ValueError):
            msg = "conductor must be a pair (eta, k), scalars or RGB triples"
            raise ArgumentError(msg, field="conductor") from None
        eta, k = np.broadcast_arrays(np.atleast_1d(np.asarray(eta, float)), np.atleast_1d(np.asarray(k, float)))
        if eta.ndim != 1 or eta.size not in (1, 3) or np.any(eta <= 0) or np.any(k < 0):
            raise ArgumentError("conductor eta > 0 and k ≥ 0, 1 or 3 channels", field="conductor")
        name = {"auto": "lazanyi", "exact": "conductor"}.get(model, model)
        if name not in ("lazanyi", "conductor"):
            raise ArgumentError(f"fresnel model '{model}' is not a conductor model", field="fresnel")
        return FresnelSpec(name, tuple(map(float, eta)), tuple(map(float, k)))
    if ior is not None:
        eta = np.atleast_1d(np.asarray(ior, dtype=float))
        if eta.ndim != 1 or eta.size not in (1, 3) or np.any(eta <= 0):
            raise ArgumentError("ior must be > 0, 1 or 3 channels", field="ior")
        name = {"auto": "schlick", "exact": "dielectric"}.get(model, model)
        if name not in ("schlick", "dielectric"):
            raise ArgumentError(f"fresnel model '{model}' is not a dielectric model", field="fresnel")
        return FresnelSpec(name, tuple(map(float, eta)), (0.0,) * eta.size)
    return FresnelSpec()


# -- one flight: from an origin to the next hit or to the lid ----------------------------------------------
def _flight(profile: Profile, px, py, dx, dy, cell):
    """Walk every ray to its next event. Returns (status, t, cell, px) with status 1 = hit, 2 = left through
    the lid, 3 = lost; px is shifted by whole periods so that it refers to the period of the final cell."""
    n = px.size
    K = profile.cells
    X, H, S = profile.x, profile.h, profile.slopes
    quart = profile.kind == "quartic"
    status = np.zeros(n, np.int8)
    t_res = np.zeros(n)
    px = px.copy()
    cell = cell.copy()
    t_lo = np.zeros(n)
    with np.errstate(divide="ignore", invalid="ignore"):
        t_exit = np.where(dy > 0, (profile.lid - py) / dy, np.inf)
        t_floor = np.where(dy < 0, (profile.bottom - py) / dy, np.inf)
    idx = np.arange(n)
    steps = 0
    max_steps = 3 * K + 8
    while idx.size:
        c = cell[idx]
        x0, y0, ddx, ddy = px[idx], py[idx], dx[idx], dy[idx]
        xa, xb = X[c], X[c + 1]
        with np.errstate(divide="ignore", invalid="ignore"):
            t_out = np.where(ddx > 0, (xb - x0) / ddx, np.where(ddx < 0, (xa - x0) / ddx, np.inf))
        te = t_exit[idx]
        tl = t_lo[idx]
        if quart:
            th = np.minimum(np.minimum(t_out, te), t_floor[idx])
            th = np.where(np.isfinite(th), th, tl)
            g_hi = y0 + th * ddy - quartic_height(x0 + th * ddx, profile.depth)
            hit = g_hi <= 0.0
            # a graze entering and leaving the curve inside one cell: possible only if g comes within
            # max g''·Δt²/8 ≤ 4D (dx Δt)² of 0 (|h''| ≤ 32 D); then g' < 0 at the start and > 0 at the end →
            # bisection on g' for the minimum of g, a hit if g_min ≤ 0 (the bracket then ends at the minimum)
            g_lo = y0 + tl * ddy - quartic_height(x0 + tl * ddx, profile.depth)
            near = ~hit & (np.minimum(g_lo, g_hi) < 8.0 * profile.depth * (ddx * (th - tl)) ** 2)
            gp_lo = ddy - ddx * quartic_slope(x0 + tl * ddx, profile.depth)
            gp_hi = ddy - ddx * quartic_slope(x0 + th * ddx, profile.depth)
            graze = np.nonzero(near & (gp_lo < 0.0) & (gp_hi > 0.0))[0]
            if graze.size:
                lo, hi = tl[graze], th[graze]
                gx, gy, gdx, gdy = x0[graze], y0[graze], ddx[graze], ddy[graze]
                for _ in range(_BISECTIONS):
                    mid = 0.5 * (lo + hi)
                    falling = gdy - gdx * quartic_slope(gx + mid * gdx, profile.depth) < 0.0
                    lo = np.where(falling, mid, lo)
                    hi = np.where(falling, hi, mid)
                g_min = gy + hi * gdy - quartic_height(gx + hi * gdx, profile.depth)
                inside = g_min <= 0.0
                hit[graze[inside]] = True
                th[graze[inside]] = hi[inside]
            if hit.any():
                lo, hi = tl[hit], th[hit]
                hx, hy, hdx, hdy = x0[hit], y0[hit], ddx[hit], ddy[hit]
                for _ in range(_BISECTIONS):
                    mid = 0.5 * (lo + hi)
                    below = hy + mid * hdy - quartic_height(hx + mid * hdx, profile.depth) <= 0.0
                    hi = np.where(below, mid, hi)
                    lo = np.where(below, lo, mid)
                t_star = np.zeros(idx.size)
                t_star[hit] = lo
            else:
                t_star = np.zeros(idx.size)
        else:
            slope = S[c]
            g0 = y0 - H[c] - (x0 - xa) * slope
            den = ddy - ddx * slope
            with np.errstate(divide="ignore", invalid="ignore"):
                t_star = -g0 / den
            t_hi = np.minimum(t_out, te)
            hit = (den < 0) & (t_star <= t_hi) & (t_star >= tl - 1e-9)
            t_star = np.maximum(t_star, 0.0)
        escaped = ~hit & (te <= t_out)
        done = hit | escaped
        status[idx[hit]] = 1
        t_res[idx[hit]] = t_star[hit]
        status[idx[escaped]] = 2
        move = ~done
        if not move.any():
            break
        mi = idx[move]
        t_lo[mi] = t_out[move]
        step = np.where(dx[mi] > 0, 1, -1)
        nc = cell[mi] + step
        px[mi] += np.where(nc >= K, -1.0, np.where(nc < 0, 1.0, 0.0))
        cell[mi] = np.mod(nc, K)
        idx = mi
        steps += 1
        if steps > max_steps:
            status[idx] = 3
            break
    return status, t_res, cell, px


@dataclass
class RayResult:
    """Per-ray outcome of :func:`trace_rays`."""

    phi_out: np.ndarray  # (n,) exit angle (NaN for lost rays)
    bounces: np.ndarray  # (n,) number of reflections
    weights: np.ndarray  # (n, T, C) product of Fresnel factors for each θ of ``thetas``
    lost: np.ndarray  # (n,) bool
    direction: np.ndarray = field(repr=False, default=None)  # (n, 2) exit direction


def trace_rays(
    profile: Profile,
    phi_in,
    x0,
    *,
    fresnel: FresnelSpec | None = None,
    thetas=THETAS,
    max_bounces: int = MAX_BOUNCES,
) -> RayResult:
    """Trace rays arriving from ``phi_in`` (radians) that enter the lid at x = ``x0`` ∈ [0, 1)."""
    fresnel = fresnel or FresnelSpec()
    phi_in = np.asarray(phi_in, dtype=np.float64).ravel()
    x0 = np.mod(np.asarray(x0, dtype=np.float64).ravel(), 1.0)
    n = phi_in.size
    cos_t = np.cos(np.asarray(thetas, dtype=np.float64))
    T, C = cos_t.size, fresnel.channels
    px, py = x0.copy(), np.full(n, profile.lid)
    dx, dy = -np.sin(phi_in), -np.cos(phi_in)
    cell = profile.cell_of(px)
    weights = np.ones((n, T, C))
    bounces = np.zeros(n, np.int64)
    lost = np.zeros(n, bool)
    out = np.zeros((n, 2))
    idx = np.arange(n)
    while idx.size:
        status, t, c, sx = _flight(profile, px[idx], py[idx], dx[idx], dy[idx], cell[idx])
        gone = status == 2
        out[idx[gone], 0], out[idx[gone], 1] = dx[idx[gone]], dy[idx[gone]]
        lost[idx[status == 3]] = True
        hit = status == 1
        hi = idx[hit]
        if hi.size == 0:
            break
        hx = sx[hit] + t[hit] * dx[hi]
        hy = py[hi] + t[hit] * dy[hi]
        if profile.kind == "quartic":
            s = quartic_slope(hx, profile.depth)
        else:
            s = profile.slopes[c[hit]]
        norm = np.sqrt(1.0 + s * s)
        mx, my = -s / norm, 1.0 / norm
        dm = dx[hi] * mx + dy[hi] * my
        if fresnel.model != "none":
            weights[hi] *= fresnel(np.abs(dm)[:, None] * cos_t[None, :])
        dx[hi] -= 2.0 * dm * mx
        dy[hi] -= 2.0 * dm * my
        px[hi], py[hi], cell[hi] = hx, hy, c[hit]
        bounces[hi] += 1
        over = bounces[hi] > max_bounces
        lost[hi[over]] = True
        idx = hi[~over]
    phi_out = np.where(lost, np.nan, np.arctan2(out[:, 0], out[:, 1]))
    return RayResult(phi_out, bounces, weights, lost, out)


# -- tallies of a whole table -------------------------------------------------------------------------------
@dataclass
class Tallies:
    """Raw sums of a table trace, indexed [φ_out bin, φ_in bin] (``rays`` rays per φ_in column).

    Every ray of column j carries the weight c(ψ) = cos ψ / c̄_j, ψ its jittered φ_in and
    c̄_j = (1/Δφ)∫_bin cos = cos φ_j · sin(Δφ/2)/(Δφ/2). With it E[tally[b, j]] / N =
    ∬_{b×j} ρ cos φ_o cos φ_i / (Δφ c̄_j), so the table ρ[b, j] = tally / (N Δφ cos φ_b) is *exactly*
    reciprocal in expectation (the document's unweighted count is reciprocal only up to the variation of
    cos φ_in inside a bin: a few % next to the sharp lines of a V-groove at 32 bins), and Σ_b ρ cos φ_b Δφ =
    mean(cos ψ)/c̄_j = 1 up to O(N^-1.5) since ψ is stratified inside the bin.
    """

    size: int
    rays: int
    thetas: tuple
    counts: np.ndarray  # (M, M) Σ c(ψ) of the rays leaving into each bin (the mirror tally)
    weights: np.ndarray  # (T, M, M, C) Σ c(ψ) × Fresnel path weight
    counts_sq: np.ndarray | None  # (M, M) Σ c(ψ)², None on the GPU path
    weights_sq: np.ndarray | None  # (T, M, M, C) sums of squared weights (variance), None on the GPU path
    lost: np.ndarray  # (M,) lost rays per column
    max_bounces: int = 0  # the most reflections of a tallied ray (−1: not recorded, GPU)


def phi_bins(size: int) -> np.ndarray:
    """Bin centres over (−π/2, π/2)."""
    return -0.5 * np.pi + (np.arange(size) + 0.5) * np.pi / size


def column_weight(psi, column, size: int) -> np.ndarray:
    """c(ψ) = cos ψ / c̄_j of a ray of column j (see :class:`Tallies`)."""
    half = 0.5 * np.pi / size
    return np.cos(psi) / (np.cos(phi_bins(size)[column]) * np.sin(half) / half)


def stratified_phi(column, rank, rays: int, size: int, u) -> np.ndarray:
    """φ_in of ray ``rank`` < ``rays`` of ``column``: stratified jitter inside the bin."""
    return -0.5 * np.pi + (column + (rank + u) / rays) * np.pi / size


def bin_of(phi, size: int) -> np.ndarray:
    return np.clip(np.floor((np.asarray(phi) + 0.5 * np.pi) * size / np.pi).astype(np.int64), 0, size - 1)


def trace_table(
    profile: Profile,
    *,
    size: int = 256,
    rays: int = 10000,
    fresnel: FresnelSpec | None = None,
    thetas=THETAS,
    seed: int = 0,
    max_bounces: int = MAX_BOUNCES,
    columns=None,
) -> Tallies:
    """Trace ``rays`` rays per φ_in bin (φ_in stratified inside the bin, x0 ~ U[0, 1)) and tally them.

    ``columns`` restricts the trace to some φ_in bins (the others stay empty)."""
    fresnel = fresnel or FresnelSpec()
    M, N = int(size), int(rays)
    if M < 2 or N < 1:
        raise ArgumentError(f"size must be ≥ 2 and rays ≥ 1, got {M}, {N}", field="size")
    rng = np.random.default_rng(seed)
    T, C = len(thetas), fresnel.channels
    counts = np.zeros(M * M)
    csq = np.zeros(M * M)
    wsum = np.zeros((T, C, M * M))
    wsq = np.zeros((T, C, M * M))
    lost = np.zeros(M)
    cols = np.arange(M) if columns is None else np.asarray(columns, dtype=np.int64)
    column = np.repeat(cols, N)
    rank = np.tile(np.arange(N), cols.size)
    most = 0
    for start in range(0, column.size, _CHUNK):
        j = column[start : start + _CHUNK]
        phi_in = stratified_phi(j, rank[start : start + _CHUNK], N, M, rng.random(j.size))
        x0 = rng.random(j.size)
        res = trace_rays(profile, phi_in, x0, fresnel=fresnel, thetas=thetas, max_bounces=max_bounces)
        ok = ~res.lost
        lost += np.bincount(j[~ok], minlength=M)
        flat = bin_of(res.phi_out[ok], M) * M + j[ok]
        cw = column_weight(phi_in[ok], j[ok], M)
        counts += np.bincount(flat, weights=cw, minlength=M * M)
        csq += np.bincount(flat, weights=cw * cw, minlength=M * M)
        for t in range(T):
            for ch in range(C):
                w = res.weights[ok, t, ch] * cw
                wsum[t, ch] += np.bincount(flat, weights=w, minlength=M * M)
                wsq[t, ch] += np.bincount(flat, weights=w * w, minlength=M * M)
        if ok.any():
            most = max(most, int(res.bounces[ok].max()))
    shape = (M, M)
    return Tallies(
        size=M,
        rays=N,
        thetas=tuple(float(t) for t in thetas),
        counts=counts.reshape(shape),
        weights=np.moveaxis(wsum.reshape(T, C, M, M), 1, -1),
        counts_sq=csq.reshape(shape),
        weights_sq=np.moveaxis(wsq.reshape(T, C, M, M), 1, -1),
        lost=lost,
        max_bounces=most,
    )
