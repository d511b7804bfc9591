"""Tests for reflets.metrics: values against an independent NumPy computation, edge cases, error images."""

from __future__ import annotations

import math

import numpy as np
import pytest

from reflets.errors import ArgumentError
from reflets.metrics import compare, difference_image, flip, flip_error_map, max_abs, psnr, relmse, rmse


@pytest.fixture
def pair():
    """A reference with HDR values and a noisy test image (some test values negative, as in MC noise)."""
    rng = np.random.default_rng(1234)
    ref = rng.uniform(0.0, 4.0, size=(32, 40, 3))
    test = ref + rng.normal(0.0, 0.2, size=ref.shape)
    return test, ref


def test_scalar_metrics_equal_an_independent_numpy_computation(pair):
    test, ref = pair
    n = test.size
    squared = [(float(t) - float(r)) ** 2 for t, r in zip(test.ravel(), ref.ravel(), strict=True)]
    expected_mse = math.fsum(squared) / n
    expected_rel = math.fsum(s / (float(r) ** 2 + 0.01) for s, r in zip(squared, ref.ravel(), strict=True)) / n
    expected_psnr = 20.0 * math.log10(float(ref.max())) - 10.0 * math.log10(expected_mse)
    expected_max = max(abs(float(t) - float(r)) for t, r in zip(test.ravel(), ref.ravel(), strict=True))

    assert rmse(test, ref) == pytest.approx(math.sqrt(expected_mse), rel=1e-12)
    assert relmse(test, ref) == pytest.approx(expected_rel, rel=1e-12)
    assert psnr(test, ref) == pytest.approx(expected_psnr, rel=1e-12)
    assert max_abs(test, ref) == expected_max


def test_relmse_eps_and_psnr_peak_parameters_are_used(pair):
    test, ref = pair
    d2 = (test - ref) ** 2

    assert relmse(test, ref, eps=1.0) == pytest.approx(np.mean(d2 / (ref**2 + 1.0)), rel=1e-12)
    assert psnr(test, ref, peak=1.0) == pytest.approx(-10.0 * np.log10(np.mean(d2)), rel=1e-12)
    with pytest.raises(ArgumentError, match=r"eps: eps must be a finite number > 0"):
        relmse(test, ref, eps=0.0)
    with pytest.raises(ArgumentError, match=r"peak: peak must be a finite number > 0"):
        psnr(test, ref, peak=-1.0)


def test_float32_inputs_are_computed_in_float64(pair):
    test, ref = (a.astype(np.float32) for a in pair)

    expected = np.sqrt(np.mean((test.astype(np.float64) - ref.astype(np.float64)) ** 2))
    assert rmse(test, ref) == pytest.approx(expected, rel=1e-14)


def test_identical_images_give_zero_errors_and_infinite_psnr(pair):
    _, ref = pair

    assert rmse(ref, ref.copy()) == 0.0
    assert relmse(ref, ref.copy()) == 0.0
    assert max_abs(ref, ref.copy()) == 0.0
    assert flip(ref, ref.copy()) == 0.0
    assert flip(ref, ref.copy(), mode="LDR") == 0.0
    assert psnr(ref, ref.copy()) == math.inf


def test_compare_returns_exactly_the_five_metrics_as_python_floats(pair):
    test, ref = pair

    result = compare(test, ref)

    assert list(result) == ["rmse", "relmse", "psnr", "max_abs", "flip"]
    assert all(type(v) is float for v in result.values())
    assert result["rmse"] == rmse(test, ref) and result["flip"] == flip(test, ref)
    assert compare(ref, ref)["psnr"] == math.inf


def test_flip_is_in_unit_range_and_grows_with_the_error(pair):
    test, ref = pair
    small = ref + 0.1 * (test - ref)

    big_error = flip(test, ref)
    small_error = flip(small, ref)

    assert 0.0 < small_error < big_error < 1.0
    assert 0.0 < flip(np.clip(small, 0, 1), np.clip(ref, 0, 1), mode="LDR") < 1.0


def test_flip_clamps_negative_values_before_evaluating():
    ref = np.random.default_rng(3).uniform(0.0, 2.0, size=(16, 16, 3))
    test = ref.copy()
    test[ref < 0.3] = -1.0
    ref[ref < 0.3] = 0.0

    assert flip(test, ref) == 0.0  # negatives clamp to exactly the reference's zeros


def test_flip_with_black_reference_scores_instead_of_exiting():
    # FLIP's automatic exposure range is undefined for a black reference (the C++ code calls exit()).
    black = np.zeros((16, 16, 3))
    grey = np.full((16, 16, 3), 0.5)

    assert 0.5 < flip(grey, black) <= 1.0
    assert flip(black, black) == 0.0
    assert flip_error_map(black, black).shape == (16, 16, 3)


def test_shape_mismatch_raises_argument_error_naming_both_shapes():
    with pytest.raises(ArgumentError, match=r"test shape \(4, 5, 3\) and reference shape \(4, 6, 3\)"):
        rmse(np.zeros((4, 5, 3)), np.zeros((4, 6, 3)))
    with pytest.raises(ArgumentError, match=r"must be equal and \(H, W, 3\)"):
        compare(np.zeros((4, 5)), np.zeros((4, 5)))


def test_non_finite_inputs_raise_argument_error():
    ref = np.ones((4, 4, 3))
    test = ref.copy()
    test[1, 2, 0] = np.nan

    with pytest.raises(ArgumentError, match=r"test: test image has NaN/inf values"):
        rmse(test, ref)
    with pytest.raises(ArgumentError, match=r"reference: reference image has NaN/inf values"):
        flip(ref, test)


def test_unknown_modes_raise_argument_error(pair):
    test, ref = pair
    with pytest.raises(ArgumentError, match=r"mode: unknown FLIP mode 'XDR'; allowed: HDR, LDR"):
        flip(test, ref, mode="XDR")
    with pytest.raises(ArgumentError, match=r"mode: unknown difference mode 'squared'; allowed: relative"):
        difference_image(test, ref, mode="squared")
    with pytest.raises(ArgumentError, match=r"scale: scale must be a finite number > 0"):
        difference_image(test, ref, scale=0.0)


@pytest.mark.parametrize("mode", ["relative", "absolute"])
def test_difference_image_is_an_rgb_uint8_heat_map(pair, mode):
    test, ref = pair

    heat = difference_image(test, ref, mode=mode)

    assert heat.shape == (32, 40, 3) and heat.dtype == np.uint8
    assert len(np.unique(heat.reshape(-1, 3), axis=0)) > 10


def test_difference_image_scale_and_identical_images():
    ref = np.ones((4, 6, 3))
    test = ref.copy()
    test[:, 3:] += 0.5  # absolute error 0.5 on the right half

    saturated = difference_image(test, ref, mode="absolute", scale=0.5)
    half = difference_image(test, ref, mode="absolute", scale=1.0)
    black = difference_image(ref, ref.copy())

    np.testing.assert_array_equal(saturated[:, 3:], np.broadcast_to(saturated[0, 3], (4, 3, 3)))
    assert saturated[0, 3].sum() > half[0, 3].sum() > half[0, 0].sum()
    np.testing.assert_array_equal(black, np.broadcast_to(black[0, 0], black.shape))
    np.testing.assert_array_equal(black[0, 0], saturated[0, 0])  # zero error maps to the colormap's start


def test_flip_error_map_is_uint8_rgb(pair):
    test, ref = pair

    errors = flip_error_map(test, ref)

    assert errors.shape == (32, 40, 3) and errors.dtype == np.uint8
    assert errors.max() > errors.min()


def test_masked_relmse_weighs_only_the_masked_pixels():
    from reflets.metrics import masked_relmse

    ref = np.ones((2, 3, 3))
    test = ref.copy()
    test[0, 0] = 2.0  # off where the mask is false only
    mask = np.ones((2, 3), bool)
    mask[0, 0] = False
    assert masked_relmse(test, ref, mask) == 0.0
    assert masked_relmse(test, ref, ~mask) == relmse(test[0, 0][None, None], ref[0, 0][None, None]) > 0.0
