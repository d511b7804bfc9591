"""The mirror material: its finite part is Lambertian, its reflectance constant or exact conductor Fresnel."""

from __future__ import annotations

import numpy as np
import pytest
from pydantic import ValidationError

from reflets.brdf import Mirror
from reflets.brdf.gpu_eval import eval_glsl
from reflets.fresnel import GOLD_ETA, GOLD_K, fresnel_conductor


def test_eval_is_the_lambertian_part_only(rng):
    m = Mirror(diffuse=(0.2, 0.1, 0.0), reflectance=(0.7, 0.8, 0.9))
    wo = np.array([[0.0, 0.0, 1.0]] * 3)
    wi = np.array([[0.0, 0.6, 0.8], [0.0, 0.0, 1.0], [0.0, 0.0, -1.0]])
    np.testing.assert_allclose(m.eval(wo, wi)[:2], np.tile(np.array([0.2, 0.1, 0.0]) / np.pi, (2, 1)))
    np.testing.assert_array_equal(m.eval(wo, wi)[2], 0.0)


def test_reflectance_is_constant_or_conductor_fresnel():
    cos = np.linspace(0.0, 1.0, 11)
    np.testing.assert_array_equal(Mirror(reflectance=(0.5, 0.6, 0.7)).specular_reflectance(cos)[3], [0.5, 0.6, 0.7])
    gold = Mirror(fresnel="conductor").specular_reflectance(cos)
    np.testing.assert_allclose(gold, fresnel_conductor(cos[:, None], GOLD_ETA, GOLD_K))
    assert np.all(gold <= 1.0) and np.allclose(gold[0], 1.0)


def test_glsl_twin_matches(ctx, rng):
    m = Mirror(diffuse=(0.3, 0.2, 0.1), reflectance=(0.6, 0.6, 0.6))
    wo = rng.normal(size=(500, 3))
    wi = rng.normal(size=(500, 3))
    wo[:, 2], wi[:, 2] = np.abs(wo[:, 2]), np.abs(wi[:, 2])
    wo /= np.linalg.norm(wo, axis=1, keepdims=True)
    wi /= np.linalg.norm(wi, axis=1, keepdims=True)
    np.testing.assert_allclose(eval_glsl(m, wo, wi, ctx), m.eval(wo, wi), rtol=1e-5, atol=1e-7)


@pytest.mark.parametrize(
    "params",
    [
        {"diffuse": (0.5, 0.5, 0.5), "reflectance": (0.6, 0.6, 0.6)},
        {"eta": (1.0, 1.0, 1.0), "k": (2.0, 2.0, 2.0)},
        {"fresnel": "conductor", "eta": (1.0, 1.0, 1.0)},
    ],
)
def test_invalid_parameters_are_rejected(params):
    with pytest.raises(ValidationError):
        Mirror(**params)
