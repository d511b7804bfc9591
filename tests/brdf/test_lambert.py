from __future__ import annotations

import numpy as np
import pytest
from brdf_checks import check_glsl_parity, direction, run_standard_checks
from brdf_helpers import hemisphere_albedo

from reflets.brdf import Lambert


def test_lambert_is_albedo_over_pi_above_and_zero_below(directions):
    wo, wi = directions
    m = Lambert(albedo=(0.2, 0.5, 0.9))
    assert np.allclose(m.eval(wo, wi), np.array([0.2, 0.5, 0.9]) / np.pi)


def test_lambert_white_furnace_albedo_equals_rho():
    m = Lambert(albedo=(1.0, 0.5, 0.25))
    assert np.allclose(hemisphere_albedo(m, direction(0.4)), [1.0, 0.5, 0.25], rtol=1e-9)


def test_lambert_standard_checks(rng):
    run_standard_checks(Lambert(albedo=(1.0, 0.5, 0.25)), rng)


def test_lambert_glsl_matches_numpy(ctx, rng):
    check_glsl_parity(Lambert(albedo=(0.2, 0.5, 0.9)), ctx, rng)


@pytest.mark.parametrize("albedo", [(1.1, 0, 0), (-0.1, 0, 0), (float("nan"), 0, 0)])
def test_lambert_rejects_unphysical_albedo(albedo):
    from pydantic import ValidationError

    with pytest.raises(ValidationError):
        Lambert(albedo=albedo)
