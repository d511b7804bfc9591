"""The 2D profile tracer and the raw tables: mirror, V-groove lines, energy, reciprocity, symmetry, Fresnel."""

from __future__ import annotations

import numpy as np
import pytest
from scipy import stats

from reflets.scratches import build_table, from_samples, parse_profile, quartic, trace_rays, trace_table
from reflets.scratches.profiles import quartic_polyline
from reflets.scratches.tracer2d import bin_of, make_fresnel, phi_bins

M = 32
IRON_RGB = ((2.91, 2.6, 2.3), (3.09, 2.9, 2.7))
# an asymmetric profile that rises above the base (h = 0 at the ends): needs the periodic trace
ASYM = from_samples(np.linspace(0.0, 1.0, 9), [0.0, -0.3, -0.55, -0.2, 0.15, -0.1, -0.4, 0.05, 0.0], name="asym")


def column_energy(rho, phi):
    return (rho * np.cos(phi)[:, None]).sum(axis=0) * np.pi / phi.size


def test_flat_profile_is_a_mirror():
    rng = np.random.default_rng(1)
    phi = rng.uniform(-np.pi / 2, np.pi / 2, 5000)
    res = trace_rays(parse_profile("flat"), phi, rng.random(5000))
    np.testing.assert_allclose(res.phi_out, -phi, atol=1e-14)
    assert np.all(res.bounces == 1)
    table = build_table("flat", ior=None, size=M, rays=200, symmetrize=False)
    expected = np.diag(1.0 / (np.pi / M * np.cos(table.phi)))[::-1]  # δ(φ_i + φ_o)/cos φ_i per bin
    np.testing.assert_allclose(table.rho_m, expected, rtol=2e-3)  # stratified mean of cos ψ / c̄ (200 rays)


@pytest.mark.parametrize("depth", [0.25, 0.5, 0.866, 2.0])
def test_vgroove_first_bounce_lines(depth):
    rng = np.random.default_rng(2)
    phi = rng.uniform(-np.pi / 2, np.pi / 2, 20000)
    res = trace_rays(parse_profile(f"vgroove:{depth}"), phi, rng.random(20000))
    s = np.arctan(2.0 * depth)  # wall slope angle atan(2d/W), W = 1
    one = res.bounces == 1
    assert one.sum() > 1000
    err = np.minimum(np.abs(res.phi_out + phi - 2 * s), np.abs(res.phi_out + phi + 2 * s))[one]
    assert err.max() < 1e-12
    # the table column φ_in ≈ 0 of a shallow V: all energy in the two bins of φ_o = ±2s (one bounce each)
    if depth == 0.25:
        table = build_table("vgroove:0.25", ior=None, size=M, rays=4000, symmetrize=False)
        j = M // 2
        e = table.rho_m[:, j] * np.cos(table.phi) * np.pi / M
        lo, hi = table.phi[j] - 0.5 * np.pi / M, table.phi[j] + 0.5 * np.pi / M  # φ_in range of the column
        lines = sorted({int(v) for sign in (-1, 1) for v in bin_of([sign * 2 * s - hi, sign * 2 * s - lo], M)})
        assert len(lines) <= 4 and e[lines].sum() > 0.999
        assert not set(lines) & {M // 2 - 1, M // 2}  # nothing in the mirror direction


@pytest.mark.parametrize("spec", ["flat", "vgroove:0.5", "vgroove:2", "quartic:1", ASYM])
def test_lossless_energy_per_column(spec):
    for symmetrize in (False, True):
        table = build_table(spec, ior=None, size=M, rays=2000, symmetrize=symmetrize)
        assert table.lost.sum() == 0
        np.testing.assert_allclose(column_energy(table.rho_m, table.phi), 1.0, atol=0.01)


def test_periodic_trace_keeps_rays_of_profiles_above_the_base():
    """Rays hitting the bumps of ASYM would leave sideways without the periodic trace: check that paths cross
    periods (exit x far from the entry period) and that all of them still leave through the lid."""
    rng = np.random.default_rng(3)
    phi = rng.uniform(-1.5, 1.5, 20000)
    res = trace_rays(ASYM, phi, rng.random(20000))
    assert not res.lost.any()
    assert np.all(res.direction[:, 1] > 0)
    assert (res.bounces >= 2).mean() > 0.05


@pytest.mark.parametrize(
    "fresnel", [dict(ior=1.5), dict(conductor=IRON_RGB), dict(conductor=IRON_RGB, fresnel="exact")]
)
def test_fresnel_loses_energy_and_is_ordered(fresnel):
    table = build_table("vgroove:0.866", size=M, rays=2000, symmetrize=False, **fresnel)
    rho_m = table.rho_m if table.rho_s0.ndim == 2 else table.rho_m[..., None]
    cos = np.cos(table.phi).reshape((-1,) + (1,) * (table.rho_s0.ndim - 1))
    e_s0 = (table.rho_s0 * cos).sum(axis=0) * np.pi / M
    assert np.all(e_s0 <= 1.0 + 1e-6) and np.all(e_s0 < 0.99)
    assert np.all(table.rho_s0 <= rho_m * (1 + 1e-5))
    assert np.all(table.rho_s3 <= rho_m * (1 + 1e-5))
    if fresnel.get("fresnel") != "exact":  # Schlick and Lazányi grow monotonically towards grazing
        assert np.all(table.rho_s0 <= table.rho_s3 * (1 + 1e-5) + 1e-7)
    # θ = π/2: every 3D cosine is 0, F = 1, the Fresnel tally is the mirror tally
    p = parse_profile("vgroove:0.866")
    model = fresnel.get("fresnel", "auto")
    spec = make_fresnel(ior=fresnel.get("ior"), conductor=fresnel.get("conductor"), model=model)
    t = trace_table(p, size=M, rays=500, fresnel=spec, thetas=(np.pi / 2,))
    np.testing.assert_allclose(t.weights[0], np.broadcast_to(t.counts[..., None], t.weights[0].shape), rtol=1e-12)


def _pair_stat(t, pairs, factor=None):
    """χ² of K[b, j] − K[pair(b, j)], K = ρ cos φ_o cos φ_i from the tallies (variances from Σ c²), and the
    relative asymmetry ‖K − K_pair‖ / ‖K‖. ``factor`` multiplies K (to build a deliberately wrong table)."""
    M, N = t.size, t.rays
    phi = phi_bins(M)
    scale = np.cos(phi)[None, :] / (N * np.pi / M) * (1.0 if factor is None else factor)
    K, V = t.counts * scale, t.counts_sq * scale**2
    b, j = np.indices(K.shape)
    pb, pj = pairs(b, j)
    keep = (b * M + j < pb * M + pj) & (V + V[pb, pj] > 0)
    d = (K - K[pb, pj])[keep]
    chi2 = float(np.sum(d * d / (V + V[pb, pj])[keep]))
    rel = float(np.linalg.norm(d) / np.linalg.norm(K))
    return stats.chi2.sf(chi2, keep.sum()), rel


def transpose(b, j):
    return j, b


def antitranspose(b, j):
    return M - 1 - j, M - 1 - b


@pytest.mark.slow
@pytest.mark.parametrize("profile", ["vgroove:0.7", "quartic:0.8", ASYM], ids=["vgroove", "quartic", "asym"])
def test_reciprocity_within_noise_and_shrinking_with_n(profile):
    p = parse_profile(profile)
    errors = []
    for rays in (1500, 6000):
        t = trace_table(p, size=M, rays=rays, seed=rays)
        pval, rel = _pair_stat(t, transpose)
        assert pval > 1e-4, (rays, pval)
        errors.append(rel)
    assert errors[1] < 0.7 * errors[0]  # noise: ~ 1/√N → ratio 0.5
    # the check has power: normalising by cos φ_in instead of cos φ_out breaks reciprocity
    phi = phi_bins(M)
    assert _pair_stat(t, transpose, factor=np.cos(phi)[:, None] / np.cos(phi)[None, :])[0] < 1e-6


@pytest.mark.slow
def test_antidiagonal_symmetry_of_symmetric_profiles_only():
    for spec in ("vgroove:0.866", "quartic:0.8"):
        errors = []
        for rays in (1500, 6000):
            t = trace_table(parse_profile(spec), size=M, rays=rays, seed=rays + 1)
            pval, rel = _pair_stat(t, antitranspose)
            assert pval > 1e-4, (spec, rays, pval)
            errors.append(rel)
        assert errors[1] < 0.7 * errors[0]
    t = trace_table(ASYM, size=M, rays=6000, seed=5)
    assert _pair_stat(t, antitranspose)[0] < 1e-6  # an asymmetric profile breaks it


def test_quartic_bisection_converges_to_dense_polylines():
    """Bisection on the exact curve vs exact segment intersection on polylines of 1024 and 4096 cells:
    exit angles agree, with an error that falls like the facet size."""
    rng = np.random.default_rng(4)
    phi, x0 = rng.uniform(-1.5, 1.5, 2000), rng.random(2000)
    exact = trace_rays(quartic(0.8), phi, x0).phi_out
    med = [np.median(np.abs(trace_rays(quartic_polyline(0.8, k), phi, x0).phi_out - exact)) for k in (1024, 4096)]
    assert med[1] < 6e-4 and med[1] < 0.4 * med[0]
