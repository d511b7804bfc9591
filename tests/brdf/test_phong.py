from __future__ import annotations

import numpy as np
import pytest
from brdf_checks import check_glsl_parity, run_standard_checks
from brdf_helpers import hemisphere_albedo
from pydantic import ValidationError

from reflets.brdf.base import MATERIALS
from reflets.brdf.phong import Phong

CASES = [
    dict(kd=(0.1, 0.2, 0.3), ks=(0.5, 0.5, 0.5), exponent=50, normalized=False),
    dict(kd=(0.05, 0.05, 0.05), ks=(0.95, 0.95, 0.95), exponent=500, normalized=True),
    dict(kd=(0.3, 0.3, 0.3), ks=(0.2, 0.4, 0.6), exponent=10, normalized=True),
]


def case_id(p: dict) -> str:
    return f"e{p['exponent']}-{'norm' if p['normalized'] else 'doc'}"


@pytest.mark.parametrize("params", CASES + [dict(kd=(0, 0, 0), ks=(1, 1, 1), exponent=0, normalized=True)], ids=case_id)
def test_phong_closed_form(directions, params):
    wo, wi = directions
    n = np.array([0.0, 0.0, 1.0])
    r = 2 * (wo @ n)[:, None] * n - wo  # mirror of wo about the normal
    cos_r = np.sum(r * wi, axis=1, keepdims=True)
    e = params["exponent"]
    lobe = np.where(cos_r > 0, np.abs(cos_r) ** e, 0.0)
    spec = (e + 2) / (2 * np.pi) * lobe if params["normalized"] else lobe / wi[:, 2:3]
    expected = np.array(params["kd"]) / np.pi + np.array(params["ks"]) * spec
    assert np.allclose(Phong(**params).eval(wo, wi), expected, rtol=1e-12, atol=0)


@pytest.mark.parametrize("params", CASES, ids=case_id)
def test_phong_glsl_matches_numpy(ctx, rng, params):
    check_glsl_parity(Phong(**params), ctx, rng)


def test_phong_glsl_large_exponent(ctx, rng):
    """Near the mirror direction the GLSL twin takes log(r·wi) from |r − wi|² (no cancellation): e = 5000."""
    check_glsl_parity(Phong(kd=(0.02, 0.02, 0.02), ks=(0.98, 0.98, 0.98), exponent=5000, normalized=True), ctx, rng)


@pytest.mark.parametrize("params", CASES, ids=case_id)
def test_phong_standard_checks(rng, params):
    run_standard_checks(Phong(**params), rng)


def test_normalized_form_is_reciprocal_and_document_form_is_not(directions):
    wo, wi = directions
    norm = Phong(kd=(0, 0, 0), exponent=40, normalized=True)
    doc = Phong(kd=(0, 0, 0), exponent=40, normalized=False)
    assert norm.reciprocal and not doc.reciprocal
    assert np.allclose(norm.eval(wo, wi), norm.eval(wi, wo), rtol=1e-12)
    assert not np.allclose(doc.eval(wo, wi), doc.eval(wi, wo))  # the 1/(n·wi) factor breaks reciprocity


@pytest.mark.parametrize("exponent", [0, 1, 20, 200])
def test_normalized_lobe_reflects_all_energy_at_normal_incidence_and_less_elsewhere(exponent):
    m = Phong(kd=(0, 0, 0), ks=(1, 1, 1), exponent=exponent, normalized=True)
    assert hemisphere_albedo(m, np.array([0.0, 0.0, 1.0]), n=800) == pytest.approx([1, 1, 1], rel=2e-3)
    for theta in (0.3, 0.6, 1.2):
        wo = np.array([np.sin(theta), 0.0, np.cos(theta)])
        albedo = hemisphere_albedo(m, wo, n=800)
        assert np.all(albedo <= 1.0 + 2e-3), (exponent, theta, albedo)


def test_document_form_creates_energy():
    """f cosθ = ρ_s (r·wi)^e integrates to 2π/(e + 1) at normal incidence: π for e = 1."""
    m = Phong(kd=(0, 0, 0), ks=(1, 1, 1), exponent=1, normalized=False)
    assert not m.energy_conserving
    assert hemisphere_albedo(m, np.array([0.0, 0.0, 1.0]), n=800) == pytest.approx([np.pi] * 3, rel=1e-3)


def test_energy_conserving_only_when_normalized_and_bounded():
    assert Phong(kd=(0.5, 0.5, 0.5), ks=(0.5, 0.5, 0.5), normalized=True).energy_conserving
    assert not Phong(kd=(0.5, 0.5, 0.6), ks=(0.5, 0.5, 0.5), normalized=True).energy_conserving
    assert not Phong(kd=(0, 0, 0), ks=(0.5, 0.5, 0.5), normalized=False).energy_conserving


def test_registered_and_parsed_from_scene_dict():
    assert MATERIALS["phong"] is Phong
    m = Phong.model_validate({"type": "phong", "kd": [0.1, 0.2, 0.3], "exponent": 30, "normalized": True})
    assert m.kd == (0.1, 0.2, 0.3) and m.exponent == 30 and m.normalized


@pytest.mark.parametrize(
    "bad",
    [
        dict(exponent=-1),
        dict(exponent=float("inf")),
        dict(exponent=2e6),
        dict(ks=(1.2, 0.5, 0.5)),
        dict(kd=(0.1, float("nan"), 0.1)),
        dict(kd=(0.1, 0.1)),
        dict(shininess=10),
    ],
)
def test_invalid_parameters_rejected(bad):
    with pytest.raises(ValidationError):
        Phong(**bad)
