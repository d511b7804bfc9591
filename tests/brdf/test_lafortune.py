from __future__ import annotations

import numpy as np
import pytest
from brdf_checks import check_glsl_parity, direction, run_standard_checks
from pydantic import ValidationError

from reflets.brdf.base import MATERIALS
from reflets.brdf.lafortune import MAX_LOBES, Lafortune
from reflets.brdf.phong import Phong

CASES = [
    dict(kd=(0.2, 0.3, 0.4)),  # the default lobe: Phong-like, C = (−1, −1, 1), n = 20
    dict(  # anisotropic off-specular lobe + retro-reflection
        kd=(0.1, 0.1, 0.1),
        lobes=[
            dict(c=(-0.8, -0.3, 0.9), exponent=12, scale=(0.6, 0.5, 0.4)),
            dict(c=(0.5, 0.5, 0.3), exponent=3, scale=(0.2, 0.2, 0.2)),
        ],
    ),
    dict(  # a sharp, slightly grazing-boosted lobe (|C| > 1), a flat n = 0 lobe and an empty C = 0 lobe
        kd=(0.05, 0.05, 0.05),
        lobes=[
            dict(c=(-1.02, -1.02, 0.97), exponent=500, scale=(1, 1, 1)),
            dict(c=(0, 0, 1), exponent=0, scale=(0.1, 0.1, 0.1)),
            dict(c=(0, 0, 0), exponent=2, scale=(1, 1, 1)),
        ],
    ),
]
#: parity also with all eight lobes in use
EIGHT = dict(
    kd=(0.1, 0.2, 0.3),
    lobes=[dict(c=(-1 - 0.05 * i, -1 + 0.05 * i, 1), exponent=2.0**i, scale=(0.1, 0.05 * i, 0.01)) for i in range(8)],
)


def case_id(p: dict) -> str:
    return "+".join(f"n{lobe['exponent']:g}" for lobe in p.get("lobes", [dict(exponent=20)]))


@pytest.mark.parametrize("params", CASES + [EIGHT], ids=case_id)
def test_lafortune_closed_form(directions, params):
    wo, wi = directions
    expected = np.tile(np.array(params["kd"]) / np.pi, (len(wo), 1))
    for lobe in params.get("lobes", [dict(c=(-1, -1, 1), exponent=20, scale=(1, 1, 1))]):
        cx, cy, cz = lobe["c"]
        x = cx * wo[:, 0] * wi[:, 0] + cy * wo[:, 1] * wi[:, 1] + cz * wo[:, 2] * wi[:, 2]
        expected += np.where(x > 0, np.abs(x) ** lobe["exponent"], 0.0)[:, None] * np.array(lobe["scale"])
    assert np.allclose(Lafortune(**params).eval(wo, wi), expected, rtol=1e-12, atol=0)


@pytest.mark.parametrize("params", CASES + [EIGHT], ids=case_id)
def test_lafortune_glsl_matches_numpy(ctx, rng, params):
    check_glsl_parity(Lafortune(**params), ctx, rng)


@pytest.mark.slow
@pytest.mark.parametrize("params", CASES, ids=case_id)
def test_lafortune_standard_checks(rng, params):
    run_standard_checks(Lafortune(**params), rng)


def test_always_reciprocal_never_declared_energy_conserving(directions):
    wo, wi = directions
    m = Lafortune(**CASES[1])
    assert m.reciprocal and not m.energy_conserving
    assert np.allclose(m.eval(wo, wi), m.eval(wi, wo), rtol=1e-12)


@pytest.mark.parametrize("exponent", [0, 7, 120])
def test_phong_lobe_equals_normalised_phong(directions, exponent):
    """C = (−1, −1, 1) with scale ρ_s (n + 2)/(2π) is the normalised Phong BRDF."""
    wo, wi = directions
    ks = np.array([0.2, 0.5, 0.7])
    scale = tuple(ks * (exponent + 2) / (2 * np.pi))
    laf = Lafortune(kd=(0.1, 0.1, 0.1), lobes=[dict(c=(-1, -1, 1), exponent=exponent, scale=scale)])
    phong = Phong(kd=(0.1, 0.1, 0.1), ks=tuple(ks), exponent=exponent, normalized=True)
    assert np.allclose(laf.eval(wo, wi), phong.eval(wo, wi), rtol=1e-12)


def test_retro_reflection_peaks_towards_the_viewer():
    m = Lafortune(lobes=[dict(c=(1, 1, 1), exponent=30)])
    wo = direction(0.8, 0.4)
    thetas = np.linspace(0.05, 1.5, 59)
    wis = np.array([direction(t, 0.4) for t in thetas])
    f = m.eval(np.broadcast_to(wo, wis.shape), wis)[:, 0]
    assert thetas[np.argmax(f)] == pytest.approx(0.8, abs=0.03)
    assert m.eval(wo, wo * [-1, -1, 1])[0] < 1e-3 * f.max()  # nothing towards the mirror direction


def test_anisotropy_follows_the_tangent():
    """C_x ≠ C_y: the reflection depends on the azimuth of wo and wi relative to the tangent (local x)."""
    m = Lafortune(lobes=[dict(c=(-0.9, -1.0, 1.0), exponent=50)])
    m_rot = Lafortune(lobes=[dict(c=(-1.0, -0.9, 1.0), exponent=50)])
    wo, wi = direction(0.6, 0.0), direction(0.6, np.pi + 0.3)  # off the mirror direction by φ
    wo_y, wi_y = direction(0.6, np.pi / 2), direction(0.6, -np.pi / 2 + 0.3)
    assert m.eval(wo, wi)[0] == pytest.approx(m_rot.eval(wo_y, wi_y)[0], rel=1e-12)  # x and y swap roles
    assert m.eval(wo, wi)[0] != pytest.approx(m.eval(wo_y, wi_y)[0], rel=1e-3)


def test_uniforms_fill_the_fixed_size_arrays():
    u = Lafortune(**CASES[1]).uniforms()
    assert u["m_lobe_count"] == 2
    assert len(u["m_lobe_c"]) == len(u["m_lobe_exponent"]) == len(u["m_lobe_scale"]) == MAX_LOBES == 8


def test_registered_and_parsed_from_scene_dict():
    assert MATERIALS["lafortune"] is Lafortune
    m = Lafortune.model_validate(
        {"type": "lafortune", "kd": [0.1, 0.1, 0.1], "lobes": [{"c": [-1, -1, 1], "exponent": 10, "scale": [2, 2, 2]}]}
    )
    assert m.lobes[0].c == (-1, -1, 1) and m.lobes[0].scale == (2, 2, 2)


@pytest.mark.parametrize(
    "bad",
    [
        dict(lobes=[]),
        dict(lobes=[dict()] * 9),
        dict(lobes=[dict(c=(float("inf"), -1, 1))]),
        dict(lobes=[dict(c=(-1, 1))]),
        dict(lobes=[dict(exponent=-1)]),
        dict(lobes=[dict(exponent=float("nan"))]),
        dict(lobes=[dict(scale=(1, -0.5, 1))]),
        dict(lobes=[dict(shininess=3)]),
        dict(kd=(1.5, 0, 0)),
        dict(ks=(1, 1, 1)),
    ],
)
def test_invalid_parameters_rejected(bad):
    with pytest.raises(ValidationError):
        Lafortune(**bad)
