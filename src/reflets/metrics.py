"""Error metrics between a rendered (test) image and a reference, plus false-colour error images.

Every technique in reflets is validated against ground truth, so the numbers must be reproducible: inputs are
converted to ``float64`` before any arithmetic (float32 sums over megapixels lose several digits), and both
images must be finite arrays of the same ``(H, W, 3)`` shape; anything else raises
:class:`~reflets.errors.ArgumentError` rather than returning a silent NaN.

Several metrics are reported because each hides something the others show: RMSE and PSNR weigh bright
pixels most, relMSE weighs dark pixels as much as bright ones, the maximum catches fireflies and seams that
averages hide, and FLIP estimates what a viewer would actually notice.

``flip_evaluator`` and ``matplotlib`` are imported inside the functions that use them.
"""

from __future__ import annotations

import functools
import math

import numpy as np

from reflets.errors import ArgumentError

__all__ = ["compare", "difference_image", "flip", "flip_error_map", "max_abs", "psnr", "relmse", "rmse"]

# Rec. 709 / sRGB luminance weights, matching the linear-RGB to XYZ matrix FLIP uses internally.
_LUMINANCE = np.array([0.2126, 0.7152, 0.0722])
# HDR-FLIP picks its exposure range from the reference's luminance and calls exit() (killing the Python
# process) when the peak luminance is below float32 epsilon. References darker than this (with a 4x margin)
# get an explicit exposure range instead; see _flip_parameters.
_FLIP_MIN_PEAK = 4.0 * float(np.finfo(np.float32).eps)
_FLIP_MODES = ("HDR", "LDR")


def _pair(test: np.ndarray, ref: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Validate a test/reference pair and return both as float64 arrays."""
    t = np.asarray(test, dtype=np.float64)
    r = np.asarray(ref, dtype=np.float64)
    if t.shape != r.shape or t.ndim != 3 or t.shape[2] != 3 or t.shape[0] == 0 or t.shape[1] == 0:
        raise ArgumentError(
            f"test shape {t.shape} and reference shape {r.shape} must be equal and (H, W, 3)", field="test"
        )
    for name, arr in (("test", t), ("reference", r)):
        if not np.isfinite(arr).all():
            raise ArgumentError(f"{name} image has NaN/inf values; metrics need finite images", field=name)
    return t, r


def _mse(t: np.ndarray, r: np.ndarray) -> float:
    return float(np.mean(np.square(t - r)))


def rmse(test: np.ndarray, ref: np.ndarray) -> float:
    """Root-mean-square error over all pixels and channels, in the images' radiance units."""
    return math.sqrt(_mse(*_pair(test, ref)))


def relmse(test: np.ndarray, ref: np.ndarray, eps: float = 1e-2) -> float:
    """Relative MSE: ``mean((test - ref)**2 / (ref**2 + eps))`` over pixels and channels.

    Monte Carlo noise grows with brightness, so plain MSE is dominated by a few highlights; dividing by the
    squared reference value weighs every pixel's error relative to its own level. This is the relMSE of the
    rendering-denoising literature (Rousselle, Knaus & Zwicker, "Adaptive sampling and reconstruction using
    greedy error minimization", 2011, and the denoisers evaluated after it); ``eps`` = 1e-2, the customary
    value there, keeps black reference pixels from dividing by zero and from dominating the mean.
    """
    if not (math.isfinite(eps) and eps > 0.0):
        raise ArgumentError(f"eps must be a finite number > 0, got {eps!r}", field="eps")
    t, r = _pair(test, ref)
    return float(np.mean(np.square(t - r) / (np.square(r) + eps)))


def masked_relmse(test: np.ndarray, ref: np.ndarray, mask: np.ndarray) -> float:
    """:func:`relmse` over the pixels where ``mask`` (H, W) is true."""
    return relmse(test[mask][None], ref[mask][None])


def psnr(test: np.ndarray, ref: np.ndarray, peak: float | None = None) -> float:
    """Peak signal-to-noise ratio ``10 * log10(peak**2 / MSE)`` in decibels.

    HDR images have no natural peak of 1, so by default ``peak`` is the reference maximum, which makes the
    value invariant to scaling both images. Returns ``inf`` when the images are identical (MSE = 0) and
    ``-inf`` when the default peak is not positive (an all-black reference) while MSE > 0.
    """
    t, r = _pair(test, ref)
    if peak is None:
        top = float(r.max())
    else:
        top = float(peak)
        if not (math.isfinite(top) and top > 0.0):
            raise ArgumentError(f"peak must be a finite number > 0, got {peak!r}", field="peak")
    mse = _mse(t, r)
    if mse == 0.0:
        return math.inf
    if top <= 0.0:
        return -math.inf
    return 10.0 * math.log10(top * top / mse)


def max_abs(test: np.ndarray, ref: np.ndarray) -> float:
    """Largest absolute difference over all pixels and channels (catches fireflies and seams)."""
    t, r = _pair(test, ref)
    return float(np.max(np.abs(t - r)))


@functools.cache
def _flip_tonemap_xmax() -> float:
    """FLIP's ``xMax``: the input that its tone mapper maps to 0.85 (a constant, read back from FLIP itself).

    For a reference with peak luminance 1, FLIP's automatic start exposure is ``log2(xMax / 1)``.
    """
    import flip_evaluator

    one = np.ones((1, 1, 3), dtype=np.float32)
    _, _, used = flip_evaluator.evaluate(one, one, "HDR")
    return 2.0 ** float(used["startExposure"])


def _flip_parameters(t32: np.ndarray, r32: np.ndarray) -> dict:
    """Exposure range for HDR-FLIP: FLIP's own automatic one unless the reference is (nearly) black.

    FLIP derives ``[log2(xMax / Ymax), log2(xMax / Ymedian)]`` from the reference alone and exits the process
    when ``Ymax`` is below float32 epsilon. In that case the same formula is applied to the brighter of the
    two images, so a black reference against a non-black test is still scored (as a large error).
    """
    y_ref = r32.astype(np.float64) @ _LUMINANCE
    if y_ref.max() >= _FLIP_MIN_PEAK:
        return {}
    y_test = t32.astype(np.float64) @ _LUMINANCE
    source = y_test if y_test.max() > y_ref.max() else y_ref
    xmax = _flip_tonemap_xmax()
    start = math.log2(xmax / max(float(source.max()), _FLIP_MIN_PEAK))
    stop = math.log2(xmax / max(float(np.median(source)), float(np.finfo(np.float32).eps)))
    return {"startExposure": start, "stopExposure": max(start, stop)}


def _flip_inputs(test: np.ndarray, ref: np.ndarray, mode: str) -> tuple[np.ndarray, np.ndarray, str]:
    """Validate and convert a pair for FLIP: clamped, contiguous float32 arrays and the upper-case mode."""
    t, r = _pair(test, ref)
    name = mode.upper() if isinstance(mode, str) else mode
    if name not in _FLIP_MODES:
        raise ArgumentError(f"unknown FLIP mode {mode!r}; allowed: {', '.join(_FLIP_MODES)}", field="mode")
    hi = None if name == "HDR" else 1.0
    # FLIP requires non-negative HDR input and LDR input in [0, 1]; its bindings want contiguous float32.
    t32 = np.ascontiguousarray(np.clip(t, 0.0, hi), dtype=np.float32)
    r32 = np.ascontiguousarray(np.clip(r, 0.0, hi), dtype=np.float32)
    return t32, r32, name


def _flip_run(t32: np.ndarray, r32: np.ndarray, mode: str, magma: bool) -> tuple[np.ndarray, float]:
    import flip_evaluator

    params = _flip_parameters(t32, r32) if mode == "HDR" else {}
    # inputsRGB=False: arrays in reflets are linear; FLIP would otherwise sRGB-decode LDR input a second time.
    errors, mean, _ = flip_evaluator.evaluate(
        r32, t32, mode, inputsRGB=False, applyMagma=magma, computeMeanError=True, parameters=params
    )
    return np.asarray(errors), float(mean)


def flip(test: np.ndarray, ref: np.ndarray, mode: str = "HDR") -> float:
    """Mean FLIP error in [0, 1] (Andersson et al., HPG 2020; HDR-FLIP, EGSR 2021) via ``flip_evaluator``.

    FLIP models what a viewer flipping between the two images would notice (colour and edge differences at
    a given viewing distance), which the pixel-wise metrics cannot. ``mode="HDR"`` (default) takes linear
    radiance and evaluates over a range of exposures; negatives are clamped to 0. ``mode="LDR"`` takes linear
    values in [0, 1] (e.g. an already tone-mapped image, linearised) and clamps to that range. Identical
    inputs (after clamping) return exactly 0.0 without running FLIP.
    """
    t32, r32, name = _flip_inputs(test, ref, mode)
    if np.array_equal(t32, r32):
        return 0.0
    return _flip_run(t32, r32, name, magma=False)[1]


def flip_per_pixel(test: np.ndarray, ref: np.ndarray, mode: str = "HDR") -> np.ndarray:
    """FLIP's error of each pixel, float32 (H, W) in [0, 1]: for means over a region (an object, a shadow)."""
    t32, r32, name = _flip_inputs(test, ref, mode)
    return np.asarray(_flip_run(t32, r32, name, magma=False)[0], np.float32).reshape(t32.shape[:2])


def flip_error_map(test: np.ndarray, ref: np.ndarray, mode: str = "HDR") -> np.ndarray:
    """FLIP per-pixel error in FLIP's magma colour map, as uint8 (H, W, 3) ready for a gallery."""
    t32, r32, name = _flip_inputs(test, ref, mode)
    errors = _flip_run(t32, r32, name, magma=True)[0]
    return np.round(np.clip(errors[:, :, :3], 0.0, 1.0) * 255.0).astype(np.uint8)


def compare(test: np.ndarray, ref: np.ndarray) -> dict[str, float]:
    """All scalar metrics at once, as plain floats: ``rmse``, ``relmse``, ``psnr``, ``max_abs``, ``flip``.

    ``psnr`` may be ``inf`` (identical images). ``flip`` uses the default HDR mode.
    """
    t, r = _pair(test, ref)
    return {
        "rmse": rmse(t, r),
        "relmse": relmse(t, r),
        "psnr": psnr(t, r),
        "max_abs": max_abs(t, r),
        "flip": flip(t, r),
    }


def difference_image(
    test: np.ndarray, ref: np.ndarray, mode: str = "relative", scale: float | None = None
) -> np.ndarray:
    """False-colour heat map of the per-pixel error, as uint8 (H, W, 3) in matplotlib's 'magma'.

    The per-pixel error is the mean over channels of ``|test - ref|`` (``mode="absolute"``) or of
    ``|test - ref| / (|ref| + 1e-2)`` (``mode="relative"``, so errors in dark regions stay visible). It is
    divided by ``scale``, or by default by its 99th percentile so that a few fireflies do not wash out the
    rest, then clamped to [0, 1]. Pass the same ``scale`` to make several maps comparable.
    """
    t, r = _pair(test, ref)
    if mode not in ("relative", "absolute"):
        raise ArgumentError(f"unknown difference mode {mode!r}; allowed: relative, absolute", field="mode")
    diff = np.abs(t - r)
    if mode == "relative":
        diff = diff / (np.abs(r) + 1e-2)
    error = diff.mean(axis=2)
    if scale is None:
        norm = float(np.percentile(error, 99.0))
        norm = norm if norm > 0.0 else 1.0  # identical images: an all-black map rather than 0 / 0
    else:
        norm = float(scale)
        if not (math.isfinite(norm) and norm > 0.0):
            raise ArgumentError(f"scale must be a finite number > 0, got {scale!r}", field="scale")
    import matplotlib

    lut = matplotlib.colormaps["magma"](np.linspace(0.0, 1.0, 256))[:, :3]
    index = np.round(np.clip(error / norm, 0.0, 1.0) * 255.0).astype(np.intp)
    return np.round(lut[index] * 255.0).astype(np.uint8)


def zscores(test: np.ndarray, ref: np.ndarray, stderr: np.ndarray) -> dict[str, float]:
    """How far ``test`` is from a Monte Carlo ``ref`` in units of the reference's own standard error.

    Over pixels/channels with stderr > 0: mean z (bias), mean |z|, and the fraction within 3 standard errors.
    A technique indistinguishable from the reference gives mean |z| ≲ 0.8 and ≳ 99 % within 3.
    """
    t, r, s = (np.asarray(x, dtype=np.float64) for x in (test, ref, stderr))
    if not (t.shape == r.shape == s.shape):
        raise ArgumentError(f"shapes differ: test {t.shape}, reference {r.shape}, stderr {s.shape}", field="stderr")
    keep = s > 1e-7 * np.maximum(np.abs(r), 1e-30)  # a zero (or rounding-level) error is no Monte Carlo noise
    if not np.any(keep):
        return {"mean_z": float("nan"), "mean_abs_z": float("nan"), "within_3_stderr": float("nan")}
    z = (t[keep] - r[keep]) / s[keep]
    return {
        "mean_z": float(z.mean()),
        "mean_abs_z": float(np.abs(z).mean()),
        "within_3_stderr": float(np.mean(np.abs(z) <= 3.0)),
    }
