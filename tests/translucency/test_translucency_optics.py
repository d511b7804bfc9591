"""Boundary and medium optics of the translucency models: Fresnel, moments, phase function, Beckmann."""

from __future__ import annotations

import numpy as np
import pytest

from reflets.translucency import optics


@pytest.mark.parametrize("eta", [1.1, 1.3, 1.5, 1.6])
def test_fresnel_normal_incidence_and_total_internal_reflection(eta):
    assert optics.fresnel_reflectance(1.0, eta) == pytest.approx(((eta - 1) / (eta + 1)) ** 2, rel=1e-12)
    assert optics.fresnel_reflectance(1.0, eta, inside=True) == pytest.approx(((eta - 1) / (eta + 1)) ** 2, rel=1e-12)
    critical = np.sqrt(1.0 - 1.0 / eta**2)  # cosine of the critical angle inside
    grazing = np.linspace(0.0, critical * 0.999, 20)
    assert np.all(optics.fresnel_reflectance(grazing, eta, inside=True) == 1.0)
    assert np.all(optics.fresnel_transmittance(grazing, eta, inside=True) == 0.0)
    assert optics.fresnel_reflectance(critical * 1.01, eta, inside=True) < 1.0


def test_fresnel_moment_fits_agree_with_quadrature():
    eta = np.linspace(1.1, 1.6, 26)
    for k in (1, 2):
        quad = optics.fresnel_moment(k, eta)
        fit = optics.fresnel_moment_fit(k, eta)
        assert np.max(np.abs(quad - fit)) < 0.005, k
    # and 2 C1 is Jensen et al.'s F_dr (their own fit), light from inside
    assert np.max(np.abs(2 * optics.fresnel_moment(1, eta) - optics.diffuse_fresnel_reflectance_fit(eta))) < 0.01


def test_fresnel_moment_quadrature_is_converged():
    for eta in (1.1, 1.3, 1.6):
        coarse = optics.fresnel_moment(1, eta, nodes=64)
        assert coarse == pytest.approx(optics.fresnel_moment(1, eta, nodes=512), abs=1e-10)
    # η = 1: no interface, no reflection
    assert optics.fresnel_moment(1, 1.0) == pytest.approx(0.0, abs=1e-12)


@pytest.mark.parametrize("g", [-0.5, 0.0, 0.3, 0.9])
def test_henyey_greenstein_normalised_with_mean_cosine_g(g):
    t, w = optics.gauss_legendre(512)
    x = 2.0 * t - 1.0  # cosθ over [−1, 1]
    p = optics.henyey_greenstein(x, g)
    assert 4 * np.pi * np.sum(w * p) == pytest.approx(1.0, abs=1e-6)
    assert 4 * np.pi * np.sum(w * p * x) == pytest.approx(g, abs=1e-6)
    samples = optics.sample_henyey_greenstein(g, np.random.default_rng(1).random(200_000))
    assert samples.mean() == pytest.approx(g, abs=4 * samples.std() / np.sqrt(samples.size))


@pytest.mark.parametrize("m", [0.1, 0.3, 0.7])
def test_beckmann_projected_integral_is_one(m):
    mu, w = optics.gauss_legendre(512)
    assert 2 * np.pi * np.sum(w * optics.beckmann_d(mu, m) * mu) == pytest.approx(1.0, abs=1e-6)
