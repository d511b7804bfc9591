"""Fresnel reflectance: closed forms against the complex Fresnel equations written independently here."""

from __future__ import annotations

import numpy as np
import pytest

from reflets.fresnel import GOLD_ETA, GOLD_K, fresnel_conductor, fresnel_dielectric, fresnel_schlick

COS = np.linspace(0.0, 1.0, 1001)


def fresnel_complex(cos_i: np.ndarray, n: complex) -> np.ndarray:
    """Unpolarised reflectance from the amplitude coefficients with complex arithmetic:
    n cosθt = sqrt(n² − sin²θi) (principal branch: the transmitted wave decays), r_s, r_p, F = (|r_s|² + |r_p|²)/2."""
    cos_i = np.asarray(cos_i, dtype=np.complex128)
    n_cos_t = np.sqrt(n * n - (1.0 - cos_i * cos_i))
    rs = (cos_i - n_cos_t) / (cos_i + n_cos_t)
    rp = (n * n * cos_i - n_cos_t) / (n * n * cos_i + n_cos_t)
    return 0.5 * (np.abs(rs) ** 2 + np.abs(rp) ** 2)


def test_dielectric_normal_incidence_and_grazing():
    assert fresnel_dielectric(1.0, 1.5) == pytest.approx(0.04, abs=1e-15)
    assert fresnel_dielectric(1.0, 1.33) == pytest.approx((0.33 / 2.33) ** 2, rel=1e-12)
    assert fresnel_dielectric(0.0, 1.5) == 1.0
    assert fresnel_dielectric(1e-4, 1.5) > 0.999
    assert np.all(np.diff(fresnel_dielectric(COS, 1.5)) <= 1e-15)  # decreasing in cosθ (past Brewster too)


def test_dielectric_total_internal_reflection():
    eta = 1.0 / 1.5
    cos_critical = np.sqrt(1.0 - eta**2)
    inside = COS[COS < cos_critical - 1e-9]
    assert np.all(fresnel_dielectric(inside, eta) == 1.0)
    assert fresnel_dielectric(cos_critical + 1e-3, eta) < 1.0
    assert fresnel_dielectric(1.0, eta) == pytest.approx(0.04, abs=1e-15)  # normal incidence is symmetric in η ↔ 1/η


@pytest.mark.parametrize("eta", [1.0001, 1.33, 1.5, 2.42, 0.75, 1 / 1.5])
def test_dielectric_matches_complex_fresnel_equations(eta):
    assert np.allclose(fresnel_dielectric(COS, eta), fresnel_complex(COS, complex(eta)), rtol=1e-12, atol=1e-15)


@pytest.mark.parametrize("eta", [1.5, 2.42, 0.7, 1 / 1.5])
def test_conductor_with_zero_k_is_the_dielectric(eta):
    assert np.allclose(fresnel_conductor(COS, eta, 0.0), fresnel_dielectric(COS, eta), rtol=1e-12, atol=1e-15)


@pytest.mark.parametrize(
    "eta, k",
    [(0.958, 6.69), (0.2, 3.9), (1.5, 0.5), (2.0, 10.0)] + list(zip(GOLD_ETA, GOLD_K, strict=True)),
)
def test_conductor_matches_complex_fresnel_equations(eta, k):
    assert np.allclose(fresnel_conductor(COS, eta, k), fresnel_complex(COS, complex(eta, k)), rtol=1e-12)


def test_conductor_known_values():
    # aluminium at 550 nm (Rakić 1995: n ≈ 0.958, k ≈ 6.69): R = ((n−1)² + k²)/((n+1)² + k²) ≈ 0.921 at normal incidence
    n, k = 0.958, 6.69
    r = ((n - 1) ** 2 + k**2) / ((n + 1) ** 2 + k**2)
    assert fresnel_conductor(1.0, n, k) == pytest.approx(r, rel=1e-12)
    assert r == pytest.approx(0.921, abs=1e-3)
    assert fresnel_conductor(0.0, n, k) == pytest.approx(1.0, abs=1e-12)
    # gold (the conductor default): yellow, red reflected most
    gold = fresnel_conductor(1.0, np.array(GOLD_ETA), np.array(GOLD_K))
    assert gold[0] > gold[1] > gold[2] and gold[0] > 0.9


def test_broadcasting_rgb():
    f = fresnel_conductor(COS[:, None], np.array(GOLD_ETA), np.array(GOLD_K))
    assert f.shape == (COS.size, 3)
    for c in range(3):
        assert np.allclose(f[:, c], fresnel_conductor(COS, GOLD_ETA[c], GOLD_K[c]), rtol=1e-15)
    assert fresnel_dielectric(COS[:, None], np.array([1.3, 1.5, 1.7])).shape == (COS.size, 3)


def test_schlick():
    f0 = np.array([0.04, 0.5, 0.9])
    assert np.allclose(fresnel_schlick(1.0, f0), f0)
    assert np.allclose(fresnel_schlick(0.0, f0), 1.0)
    assert np.allclose(fresnel_schlick(0.5, f0), f0 + (1 - f0) / 32)
    # an approximation of the exact dielectric with the same F0 (η = 1.5): 0.036 apart at worst, near grazing
    assert np.max(np.abs(fresnel_schlick(COS, 0.04) - fresnel_dielectric(COS, 1.5))) < 0.04


def test_cosines_are_clipped():
    assert fresnel_dielectric(-0.5, 1.5) == 1.0 and fresnel_dielectric(1.5, 1.5) == pytest.approx(0.04)
    assert fresnel_conductor(-0.5, 0.2, 3.9) == pytest.approx(1.0)
    assert fresnel_schlick(-0.5, 0.04) == 1.0
