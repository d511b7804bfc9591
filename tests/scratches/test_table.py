"""Tables: layout, γ fit, symmetrisation, .npz round trip, plots, and importance sampling (pdf, χ², unbiasedness)."""

from __future__ import annotations

import numpy as np
import pytest
from scipy import stats

from reflets.errors import ArgumentError, OutputError
from reflets.scratches import build_table, fit_gamma, load_table, plot_table

M = 32
IRON_RGB = ((2.91, 2.6, 2.3), (3.09, 2.9, 2.7))


@pytest.fixture(scope="module")
def iron():
    return build_table("quartic:0.8", conductor=IRON_RGB, size=M, rays=3000, seed=7)


@pytest.fixture(scope="module")
def vtable():
    return build_table("vgroove:0.866", ior=1.5, size=M, rays=3000, seed=8)


def test_layout(iron, vtable):
    assert iron.phi.shape == (M,) and np.all(np.diff(iron.phi) > 0)
    assert -np.pi / 2 < iron.phi[0] and iron.phi[-1] < np.pi / 2
    assert iron.rho_m.shape == (M, M) and iron.rho_s0.shape == (M, M, 3) and iron.gamma.shape == (M, M, 3)
    assert vtable.rho_s0.shape == (M, M) and vtable.gamma.shape == (M, M) and vtable.channels == 1
    assert iron.pdf.shape == (M, M) and iron.cdf.shape == (M, M + 1) and iron.icdf.shape == (M, M)
    assert np.all(np.isfinite(iron.gamma)) and np.all(iron.gamma > 0)
    assert iron.meta["fresnel"]["model"] == "lazanyi" and vtable.meta["fresnel"]["model"] == "schlick"


def test_symmetrised_table_is_exactly_reciprocal_symmetric_and_keeps_energy(iron):
    cos = np.cos(iron.phi)
    K = iron.rho_m.astype(np.float64) * np.outer(cos, cos)
    np.testing.assert_allclose(K, K.T, rtol=1e-5, atol=1e-7)
    np.testing.assert_allclose(K, K[::-1, ::-1].T, rtol=1e-5, atol=1e-7)  # quartic: anti-diagonal
    np.testing.assert_allclose((iron.rho_m * cos[:, None]).sum(0) * np.pi / M, 1.0, atol=1e-5)
    np.testing.assert_allclose((iron.rho_m * cos[None, :]).sum(1) * np.pi / M, 1.0, atol=1e-5)  # rows too
    assert np.all(iron.rho_s0 <= iron.rho_m[..., None] * (1 + 1e-5))


def test_gamma_fit_recovers_known_exponents_and_guards():
    rng = np.random.default_rng(0)
    rho_m = rng.uniform(0.5, 2.0, (8, 8))
    rho_s0 = rho_m * rng.uniform(0.05, 0.9, (8, 8))
    gamma = rng.uniform(0.1, 8.0, (8, 8))
    f = (2.0 / 3.0) ** gamma  # F_γ(π/3)
    rho_s3 = f * rho_m + (1 - f) * rho_s0
    np.testing.assert_allclose(fit_gamma(rho_m, rho_s0, rho_s3), gamma, rtol=1e-9)
    # no Fresnel loss or no light: γ is irrelevant there and filled with the median of the valid cells
    rho_s0[0, 0] = rho_s3[0, 0] = rho_m[0, 0]
    rho_m[1, 1] = rho_s0[1, 1] = rho_s3[1, 1] = 0.0
    g = fit_gamma(rho_m, rho_s0, rho_s3)
    assert g[0, 0] == g[1, 1] == pytest.approx(np.median(np.delete(gamma.ravel(), [0, 9])))


def test_table_blend_reproduces_its_two_fresnel_tallies(iron):
    np.testing.assert_allclose(iron.rho_s(0.0), iron.rho_s0, rtol=1e-6, atol=1e-9)
    np.testing.assert_allclose(iron.rho_s(np.pi / 2), np.broadcast_to(iron.rho_m[..., None], iron.rho_s0.shape))
    t = (iron.rho_s3 - iron.rho_s0) / np.maximum(iron.rho_m[..., None] - iron.rho_s0, 1e-30)
    ok = (iron.rho_m[..., None] > 0) & (t > 1e-3) & (t < 1 - 1e-3)
    np.testing.assert_allclose(iron.rho_s(np.pi / 3)[ok], iron.rho_s3[ok], rtol=1e-4)


def test_save_load_round_trip_and_errors(iron, tmp_path):
    path = iron.save(tmp_path / "iron.npz")
    back = load_table(path)
    for key in ("phi", "rho_m", "rho_s0", "rho_s3", "gamma", "pdf", "cdf", "icdf", "energy", "profile_h"):
        np.testing.assert_array_equal(getattr(back, key), getattr(iron, key))
    assert back.meta == iron.meta
    with pytest.raises(OutputError):
        iron.save(tmp_path / "missing" / "t.npz")
    with pytest.raises(OutputError):
        iron.save(tmp_path / "t.png")
    np.savez(tmp_path / "other.npz", a=np.zeros(3))
    with pytest.raises(ArgumentError, match="not a scratch table"):
        load_table(tmp_path / "other.npz")
    with pytest.raises(ArgumentError, match="backend"):
        build_table("flat", backend="cuda", size=4, rays=1)


def test_plot_writes_a_png(vtable, tmp_path):
    path = plot_table(vtable, tmp_path / "v.png")
    assert path.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"


def test_pdf_rows_integrate_to_one_and_icdf_inverts_cdf(iron):
    np.testing.assert_allclose(iron.pdf.sum(axis=1) * np.pi / M, 1.0, atol=1e-5)
    assert np.all(np.diff(iron.cdf, axis=1) >= 0) and np.all(np.diff(iron.icdf, axis=1) >= -1e-6)
    edges = -np.pi / 2 + np.arange(M + 1) * np.pi / M
    u = np.linspace(0.0, 1.0, M)
    for b in range(M):
        np.testing.assert_allclose(np.interp(iron.icdf[b], edges, iron.cdf[b]), u, atol=1e-5)


@pytest.mark.parametrize("row", [3, 16, 27])
def test_chi_square_of_sampled_phi_in(vtable, row):
    rng = np.random.default_rng(row)
    n = 40000
    phi_o = vtable.phi[row]
    expected = vtable.pdf[row].astype(np.float64) * np.pi / M * n

    def pvalue(samples):
        """Pearson χ² over the bins with expected count > 5, the others merged into one bin."""
        counts = np.bincount(np.clip(((samples + np.pi / 2) * M / np.pi).astype(int), 0, M - 1), minlength=M)
        keep = expected > 5
        obs = np.append(counts[keep], counts[~keep].sum())
        exp = np.append(expected[keep], expected[~keep].sum())
        if exp[-1] < 1e-9:  # the pdf is zero there: any sample in it rejects
            if obs[-1] > 0:
                return 0.0
            obs, exp = obs[:-1], exp[:-1]
        chi2 = float(np.sum((obs - exp) ** 2 / exp))
        return stats.chi2.sf(chi2, obs.size - 1)

    phi_in, pdf = vtable.sample(phi_o, rng.random(n))
    assert np.all(pdf > 0)
    assert pvalue(phi_in) > 1e-3
    # power: the neighbouring row's distribution, or samples shifted by a quarter bin, are rejected
    other, _ = vtable.sample(vtable.phi[row + 2 if row < M - 2 else row - 2], rng.random(n))
    assert pvalue(other) < 1e-6
    assert pvalue(phi_in + 0.25 * np.pi / M) < 1e-6


def test_importance_sampling_estimator_is_unbiased(iron):
    """(1/N) Σ ρ_s cos φ_i L / pdf (eq. 3.5) with φ_i from the table's CDF against uniform sampling and against
    the quadrature of the same piecewise-constant table; the document's (1/N) Σ L (eq. 3.6) ignores Fresnel."""
    rng = np.random.default_rng(11)
    row, theta_o = 20, 0.7

    def radiance(phi):
        return 1.0 + 0.5 * np.sin(3 * phi) + 4.0 * np.exp(-((phi + 0.4) ** 2) / 0.02)

    rho = iron.rho_s(theta_o)[row].astype(np.float64)  # (M, 3)
    x, w = np.polynomial.legendre.leggauss(64)
    edges = -np.pi / 2 + np.arange(M + 1) * np.pi / M
    mids, half = 0.5 * (edges[1:] + edges[:-1]), 0.5 * np.pi / M
    nodes = mids[:, None] + half * x[None, :]
    per_bin = (np.cos(nodes) * radiance(nodes) * w[None, :]).sum(1) * half
    exact = (rho * per_bin[:, None]).sum(axis=0)

    n = 200000
    phi_i, pdf = iron.sample(iron.phi[row], rng.random(n))
    f = iron.eval(np.full(n, iron.phi[row]), phi_i, theta_o) * (np.cos(phi_i) * radiance(phi_i))[:, None]
    est = f / pdf[:, None]
    u = rng.uniform(-np.pi / 2, np.pi / 2, n)
    g = iron.eval(np.full(n, iron.phi[row]), u, theta_o) * (np.cos(u) * radiance(u))[:, None] * np.pi
    for samples in (est, g):
        mean, err = samples.mean(0), samples.std(0) / np.sqrt(n)
        assert np.all(np.abs(mean - exact) < 4 * err), (mean, exact, err)
    assert est.std(0).max() < g.std(0).min()  # importance sampling reduces the variance
    simplified = radiance(phi_i)  # eq. 3.6: the mirror BRDF's estimator, no Fresnel
    assert np.all(np.abs(simplified.mean() - exact) > 20 * est.std(0) / np.sqrt(n))
