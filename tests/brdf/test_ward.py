from __future__ import annotations

import numpy as np
import pytest
from brdf_checks import albedo_sampled, check_glsl_parity, direction, run_standard_checks
from pydantic import ValidationError

from reflets.brdf.base import MATERIALS
from reflets.brdf.ward import Ward

CASES = [
    dict(kd=(0.1, 0.2, 0.3), ks=(0.5, 0.5, 0.5), alpha=0.2),
    dict(kd=(0.0, 0.0, 0.0), ks=(1.0, 1.0, 1.0), alpha=(0.05, 0.3)),
    dict(kd=(0.3, 0.3, 0.3), ks=(0.2, 0.4, 0.6), alpha=(0.8, 0.4), variant="original"),
    dict(kd=(0.2, 0.2, 0.2), ks=(0.8, 0.8, 0.8), alpha=(0.01, 0.001)),
]


def case_id(p: dict) -> str:
    return f"a{p['alpha']}-{p.get('variant', 'duer')}".replace(" ", "")


@pytest.mark.parametrize("params", CASES + [dict(CASES[1], variant="original")], ids=case_id)
def test_ward_closed_form(directions, params):
    """Against Ward's angular form: θ_h, φ_h of the normalised half vector."""
    wo, wi = directions
    m = Ward(**params)
    ax, ay = (params["alpha"],) * 2 if np.isscalar(params["alpha"]) else params["alpha"]
    h = (wo + wi) / np.linalg.norm(wo + wi, axis=1, keepdims=True)
    theta_h = np.arccos(h[:, 2])
    phi_h = np.arctan2(h[:, 1], h[:, 0])
    lobe = np.exp(-(np.tan(theta_h) ** 2) * (np.cos(phi_h) ** 2 / ax**2 + np.sin(phi_h) ** 2 / ay**2))
    if params.get("variant") == "original":
        spec = lobe / (4 * np.pi * ax * ay * np.sqrt(wo[:, 2] * wi[:, 2]))
    else:  # (h·h)/(h·n)⁴ of the unnormalised h = wo + wi, i.e. 1/(|wo + wi|² cos⁴θ_h)
        spec = lobe / (np.sum((wo + wi) ** 2, axis=1) * np.cos(theta_h) ** 4) / (np.pi * ax * ay)
    expected = np.array(params["kd"]) / np.pi + np.array(params["ks"]) * spec[:, None]
    assert np.allclose(m.eval(wo, wi), expected, rtol=1e-9, atol=1e-300)


@pytest.mark.parametrize(
    "params", CASES + [dict(kd=(0, 0, 0), ks=(1, 1, 1), alpha=1.0, variant="original")], ids=case_id
)
def test_ward_glsl_matches_numpy(ctx, rng, params):
    check_glsl_parity(Ward(**params), ctx, rng)


@pytest.mark.parametrize("params", CASES, ids=case_id)
def test_ward_standard_checks(rng, params):
    run_standard_checks(Ward(**params), rng)


def test_both_variants_reciprocal_only_duer_energy_conserving():
    assert Ward(variant="original").reciprocal and Ward(variant="duer").reciprocal
    assert Ward(kd=(0.5, 0.5, 0.5), ks=(0.5, 0.5, 0.5)).energy_conserving
    assert not Ward(kd=(0.5, 0.5, 0.5), ks=(0.6, 0.5, 0.5)).energy_conserving
    assert not Ward(kd=(0, 0, 0), ks=(0.1, 0.1, 0.1), variant="original").energy_conserving


def test_original_creates_energy_at_grazing_and_duer_does_not(rng):
    """Ward's 1/sqrt(cosθ_i cosθ_o) makes the albedo grow without bound as θ_o → 90°; Dür's form stays ≤ 1."""
    wo = direction(1.570, 0.0)
    original, err_o = albedo_sampled(Ward(alpha=0.3, variant="original"), wo, rng, 100000)
    duer, err_d = albedo_sampled(Ward(alpha=0.3, variant="duer"), wo, rng, 100000)
    assert np.all(original - 3 * err_o > 1.3), original
    assert np.all(duer - 3 * err_d <= 1.0), duer


def test_duer_reflects_almost_everything_when_smooth(rng):
    """A smooth white Dür lobe is a near-perfect mirror away from grazing (albedo → 1 as α → 0)."""
    for theta in (0.0, 0.6, 1.2):
        albedo, err = albedo_sampled(Ward(alpha=0.01), direction(theta), rng, 50000)
        assert albedo == pytest.approx([1, 1, 1], abs=2e-3 + 3 * err.max()), (theta, albedo)


def test_scalar_alpha_is_isotropic_pair(directions):
    wo, wi = directions
    assert np.array_equal(Ward(alpha=0.2).eval(wo, wi), Ward(alpha=(0.2, 0.2)).eval(wo, wi))


def test_anisotropy_follows_the_tangent():
    """α_x > α_y: the highlight spreads along x (the tangent), not along y."""
    m = Ward(alpha=(0.4, 0.05))
    wo = direction(0.5, 0.0)
    mirror = wo * [-1, -1, 1]
    along_x = mirror + [0.2, 0, 0]
    along_y = mirror + [0, 0.2, 0]
    fx = m.eval(wo, along_x / np.linalg.norm(along_x))
    fy = m.eval(wo, along_y / np.linalg.norm(along_y))
    assert np.all(fx > 10 * fy)


def test_registered_and_parsed_from_scene_dict():
    assert MATERIALS["ward"] is Ward
    m = Ward.model_validate({"type": "ward", "alpha": [0.1, 0.3], "variant": "original"})
    assert m.alpha_xy == (0.1, 0.3) and m.variant == "original"


@pytest.mark.parametrize(
    "bad",
    [
        dict(alpha=0.0),
        dict(alpha=5e-4),
        dict(alpha=1.5),
        dict(alpha=(0.1, 2.0)),
        dict(alpha=(0.1,)),
        dict(alpha=(0.1, 0.2, 0.3)),
        dict(alpha=float("nan")),
        dict(variant="ward1992"),
        dict(ks=(1.0, 1.0, -0.1)),
        dict(roughness=0.1),
    ],
)
def test_invalid_parameters_rejected(bad):
    with pytest.raises(ValidationError):
        Ward(**bad)
