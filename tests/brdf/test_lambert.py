from __future__ import annotations

import numpy as np
import pytest
from brdf_helpers import hemisphere_albedo

from reflets.brdf import Lambert
from reflets.brdf.gpu_eval import eval_glsl


def test_lambert_is_albedo_over_pi_above_and_zero_below(directions):
    wo, wi = directions
    m = Lambert(albedo=(0.2, 0.5, 0.9))
    assert np.allclose(m.eval(wo, wi), np.array([0.2, 0.5, 0.9]) / np.pi)
    below = wi * [1, 1, -1]
    assert np.all(m.eval(wo, below) == 0) and np.all(m.eval(below, wi) == 0)


def test_lambert_white_furnace_albedo_equals_rho():
    m = Lambert(albedo=(1.0, 0.5, 0.25))
    assert np.allclose(
        hemisphere_albedo(m, np.array([0.3, 0.1, 0.95]) / np.linalg.norm([0.3, 0.1, 0.95])),
        [1.0, 0.5, 0.25],
        rtol=1e-9,
    )


def test_lambert_glsl_matches_numpy(ctx, directions):
    wo, wi = directions
    m = Lambert(albedo=(0.2, 0.5, 0.9))
    assert np.allclose(eval_glsl(m, wo, wi, ctx), m.eval(wo, wi), rtol=1e-6)


@pytest.mark.parametrize("albedo", [(1.1, 0, 0), (-0.1, 0, 0), (float("nan"), 0, 0)])
def test_lambert_rejects_unphysical_albedo(albedo):
    from pydantic import ValidationError

    with pytest.raises(ValidationError):
        Lambert(albedo=albedo)
