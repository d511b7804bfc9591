"""``multiple_fit``: a diffusion profile for multiple scattering only, fitted to volumetric Monte Carlo.

Why: the dipoles and normalised diffusion stand for *all* orders of scattering (normalised diffusion is fitted
to the total profile, the better dipole's total is the Monte Carlo's single + multiple within a few %), and the
document adds single scattering as its own term on top: on a semi-infinite skin1 slab the better dipole carries
+24 / +24 / +22 % (η = 1) and +10 / +9 / +11 % (η = 1.3) more than the Monte Carlo's multiple scattering, and
the skin1 bunny came out 16 / 10 / 6 % too bright against volumetric path tracing at η = 1.

This profile models what the single-scattering term leaves out, and only that. A table made by
tools/tabulate_multiple_scattering.py (data/translucency/multiple_scattering.npz) holds, per relative index η
and reduced albedo α' (isotropic scattering, lengths in reduced mean free paths 1/σ'_t), the Monte Carlo's
photons that leave a semi-infinite slab after two or more events: their exitance per unit transmitted flux at
normal incidence (the profile's total), its radial cumulative distribution, and its dependence on the
incidence cosine. Interpolated bilinearly in η and u = sqrt(1 − α') (the energy as its ratio to the better
dipole's total, which is smooth), the radial distribution is fitted with

    R(r) = A Σ_k w_k s_k e^{−s_k (d_k − z_k)} / (2π d_k),   d_k = sqrt(r² + z_k²),  k = 1, 2,  w_2 = 1 − w_1,

two exponentials softened at the centre (each term integrates to 1 over the plane; multiple scattering is
finite where the beam enters, unlike normalised diffusion's 1/r), whose cumulative ∫₀^x R u du =
(A/2π) Σ w_k (1 − e^{−s_k (d_k(x) − z_k)}) the shader's first ring needs in closed form. The fit follows the
Monte Carlo's radial exitance within about ±10 % per bin over 0.005–100 mean free paths (noise included).

Oblique light penetrates less and more of it comes back after several events (skin1 blue at η = 1: +26 % at a
cosine of 0.2): the technique multiplies the light entering at each ring node by the tabulated factor
M(μ) = exitance(μ) / exitance(1) at that node's incidence cosine (``incidence_factor``). With g ≠ 0 the profile
is that of the similar isotropic medium (σ'_s, σ_a), as for the dipoles.

Outside the table: η is clamped to its range (1–1.5; the energy, a ratio to the better dipole's total at the
true η, keeps that profile's η dependence), and α' below 0.02 takes the last row's ratio and shape.
"""

from __future__ import annotations

import functools
from collections.abc import Callable
from importlib import resources

import numpy as np

from .medium import Medium

TABLE = "data/translucency/multiple_scattering.npz"

#: ring spacing β of the technique for this profile (rings r_max x(eˣ − 1)/(e − 1), densest at the centre). The
#: document's criterion (minimise ∫|g''|, g = R_d ∘ f_β) sends β to its bound for a profile peaked at the centre:
#: the first ring at 57 % of r_max (7.4 mm for skin1), the near field left to the closed-form first cell, whose
#: straight-line model of the true distance fails on curved surfaces (measured: multiple scattering +38 / +57 /
#: +70 % on a 10 mm skin1 sphere). β = 0.1 puts the first ring at 0.44 mm for skin1 (the better dipole's fit:
#: 0.43 mm); the bunny's mean ratios are within 0.2 % of β = 0's there, 0.3 brightens them by 1–2 %.
RING_BETA = 0.1


@functools.cache
def table() -> dict[str, np.ndarray]:
    """The Monte Carlo table (module docstring), with a row for α' = 0 (u = 1) copied from the last."""
    with resources.files("reflets").joinpath(TABLE).open("rb") as f, np.load(f) as data:
        t = {key: np.asarray(data[key], dtype=np.float64) for key in data.files}
    t["u"] = np.append(t["u"], 1.0)
    for key in ("energy", "cdf", "incidence"):
        t[key] = np.concatenate([t[key], t[key][:, -1:]], axis=1)
    return t


#: the better dipole's ∫2πr R_d dr at (α', η) in reduced units, given by profiles.py (which imports this
#: module): the energy is interpolated as a ratio to it
DipoleTotal = Callable[[float, float], float]


@functools.lru_cache(maxsize=4096)
def _energy_ratio(i: int, j: int, dipole_total: DipoleTotal) -> float:
    """The table's energy at (η_i, u_j) relative to the better dipole's total there: smooth (0.8–0.9 over most
    of the table) where the energy itself varies by decades, so it interpolates with far less error."""
    t = table()
    u = min(t["u"][j], t["u"][-2])  # the α' = 0 row is the last one's
    dipole = dipole_total(1.0 - u * u, float(t["eta"][i]))
    return float(t["energy"][i, j] / dipole) if dipole > 1e-12 else 1.0


def _corners(eta: float, albedo_prime: float) -> list[tuple[int, int, float]]:
    """The table cells around (η, u = sqrt(1 − α')) and their bilinear weights, η clamped to the table."""
    t = table()
    u = float(np.sqrt(np.clip(1.0 - albedo_prime, 0.0, 1.0)))
    axes = []
    for grid, x in ((t["eta"], float(np.clip(eta, t["eta"][0], t["eta"][-1]))), (t["u"], u)):
        i = int(np.clip(np.searchsorted(grid, x, side="right") - 1, 0, max(len(grid) - 2, 0)))
        frac = 0.0 if len(grid) == 1 else (x - grid[i]) / (grid[i + 1] - grid[i])
        axes.append(((i, 1.0 - frac), (min(i + 1, len(grid) - 1), frac)))
    return [(i, j, wi * wj) for i, wi in axes[0] for j, wj in axes[1] if wi * wj > 0.0]


def _interpolate(values: np.ndarray, eta: float, albedo_prime: float) -> np.ndarray:
    """Bilinear interpolation of table[η, u, ...]."""
    return sum(weight * values[i, j] for i, j, weight in _corners(eta, albedo_prime))


def energy(albedo_prime: float, eta: float, dipole_total: DipoleTotal) -> float:
    """Multiple scattering's exitance per unit transmitted flux at normal incidence: the interpolated ratio to
    the better dipole's total, times that total."""
    ratio = sum(weight * _energy_ratio(i, j, dipole_total) for i, j, weight in _corners(eta, albedo_prime))
    return ratio * dipole_total(albedo_prime, eta)


def shape_cdf(w, s1, s2, z1, z2, x) -> np.ndarray:
    """Share of the profile's energy within radius x (reduced units)."""
    d1, d2 = np.sqrt(x * x + z1 * z1), np.sqrt(x * x + z2 * z2)
    return w * -np.expm1(-s1 * (d1 - z1)) + (1.0 - w) * -np.expm1(-s2 * (d2 - z2))


@functools.lru_cache(maxsize=512)
def reduced_parameters(albedo_prime: float, eta: float, dipole_total: DipoleTotal) -> tuple[float, ...]:
    """(A, w, s1, s2, z1, z2) in reduced units (lengths × σ'_t = 1): A the interpolated energy, the shape fitted
    to the interpolated radial distribution by least squares on the bins' shares (relative, Poisson-like
    weights), from a few starts (the two terms may swap roles)."""
    t = table()
    total = energy(albedo_prime, eta, dipole_total)
    edges = t["edges"]
    share = np.diff(_interpolate(t["cdf"], eta, albedo_prime))
    keep = share > 1e-6
    target = share[keep]

    def residual(p):
        w, s1, s2, z1, z2 = p[0], *np.exp(p[1:])
        model = np.diff(shape_cdf(w, s1, s2, z1, z2, edges))[keep]
        return (model - target) / np.sqrt(target + 1e-4)

    best = None
    for start in ([0.5, 0.0, -2.0, -1.5, -0.5], [0.3, 1.0, -1.0, -2.5, 0.0], [0.8, -1.0, -3.0, -1.0, -2.0]):
        from scipy import optimize  # imported when used (start-up time)

        fit = optimize.least_squares(residual, start, bounds=([0, -9, -9, -9, -9], [1, 5, 5, 4, 4]))
        if best is None or fit.cost < best.cost:
            best = fit
    w, s1, s2, z1, z2 = best.x[0], *np.exp(best.x[1:])
    return total, float(w), float(s1), float(s2), float(z1), float(z2)


def parameters(medium: Medium, dipole_total: DipoleTotal) -> dict[str, np.ndarray]:
    """Per channel A, w and s1, s2 (1/mm), z1, z2 (mm) of the profile (profiles.multiple_fit_parameters)."""
    alpha = np.atleast_1d(medium.albedo_prime)
    st = np.atleast_1d(medium.sigma_t_prime)
    rows = np.array([reduced_parameters(float(a), float(medium.eta), dipole_total) for a in alpha])
    out = {
        "A": rows[:, 0],
        "w": rows[:, 1],
        "s1": rows[:, 2] * st,
        "s2": rows[:, 3] * st,
        "z1": rows[:, 4] / st,
        "z2": rows[:, 5] / st,
    }
    if np.ndim(medium.sigma_a) == 0:
        out = {k: v[0] for k, v in out.items()}
    return out


def multiple_fit_rd(r, medium: Medium, dipole_total: DipoleTotal) -> np.ndarray:
    """R(r) of the fitted profile (module docstring); r in mm, broadcasts against the channels."""
    p = parameters(medium, dipole_total)
    r = np.asarray(r, dtype=np.float64)
    total = 0.0
    for weight, s, z in ((p["w"], p["s1"], p["z1"]), (1.0 - p["w"], p["s2"], p["z2"])):
        d = np.sqrt(r * r + z * z)
        total = total + weight * s * np.exp(-s * (d - z)) / (2.0 * np.pi * d)
    return p["A"] * total


def incidence_factor(medium: Medium, cos_incidence) -> np.ndarray:
    """M(μ): multiple scattering at outside incidence cosine μ relative to normal incidence, per channel
    (linear in μ between the table's cosines, constant beyond them)."""
    t = table()
    alpha = np.atleast_1d(medium.albedo_prime)
    rows = np.array([_interpolate(t["incidence"], float(medium.eta), float(a)) for a in alpha])  # (C, M)
    cosines = t["cosines"][::-1]
    mu = np.asarray(cos_incidence, dtype=np.float64)
    out = np.stack([np.interp(mu, cosines, row[::-1]) for row in rows], axis=-1)
    return out[..., 0] if np.ndim(medium.sigma_a) == 0 else out


def incidence_table(medium: Medium) -> tuple[np.ndarray, np.ndarray]:
    """The table's cosines (descending) and M at each, one row per cosine, one column per channel (the
    shader's piecewise-linear twin of ``incidence_factor``)."""
    t = table()
    return t["cosines"], incidence_factor(medium, t["cosines"]).reshape(len(t["cosines"]), -1)


def single_scattering_albedo(medium: Medium, nodes: int = 64) -> np.ndarray:
    """Single scattering's exitance per unit transmitted flux at normal incidence (Hanrahan–Krueger, the closed
    form of single.py, integrated over the exit hemisphere): what the far-field BRDF adds to this profile's total
    to stand for all orders."""
    from .optics import fresnel_transmittance, gauss_legendre
    from .single import half_space_single_scattering

    mu, weight = gauss_legendre(nodes)  # outside exit cosines
    radiance = half_space_single_scattering(medium, 1.0, mu[:, None]) / fresnel_transmittance(1.0, medium.eta)
    return 2.0 * np.pi * np.sum((weight * mu)[:, None] * radiance, axis=0).reshape(np.shape(medium.albedo))
