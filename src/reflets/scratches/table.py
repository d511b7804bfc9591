"""Scratch BRDF tables: ρ_m, ρ_s(0), ρ_s(π/3), γ, the per-row pdf / CDF / inverse CDF; symmetrisation; .npz I/O.

Layout (M = ``size``): ``phi`` (M,) bin centres over (−π/2, π/2), Δφ = π/M; every 2D array is indexed
[φ_out, φ_in]. ``rho_m`` is the mirror BRDF (F = 1) in the cone parameterisation,
ρ[b, j] = A[b, j] / (N Δφ cos φ_b) (A = rays of column j leaving into bin b, each weighted by
cos φ_in / ⟨cos⟩_bin ≈ 1 to make the estimate exactly reciprocal, see :class:`~.tracer2d.Tallies`; N rays per
column), so Σ_b ρ_m[b, j] cos φ_b Δφ = 1 for a lossless profile (the document's per-ray weight M/(N cos φ_out)
lacks 1/Δφ).
``rho_s0`` / ``rho_s3`` are the same tallies with every path weighted by the product of its Fresnel factors at
θ = 0 and θ = π/3 — (M, M) for one channel, (M, M, 3) for RGB — and ``gamma`` the per-cell exponent of
F_γ(θ) = (2|θ|/π)^γ with ρ_s(θ) ≈ F_γ ρ_m + (1 − F_γ) ρ_s(0) (eq. 3.2).

Sampling (eq. 3.5): for a row φ_out the density of φ_in is pdf = ρ_m(φ_out, ·) cos φ_in / Z (Z = 1 for a lossless,
symmetrised table), piecewise constant per bin. ``cdf`` (M, M+1) holds its values at the bin edges and ``icdf``
(M, M) its inverse at u_k = k/(M − 1) (for a texture: linear interpolation inside a bin is exact for a piecewise
constant pdf only between the CDF's knots, so :meth:`ScratchTable.sample` inverts ``cdf`` exactly).
"""

from __future__ import annotations

import json
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from ..errors import ARRAY_READ_ERRORS, ArgumentError, OutputError
from .profiles import Profile, parse_profile
from .tracer2d import THETAS, FresnelSpec, Tallies, bin_of, make_fresnel, phi_bins, trace_table

FORMAT_VERSION = 1
GAMMA_T_CLAMP = 1e-4  # t = (ρ_s(π/3) − ρ_s(0)) / (ρ_m − ρ_s(0)) is clamped to [1e-4, 1 − 1e-4]
_ARRAYS = (
    *("phi", "rho_m", "rho_s0", "rho_s3", "gamma", "pdf", "cdf", "icdf"),
    *("energy", "lost", "profile_x", "profile_h"),
)


@dataclass
class ScratchTable:
    """A scratch BRDF table (see the module docstring for the meaning of every array)."""

    phi: np.ndarray
    rho_m: np.ndarray
    rho_s0: np.ndarray
    rho_s3: np.ndarray
    gamma: np.ndarray
    pdf: np.ndarray
    cdf: np.ndarray
    icdf: np.ndarray
    energy: np.ndarray  # (M,) Σ_b ρ_m cos φ_b Δφ per column of the raw trace (1 − lost fraction)
    lost: np.ndarray  # (M,) lost rays per column
    profile_x: np.ndarray
    profile_h: np.ndarray
    meta: dict = field(default_factory=dict)

    @property
    def size(self) -> int:
        return self.phi.size

    @property
    def channels(self) -> int:
        return 1 if self.rho_s0.ndim == 2 else self.rho_s0.shape[-1]

    # -- evaluation -----------------------------------------------------------------------------------------
    def fresnel_weight(self, theta_o) -> np.ndarray:
        """F_γ(θ_o) = (2|θ_o|/π)^γ for every cell, shape (M, M[, C])."""
        x = np.clip(2.0 * abs(float(theta_o)) / np.pi, 0.0, 1.0)
        return np.power(x, self.gamma) if x > 0 else np.where(self.gamma > 0, 0.0, 1.0)

    def rho_s(self, theta_o) -> np.ndarray:
        """ρ_s(θ_o) on the whole grid (eq. 3.2), (M, M[, C])."""
        F = self.fresnel_weight(theta_o)
        rho_m = self.rho_m if self.rho_s0.ndim == 2 else self.rho_m[..., None]
        return F * rho_m + (1.0 - F) * self.rho_s0

    def eval(self, phi_o, phi_i, theta_o=0.0) -> np.ndarray:
        """ρ_s(ω_o, ω_i) at cone angles (nearest bin): shape of phi_o/phi_i (+ (C,) for RGB)."""
        b, j = bin_of(phi_o, self.size), bin_of(phi_i, self.size)
        return self.rho_s(theta_o)[b, j]

    def pdf_at(self, phi_o, phi_i) -> np.ndarray:
        """Density of :meth:`sample` (per radian of φ_in)."""
        return self.pdf[bin_of(phi_o, self.size), bin_of(phi_i, self.size)]

    def sample(self, phi_o, u) -> tuple[np.ndarray, np.ndarray]:
        """φ_in ~ ρ_m(φ_o, ·) cos φ_in by exact inversion of the row's piecewise-linear CDF; returns (φ_in, pdf)."""
        u = np.asarray(u, dtype=np.float64)
        b = np.broadcast_to(bin_of(phi_o, self.size), u.shape)
        phi_in = _invert_rows(self.cdf, b, u)
        return phi_in, self.pdf_at(phi_o, phi_in)

    # -- I/O ------------------------------------------------------------------------------------------------
    def save(self, path: str | Path) -> Path:
        import io

        from ..outputs import atomic_write

        path = Path(path)
        if path.suffix.lower() != ".npz":
            raise OutputError("a scratch table is written as .npz", file=path)
        if not path.parent.exists():
            raise OutputError("output directory does not exist", file=path)
        arrays = {k: getattr(self, k) for k in _ARRAYS}
        with io.BytesIO() as buffer:
            np.savez_compressed(buffer, **arrays, meta=np.array(json.dumps(self.meta)))
            atomic_write(path, buffer.getvalue())
        return path


def load_table(path: str | Path) -> ScratchTable:
    """Read a table written by :meth:`ScratchTable.save`."""
    path = Path(path)
    try:
        with np.load(path) as data:
            missing = [k for k in (*_ARRAYS, "meta") if k not in data]
            if missing:
                raise ArgumentError(f"not a scratch table (missing {', '.join(missing)})", file=path)
            arrays = {k: data[k] for k in _ARRAYS}
            meta = json.loads(str(data["meta"]))
    except ARRAY_READ_ERRORS as exc:
        raise ArgumentError(f"cannot read scratch table: {exc}", file=path) from None
    return ScratchTable(**arrays, meta=meta)


# -- building -----------------------------------------------------------------------------------------------
def _invert_rows(cdf: np.ndarray, rows: np.ndarray, u: np.ndarray) -> np.ndarray:
    """φ with CDF_row(φ) = u, for piecewise-linear CDFs given at the M+1 bin edges (flat parts skipped).

    The bin of each u is a binary search in its own row (the requests grouped by row), so memory stays
    proportional to the requests — gathering every request's whole row was M³ bytes × 9 for a table's M × M
    inverse (9.7 GB at M = 1024)."""
    M = cdf.shape[0]
    rows = np.asarray(rows)
    u = np.clip(np.broadcast_to(u, rows.shape), 0.0, 1.0)
    flat_rows, flat_u = rows.ravel(), u.ravel()
    k = np.empty(flat_rows.shape, np.int64)  # bin index whose [c_k, c_k+1) contains u
    order = np.argsort(flat_rows, kind="stable")
    bounds = np.searchsorted(flat_rows[order], np.arange(M + 1))
    for b in np.flatnonzero(np.diff(bounds)):
        chosen = order[bounds[b] : bounds[b + 1]]
        k[chosen] = np.searchsorted(cdf[b, 1:-1], flat_u[chosen], side="right")  # = #{c ≤ u}: the CDF is sorted
    k = k.reshape(rows.shape)
    lo, hi = cdf[rows, k], cdf[rows, k + 1]
    frac = np.where(hi > lo, (u - lo) / np.where(hi > lo, hi - lo, 1.0), 0.5)
    return -0.5 * np.pi + (k + np.clip(frac, 0.0, 1.0)) * np.pi / M


def _symmetry_average(K: np.ndarray, symmetric: bool) -> np.ndarray:
    """Average a kernel [b, j, ...] over reciprocity (transpose) and, for mirror-symmetric profiles, the
    anti-diagonal reflection ρ(φ_o, φ_i) = ρ(−φ_i, −φ_o) (and their composition)."""
    T = np.swapaxes(K, 0, 1)
    if not symmetric:
        return 0.5 * (K + T)
    R = K[::-1, ::-1]
    return 0.25 * (K + T + R + np.swapaxes(R, 0, 1))


def _balance(K: np.ndarray, target: np.ndarray, iterations: int = 500) -> np.ndarray:
    """Symmetric scaling s with s_b K[b, j] s_j summing to ``target`` per column (Knight's iteration)."""
    s = np.ones(K.shape[0])
    for _ in range(iterations):
        Ks = K @ s
        ok = Ks > 0
        new = s.copy()
        new[ok] = np.sqrt(s[ok] * target[ok] / Ks[ok])
        if np.max(np.abs(new - s)) < 1e-13:
            s = new
            break
        s = new
    return s


def fit_gamma(rho_m: np.ndarray, rho_s0: np.ndarray, rho_s3: np.ndarray) -> np.ndarray:
    """γ per cell from ρ_s(π/3) = F_γ(π/3) ρ_m + (1 − F_γ(π/3)) ρ_s(0), F_γ(π/3) = (2/3)^γ.

    t = (ρ_s(π/3) − ρ_s(0)) / (ρ_m − ρ_s(0)) is clamped to [1e-4, 1 − 1e-4] and γ = ln t / ln(2/3). Cells where
    ρ_m − ρ_s(0) ≤ 1e-9 ρ_m (no light, or no Fresnel loss) take the median γ of the valid cells of their
    channel (their ρ_s does not depend on γ; the median keeps bilinear texture filtering smooth)."""
    rm = rho_m if rho_s0.ndim == 2 else rho_m[..., None]
    rm = np.broadcast_to(rm, rho_s0.shape)
    den = rm - rho_s0
    valid = (rm > 0) & (den > 1e-9 * rm)
    with np.errstate(divide="ignore", invalid="ignore"):
        t = np.where(valid, (rho_s3 - rho_s0) / np.where(valid, den, 1.0), 0.5)
    t = np.clip(t, GAMMA_T_CLAMP, 1.0 - GAMMA_T_CLAMP)
    gamma = np.log(t) / np.log(2.0 / 3.0)
    chans = gamma[..., None] if gamma.ndim == 2 else gamma
    vmask = valid[..., None] if valid.ndim == 2 else valid
    for c in range(chans.shape[-1]):
        v = vmask[..., c]
        fill = float(np.median(chans[..., c][v])) if v.any() else 1.0
        chans[..., c][~v] = fill
    return gamma


def table_from_tallies(
    tallies: Tallies, profile: Profile, fresnel: FresnelSpec, *, symmetrize: bool = True, meta: dict | None = None
) -> ScratchTable:
    """Normalise raw tallies into a :class:`ScratchTable` (optionally symmetrised, see :func:`build_table`)."""
    M, N = tallies.size, tallies.rays
    phi = phi_bins(M)
    dphi = np.pi / M
    cos = np.cos(phi)
    rho_m = tallies.counts / (N * dphi * cos[:, None])
    rho_t = tallies.weights / (N * dphi * cos[None, :, None, None])  # (T, M, M, C)
    t0 = int(np.argmin(np.abs(np.asarray(tallies.thetas) - THETAS[0])))
    t3 = int(np.argmin(np.abs(np.asarray(tallies.thetas) - THETAS[1])))
    rho_s0, rho_s3 = rho_t[t0], rho_t[t3]
    energy = tallies.counts.sum(axis=0) / N
    if symmetrize:
        symmetric = profile.symmetric
        cc = np.outer(cos, cos)
        Km = _symmetry_average(rho_m * cc, symmetric)
        K0 = _symmetry_average(rho_s0 * cc[..., None], symmetric)
        K3 = _symmetry_average(rho_s3 * cc[..., None], symmetric)
        target = 0.5 * (energy + energy[::-1]) if symmetric else energy
        s = _balance(Km, target * cos / dphi)
        ss = np.outer(s, s)
        rho_m = Km * ss / cc
        rho_s0 = K0 * ss[..., None] / cc[..., None]
        rho_s3 = K3 * ss[..., None] / cc[..., None]
    if rho_s0.shape[-1] == 1:
        rho_s0, rho_s3 = rho_s0[..., 0], rho_s3[..., 0]
    gamma = fit_gamma(rho_m, rho_s0, rho_s3)
    # sampling: rows φ_out, density over φ_in
    w = rho_m * cos[None, :]
    Z = w.sum(axis=1) * dphi
    pdf = np.where(Z[:, None] > 0, w / np.where(Z > 0, Z, 1.0)[:, None], 1.0 / np.pi)
    cdf = np.concatenate([np.zeros((M, 1)), np.cumsum(pdf * dphi, axis=1)], axis=1)
    cdf /= cdf[:, -1:]
    cdf[:, -1] = 1.0
    u = np.linspace(0.0, 1.0, M)
    icdf = _invert_rows(cdf, np.repeat(np.arange(M)[:, None], M, axis=1), np.broadcast_to(u, (M, M)))
    return ScratchTable(
        phi=phi,
        rho_m=rho_m.astype(np.float32),
        rho_s0=rho_s0.astype(np.float32),
        rho_s3=rho_s3.astype(np.float32),
        gamma=gamma.astype(np.float32),
        pdf=pdf.astype(np.float32),
        cdf=cdf,
        icdf=icdf.astype(np.float32),
        energy=energy,
        lost=tallies.lost.astype(np.float64),
        profile_x=profile.x.copy(),
        profile_h=profile.h.copy(),
        meta={
            "format": FORMAT_VERSION,
            "profile": profile.name,
            "profile_kind": profile.kind,
            "symmetric_profile": profile.symmetric,
            "fresnel": fresnel.describe(),
            "size": M,
            "rays": N,
            "symmetrized": bool(symmetrize),
            "max_bounces": int(tallies.max_bounces),
            **(meta or {}),
        },
    )


#: the fixed working set of the NumPy tracer's chunk of rays (measured 67–71 MB)
TRACE_CHUNK_BYTES = 80_000_000


def table_bytes(size: int, rays: int, channels: int, backend: str) -> int:
    """Peak bytes of :func:`build_table` for ``size`` M bins, ``rays`` N per column, C Fresnel ``channels``:
    M² (160 + 96 C) (the float64 tallies, their symmetrised and balanced copies, the CDF and its inverse) + for the
    NumPy tracer 16 M N (each ray's column and rank, int64) + TRACE_CHUNK_BYTES, for the GPU 16 · 7 M² (its tally
    slots, read back and converted). Measured (tracemalloc peak, NumPy tracer, N = 200) / estimated: C = 1, M = 512
    64 / 149 MB, M = 1024 248 / 352 MB; C = 3, M = 1024 433 / 553 MB; M = 128, N = 16,000 105 / 117 MB;
    M = 64, N = 200,000 276 / 286 MB."""
    m, n = int(size), int(rays)
    common = m * m * (160 + 96 * channels)
    if backend == "numpy":
        return common + 16 * m * n + TRACE_CHUNK_BYTES
    return common + 16 * 7 * m * m


def check_table(size: int, rays: int, channels: int, backend: str, names: tuple[str, str] = ("size", "rays")) -> None:
    """Refuse a table whose :func:`table_bytes` exceed the available memory (reflets.resources), naming ``size``
    or, where the rays take most of it, ``rays`` (``names``: the caller's names of the two)."""
    from ..resources import check, largest_fitting

    m, n = int(size), int(rays)
    estimate = table_bytes(m, n, channels, backend)
    what = f"{m}² bins" + (f", {m * n:,} rays" if backend == "numpy" else "")
    if backend == "numpy" and 16 * m * n > estimate / 2:
        check(
            names[1],
            estimate,
            value=f"{n:,} with {names[0]} = {m}",
            what=what,
            fits=lambda budget: largest_fitting(lambda k: table_bytes(m, k, channels, backend), 1, n, budget),
        )
    else:
        check(
            names[0],
            estimate,
            value=m,
            what=what,
            fits=lambda budget: largest_fitting(lambda k: table_bytes(k, n, channels, backend), 2, m, budget),
        )


def build_table(
    profile_spec: str | Profile,
    *,
    ior=1.5,
    conductor=None,
    fresnel: str = "auto",
    size: int = 256,
    rays: int = 10000,
    seed: int = 0,
    backend: str = "numpy",
    symmetrize: bool = True,
    ctx=None,
    names: tuple[str, str] = ("size", "rays"),
) -> ScratchTable:
    """Precompute the scratch BRDF table of a profile.

    ``profile_spec``: ``vgroove:D`` (depth D for width 1), ``quartic:D``, ``flat``, ``file:PATH`` or a
    :class:`Profile`. Fresnel of the walls: ``conductor=(eta, k)`` (scalars or RGB triples; Lazányi by default)
    overrides ``ior`` (real index, scalar or RGB; Schlick by default); ``ior=None`` and no conductor → F = 1.
    ``fresnel="exact"`` uses the exact dielectric / complex Fresnel instead. ``size`` × ``size`` bins (checked
    with ``rays`` against the available memory first: :func:`table_bytes`; ``names`` are theirs in errors),
    ``rays`` rays per φ_in column, ``seed`` of the random numbers, ``backend`` ``"numpy"`` (float64 reference)
    or ``"gpu"`` (compute shader, float32). ``symmetrize`` averages the table over reciprocity (and the
    anti-diagonal for symmetric profiles) and rescales it symmetrically so each column keeps its traced energy.
    """
    profile = parse_profile(profile_spec)
    fres = make_fresnel(ior=ior, conductor=conductor, model=fresnel)
    if backend in ("numpy", "gpu"):
        check_table(size, rays, fres.channels, backend, names)
    if backend == "numpy":
        tallies = trace_table(profile, size=size, rays=rays, fresnel=fres, seed=seed)
    elif backend == "gpu":
        from .gpu import trace_table_gpu

        tallies = trace_table_gpu(profile, size=size, rays=rays, fresnel=fres, seed=seed, ctx=ctx)
    else:
        raise ArgumentError(f"unknown backend '{backend}'; allowed: numpy, gpu", field="backend")
    return table_from_tallies(tallies, profile, fres, symmetrize=symmetrize, meta={"backend": backend, "seed": seed})


def plot_table(table: ScratchTable, path: str | Path) -> Path:
    """A PNG overview: the profile, log ρ_m cos φ_out, ρ_s(0)/ρ_m (channel mean) and γ."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    path = Path(path)
    if not path.parent.exists():
        raise OutputError("output directory does not exist", file=path)
    deg = np.degrees(table.phi)
    ext = [deg[0], deg[-1], deg[0], deg[-1]]
    fig, ax = plt.subplots(1, 4, figsize=(17, 4.2))
    ax[0].plot(np.append(table.profile_x, 1 + table.profile_x[1:]), np.append(table.profile_h, table.profile_h[1:]))
    ax[0].axhline(table.profile_h.max(), color="0.6", lw=0.8, ls="--")
    ax[0].axvline(1.0, color="0.8", lw=0.8)
    ax[0].set_aspect("equal")
    ax[0].set_title(f"profile {table.meta.get('profile', '')} (two periods, lid dashed)")
    cosb = np.cos(table.phi)[:, None]
    im = ax[1].imshow(np.log10(table.rho_m * cosb + 1e-4), origin="lower", extent=ext, cmap="inferno")
    ax[1].set_title("log10 ρ_m cos φ_out")
    fig.colorbar(im, ax=ax[1])
    s0 = table.rho_s0 if table.rho_s0.ndim == 2 else table.rho_s0.mean(axis=-1)
    with np.errstate(divide="ignore", invalid="ignore"):
        ratio = np.where(table.rho_m > 0, s0 / table.rho_m, np.nan)
    im = ax[2].imshow(ratio, origin="lower", extent=ext, vmin=0, vmax=1, cmap="viridis")
    ax[2].set_title("ρ_s(0) / ρ_m")
    fig.colorbar(im, ax=ax[2])
    g = table.gamma if table.gamma.ndim == 2 else table.gamma.mean(axis=-1)
    im = ax[3].imshow(np.where(table.rho_m > 0, g, np.nan), origin="lower", extent=ext, cmap="magma")
    ax[3].set_title("γ")
    fig.colorbar(im, ax=ax[3])
    for a in ax[1:]:
        a.set_xlabel("φ_in (deg)")
        a.set_ylabel("φ_out (deg)")
    fig.tight_layout()
    import io

    from ..outputs import atomic_write

    with io.BytesIO() as buffer:
        fig.savefig(buffer, dpi=110, format="png")
        atomic_write(Path(path), buffer.getvalue())
    plt.close(fig)
    return path
