from __future__ import annotations

import numpy as np
import pytest
from brdf_checks import check_glsl_parity, check_white_furnace, direction, run_standard_checks
from brdf_helpers import hemisphere_albedo
from pydantic import ValidationError

from reflets.brdf.ashikhmin_shirley import AshikhminShirley
from reflets.brdf.base import MATERIALS

CASES = [
    dict(rs=(0.05, 0.1, 0.2), rd=(0.5, 0.4, 0.3), nu=10, nv=10),
    dict(rs=(0.3, 0.3, 0.3), rd=(0.6, 0.6, 0.6), nu=1e4, nv=2),  # the scratches document's comparison
    dict(rs=(0.9, 0.8, 0.7), rd=(0.0, 0.0, 0.0), nu=2, nv=300),
]
#: parity also on the bare n_u = 1e4, n_v = 2 lobe (no diffuse term hiding specular errors) and isotropic 0
PARITY = CASES + [
    dict(rs=(0.9, 0.9, 0.9), rd=(0.0, 0.0, 0.0), nu=1e4, nv=2),
    dict(rs=(0.04,) * 3, rd=(0.8,) * 3, nu=0, nv=0),
]


def case_id(p: dict) -> str:
    return f"nu{p['nu']:g}-nv{p['nv']:g}-rd{p['rd'][0]:g}"


def reference(p: dict, wo: np.ndarray, wi: np.ndarray) -> np.ndarray:
    """The paper's formulas with angles: φ_h from atan2, a plain power, k = wi."""
    rs, rd = np.array(p["rs"]), np.array(p["rd"])
    h = (wo + wi) / np.linalg.norm(wo + wi, axis=1, keepdims=True)
    phi = np.arctan2(h[:, 1], h[:, 0])
    exponent = p["nu"] * np.cos(phi) ** 2 + p["nv"] * np.sin(phi) ** 2
    k_h = np.sum(wi * h, axis=1)
    fresnel = rs + (1 - rs) * (1 - k_h[:, None]) ** 5
    spec = np.sqrt((p["nu"] + 1) * (p["nv"] + 1)) / (8 * np.pi) * h[:, 2] ** exponent
    spec = spec / (k_h * np.maximum(wo[:, 2], wi[:, 2]))
    diffuse = 28 * rd / (23 * np.pi) * (1 - rs) * ((1 - (1 - wo[:, 2:3] / 2) ** 5) * (1 - (1 - wi[:, 2:3] / 2) ** 5))
    return spec[:, None] * fresnel + diffuse


@pytest.mark.parametrize("params", PARITY, ids=case_id)
def test_ashikhmin_shirley_closed_form(directions, params):
    wo, wi = directions
    assert np.allclose(AshikhminShirley(**params).eval(wo, wi), reference(params, wo, wi), rtol=1e-9, atol=1e-300)


@pytest.mark.parametrize("params", PARITY, ids=case_id)
def test_ashikhmin_shirley_glsl_matches_numpy(ctx, rng, params):
    check_glsl_parity(AshikhminShirley(**params), ctx, rng)


@pytest.mark.slow
@pytest.mark.parametrize("params", CASES, ids=case_id)
def test_ashikhmin_shirley_standard_checks(rng, params):
    run_standard_checks(AshikhminShirley(**params), rng)


@pytest.mark.parametrize("nu, nv", [(1e4, 2), (2, 1e4), (1e6, 1e6), (1e6, 0), (0, 0)])
def test_stable_at_the_normal_and_for_huge_exponents(nu, nv):
    """h = n exactly (exponent 0/0 in the paper's form) and h near the horizon: finite, no warnings."""
    m = AshikhminShirley(rs=(1, 1, 1), rd=(0, 0, 0), nu=nu, nv=nv)
    wo = np.array([direction(t, p) for t in (0.0, 0.3, 1.0, 1.5, 1.5707963) for p in (0.0, 0.7, 2.0)])
    with np.errstate(over="raise", invalid="raise", divide="raise"):
        mirror = m.eval(wo, wo * [-1, -1, 1])  # h = n
        grazing = m.eval(wo, wo * [1, -1, 1])  # h in the xz plane, possibly near the horizon
        pdf = m.pdf(wo, wo * [-1, -1, 1])
    # at h = n the lobe is 1: f = sqrt((nu+1)(nv+1))/(8π) / (cosθ · cosθ) with F(cosθ)
    cos = wo[:, 2]
    fresnel = 1.0
    expected = np.sqrt((nu + 1) * (nv + 1)) / (8 * np.pi) * fresnel / (cos * cos)
    assert np.allclose(mirror, expected[:, None], rtol=1e-12)
    assert np.allclose(pdf, np.sqrt((nu + 1) * (nv + 1)) / (2 * np.pi) / (4 * cos), rtol=1e-12)
    assert np.all(np.isfinite(grazing)) and np.all(grazing >= 0)


def test_diffuse_albedo_is_exactly_coupled_to_the_specular_reflectance():
    """∫ f_d cosθ_i dω_i = R_d (1 − R_s)(1 − (1 − cosθ_o/2)⁵): the 28/23 makes it 31/32 R_d (1 − R_s) at
    normal incidence, and it vanishes at grazing, where Schlick's Fresnel sends everything to the lobe."""
    rd, rs = np.array([1.0, 0.5, 0.2]), np.array([0.0, 0.1, 0.5])
    with_d = AshikhminShirley(rs=tuple(rs), rd=tuple(rd), nu=10, nv=10)
    without = AshikhminShirley(rs=tuple(rs), rd=(0, 0, 0), nu=10, nv=10)
    for theta in (0.0, 0.7, 1.3):
        wo = direction(theta)
        diffuse = hemisphere_albedo(with_d, wo, n=400) - hemisphere_albedo(without, wo, n=400)
        expected = rd * (1 - rs) * (1 - (1 - np.cos(theta) / 2) ** 5)
        assert diffuse == pytest.approx(expected, rel=1e-4), theta


@pytest.mark.parametrize(
    "params",
    [
        dict(rs=(0.5, 0.5, 0.5), rd=(1, 1, 1), nu=1e5, nv=1e5),  # near-mirror: the largest albedo found
        dict(rs=(0, 0, 0), rd=(1, 1, 1), nu=10, nv=10),
        dict(rs=(0.02, 0.02, 0.02), rd=(1, 1, 1), nu=0, nv=0),
    ],
    ids=["mirror", "rough", "flat"],
)
def test_white_furnace_extremes(rng, params):
    m = AshikhminShirley(**params)
    assert m.energy_conserving and m.reciprocal
    check_white_furnace(m, rng, thetas=(0.0, 0.8, 1.4, 1.55), n=100000)


def test_registered_and_parsed_from_scene_dict():
    assert MATERIALS["ashikhmin_shirley"] is AshikhminShirley
    m = AshikhminShirley.model_validate({"type": "ashikhmin_shirley", "rs": [0.1, 0.1, 0.1], "nu": 1e4, "nv": 2})
    assert m.nu == 1e4 and m.nv == 2 and m.rd == (0.5, 0.5, 0.5)


@pytest.mark.parametrize(
    "bad",
    [
        dict(nu=-1),
        dict(nv=float("inf")),
        dict(nu=2e6),
        dict(rs=(1.1, 0.1, 0.1)),
        dict(rd=(0.1, 0.1, -0.1)),
        dict(rs=(0.1, 0.1)),
        dict(n=100),
    ],
)
def test_invalid_parameters_rejected(bad):
    with pytest.raises(ValidationError):
        AshikhminShirley(**bad)
