"""Microfacet (Cook–Torrance) BRDF: distribution identities by quadrature, eval against formulas written here,
the standard BRDF checks, GLSL parity, parameter validation, and (when installed) Mitsuba 3's roughconductor."""

from __future__ import annotations

import numpy as np
import pytest
from brdf_checks import check_glsl_parity, run_standard_checks, upper_hemisphere
from pydantic import ValidationError
from scipy.special import erf

from reflets.brdf.microfacet import Distribution, Microfacet
from reflets.fresnel import GOLD_ETA, GOLD_K

# ------------------------------------------------------------------------------------------ quadrature


def hemisphere_rule(wo=None, stretch=(1.0, 1.0), panels: int = 40, order: int = 12, n_phi: int = 48):
    """Directions h and solid-angle weights integrating smooth functions over the upper hemisphere, or — with
    ``wo`` — over its part where wo·h > 0 (so integrands with a max(0, wo·h) factor stay smooth).

    θ: Gauss–Legendre on panels refined geometrically towards the pole (narrow lobes), with a break where the
    visible arc starts to shrink (θ = π/2 − θo). φ: the visible arc |φ − φo| < β(θ), cos β = −cotθ cotθo (the
    whole circle when θ ≤ π/2 − θo), by Gauss–Legendre in the stretched angle ψ, tanφ = (ay/ax) tanψ, which
    makes an anisotropic lobe with roughness ``stretch`` = (ax, ay) isotropic.
    """
    ax, ay = stretch
    edges = np.concatenate([[0.0], np.geomspace(1e-6, np.pi / 2, panels)])
    if wo is not None:
        edges = np.unique(np.concatenate([edges, [np.pi / 2 - np.arccos(wo[2])]]))
    x, w = np.polynomial.legendre.leggauss(order)
    width = np.diff(edges)[:, None]
    theta = (edges[:-1, None] + width * (x + 1) / 2).ravel()
    w_theta = (width * w / 2).ravel() * np.sin(theta)

    if wo is None:
        phi_o, beta = 0.0, np.full_like(theta, np.pi)
    else:
        phi_o = np.arctan2(wo[1], wo[0])
        with np.errstate(divide="ignore"):
            c = -wo[2] / np.sqrt(1 - wo[2] ** 2) / np.tan(theta)  # −cotθo cotθ
        beta = np.arccos(np.clip(c, -1.0, 1.0))

    def to_psi(phi):  # monotone, fixes multiples of π/2, so ψ stays within π/2 of φ
        psi = np.arctan2(ax * np.sin(phi), ay * np.cos(phi))
        return psi + 2 * np.pi * np.round((phi - psi) / (2 * np.pi))

    lo, hi = to_psi(phi_o - beta), to_psi(phi_o + beta)
    xp, wp = np.polynomial.legendre.leggauss(n_phi)
    psi = (lo + hi)[:, None] / 2 + (hi - lo)[:, None] / 2 * xp
    phi = np.arctan2(ay * np.sin(psi), ax * np.cos(psi))
    dphi_dpsi = ax * ay / (ax**2 * np.cos(psi) ** 2 + ay**2 * np.sin(psi) ** 2)
    weights = w_theta[:, None] * (hi - lo)[:, None] / 2 * wp * dphi_dpsi
    s = np.sin(theta)[:, None]
    h = np.stack(np.broadcast_arrays(s * np.cos(phi), s * np.sin(phi), np.cos(theta)[:, None]), axis=-1)
    return h.reshape(-1, 3), weights.ravel()


def direction(theta: float, phi: float) -> np.ndarray:
    return np.array([np.sin(theta) * np.cos(phi), np.sin(theta) * np.sin(phi), np.cos(theta)])


DISTRIBUTIONS = [
    Distribution("ggx", 0.3, 0.3),
    Distribution("ggx", 0.05, 0.05),
    Distribution("ggx", 0.1, 0.5),
    Distribution("ggx", 1.0, 1.0),
    Distribution("beckmann", 0.3, 0.3),
    Distribution("beckmann", 0.05, 0.05),
    Distribution("beckmann", 0.5, 0.1),
    Distribution("beckmann", 1.0, 1.0),
]


def dist_id(d: Distribution) -> str:
    return f"{d.name}-{d.alpha_x}-{d.alpha_y}"


@pytest.mark.parametrize("ndf", DISTRIBUTIONS, ids=dist_id)
def test_distribution_is_normalised(ndf):
    """∫ D(h) cosθ_h dω_h = 1."""
    h, w = hemisphere_rule(stretch=(ndf.alpha_x, ndf.alpha_y))
    assert np.sum(ndf.d(h) * h[:, 2] * w) == pytest.approx(1.0, abs=1e-7)


@pytest.mark.parametrize("ndf", DISTRIBUTIONS, ids=dist_id)
def test_smith_masking_conserves_projected_area(ndf):
    """Heitz 2014 eq. 2: ∫ G1(wo, h) max(0, wo·h) D(h) dω_h = cosθo for every wo."""
    n_phi = 48 if ndf.alpha_x == ndf.alpha_y else 96
    for theta_o in (0.2, 0.8, 1.2, 1.5, 1.56):
        for phi_o in (0.0, 0.7, np.pi / 2):
            wo = direction(theta_o, phi_o)
            h, w = hemisphere_rule(wo, (ndf.alpha_x, ndf.alpha_y), n_phi=n_phi)
            projected = np.sum(ndf.g1(wo, h) * np.maximum(h @ wo, 0.0) * ndf.d(h) * w)
            assert projected == pytest.approx(wo[2], rel=1e-6), (theta_o, phi_o)


@pytest.mark.parametrize("ndf", DISTRIBUTIONS[2:3] + DISTRIBUTIONS[6:7], ids=dist_id)
def test_half_vector_sampling_follows_d_cos(ndf, rng):
    """Moments of ``sample_h`` against ∫ g(h) D(h) cosθ_h dω_h (quadrature)."""
    n = 200_000
    samples = ndf.sample_h(rng.random(n), rng.random(n))
    assert np.allclose(np.linalg.norm(samples, axis=1), 1.0)
    h, w = hemisphere_rule(stretch=(ndf.alpha_x, ndf.alpha_y))
    weight = ndf.pdf_h(h) * w
    for g in (lambda v: v[:, 2], lambda v: v[:, 0] ** 2, lambda v: v[:, 1] ** 2, lambda v: v[:, 0] * v[:, 1]):
        values = g(samples)
        expected = np.sum(g(h) * weight)
        assert abs(values.mean() - expected) < 4 * values.std() / np.sqrt(n) + 1e-12


def test_beckmann_lambda_matches_erf_form_and_the_glsl_approximation():
    """The erfcx form equals (erf(a) − 1)/2 + exp(−a²)/(2a√π); the GLSL twin's Abramowitz–Stegun 7.1.26 erfc
    (the same polynomial, written here in float64) keeps |ΔΛ| < 7.5e-8."""
    a = np.concatenate([np.geomspace(1e-4, 1, 500), np.linspace(1, 6, 500)])
    w = np.stack([np.ones_like(a), np.zeros_like(a), a], axis=-1)  # α = 1, tanθ = 1/a
    w /= np.linalg.norm(w, axis=1, keepdims=True)
    lam = Distribution("beckmann", 1.0, 1.0).smith_lambda(w)
    erf_form = (erf(a) - 1) / 2 + np.exp(-(a**2)) / (2 * a * np.sqrt(np.pi))
    assert np.allclose(lam, erf_form, rtol=1e-9, atol=1e-15)
    t = 1 / (1 + 0.3275911 * a)
    poly = t * (0.254829592 + t * (-0.284496736 + t * (1.421413741 + t * (-1.453152027 + t * 1.061405429))))
    approx = 0.5 * np.exp(-(a**2)) * (1 / (a * np.sqrt(np.pi)) - poly)
    assert np.max(np.abs(approx - lam)) < 7.5e-8


# ------------------------------------------------------------------------------------------ closed form


def fresnel_complex(cos_i, n):
    n_cos_t = np.sqrt(n * n - (1.0 - cos_i * cos_i) + 0j)
    rs = (cos_i - n_cos_t) / (cos_i + n_cos_t)
    rp = (n * n * cos_i - n_cos_t) / (n * n * cos_i + n_cos_t)
    return 0.5 * (np.abs(rs) ** 2 + np.abs(rp) ** 2)


def expected_f(params: dict, wo: np.ndarray, wi: np.ndarray) -> np.ndarray:
    """f written from the papers' angular forms (θ, φ of h and of each direction)."""
    ax, ay = np.broadcast_to(params.get("alpha", 0.3), 2)
    h = (wo + wi) / np.linalg.norm(wo + wi, axis=1, keepdims=True)
    th, ph = np.arccos(h[:, 2]), np.arctan2(h[:, 1], h[:, 0])
    k2 = np.tan(th) ** 2 * (np.cos(ph) ** 2 / ax**2 + np.sin(ph) ** 2 / ay**2)
    if params.get("distribution", "ggx") == "ggx":
        d = 1 / (np.pi * ax * ay * np.cos(th) ** 4 * (1 + k2) ** 2)
    else:
        d = np.exp(-k2) / (np.pi * ax * ay * np.cos(th) ** 4)

    def lam(v):
        t, p = np.arccos(v[:, 2]), np.arctan2(v[:, 1], v[:, 0])
        alpha = np.sqrt(np.cos(p) ** 2 * ax**2 + np.sin(p) ** 2 * ay**2)
        if params.get("distribution", "ggx") == "ggx":
            return (-1 + np.sqrt(1 + alpha**2 * np.tan(t) ** 2)) / 2
        a = 1 / (alpha * np.tan(t))
        return (erf(a) - 1) / 2 + np.exp(-(a**2)) / (2 * a * np.sqrt(np.pi))

    lo, li = lam(wo), lam(wi)
    g = 1 / (1 + lo + li) if params.get("masking") == "correlated" else 1 / ((1 + lo) * (1 + li))
    c = np.sum(wi * h, axis=1)[:, None]
    spec = np.array(params.get("specular", (1, 1, 1)), dtype=float)
    kind = params.get("fresnel", "none")
    if kind == "schlick":
        fres = spec + (1 - spec) * (1 - c) ** 5
    elif kind == "dielectric":
        eta = np.broadcast_to(params.get("eta", 1.5), 3)
        fres = spec * np.stack([fresnel_complex(c[:, 0], e) for e in eta], axis=1)
    elif kind == "conductor":
        eta, k = params.get("eta", GOLD_ETA), params.get("k", GOLD_K)
        fres = spec * np.stack([fresnel_complex(c[:, 0], complex(e, kk)) for e, kk in zip(eta, k, strict=True)], axis=1)
    else:
        fres = spec[None, :]
    lobe = (d * g / (4 * wo[:, 2] * wi[:, 2]))[:, None]
    return np.array(params.get("diffuse", (0, 0, 0))) / np.pi + fres * lobe


# the standard checks, the closed form and parity run on these (ggx/beckmann, iso/aniso, α 0.05…0.8, every
# Fresnel mode, both masking forms, with and without the diffuse term)
CASES = [
    dict(distribution="ggx", alpha=0.3),
    dict(distribution="ggx", alpha=(0.1, 0.5), fresnel="conductor", masking="correlated"),
    dict(distribution="ggx", alpha=0.05, fresnel="schlick", specular=(0.9, 0.6, 0.3), diffuse=(0.2, 0.3, 0.4)),
    dict(distribution="beckmann", alpha=0.05, fresnel="dielectric", eta=(1.3, 1.5, 1.8)),
    dict(
        distribution="beckmann",
        alpha=(0.8, 0.2),
        fresnel="conductor",
        eta=(0.2, 0.9, 1.1),
        k=(3.9, 2.4, 1.6),
        specular=(0.5, 0.5, 0.5),
        diffuse=(0.5, 0.4, 0.3),
        masking="correlated",
    ),
]
# closed form and parity only: the ends of the α range, total internal reflection
MORE = [
    dict(distribution="ggx", alpha=0.8, fresnel="dielectric", eta=1.5, diffuse=(0.5, 0.4, 0.3)),
    dict(distribution="ggx", alpha=1e-3),
    dict(distribution="ggx", alpha=1.0, fresnel="dielectric", eta=0.7),
    dict(distribution="beckmann", alpha=1.0, fresnel="schlick", specular=(0.04,) * 3, masking="correlated"),
    dict(distribution="beckmann", alpha=(1.0, 0.05), fresnel="conductor", masking="correlated"),
]


def case_id(p: dict) -> str:
    alpha = p["alpha"] if np.isscalar(p["alpha"]) else "x".join(map(str, p["alpha"]))
    return f"{p['distribution']}-{alpha}-{p.get('fresnel', 'none')}-{p.get('masking', 'sep')[:3]}"


@pytest.mark.parametrize("params", CASES + MORE, ids=case_id)
def test_eval_matches_angular_formulas(directions, params):
    wo, wi = directions
    assert np.allclose(Microfacet(**params).eval(wo, wi), expected_f(params, wo, wi), rtol=1e-9, atol=0)


@pytest.mark.parametrize("params", CASES, ids=case_id)
def test_standard_checks(rng, params):
    run_standard_checks(Microfacet(**params), rng, thetas=(0.1, 1.3))


@pytest.mark.parametrize("params", CASES + MORE, ids=case_id)
def test_glsl_matches_numpy(ctx, rng, params):
    check_glsl_parity(Microfacet(**params), ctx, rng)


def test_anisotropy_axes():
    """alpha_x is the roughness along the tangent (x): a lobe stretched along x reaches further in x."""
    m = Microfacet(alpha=(0.5, 0.1))
    wo = np.array([0.0, 0.0, 1.0])
    along_x, along_y = direction(0.6, 0.0), direction(0.6, np.pi / 2)
    assert m.eval(wo, along_x)[0] > 10 * m.eval(wo, along_y)[0]
    assert m.alpha_xy == (0.5, 0.1) and Microfacet(alpha=0.2).alpha_xy == (0.2, 0.2)


def test_correlated_masking_reflects_more_than_separable(directions):
    wo, wi = directions
    sep = Microfacet(alpha=0.5).eval(wo, wi)
    cor = Microfacet(alpha=0.5, masking="correlated").eval(wo, wi)
    assert np.all(cor >= sep) and np.any(cor > 1.01 * sep)


def test_energy_conserving_flag():
    assert Microfacet().energy_conserving
    assert Microfacet(fresnel="schlick", specular=(1, 1, 1)).energy_conserving
    assert Microfacet(fresnel="conductor", diffuse=(0, 0, 0)).energy_conserving
    assert not Microfacet(specular=(1.2, 1, 1)).energy_conserving
    assert not Microfacet(fresnel="dielectric", specular=(2, 2, 2)).energy_conserving
    assert Microfacet(specular=(0.5, 0.5, 0.5), diffuse=(0.5, 0.5, 0.5)).energy_conserving
    assert not Microfacet(specular=(0.5, 0.5, 0.5), diffuse=(0.6, 0.5, 0.5)).energy_conserving
    assert not Microfacet(fresnel="schlick", specular=(0.04,) * 3, diffuse=(0.5,) * 3).energy_conserving


def test_defaults_and_resolved_fresnel_parameters():
    m = Microfacet()
    assert (m.distribution, m.alpha, m.fresnel, m.masking) == ("ggx", 0.3, "none", "separable")
    assert m.specular == (1, 1, 1) and m.diffuse == (0, 0, 0) and m.eta is None and m.k is None
    assert Microfacet(fresnel="dielectric").eta_rgb == (1.5, 1.5, 1.5)
    assert Microfacet(fresnel="dielectric", eta=1.33).eta_rgb == (1.33, 1.33, 1.33)
    gold = Microfacet(fresnel="conductor")
    assert gold.eta_rgb == GOLD_ETA and gold.k_rgb == GOLD_K
    assert Microfacet(fresnel="conductor", eta=(1, 2, 3), k=(0, 1, 2)).k_rgb == (0, 1, 2)
    assert Microfacet(type="microfacet", alpha=[0.1, 0.4]).alpha == (0.1, 0.4)  # TOML arrays are lists


@pytest.mark.parametrize(
    "params",
    [
        dict(alpha=0.0),
        dict(alpha=1e-4),
        dict(alpha=1.5),
        dict(alpha=(0.1,)),
        dict(alpha=(0.1, 0.2, 0.3)),
        dict(alpha=(0.1, -0.2)),
        dict(alpha=float("nan")),
        dict(distribution="phong"),
        dict(fresnel="fake"),
        dict(masking="joint"),
        dict(specular=(-0.1, 1, 1)),
        dict(diffuse=(1.2, 0, 0)),
        dict(fresnel="schlick", specular=(1.1, 0.5, 0.5)),
        dict(eta=1.5),  # fresnel = "none" takes no eta
        dict(fresnel="schlick", eta=1.5),
        dict(fresnel="dielectric", k=(1, 1, 1)),
        dict(fresnel="dielectric", eta=0.0),
        dict(fresnel="dielectric", eta=(1.5, -1.0, 1.5)),
        dict(fresnel="conductor", eta=(0.2, 0.9, 1.1)),  # k missing
        dict(fresnel="conductor", k=(3.9, 2.4, 1.6)),  # eta missing
        dict(fresnel="conductor", eta=(0.2, 0.9, 1.1), k=(3.9, -2.4, 1.6)),
        dict(roughness=0.3),
    ],
    ids=repr,
)
def test_invalid_parameters_are_rejected(params):
    with pytest.raises(ValidationError):
        Microfacet(**params)


def test_assignment_is_validated():
    m = Microfacet(fresnel="dielectric", eta=1.33)
    with pytest.raises(ValidationError, match="eta applies only"):
        m.fresnel = "none"


# ------------------------------------------------------------------------------------------ Mitsuba 3


@pytest.mark.parametrize("distribution", ["ggx", "beckmann"])
def test_matches_mitsuba_roughconductor(rng, distribution):
    """Mitsuba 3's roughconductor (alpha_u, alpha_v along the shading frame's s, t) returns f cosθ with its wi
    our wo. GGX agrees to float32 precision; Mitsuba's Beckmann G1 is a rational approximation (< 0.35 % per G1)."""
    mi = pytest.importorskip("mitsuba")
    previous = mi.variant()
    mi.set_variant("scalar_rgb")
    try:
        eta, k = (0.2, 0.9, 1.1), (3.9, 2.4, 1.6)
        ours = Microfacet(distribution=distribution, alpha=(0.1, 0.5), fresnel="conductor", eta=eta, k=k)
        bsdf = mi.load_dict(
            {
                "type": "roughconductor",
                "distribution": distribution,
                "alpha_u": 0.1,
                "alpha_v": 0.5,
                "eta": {"type": "rgb", "value": list(eta)},
                "k": {"type": "rgb", "value": list(k)},
            }
        )
        si = mi.SurfaceInteraction3f()
        si.sh_frame = mi.Frame3f(mi.Vector3f(0, 0, 1))
        wo, wi = upper_hemisphere(rng, 500), upper_hemisphere(rng, 500)
        theirs = []
        for a, b in zip(wo, wi, strict=True):
            si.wi = mi.Vector3f(*a)
            theirs.append(np.array(bsdf.eval(mi.BSDFContext(), si, mi.Vector3f(*b))))
        expected = ours.eval(wo, wi) * wi[:, 2:3]
        keep = expected > 1e-4
        rel = np.abs(np.array(theirs) - expected)[keep] / expected[keep]
        assert rel.max() < (1e-4 if distribution == "ggx" else 7e-3), rel.max()
    finally:
        if previous is not None:
            mi.set_variant(previous)
