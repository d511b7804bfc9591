"""The fixed test set every BRDF model runs (STYLE.md §7), as plain functions with failure messages that
name the model and its parameters. Each model's test file calls them with its own parameter sets."""

from __future__ import annotations

import numpy as np

from reflets.brdf.base import Material


def upper_hemisphere(rng: np.random.Generator, n: int) -> np.ndarray:
    v = rng.normal(size=(n, 3))
    v /= np.linalg.norm(v, axis=1, keepdims=True)
    v[:, 2] = np.abs(v[:, 2]) + 1e-6
    return v / np.linalg.norm(v, axis=1, keepdims=True)


def uniform_sphere(rng: np.random.Generator, n: int) -> np.ndarray:
    v = rng.normal(size=(n, 3))
    return v / np.linalg.norm(v, axis=1, keepdims=True)


def direction(theta: float, phi: float = 0.3) -> np.ndarray:
    return np.array([np.sin(theta) * np.cos(phi), np.sin(theta) * np.sin(phi), np.cos(theta)])


def name(m: Material) -> str:
    return f"{m.type}({m.model_dump(exclude={'type'})})"


def check_reciprocity(m: Material, rng: np.random.Generator, n: int = 5000) -> None:
    wo, wi = upper_hemisphere(rng, n), upper_hemisphere(rng, n)
    a, b = m.eval(wo, wi), m.eval(wi, wo)
    assert np.allclose(a, b, rtol=1e-9, atol=1e-12), f"{name(m)} is not reciprocal"


def check_zero_below_horizon(m: Material, rng: np.random.Generator, n: int = 2000) -> None:
    wo, wi = upper_hemisphere(rng, n), upper_hemisphere(rng, n)
    down = wi * [1, 1, -1]
    assert np.all(m.eval(wo, down) == 0) and np.all(m.eval(down, wi) == 0), f"{name(m)} leaks below the horizon"


def albedo_uniform(m: Material, wo: np.ndarray, rng: np.random.Generator, n: int) -> tuple[np.ndarray, np.ndarray]:
    """∫ f cosθ dω by uniform hemisphere sampling: mean and standard error per channel."""
    wi = upper_hemisphere(rng, n)
    est = m.eval(np.broadcast_to(wo, wi.shape), wi) * wi[:, 2:3] * (2 * np.pi)
    return est.mean(axis=0), est.std(axis=0) / np.sqrt(n)


def albedo_sampled(m: Material, wo: np.ndarray, rng: np.random.Generator, n: int) -> tuple[np.ndarray, np.ndarray]:
    """∫ f cosθ dω with the model's own importance sampling."""
    wi, pdf = m.sample(wo, rng.random(n), rng.random(n))
    f = m.eval(np.broadcast_to(wo, wi.shape), wi)
    ok = (pdf > 0)[:, None]
    est = np.where(ok, f * np.maximum(wi[:, 2:3], 0) / np.where(ok, pdf[:, None], 1.0), 0.0)
    return est.mean(axis=0), est.std(axis=0) / np.sqrt(n)


def check_sample_pdf_consistent(m: Material, wo: np.ndarray, rng: np.random.Generator, n: int = 20000) -> None:
    """The pdf ``sample`` returns is ``pdf(wo, wi)`` (or 0 for a failed sample, pointing below the surface),
    and is positive wherever f > 0 was sampled."""
    wi, pdf = m.sample(wo, rng.random(n), rng.random(n))
    assert wi.shape == (n, 3) and pdf.shape == (n,)
    assert np.allclose(np.linalg.norm(wi, axis=1), 1, atol=1e-9), f"{name(m)}: sampled directions not unit"
    ok = pdf > 0
    assert np.all(wi[~ok, 2] < 0), f"{name(m)}: a failed sample must point below the surface"
    expected = m.pdf(np.broadcast_to(wo, wi.shape)[ok], wi[ok])
    assert np.allclose(pdf[ok], expected, rtol=1e-9), f"{name(m)}: sample's pdf differs from pdf()"
    f = m.eval(np.broadcast_to(wo, wi.shape), wi)
    assert np.all(pdf[np.any(f > 0, axis=1)] > 0), f"{name(m)}: zero pdf for a sampled direction with f > 0"


def check_pdf_integrates_to_one(m: Material, wo: np.ndarray, rng: np.random.Generator, n: int = 200000) -> None:
    """∫_sphere pdf dω = 1 − P(failed sample), estimated with the defensive mixture q = ½ uniform + ½ pdf
    (ratio pdf/q ≤ 2). Half the points come from ``sample`` and half are uniform; if ``sample`` does not follow
    ``pdf`` the estimate is biased, so this also checks that the two agree."""
    half = n // 2
    w_s, p_s = m.sample(wo, rng.random(half), rng.random(half))
    expected = 1.0 - np.mean(p_s == 0)
    w = np.concatenate([w_s, uniform_sphere(rng, half)])
    p = m.pdf(np.broadcast_to(wo, w.shape), w)
    ratio = p / (0.5 / (4 * np.pi) + 0.5 * p)
    mean, err = ratio.mean(), ratio.std() / np.sqrt(len(ratio))
    assert abs(mean - expected) < 4 * err + 2e-3, f"{name(m)}: ∫pdf = {mean:.4f} ± {err:.4f} ≠ {expected} (wo={wo})"


def check_sampling_agrees_with_uniform(m: Material, wo: np.ndarray, rng: np.random.Generator, n=400000) -> None:
    a, ea = albedo_sampled(m, wo, rng, n)
    b, eb = albedo_uniform(m, wo, rng, n)
    tol = 3 * np.sqrt(ea**2 + eb**2) + 1e-6
    assert np.all(np.abs(a - b) <= tol), f"{name(m)} wo={wo}: sampled {a} ± {ea} vs uniform {b} ± {eb}"


def check_white_furnace(m: Material, rng: np.random.Generator, thetas=(0.0, 0.5, 1.0, 1.4), n=400000) -> None:
    """Directional albedo ≤ 1 (within 3 standard errors of the lower-variance estimate)."""
    for theta in thetas:
        wo = direction(theta)
        a, ea = albedo_sampled(m, wo, rng, n)
        assert np.all(a - 3 * ea <= 1.0 + 1e-6), f"{name(m)}: albedo {a} ± {ea} > 1 at θo = {theta}"


def check_glsl_parity(m: Material, ctx, rng: np.random.Generator, n: int = 10000) -> None:
    """GLSL float32 vs NumPy float64 on ≥ 10,000 random direction pairs: max relative error < 1e-3 where the
    value exceeds 1e-4."""
    from reflets.brdf.gpu_eval import eval_glsl

    wo, wi = upper_hemisphere(rng, n), upper_hemisphere(rng, n)
    ref = m.eval(wo, wi)
    gpu = eval_glsl(m, wo, wi, ctx)
    keep = np.abs(ref) > 1e-4
    rel = np.abs(gpu - ref)[keep] / np.abs(ref)[keep]
    assert keep.sum() > 0.05 * keep.size or keep.sum() > 500, f"{name(m)}: too few significant values"
    assert np.all(np.isfinite(gpu)), f"{name(m)}: GLSL produced non-finite values"
    assert rel.max() < 1e-3, f"{name(m)}: GLSL vs NumPy max relative error {rel.max():.2e}"


def run_standard_checks(m: Material, rng: np.random.Generator, thetas=(0.1, 0.7, 1.3)) -> None:
    """Everything but the GPU parity: horizon, reciprocity (if declared), sampling, pdf, furnace."""
    check_zero_below_horizon(m, rng)
    if m.reciprocal:
        check_reciprocity(m, rng)
    for theta in thetas:
        wo = direction(theta)
        check_sample_pdf_consistent(m, wo, rng)
        check_pdf_integrates_to_one(m, wo, rng)
        check_sampling_agrees_with_uniform(m, wo, rng)
    if m.energy_conserving:
        check_white_furnace(m, rng)
