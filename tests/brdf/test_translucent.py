"""The translucent material's data model (presets, validation) and its far-field BRDF."""

from __future__ import annotations

import numpy as np
import pytest
from brdf_checks import check_glsl_parity, run_standard_checks
from pydantic import ValidationError

import reflets
from reflets.brdf.base import MATERIALS
from reflets.translucency import PRESETS
from reflets.translucency.material import Translucent

CASES = [
    dict(preset="skin1"),
    dict(preset="marble", roughness=0.3),
    dict(sigma_a=(0.01, 0.1, 0.5), sigma_s=(2.0, 2.0, 2.0), g=0.6, eta=1.4, roughness=0.1),
    dict(preset="ketchup", eta=1.0, profile="dipole"),
]


def case_id(p: dict) -> str:
    return "-".join(f"{k}{v}" for k, v in p.items() if k in ("preset", "roughness", "eta", "g"))


@pytest.mark.parametrize("params", CASES, ids=case_id)
def test_translucent_glsl_matches_numpy(ctx, rng, params):
    check_glsl_parity(Translucent(**params), ctx, rng)


@pytest.mark.parametrize("params", CASES, ids=case_id)
def test_translucent_standard_checks(rng, params):
    run_standard_checks(Translucent(**params), rng)


@pytest.mark.parametrize("profile", ["multiple_fit", "better_dipole"])
def test_diffuse_part_reemits_the_profile_total_reflectance(profile):
    """∫ f cosθ_o dω_o of the smooth material = F_T(θ_i) R_total: the far-field limit of S_d (all orders:
    ``multiple_fit`` adds single scattering to its own total, the document's profiles stand for all orders)."""
    from reflets.translucency.profiles import far_field_reflectance

    m = Translucent(preset="skin1", profile=profile)
    mu, w = np.polynomial.legendre.leggauss(400)
    mu = 0.5 * (mu + 1.0)
    wo = np.stack([np.sqrt(1 - mu**2), np.zeros_like(mu), mu], axis=1)
    wi = np.array([0.0, 0.0, 1.0])
    f = m.eval(wo, np.broadcast_to(wi, wo.shape))
    exitance = 2 * np.pi * 0.5 * np.sum(w[:, None] * f * mu[:, None], axis=0)
    ft = 1 - ((m.eta - 1) / (m.eta + 1)) ** 2
    np.testing.assert_allclose(exitance, ft * far_field_reflectance(profile, m.medium()), rtol=1e-6)
    if profile == "better_dipole":
        np.testing.assert_allclose(exitance, ft * m.total_reflectance(), rtol=1e-6)


def test_presets_fill_coefficients_and_explicit_values_win():
    for name in PRESETS:
        m = Translucent(preset=name)
        np.testing.assert_allclose(m.reduced_scattering, PRESETS[name]["sigma_s_prime"])
        assert m.eta == PRESETS[name]["eta"]
    assert Translucent(preset="skin1", eta=1.0).eta == 1.0
    np.testing.assert_allclose(Translucent(preset="skin1", sigma_a=(1, 1, 1)).sigma_a, (1, 1, 1))
    np.testing.assert_allclose(Translucent(sigma_a=(0, 0, 0), sigma_s=(2, 2, 2), g=0.5).reduced_scattering, 1.0)
    assert MATERIALS["translucent"] is Translucent


@pytest.mark.parametrize(
    "params, message",
    [
        (dict(preset="skin3"), "unknown preset 'skin3'"),
        (dict(sigma_s_prime=(1, 1, 1)), "give sigma_a"),
        (dict(sigma_a=(1, 1, 1)), "exactly one of sigma_s_prime and sigma_s"),
        (dict(sigma_a=(0, 0, 0), sigma_s_prime=(0, 1, 1)), "must be > 0"),
        (dict(preset="skin1", profile="tripole"), "profile"),
        (dict(preset="skin1", eta=0.5), "eta"),
    ],
)
def test_bad_parameters_are_named(params, message):
    with pytest.raises(ValidationError, match=message):
        Translucent(**params)


def test_scene_file_form(tmp_path):
    scene = tmp_path / "s.toml"
    scene.write_text(
        '[camera]\nposition = [0, 0, 3]\nlook_at = [0, 0, 0]\nsize = [32, 24]\n[materials.skin]\ntype = "translucent"\n'
        'preset = "skin1"\nroughness = 0.3\nmm_per_unit = 100\n[[mesh]]\nshape = "sphere"\nmaterial = "skin"\n'
        '[[light]]\ntype = "point"\nposition = [2, 2, 2]\nintensity = [10, 10, 10]\n'
    )
    loaded = reflets.load_scene(scene)
    assert loaded.materials["skin"].mm_per_unit == 100
    with pytest.raises(reflets.errors.SceneError, match="materials.skin"):
        reflets.load_scene(scene.write_text(scene.read_text().replace('"skin1"', '"skin9"')) and scene)
