"""The 2D table against brute-force 3D tracing of the extruded profile at θ ∈ {0, π/6, π/3}."""

from __future__ import annotations

import numpy as np
import pytest
from scipy import stats

from reflets.scratches import from_samples, parse_profile, table_from_tallies, trace_table
from reflets.scratches.tracer2d import make_fresnel
from reflets.scratches.tracer3d import trace3d

M = 32
COLUMNS = [2, 9, 16, 23, 30]
THETAS = (0.0, np.pi / 6, np.pi / 3)
ASYM = from_samples(np.linspace(0.0, 1.0, 9), [0.0, -0.3, -0.55, -0.2, 0.15, -0.1, -0.4, 0.05, 0.0], name="asym")
CASES = {
    "vgroove-iron-lazanyi": ("vgroove:0.7", dict(conductor=((2.91, 2.6, 2.3), (3.09, 2.9, 2.7)))),
    "quartic-glass-exact": ("quartic:0.8", dict(ior=1.5, model="exact")),
    "asym-periodic-schlick": (ASYM, dict(ior=1.8)),
}


def _compare(a_mean, a_var, b_mean, b_var):
    """p-value of χ² = Σ (a − b)² / (var_a + var_b) over bins with non-zero variance."""
    v = a_var + b_var
    keep = v > 0
    chi2 = float(np.sum((a_mean - b_mean)[keep] ** 2 / v[keep]))
    return stats.chi2.sf(chi2, keep.sum()), keep.sum()


@pytest.mark.parametrize("case", list(CASES))
def test_2d_table_equals_3d_trace(case):
    spec, fres = CASES[case]
    profile = parse_profile(spec)
    fresnel = make_fresnel(**fres)
    rays2d, rays3d = 20000, 3000
    t2 = trace_table(profile, size=M, rays=rays2d, fresnel=fresnel, thetas=THETAS, columns=COLUMNS, seed=1)
    norm2 = rays2d * (np.pi / M) * np.cos(t2_phi())
    for k, theta in enumerate(THETAS):
        t3 = trace3d(profile, theta=theta, size=M, rays=rays3d, columns=COLUMNS, fresnel=fresnel, seed=2 + k)
        assert t3.lost == 0 and t3.off_cone < 1e-12  # θ_out = −θ_in on every ray
        rho2 = t2.weights[k][:, COLUMNS] / norm2[:, None, None]
        var2 = t2.weights_sq[k][:, COLUMNS] / norm2[:, None, None] ** 2  # Σw²/norm² ≥ variance of the mean
        rho3, var3 = t3.rho(), t3.weights_sq / (t3.rays * (np.pi / M) * np.cos(t2_phi()))[:, None, None] ** 2
        pval, n = _compare(rho2, var2, rho3, var3)
        assert n > 20 and pval > 1e-3, (theta, pval, n)
        # and the mirror tally
        mirror2 = t2.counts[:, COLUMNS] / norm2[:, None]
        mvar2 = t2.counts_sq[:, COLUMNS] / norm2[:, None] ** 2
        mvar3 = t3.counts / (t3.rays * (np.pi / M) * np.cos(t2_phi()))[:, None] ** 2 * 2.0  # c(ψ) ≤ 2
        assert _compare(mirror2, mvar2, t3.rho("mirror"), mvar3)[0] > 1e-3
    # the comparison has power: a 3D trace of a slightly different profile is rejected
    if case == "vgroove-iron-lazanyi":
        t3 = trace3d(parse_profile("vgroove:0.75"), theta=0.0, size=M, rays=rays3d, columns=COLUMNS, fresnel=fresnel)
        rho2 = t2.weights[0][:, COLUMNS] / norm2[:, None, None]
        var2 = t2.weights_sq[0][:, COLUMNS] / norm2[:, None, None] ** 2
        var3 = t3.weights_sq / (t3.rays * (np.pi / M) * np.cos(t2_phi()))[:, None, None] ** 2
        assert _compare(rho2, var2, t3.rho(), var3)[0] < 1e-6


def t2_phi():
    return -0.5 * np.pi + (np.arange(M) + 0.5) * np.pi / M


@pytest.mark.slow
def test_gamma_model_against_3d():
    """The table's power-law blend (eq. 3.2) where it is a fit, against the 3D ground truth (column energies).

    θ = π/6: within 0.5 % of the mirror energy (measured ≤ 0.07 %, noise level). θ = 75°: the blend is only an
    approximation (measured: up to 4 % of the mirror energy for iron on quartic:0.8), but it must still capture
    most of the θ dependence that using ρ_s(0) at every θ misses (measured: residual ≈ 10 % of it)."""
    profile = parse_profile("quartic:0.8")
    fresnel = make_fresnel(conductor=(2.91, 3.09))
    tall = trace_table(profile, size=M, rays=20000, fresnel=fresnel, seed=3)
    table = table_from_tallies(tall, profile, fresnel, symmetrize=False)
    cos = np.cos(table.phi) * np.pi / M
    mirror = (table.rho_m[:, COLUMNS] * cos[:, None]).sum(axis=0)
    flat = (table.rho_s0[:, COLUMNS] * cos[:, None]).sum(axis=0)
    for theta in (np.pi / 6, 5 * np.pi / 12):
        t3 = trace3d(profile, theta=theta, size=M, rays=4000, columns=COLUMNS, fresnel=fresnel, seed=4)
        model = (table.rho_s(theta)[:, COLUMNS] * cos[:, None]).sum(axis=0)
        truth = (t3.rho()[..., 0] * cos[:, None]).sum(axis=0)
        if theta < 1.0:
            assert np.all(np.abs(model - truth) < 0.005 * mirror), (model, truth)
        else:
            assert np.abs(model - truth).sum() < 0.2 * np.abs(flat - truth).sum(), (model, truth, flat)
            assert np.abs(flat - truth).sum() > 0.1 * mirror.sum()
