"""Scratch profiles: the 1D height field h(x) that is extruded along the scratch direction **u**.

Conventions (shared by the 2D tracer, the 3D reference and the GPU shader):

- the profile plane has x along **v** = **n** × **u** and y along the normal **n**; one period spans
  x ∈ [0, 1) (only the aspect ratio matters: the BRDF is scale invariant, so every profile is normalised
  to width 1, tabulated ones by scaling x and h by the same factor);
- the profile is traced as **periodic** with period 1 and its highest point is the *lid* y = ``lid``:
  rays enter through the lid and a ray going up through the lid has left the scratch. For profiles dug
  into the base (V-groove, quartic) the lid is the base level y = 0 and the ends of the period meet it,
  so periodicity changes nothing; for tabulated profiles that rise above the base it keeps rays that have
  not really left the scratch (chapter 3, §3.3.3, figure 3.9);
- a profile is a polyline through knots (x_k, h_k), k = 0..K with x_0 = 0, x_K = 1, h_K = h_0. For
  ``kind="polyline"`` (V-grooves, tables) the polyline *is* the profile and intersections are exact per
  segment; for ``kind="quartic"`` the knots only bracket the intersection, which is then found by bisection
  on the exact curve and shaded with its exact normal.

Spec strings (``parse_profile``): ``vgroove:D``, ``quartic:D``, ``flat`` and ``file:PATH`` (CSV / text with
two columns x, h in the same unit, ``.npy`` of shape (n, 2), or ``.npz`` with arrays ``x`` and ``h``).
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np

from ..errors import ARRAY_READ_ERRORS, ArgumentError

#: number of bracketing cells of the quartic (a ray crossing the curve twice inside one cell of 1/128 is
#: missed; that needs a chord closer than ~1e-4 to the curve, see docs of :func:`quartic`)
QUARTIC_CELLS = 128


@dataclass(frozen=True, eq=False)
class Profile:
    """A periodic scratch profile of width 1 (see the module docstring for the conventions)."""

    name: str
    x: np.ndarray  # (K+1,) increasing knots, x[0] = 0, x[-1] = 1
    h: np.ndarray  # (K+1,) heights at the knots, h[-1] = h[0]
    kind: str = "polyline"  # "polyline" or "quartic"
    depth: float = 0.0  # quartic depth D (kind == "quartic")

    def __post_init__(self):
        x = np.asarray(self.x, dtype=np.float64)
        h = np.asarray(self.h, dtype=np.float64)
        if x.ndim != 1 or x.shape != h.shape or x.size < 2:
            raise ArgumentError("profile knots must be two 1D arrays of the same length ≥ 2", field="profile")
        if not (np.all(np.isfinite(x)) and np.all(np.isfinite(h))):
            raise ArgumentError("profile knots must be finite", field="profile")
        if abs(x[0]) > 1e-12 or abs(x[-1] - 1.0) > 1e-12 or np.any(np.diff(x) <= 0):
            raise ArgumentError("profile knots must increase strictly from x = 0 to x = 1", field="profile")
        if abs(h[-1] - h[0]) > 1e-12 * max(1.0, np.ptp(h)):
            raise ArgumentError("a periodic profile needs h(1) = h(0)", field="profile")
        if self.kind not in ("polyline", "quartic"):
            raise ArgumentError(f"unknown profile kind '{self.kind}'", field="profile")
        object.__setattr__(self, "x", x)
        object.__setattr__(self, "h", h)

    # -- geometry ---------------------------------------------------------------------------------------
    @property
    def cells(self) -> int:
        return self.x.size - 1

    @property
    def lid(self) -> float:
        """Height of the highest point: rays enter and leave the scratch through y = lid."""
        return float(self.h.max())

    @property
    def bottom(self) -> float:
        return float(self.h.min())

    @property
    def slopes(self) -> np.ndarray:
        """(K,) slope of each polyline segment."""
        return np.diff(self.h) / np.diff(self.x)

    @property
    def max_slope(self) -> float:
        """A Lipschitz bound of h (used by the 3D reference's conservative march)."""
        if self.kind == "quartic":
            return 8.0 * abs(self.depth) * 2.0 / (3.0 * np.sqrt(3.0))  # max |8D s (1 − s²)|, s = 1/√3
        return float(np.abs(self.slopes).max())

    @property
    def symmetric(self) -> bool:
        """True when h(x) = h(1 − x): the table then also has the anti-diagonal symmetry."""
        if self.kind == "quartic":
            return True
        xs = np.linspace(0.0, 1.0, 4 * self.cells + 1)
        a, b = self.height(xs), self.height(1.0 - xs)
        return bool(np.allclose(a, b, rtol=0.0, atol=1e-9 * max(1.0, np.ptp(self.h))))

    def flat_fraction(self, degrees: float = 1.0, samples: int = 1 << 16) -> float:
        """Share of the profile's width tilted less than ``degrees`` from flat: what reflects a delta light
        towards its mirror direction (the table's mirror peak). 0 for V-grooves, whose walls send it to
        ±2·atan(slope) off the mirror direction."""
        x = (np.arange(samples) + 0.5) / samples
        return float(np.mean(np.abs(self.slope(x)) < np.tan(np.radians(degrees))))

    def cell_of(self, x) -> np.ndarray:
        """Index of the polyline cell containing x (x taken modulo 1)."""
        xm = np.mod(np.asarray(x, dtype=np.float64), 1.0)
        return np.clip(np.searchsorted(self.x, xm, side="right") - 1, 0, self.cells - 1)

    def height(self, x) -> np.ndarray:
        """h(x), periodic with period 1."""
        x = np.asarray(x, dtype=np.float64)
        if self.kind == "quartic":
            return quartic_height(np.mod(x, 1.0), self.depth)
        return np.interp(np.mod(x, 1.0), self.x, self.h)

    def slope(self, x) -> np.ndarray:
        """h'(x), periodic (for a polyline: the slope of the segment containing x)."""
        x = np.asarray(x, dtype=np.float64)
        if self.kind == "quartic":
            return quartic_slope(np.mod(x, 1.0), self.depth)
        return self.slopes[self.cell_of(x)]

    def __repr__(self) -> str:
        return f"Profile({self.name!r}, kind={self.kind}, cells={self.cells}, lid={self.lid:g}, bottom={self.bottom:g})"


# -- analytic profiles -------------------------------------------------------------------------------------
def quartic_height(x, depth):
    """Symmetric quartic y(x) = −D (1 − s²)², s = 2x − 1, x ∈ [0, 1] (the document gives no formula).

    It is 0 with zero slope at both rims, has a flat bottom −D at x = ½ (so the mirror peak on the
    anti-diagonal survives, as in figure 3.5) and its steepest slope ±16 D/(3√3) ≈ ±3.079 D at
    s = ±1/√3; it is concave in the middle third and convex near the rims.
    """
    s = 2.0 * np.asarray(x, dtype=np.float64) - 1.0
    q = 1.0 - s * s
    return -depth * q * q


def quartic_slope(x, depth):
    """dy/dx of :func:`quartic_height`: 8 D s (1 − s²)."""
    s = 2.0 * np.asarray(x, dtype=np.float64) - 1.0
    return 8.0 * depth * s * (1.0 - s * s)


def vgroove(depth: float) -> Profile:
    """A V of depth ``depth`` for width 1: knots (0, 0), (½, −D), (1, 0). Wall slope angle atan(2D)."""
    if not depth >= 0.0 or not np.isfinite(depth):
        raise ArgumentError(f"V-groove depth must be a finite number ≥ 0, got {depth}", field="profile")
    return Profile(f"vgroove:{depth:g}", np.array([0.0, 0.5, 1.0]), np.array([0.0, -depth, 0.0]))


def flat() -> Profile:
    """A flat profile (an ideal mirror: ρ_m = δ(φ_i + φ_o)/cos φ_i)."""
    return Profile("flat", np.array([0.0, 1.0]), np.array([0.0, 0.0]))


def quartic(depth: float, cells: int = QUARTIC_CELLS) -> Profile:
    """The symmetric quartic of :func:`quartic_height`, intersected by bisection on the exact curve."""
    if not depth >= 0.0 or not np.isfinite(depth):
        raise ArgumentError(f"quartic depth must be a finite number ≥ 0, got {depth}", field="profile")
    x = np.linspace(0.0, 1.0, cells + 1)
    return Profile(f"quartic:{depth:g}", x, quartic_height(x, depth), kind="quartic", depth=float(depth))


def quartic_polyline(depth: float, cells: int = 4096) -> Profile:
    """The quartic as a dense polyline (to check the bisection path against exact segment intersection)."""
    x = np.linspace(0.0, 1.0, cells + 1)
    h = quartic_height(x, depth)
    h[-1] = h[0]
    return Profile(f"quartic-polyline:{depth:g}:{cells}", x, h)


def from_samples(x, h, name: str = "table") -> Profile:
    """A tabulated height field (x, h) in any unit, made periodic and normalised to width 1.

    The samples are sorted by x. If the last height equals the first, the last sample is the start of the
    next period (period = x_n − x_0); otherwise the period is closed by one more segment of the mean sample
    spacing joining the last sample to the first one of the next period. Both x and h are divided by the
    period, which keeps the aspect ratio (the only thing the BRDF depends on).
    """
    x = np.asarray(x, dtype=np.float64).ravel()
    h = np.asarray(h, dtype=np.float64).ravel()
    if x.size != h.size or x.size < 2:
        raise ArgumentError("a tabulated profile needs at least 2 samples of (x, h)", field="profile")
    if not (np.all(np.isfinite(x)) and np.all(np.isfinite(h))):
        raise ArgumentError("a tabulated profile must contain finite numbers only", field="profile")
    order = np.argsort(x, kind="stable")
    x, h = x[order], h[order]
    if np.any(np.diff(x) <= 0):
        raise ArgumentError("tabulated profile x values must be distinct", field="profile")
    if abs(h[-1] - h[0]) <= 1e-12 * max(np.ptp(h), 1e-300) or np.ptp(h) == 0.0:
        period = x[-1] - x[0]
        xs, hs = x - x[0], h.copy()
        hs[-1] = hs[0]
    else:
        period = (x[-1] - x[0]) * x.size / (x.size - 1)
        xs = np.append(x - x[0], period)
        hs = np.append(h, h[0])
    xs, hs = xs / period, hs / period
    xs[-1] = 1.0
    return Profile(name, xs, hs)


def read_profile(path: str | Path) -> Profile:
    """Read a tabulated profile: CSV/text (two columns x, h; ``#`` comments and one header line allowed),
    ``.npy`` (shape (n, 2)) or ``.npz`` (arrays ``x`` and ``h``)."""
    path = Path(path)
    if not path.is_file():
        raise ArgumentError("profile file not found", file=path)
    try:
        if path.suffix == ".npz":
            with np.load(path) as data:
                if "x" not in data or "h" not in data:
                    raise ArgumentError("an .npz profile needs arrays 'x' and 'h'", file=path)
                x, h = data["x"], data["h"]
        elif path.suffix == ".npy":
            arr = np.load(path)
            if arr.ndim != 2 or arr.shape[1] != 2:
                raise ArgumentError(f"an .npy profile must have shape (n, 2), got {arr.shape}", file=path)
            x, h = arr[:, 0], arr[:, 1]
        else:
            text = path.read_text(encoding="utf-8").splitlines()
            rows = [ln.replace(",", " ").replace(";", " ").split() for ln in text]
            rows = [r for r in rows if r and not r[0].startswith("#")]
            try:
                values = [[float(v) for v in r] for r in rows[1:]]
                first = [float(v) for v in rows[0]]
                values.insert(0, first)
            except ValueError:
                values = [[float(v) for v in r] for r in rows[1:]]  # one header line
            arr = np.array(values, dtype=np.float64)
            if arr.ndim != 2 or arr.shape[1] != 2:
                raise ArgumentError("a CSV profile needs two numeric columns x, h", file=path)
            x, h = arr[:, 0], arr[:, 1]
    except ArgumentError:
        raise
    except (*ARRAY_READ_ERRORS, IndexError) as exc:
        raise ArgumentError(f"cannot read profile: {exc}", file=path) from None
    profile = from_samples(x, h, name=f"file:{path}")
    return profile


def parse_profile(spec: str | Profile) -> Profile:
    """``vgroove:D`` | ``quartic:D`` | ``flat`` | ``file:PATH`` → :class:`Profile` (a Profile passes through)."""
    if isinstance(spec, Profile):
        return spec
    if not isinstance(spec, str):
        raise ArgumentError(f"profile spec must be a string, got {type(spec).__name__}", field="profile")
    kind, _, arg = spec.partition(":")
    kind = kind.strip().lower()
    if kind == "flat" and not arg:
        return flat()
    if kind == "file":
        if not arg:
            raise ArgumentError("file: needs a path, e.g. file:profile.csv", field="profile")
        return read_profile(arg)
    if kind in ("vgroove", "quartic"):
        try:
            depth = float(arg)
        except ValueError:
            raise ArgumentError(
                f"'{spec}': expected {kind}:DEPTH with DEPTH a number (depth for width 1)", field="profile"
            ) from None
        return vgroove(depth) if kind == "vgroove" else quartic(depth)
    raise ArgumentError(
        f"unknown profile '{spec}'; allowed: vgroove:DEPTH, quartic:DEPTH, flat, file:PATH", field="profile"
    )
