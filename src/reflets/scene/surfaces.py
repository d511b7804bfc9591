"""Parametric reflectors ``f(u, v)`` with analytic first and second derivatives, for the Fermat search.

The per-vertex reflection search (issue 6) needs, at any ``(u, v)``, the point ``f``, the tangents ``f_u``,
``f_v`` (gradient of the path length) and ``f_uu``, ``f_uv``, ``f_vv`` (its Hessian, for Newton steps). Every
method is vectorised over arrays of ``(u, v)`` of any common shape and returns float64 ``(..., 3)`` arrays, so
the same per-element arithmetic ports one-to-one to a vertex shader.

Conventions, shared with :mod:`reflets.scene.shapes` so the GPU meshes and these surfaces agree:

* every domain is ``[0, 1]²`` (texture coordinates); a periodic direction accepts any real value (the
  formulas wrap by themselves), a non-periodic one is clamped by :meth:`Surface.clamp`;
* sphere / ellipsoid ``f = c + D (sinθ sinφ, cosθ, sinθ cosφ)`` with ``φ = 2πu``, ``θ = πv`` (v = 0 at +y);
  cylinder side ``(r sinφ, h/2 − h v, r cosφ)``; torus ``((R + r cosθ) sinφ, r sinθ, (R + r cosθ) cosφ)``
  with ``θ = 2πv``;
* :meth:`Surface.normal` is the unit outward normal for closed surfaces and ``unit(f_u × f_v)`` for open
  ones (``orientation`` flips the lat-long charts, whose ``f_u × f_v`` points inwards).

Closed surfaces give an interior point O for the document's initialisation ``A = [V, O] ∩ S``,
``B = [E, O] ∩ S``; open ones give a point behind them, which plays the same role for a viewer in front.
"""

from __future__ import annotations

import math

import numpy as np

TWO_PI = 2.0 * math.pi


# ------------------------------------------------------------------------------------------------- helpers
def _vec(x, y, z) -> np.ndarray:
    x, y, z = np.broadcast_arrays(x, y, z)
    return np.stack([x, y, z], axis=-1)


def _dot(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    return np.sum(a * b, axis=-1)


def _unit(a: np.ndarray, eps: float = 1e-300) -> np.ndarray:
    """Normalise along the last axis; zero vectors stay (near) zero instead of becoming NaN."""
    return a / np.maximum(np.linalg.norm(a, axis=-1, keepdims=True), eps)


def _uv(u, v) -> tuple[np.ndarray, np.ndarray]:
    u, v = np.broadcast_arrays(np.asarray(u, dtype=np.float64), np.asarray(v, dtype=np.float64))
    return u, v


def _solve3(m: np.ndarray, rhs: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Solve batched 3×3 systems by Cramer's rule (as a shader would); ``ok`` is False where singular.

    ``m`` is (N, 3, 3) with the unknowns' columns in ``m[..., :, k]``; singular rows get a zero solution.
    """
    c0, c1, c2 = m[..., :, 0], m[..., :, 1], m[..., :, 2]
    det = _dot(c0, np.cross(c1, c2))
    scale = np.linalg.norm(c0, axis=-1) * np.linalg.norm(c1, axis=-1) * np.linalg.norm(c2, axis=-1)
    ok = np.isfinite(det) & (np.abs(det) > 1e-14 * scale)
    d = np.where(ok, det, 1.0)
    x = np.stack([_dot(rhs, np.cross(c1, c2)), _dot(c0, np.cross(rhs, c2)), _dot(c0, np.cross(c1, rhs))], -1)
    return np.where(ok[..., None], x / d[..., None], 0.0), ok


# The global lat-long parameterisation written as a frame: s = sinθcosφ e1 + sinθsinφ e2 + cosθ e3 with
# (e1, e2, e3) = (z, x, y) gives (sinθ sinφ, cosθ, sinθ cosφ), the convention of reflets.scene.shapes.sphere.
GLOBAL_FRAME = np.array([[0.0, 1.0, 0.0], [0.0, 0.0, 1.0], [1.0, 0.0, 0.0]])


def _frame_sphere(frame: np.ndarray, u: np.ndarray, v: np.ndarray, order: int):
    """Unit-sphere point and derivatives in a lat-long chart whose pole is ``frame[:, 2]``.

    ``φ = 2πu`` around the pole from ``e1`` towards ``e2``, ``θ = πv`` from the pole. Returns ``[s]``,
    ``[s, s_u, s_v]`` or ``[s, s_u, s_v, s_uu, s_uv, s_vv]`` (world directions, derivatives w.r.t. u, v).
    """
    phi, theta = TWO_PI * u, math.pi * v
    sp, cp, st, ct = np.sin(phi), np.cos(phi), np.sin(theta), np.cos(theta)
    zero = np.zeros_like(sp)
    loc = [_vec(st * cp, st * sp, ct)]
    if order >= 1:
        loc += [TWO_PI * _vec(-st * sp, st * cp, zero), math.pi * _vec(ct * cp, ct * sp, -st)]
    if order >= 2:
        loc += [
            TWO_PI**2 * _vec(-st * cp, -st * sp, zero),
            TWO_PI * math.pi * _vec(-ct * sp, ct * cp, zero),
            math.pi**2 * _vec(-st * cp, -st * sp, -ct),
        ]
    return [np.einsum("...ij,...j->...i", frame, x) for x in loc]


def _frame_inverse(frame: np.ndarray, d: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Chart coordinates ``(u, v)`` of unit directions ``d`` in the lat-long chart of ``frame``."""
    loc = np.einsum("...ji,...j->...i", frame, d)  # frameᵀ d
    u = np.mod(np.arctan2(loc[..., 1], loc[..., 0]) / TWO_PI, 1.0)
    v = np.arccos(np.clip(loc[..., 2], -1.0, 1.0)) / math.pi
    return u, v


def _by_order(contract, order: int) -> list[np.ndarray]:
    """``[f]``, then ``f_u, f_v``, then ``f_uu, f_uv, f_vv`` from ``contract(a, b)`` = ∂^{a+b} f / ∂u^a ∂v^b."""
    out = [contract(0, 0)]
    if order >= 1:
        out += [contract(1, 0), contract(0, 1)]
    if order >= 2:
        out += [contract(2, 0), contract(1, 1), contract(0, 2)]
    return out


# ------------------------------------------------------------------------------------------- cubic grids
def _catmull_rom(t: np.ndarray, order: int) -> np.ndarray:
    """Catmull–Rom weights of the 4 nodes around a cell (or their 1st / 2nd derivatives), shape (..., 4)."""
    if order == 0:
        w = [-t + 2 * t**2 - t**3, 2 - 5 * t**2 + 3 * t**3, t + 4 * t**2 - 3 * t**3, -(t**2) + t**3]
    elif order == 1:
        w = [-1 + 4 * t - 3 * t**2, -10 * t + 9 * t**2, 1 + 8 * t - 9 * t**2, -2 * t + 3 * t**2]
    else:
        w = [4 - 6 * t, -10 + 18 * t, 8 - 18 * t, -2 + 6 * t]
    return 0.5 * np.stack(np.broadcast_arrays(*w), axis=-1)


def _linear(t: np.ndarray, order: int) -> np.ndarray:
    """Linear-interpolation weights on the same 4-node stencil (outer nodes weigh 0)."""
    z = np.zeros_like(t)
    if order == 0:
        w = [z, 1 - t, t, z]
    elif order == 1:
        w = [z, z - 1, z + 1, z]
    else:
        w = [z, z, z, z]
    return np.stack(w, axis=-1)


class GridInterpolator:
    """Bilinear or Catmull–Rom bicubic interpolation of a ``(n_v, n_u, C)`` grid over ``[0, 1]²``.

    Node placement mirrors a float texture: a periodic direction has ``n`` nodes at ``k / n`` (wrap
    addressing), a clamped one ``n`` nodes at ``k / (n − 1)`` so both edges are sampled exactly. The grid is
    padded once with one ghost node before and two after (wrapped, or linearly extrapolated on clamped
    edges, so the edge tangent is not flattened); every lookup then reads the 4×4 stencil ``i..i+3``.
    Catmull–Rom is C1, so the Fermat gradient is continuous; its second derivatives jump across cells.
    """

    def __init__(self, grid: np.ndarray, periodic: tuple[bool, bool], kind: str = "bicubic"):
        if kind not in ("bilinear", "bicubic"):
            raise ValueError(f"interpolation must be 'bilinear' or 'bicubic', got {kind!r}")
        g = np.asarray(grid, dtype=np.float64)
        if g.ndim == 2:
            g = g[..., None]
        if g.shape[0] < 2 or g.shape[1] < 2:
            raise ValueError(f"a grid needs at least 2 × 2 nodes, got {g.shape[:2]}")
        self.kind, self.periodic = kind, periodic
        self.n_v, self.n_u = g.shape[:2]
        self.channels = g.shape[2]
        self.grid = self._pad(self._pad(g, 1, periodic[0]), 0, periodic[1])

    @staticmethod
    def _pad(g: np.ndarray, axis: int, periodic: bool) -> np.ndarray:
        if periodic:
            return np.pad(g, [(1, 2) if a == axis else (0, 0) for a in range(3)], mode="wrap")
        first, second = np.take(g, [0], axis), np.take(g, [1], axis)
        last, before = np.take(g, [-1], axis), np.take(g, [-2], axis)
        after = 2 * last - before
        return np.concatenate([2 * first - second, g, after, 2 * after - last], axis=axis)

    def _cell(self, x: np.ndarray, n: int, periodic: bool) -> tuple[np.ndarray, np.ndarray, float]:
        """Cell index into the padded grid, fraction in the cell, and d(grid coordinate)/d(parameter)."""
        if periodic:
            s = x * n
            i = np.floor(s)
            return np.mod(i, n).astype(np.intp), s - i, float(n)
        s = np.clip(x, 0.0, 1.0) * (n - 1)
        i = np.minimum(np.floor(s), n - 2)
        return i.astype(np.intp), s - i, float(n - 1)

    def __call__(self, u, v, order: int = 0) -> list[np.ndarray]:
        """Value, then (order ≥ 1) d/du, d/dv, then (order ≥ 2) d²/du², d²/dudv, d²/dv², each (..., C)."""
        u, v = _uv(u, v)
        iu, tu, su = self._cell(u, self.n_u, self.periodic[0])
        iv, tv, sv = self._cell(v, self.n_v, self.periodic[1])
        k = np.arange(4)
        patch = self.grid[(iv[..., None] + k)[..., :, None], (iu[..., None] + k)[..., None, :]]  # (..., 4, 4, C)
        weights = _catmull_rom if self.kind == "bicubic" else _linear
        wu = [weights(tu, o) for o in range(order + 1)]
        wv = [weights(tv, o) for o in range(order + 1)]

        def contract(a: int, b: int) -> np.ndarray:
            return np.einsum("...j,...i,...jic->...c", wv[b], wu[a], patch) * (su**a * sv**b)

        return _by_order(contract, order)


# ---------------------------------------------------------------------------------------------- surfaces
class Surface:
    """A parametric reflector over ``[0, 1]²``; subclasses implement :meth:`_eval`.

    Attributes
    ----------
    periodic : (bool, bool)
        Whether u, v wrap (no clamping, seams are unwrapped by the solvers).
    closed : bool
        Whether the surface bounds a volume (then ``normal`` points out of it).
    orientation : float
        ±1 so that ``normal = orientation · unit(f_u × f_v)``.
    """

    periodic: tuple[bool, bool] = (False, False)
    closed: bool = False
    orientation: float = 1.0
    domain: tuple[tuple[float, float], tuple[float, float]] = ((0.0, 1.0), (0.0, 1.0))
    #: Cells of the coarse grid that seeds the generic segment intersection.
    hit_grid: int = 16

    # -- to implement
    def _eval(self, u: np.ndarray, v: np.ndarray, order: int) -> list[np.ndarray]:
        """``[f]``, ``[f, f_u, f_v]`` or ``[f, f_u, f_v, f_uu, f_uv, f_vv]`` at broadcast (u, v)."""
        raise NotImplementedError

    # -- evaluation
    def position(self, u, v) -> np.ndarray:
        return self._eval(*_uv(u, v), 0)[0]

    def derivatives(self, u, v) -> tuple[np.ndarray, np.ndarray]:
        _, fu, fv = self._eval(*_uv(u, v), 1)
        return fu, fv

    def second_derivatives(self, u, v) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        _, _, _, fuu, fuv, fvv = self._eval(*_uv(u, v), 2)
        return fuu, fuv, fvv

    def evaluate(self, u, v, order: int = 2) -> list[np.ndarray]:
        """Position and derivatives up to ``order`` in one pass (what the solvers call)."""
        return self._eval(*_uv(u, v), order)

    def normal(self, u, v) -> np.ndarray:
        fu, fv = self.derivatives(u, v)
        return self.orientation * _unit(np.cross(fu, fv))

    # -- domain
    def clamp(self, u, v) -> tuple[np.ndarray, np.ndarray]:
        """Clamp the non-periodic directions to the domain; periodic ones stay unwrapped."""
        u, v = _uv(u, v)
        (u0, u1), (v0, v1) = self.domain
        return (u if self.periodic[0] else np.clip(u, u0, u1)), (v if self.periodic[1] else np.clip(v, v0, v1))

    def wrap(self, u, v) -> tuple[np.ndarray, np.ndarray]:
        """Bring periodic directions back to [0, 1) and clamp the others."""
        u, v = self.clamp(u, v)
        return (np.mod(u, 1.0) if self.periodic[0] else u), (np.mod(v, 1.0) if self.periodic[1] else v)

    def contains(self, u, v, tol: float = 1e-9) -> np.ndarray:
        """True where (u, v) lies in the domain (periodic directions always do)."""
        u, v = _uv(u, v)
        (u0, u1), (v0, v1) = self.domain
        ok_u = np.ones(u.shape, bool) if self.periodic[0] else (u >= u0 - tol) & (u <= u1 + tol)
        ok_v = np.ones(v.shape, bool) if self.periodic[1] else (v >= v0 - tol) & (v <= v1 + tol)
        return ok_u & ok_v

    # -- initialisation support
    @property
    def interior(self) -> np.ndarray:
        """The point O: inside a closed surface, behind an open one."""
        raise NotImplementedError

    def interior_point(self, E, V) -> np.ndarray:
        """O for each eye / vertex pair, (N, 3); a constant unless the surface (a torus) needs it to vary."""
        E = np.asarray(E, dtype=np.float64)
        shape = np.broadcast_shapes(E.shape, np.shape(V))
        return np.broadcast_to(self.interior, shape).copy()

    def segment_hit(self, P, O=None) -> tuple[np.ndarray, np.ndarray]:
        """(u, v) where the segment from P (outside) towards O (inside / behind) first meets the surface.

        Generic fallback: seed at the node of a coarse ``hit_grid²`` grid nearest to the segment, then 16
        Newton steps (each at most half a coarse cell in (u, v)) on ``f(u, v) = P + t (O − P)`` (3 equations,
        unknowns u, v, t). It finds *a* crossing near the segment, not necessarily the first, and can miss a
        grazing one. Subclasses with a closed form or an implicit equation override it.
        """
        P = np.asarray(P, dtype=np.float64)
        O = np.broadcast_to(self.interior if O is None else np.asarray(O, dtype=np.float64), P.shape)
        flat_p, flat_o = P.reshape(-1, 3), O.reshape(-1, 3)
        g = self.hit_grid
        gu, gv = np.meshgrid(np.linspace(0, 1, g + 1), np.linspace(0, 1, g + 1), indexing="xy")
        X = self.position(gu.ravel(), gv.ravel())  # (M, 3)
        D = flat_o - flat_p
        dd = np.maximum(_dot(D, D), 1e-300)[:, None]
        t = np.clip((X @ D.T).T / dd - (_dot(flat_p, D)[:, None] / dd), 0.0, 1.0)  # (N, M)
        dist2 = (
            _dot(X, X)[None, :]
            + _dot(flat_p, flat_p)[:, None]
            + t**2 * dd
            - 2 * (flat_p @ X.T)
            - 2 * t * (D @ X.T)
            + 2 * t * _dot(flat_p, D)[:, None]
        )
        best = np.argmin(dist2, axis=1)
        u, v, s = gu.ravel()[best], gv.ravel()[best], t[np.arange(len(best)), best]
        for _ in range(16):
            f, fu, fv = self.evaluate(u, v, 1)
            F = f - flat_p - s[:, None] * D
            step, ok = _solve3(np.stack([fu, fv, -D], axis=-1), -F)
            # At most half a coarse cell per step, so that a wild first step cannot jump to another sheet.
            step *= np.minimum(1.0, 0.5 / g / np.maximum(np.linalg.norm(step[:, :2], axis=-1), 1e-300))[:, None]
            u, v = self.clamp(u + step[:, 0], v + step[:, 1])
            s = np.clip(s + step[:, 2], 0.0, 1.0)
        u, v = self.wrap(u, v)
        return u.reshape(P.shape[:-1]), v.reshape(P.shape[:-1])

    # -- solver support
    def chart(self, a_uv, b_uv) -> Chart:
        """A local chart around the arc A → B in which the solvers iterate; the identity by default."""
        return IdentityChart(self, a_uv, b_uv)


class ImplicitSurface(Surface):
    """A surface that is also the zero set of ``implicit(x)`` (< 0 inside / behind) and can invert ``f``."""

    #: March steps then bisection steps of the implicit segment intersection.
    march_steps: int = 32
    bisection_steps: int = 48

    def implicit(self, x: np.ndarray) -> np.ndarray:
        raise NotImplementedError

    def uv_of(self, x: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """(u, v) of a point on (or projected onto) the surface."""
        raise NotImplementedError

    def segment_hit(self, P, O=None) -> tuple[np.ndarray, np.ndarray]:
        """March from P towards O to the first sign change of ``implicit``, then bisect (fixed counts)."""
        P = np.asarray(P, dtype=np.float64)
        O = np.broadcast_to(self.interior if O is None else np.asarray(O, dtype=np.float64), P.shape)
        D = O - P
        ts = np.linspace(0.0, 1.0, self.march_steps + 1)
        F = self.implicit(P[..., None, :] + ts[:, None] * D[..., None, :])  # (..., steps + 1)
        change = np.signbit(F[..., 1:]) != np.signbit(F[..., :1])
        k = np.where(change.any(axis=-1), np.argmax(change, axis=-1), self.march_steps - 1)
        lo, hi = ts[k], ts[k + 1]
        f_lo = np.take_along_axis(F, k[..., None], axis=-1)[..., 0]
        for _ in range(self.bisection_steps):
            mid = 0.5 * (lo + hi)
            f_mid = self.implicit(P + mid[..., None] * D)
            same = np.signbit(f_mid) == np.signbit(f_lo)
            lo, hi = np.where(same, mid, lo), np.where(same, hi, mid)
            f_lo = np.where(same, f_mid, f_lo)
        return self.uv_of(P + (0.5 * (lo + hi))[..., None] * D)


class Plane(Surface):
    """A flat rectangle ``f = point + (u − ½) axis_u + (v − ½) axis_v``; normal ``unit(axis_u × axis_v)``."""

    def __init__(self, point=(0.0, 0.0, 0.0), axis_u=(2.0, 0.0, 0.0), axis_v=(0.0, 0.0, -2.0)):
        self.point = np.asarray(point, dtype=np.float64)
        self.axis_u = np.asarray(axis_u, dtype=np.float64)
        self.axis_v = np.asarray(axis_v, dtype=np.float64)
        cross = np.cross(self.axis_u, self.axis_v)
        if not np.linalg.norm(cross) > 0:
            raise ValueError("axis_u and axis_v must span a plane")
        self.unit_normal = cross / np.linalg.norm(cross)

    def _eval(self, u, v, order):
        f = self.point + (u - 0.5)[..., None] * self.axis_u + (v - 0.5)[..., None] * self.axis_v
        out = [f]
        if order >= 1:
            out += [np.broadcast_to(self.axis_u, f.shape), np.broadcast_to(self.axis_v, f.shape)]
        if order >= 2:
            out += [np.zeros_like(f)] * 3
        return out

    def normal(self, u, v):
        return np.broadcast_to(self.unit_normal, _uv(u, v)[0].shape + (3,)).copy()

    @property
    def interior(self):
        size = np.linalg.norm(self.axis_u) + np.linalg.norm(self.axis_v)
        return self.point - size * self.unit_normal

    def segment_hit(self, P, O=None):
        """Closed form: intersect the line with the plane, express the point in (axis_u, axis_v)."""
        P = np.asarray(P, dtype=np.float64)
        O = np.broadcast_to(self.interior if O is None else np.asarray(O, dtype=np.float64), P.shape)
        D = O - P
        den = _dot(D, self.unit_normal)
        t = _dot(self.point - P, self.unit_normal) / np.where(np.abs(den) > 1e-300, den, 1e-300)
        x = P + np.clip(t, 0.0, 1.0)[..., None] * D - self.point
        g = np.array([[self.axis_u @ self.axis_u, self.axis_u @ self.axis_v], [0.0, self.axis_v @ self.axis_v]])
        g[1, 0] = g[0, 1]
        rhs = np.stack([x @ self.axis_u, x @ self.axis_v]).reshape(2, -1)
        a = np.linalg.solve(g, rhs).reshape(2, *x.shape[:-1])
        return self.clamp(a[0] + 0.5, a[1] + 0.5)


class Ellipsoid(ImplicitSurface):
    """An axis-aligned ellipsoid ``c + D s(u, v)``, ``D = diag(radii)``, lat-long about +y (poles at v = 0, 1).

    Its chart (:meth:`chart`) is the same lat-long parameterisation rotated so that its equator passes
    through A and B: the pole, where ``f_u = 0`` and the Hessian degenerates, is then 90° from the arc the
    reflection lies on (exactly on it for a sphere).
    """

    periodic = (True, False)
    closed = True
    orientation = -1.0

    def __init__(self, center=(0.0, 0.0, 0.0), radii=(1.0, 1.0, 1.0)):
        self.center = np.asarray(center, dtype=np.float64)
        self.radii = np.broadcast_to(np.asarray(radii, dtype=np.float64), (3,)).copy()
        if not np.all(self.radii > 0):
            raise ValueError(f"radii must be > 0, got {radii!r}")

    def _eval(self, u, v, order):
        s = _frame_sphere(GLOBAL_FRAME, u, v, order)
        return [self.center + self.radii * s[0]] + [self.radii * x for x in s[1:]]

    def normal(self, u, v):
        """Gradient of ``|D⁻¹(x − c)|²``: defined at the poles too, where ``f_u × f_v`` vanishes."""
        s = _frame_sphere(GLOBAL_FRAME, *_uv(u, v), 0)[0]
        return _unit(s / self.radii)

    @property
    def interior(self):
        return self.center

    def implicit(self, x):
        q = (np.asarray(x) - self.center) / self.radii
        return _dot(q, q) - 1.0

    def uv_of(self, x):
        return _frame_inverse(GLOBAL_FRAME, _unit((np.asarray(x) - self.center) / self.radii))

    def segment_hit(self, P, O=None):
        """Closed form: in the scaled space the ellipsoid is the unit sphere; take the first root in [0, 1]."""
        P = np.asarray(P, dtype=np.float64)
        O = np.broadcast_to(self.interior if O is None else np.asarray(O, dtype=np.float64), P.shape)
        p, d = (P - self.center) / self.radii, (O - P) / self.radii
        a, b, c = _dot(d, d), _dot(p, d), _dot(p, p) - 1.0
        disc = b * b - a * c
        t = (-b - np.sqrt(np.maximum(disc, 0.0))) / np.maximum(a, 1e-300)
        t = np.where((disc >= 0) & (t >= 0), t, np.where(c < 0, 0.0, -b / np.maximum(a, 1e-300)))
        return _frame_inverse(GLOBAL_FRAME, _unit(p + np.clip(t, 0.0, 1.0)[..., None] * d))

    def chart(self, a_uv, b_uv):
        return SphereChart(self, a_uv, b_uv)


class Sphere(Ellipsoid):
    """A sphere: an ellipsoid with equal radii (kept separate for the analytic references)."""

    def __init__(self, center=(0.0, 0.0, 0.0), radius: float = 1.0):
        if not radius > 0:
            raise ValueError(f"radius must be > 0, got {radius!r}")
        super().__init__(center, (radius, radius, radius))
        self.radius = float(radius)


class Cylinder(ImplicitSurface):
    """The side of a cylinder along y: ``c + (r sinφ, h/2 − h v, r cosφ)``, open at both ends.

    O is taken on the axis at the eye / vertex mean height (clamped to the cylinder), so that [P, O] meets
    the side rather than leaving through an open end.
    """

    periodic = (True, False)
    closed = True
    orientation = -1.0

    def __init__(self, center=(0.0, 0.0, 0.0), radius: float = 1.0, height: float = 2.0):
        self.center = np.asarray(center, dtype=np.float64)
        self.radius, self.height = float(radius), float(height)
        if not (self.radius > 0 and self.height > 0):
            raise ValueError("radius and height must be > 0")

    def _eval(self, u, v, order):
        phi = TWO_PI * u
        sp, cp, zero = np.sin(phi), np.cos(phi), np.zeros_like(u)
        r, h = self.radius, self.height
        out = [self.center + _vec(r * sp, 0.5 * h - h * v, r * cp)]
        if order >= 1:
            out += [TWO_PI * r * _vec(cp, zero, -sp), _vec(zero, zero - h, zero)]
        if order >= 2:
            out += [-(TWO_PI**2) * r * _vec(sp, zero, cp), _vec(zero, zero, zero), _vec(zero, zero, zero)]
        return out

    @property
    def interior(self):
        return self.center

    def interior_point(self, E, V):
        E, V = np.broadcast_arrays(np.asarray(E, dtype=np.float64), np.asarray(V, dtype=np.float64))
        y = np.clip(0.5 * (E[..., 1] + V[..., 1]) - self.center[1], -0.5 * self.height, 0.5 * self.height)
        return self.center + _vec(np.zeros_like(y), y, np.zeros_like(y))

    def implicit(self, x):
        q = np.asarray(x) - self.center
        return (q[..., 0] ** 2 + q[..., 2] ** 2) / self.radius**2 - 1.0

    def uv_of(self, x):
        q = np.asarray(x) - self.center
        u = np.mod(np.arctan2(q[..., 0], q[..., 2]) / TWO_PI, 1.0)
        return self.clamp(u, 0.5 - q[..., 1] / self.height)

    def segment_hit(self, P, O=None):
        """Closed form in the xz plane; a segment that misses the side (enters through an end) is projected."""
        P = np.asarray(P, dtype=np.float64)
        O = np.broadcast_to(self.interior if O is None else np.asarray(O, dtype=np.float64), P.shape)
        p, d = (P - self.center)[..., [0, 2]], (O - P)[..., [0, 2]]
        a, b, c = _dot(d, d), _dot(p, d), _dot(p, p) - self.radius**2
        disc = b * b - a * c
        t = (-b - np.sqrt(np.maximum(disc, 0.0))) / np.maximum(a, 1e-300)
        t = np.where((disc >= 0) & (t >= 0), np.clip(t, 0.0, 1.0), 0.0)
        return self.uv_of(P + t[..., None] * (O - P))


class Torus(ImplicitSurface):
    """A ring torus about y: ``c + ((R + r cosθ) sinφ, r sinθ, (R + r cosθ) cosφ)``, ``θ = 2πv``.

    Both directions are periodic and the parameterisation is regular everywhere, so the identity chart
    (with seams unwrapped) serves. The centre is not inside the torus: O is the point of the core circle
    at the azimuth of the eye / vertex midpoint.
    """

    periodic = (True, True)
    closed = True
    orientation = 1.0

    def __init__(self, center=(0.0, 0.0, 0.0), major: float = 1.0, minor: float = 0.25):
        self.center = np.asarray(center, dtype=np.float64)
        self.major, self.minor = float(major), float(minor)
        if not 0 < self.minor < self.major:
            raise ValueError("a ring torus needs 0 < minor < major")

    def _eval(self, u, v, order):
        phi, theta = TWO_PI * u, TWO_PI * v
        sp, cp, st, ct = np.sin(phi), np.cos(phi), np.sin(theta), np.cos(theta)
        R, r, zero = self.major, self.minor, np.zeros_like(u)
        w = R + r * ct
        out = [self.center + _vec(w * sp, r * st, w * cp)]
        if order >= 1:
            out += [TWO_PI * w[..., None] * _vec(cp, zero, -sp), TWO_PI * r * _vec(-st * sp, ct, -st * cp)]
        if order >= 2:
            k = TWO_PI**2
            out += [
                -k * w[..., None] * _vec(sp, zero, cp),
                -k * r * st[..., None] * _vec(cp, zero, -sp),
                -k * r * _vec(ct * sp, st, ct * cp),
            ]
        return out

    @property
    def interior(self):
        return self.center + np.array([0.0, 0.0, self.major])

    def interior_point(self, E, V):
        E, V = np.broadcast_arrays(np.asarray(E, dtype=np.float64), np.asarray(V, dtype=np.float64))
        m = 0.5 * (E + V) - self.center
        phi = np.arctan2(m[..., 0], m[..., 2])
        return self.center + self.major * _vec(np.sin(phi), np.zeros_like(phi), np.cos(phi))

    def implicit(self, x):
        q = np.asarray(x) - self.center
        rho = np.hypot(q[..., 0], q[..., 2])
        return (rho - self.major) ** 2 + q[..., 1] ** 2 - self.minor**2

    def uv_of(self, x):
        q = np.asarray(x) - self.center
        u = np.mod(np.arctan2(q[..., 0], q[..., 2]) / TWO_PI, 1.0)
        v = np.mod(np.arctan2(q[..., 1], np.hypot(q[..., 0], q[..., 2]) - self.major) / TWO_PI, 1.0)
        return u, v


def _bernstein(t: np.ndarray, order: int) -> np.ndarray:
    """Cubic Bernstein basis (or its derivatives), shape (..., 4)."""
    s = 1.0 - t
    if order == 0:
        b = [s**3, 3 * t * s**2, 3 * t**2 * s, t**3]
    elif order == 1:
        b = [-3 * s**2, 3 * s**2 - 6 * t * s, 6 * t * s - 3 * t**2, 3 * t**2]
    else:
        b = [6 * s, -12 * s + 6 * t, 6 * s - 12 * t, 6 * t]
    return np.stack(np.broadcast_arrays(*b), axis=-1)


class BezierPatch(Surface):
    """A bicubic Bézier patch; ``control[i, j]`` multiplies ``B_i(u) B_j(v)``; normal ``unit(f_u × f_v)``."""

    def __init__(self, control, interior=None):
        self.control = np.asarray(control, dtype=np.float64)
        if self.control.shape != (4, 4, 3):
            raise ValueError(f"control points must be 4 × 4 × 3, got {self.control.shape}")
        self._interior = None if interior is None else np.asarray(interior, dtype=np.float64)

    def _eval(self, u, v, order):
        bu = [_bernstein(u, o) for o in range(order + 1)]
        bv = [_bernstein(v, o) for o in range(order + 1)]

        def contract(a: int, b: int) -> np.ndarray:
            return np.einsum("...i,...j,ijc->...c", bu[a], bv[b], self.control)

        return _by_order(contract, order)

    @property
    def interior(self):
        """Given, or the patch centre pushed back along its normal by the control polygon's size."""
        if self._interior is not None:
            return self._interior
        size = np.ptp(self.control.reshape(-1, 3), axis=0).max()
        return self.position(0.5, 0.5) - size * self.normal(0.5, 0.5)


class HeightField(ImplicitSurface):
    """``z = h(x, y)`` sampled on a regular grid, Catmull–Rom bicubic (C1), ``f(u, v) = (x, y, h)``.

    ``heights[j, i]`` is the height at ``x = x0 + i (x1 − x0)/(n_x − 1)``, ``y = y0 + j (y1 − y0)/(n_y − 1)``;
    u runs along x, v along y, so ``f_u × f_v`` (the normal) has a positive z component.

    ``up = "y"`` lays the same field in a y-up world, ``f(u, v) = (x, h, z)``, the second range running along z
    (scene height fields: ``y = h(x, z)``). With a decreasing z range (v along −z, as on the scene's planes)
    ``f_u × f_v`` points to +y; ``implicit`` is negative below the field either way.
    """

    def __init__(self, heights, x_range=(-1.0, 1.0), y_range=(-1.0, 1.0), up: str = "z"):
        self.heights = np.asarray(heights, dtype=np.float64)
        if self.heights.ndim != 2:
            raise ValueError("heights must be a 2D array (n_y, n_x)")
        if up not in ("y", "z"):
            raise ValueError(f"up must be 'y' or 'z', got {up!r}")
        self.up, self._axis = up, (1 if up == "y" else 2)
        self.x_range, self.y_range = tuple(map(float, x_range)), tuple(map(float, y_range))
        self._h = GridInterpolator(self.heights, (False, False), "bicubic")
        self._lx = self.x_range[1] - self.x_range[0]
        self._ly = self.y_range[1] - self.y_range[0]

    def _place(self, a, b, h) -> np.ndarray:
        """World vector from the grid's two axes and the height axis."""
        return _vec(a, h, b) if self.up == "y" else _vec(a, b, h)

    def _eval(self, u, v, order):
        parts = [p[..., 0] for p in self._h(u, v, order)]
        x, y = self.x_range[0] + self._lx * u, self.y_range[0] + self._ly * v
        zero = np.zeros_like(parts[0])
        out = [self._place(x, y, parts[0])]
        if order >= 1:
            out += [self._place(zero + self._lx, zero, parts[1]), self._place(zero, zero + self._ly, parts[2])]
        if order >= 2:
            out += [self._place(zero, zero, p) for p in parts[3:]]
        return out

    @property
    def interior(self):
        extent = max(abs(self._lx), abs(self._ly))
        return self._place(np.mean(self.x_range), np.mean(self.y_range), self.heights.min() - extent)

    def implicit(self, x):
        x = np.asarray(x)
        u, v = self.uv_of(x)
        return x[..., self._axis] - self._h(u, v)[0][..., 0]

    def uv_of(self, x):
        x = np.asarray(x)
        u = (x[..., 0] - self.x_range[0]) / self._lx
        v = (x[..., 3 - self._axis] - self.y_range[0]) / self._ly
        return self.clamp(u, v)


class SampledSurface(Surface):
    """A reflector stored as a position grid over (u, v), as the GPU keeps it in float textures.

    ``positions[j, i]`` is ``f`` at node ``(u_i, v_j)`` (see :class:`GridInterpolator` for node placement).
    With ``interpolation='bilinear'`` (hardware filtering) and only positions, ``f_u``, ``f_v`` are the
    derivatives of the bilinear interpolant (piecewise constant across cells); passing derivative grids
    (``derivatives=(f_u, f_v)``, the document's optional derivative textures) interpolates them instead.
    Second derivatives are always those of whichever interpolant gives the first derivatives.
    """

    def __init__(
        self,
        positions,
        periodic: tuple[bool, bool] = (False, False),
        interpolation: str = "bicubic",
        derivatives=None,
        orientation: float = 1.0,
        interior=None,
        closed: bool = False,
    ):
        self.positions = np.asarray(positions, dtype=np.float64)
        self.periodic, self.orientation, self.closed = tuple(periodic), float(orientation), closed
        self.interpolation = interpolation
        self._f = GridInterpolator(self.positions, self.periodic, interpolation)
        self._d = None
        if derivatives is not None:
            self._d = GridInterpolator(np.concatenate(derivatives, axis=-1), self.periodic, interpolation)
        self._interior = None if interior is None else np.asarray(interior, dtype=np.float64)
        self._interior_fn = None
        n_v, n_u = self.positions.shape[:2]
        self.hit_grid = max(4, min(32, n_u - 1, n_v - 1))

    @classmethod
    def from_surface(
        cls, surface: Surface, resolution: int | tuple[int, int], interpolation: str = "bicubic", derivatives=False
    ) -> SampledSurface:
        """Sample ``surface`` on an ``n_u × n_v`` node grid (optionally with derivative grids)."""
        n_u, n_v = (resolution, resolution) if np.isscalar(resolution) else resolution
        pu, pv = surface.periodic
        u = np.arange(n_u) / n_u if pu else np.linspace(0.0, 1.0, n_u)
        v = np.arange(n_v) / n_v if pv else np.linspace(0.0, 1.0, n_v)
        uu, vv = np.meshgrid(u, v, indexing="xy")
        f, fu, fv = surface.evaluate(uu, vv, 1)
        out = cls(
            f,
            surface.periodic,
            interpolation,
            derivatives=(fu, fv) if derivatives else None,
            orientation=surface.orientation,
            interior=surface.interior,
            closed=surface.closed,
        )
        out._interior_fn = surface.interior_point
        return out

    def _eval(self, u, v, order):
        f = self._f(u, v, order if self._d is None else 0)
        if self._d is None:
            return f
        d = self._d(u, v, max(order - 1, 0))
        out = [f[0]]
        if order >= 1:
            out += [d[0][..., :3], d[0][..., 3:]]
        if order >= 2:
            out += [d[1][..., :3], 0.5 * (d[2][..., :3] + d[1][..., 3:]), d[2][..., 3:]]
        return out

    @property
    def interior(self):
        if self._interior is None:
            raise ValueError("this sampled surface was given no interior point")
        return self._interior

    def interior_point(self, E, V):
        return super().interior_point(E, V) if self._interior_fn is None else self._interior_fn(E, V)


# ------------------------------------------------------------------------------------------------ charts
class Chart:
    """Per-element local coordinates ``(s, t)`` on a surface, in which the solvers iterate.

    Quacks like a :class:`Surface` for ``evaluate`` / ``clamp``; ``a`` and ``b`` are the chart coordinates
    of the initial points A and B ((N,) arrays each), and :meth:`to_uv` maps back to the global (u, v).
    """

    periodic: tuple[bool, bool]
    a: tuple[np.ndarray, np.ndarray]
    b: tuple[np.ndarray, np.ndarray]

    def evaluate(self, s, t, order: int = 2) -> list[np.ndarray]:
        raise NotImplementedError

    def clamp(self, s, t) -> tuple[np.ndarray, np.ndarray]:
        raise NotImplementedError

    def to_uv(self, s, t) -> tuple[np.ndarray, np.ndarray]:
        raise NotImplementedError

    def from_uv(self, u, v) -> tuple[np.ndarray, np.ndarray]:
        """Chart coordinates of global (u, v), periodic ones taken nearest the midpoint of A and B."""
        raise NotImplementedError

    def _near_middle(self, s, t) -> tuple[np.ndarray, np.ndarray]:
        ms, mt = 0.5 * (self.a[0] + self.b[0]), 0.5 * (self.a[1] + self.b[1])
        s = s - np.round(s - ms) if self.periodic[0] else s
        t = t - np.round(t - mt) if self.periodic[1] else t
        return s, t


class IdentityChart(Chart):
    """The global parameterisation, with B's periodic coordinates moved to the image nearest A."""

    def __init__(self, surface: Surface, a_uv, b_uv, unwrap: bool = True):
        self.surface, self.periodic = surface, surface.periodic
        ua, va = _uv(*a_uv)
        ub, vb = _uv(*b_uv)
        if unwrap:
            ub = ub - np.round(ub - ua) if surface.periodic[0] else ub
            vb = vb - np.round(vb - va) if surface.periodic[1] else vb
        self.a, self.b = (ua, va), (ub, vb)

    def evaluate(self, s, t, order=2):
        return self.surface.evaluate(*self.surface.clamp(s, t), order)

    def clamp(self, s, t):
        return self.surface.clamp(s, t)

    def to_uv(self, s, t):
        return self.surface.wrap(s, t)

    def from_uv(self, u, v):
        return self._near_middle(*_uv(u, v))


class SphereChart(Chart):
    """Lat-long chart of an ellipsoid whose equator is the great circle through A and B (in scaled space).

    ``e1 = Â``, ``e2`` = the unit part of ``B̂`` orthogonal to ``Â``, pole ``e3 = e1 × e2`` (any normal to
    ``Â`` when A = ±B). A is at ``(0, ½)``, B at ``(∠AB / 2π, ½)``. For a sphere the plane (E, V, centre)
    contains A and B, so the reflection lies on the chart's equator: the iteration never gets near a pole
    and the longitude never crosses a seam (it is not wrapped). Costs a 3×3 frame per vertex on the GPU.
    """

    periodic = (True, False)

    def __init__(self, surface: Ellipsoid, a_uv, b_uv):
        self.surface = surface
        da = _frame_sphere(GLOBAL_FRAME, *_uv(*a_uv), 0)[0]
        db = _frame_sphere(GLOBAL_FRAME, *_uv(*b_uv), 0)[0]
        w = db - _dot(db, da)[..., None] * da
        # Fallback normal to Â when A = ±B: cross with the axis least aligned with Â.
        axis = np.eye(3)[np.argmin(np.abs(da), axis=-1)]
        w = np.where(np.linalg.norm(w, axis=-1, keepdims=True) > 1e-12, w, np.cross(da, axis))
        e2 = _unit(w)
        self.frame = np.stack([da, e2, np.cross(da, e2)], axis=-1)
        angle = np.arctan2(_dot(db, e2), _dot(db, da))
        self.a = (np.zeros_like(angle), np.full_like(angle, 0.5))
        self.b = (angle / TWO_PI, np.full_like(angle, 0.5))

    def evaluate(self, s, t, order=2):
        s, t = self.clamp(s, t)
        x = _frame_sphere(self.frame, s, t, order)
        return [self.surface.center + self.surface.radii * x[0]] + [self.surface.radii * y for y in x[1:]]

    def clamp(self, s, t):
        s, t = _uv(s, t)
        return s, np.clip(t, 0.0, 1.0)

    def to_uv(self, s, t):
        return _frame_inverse(GLOBAL_FRAME, _frame_sphere(self.frame, *self.clamp(s, t), 0)[0])

    def from_uv(self, u, v):
        return self._near_middle(*_frame_inverse(self.frame, _frame_sphere(GLOBAL_FRAME, *_uv(u, v), 0)[0]))
