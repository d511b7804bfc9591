"""Diffusion profiles R_d(r): radiant exitance at distance r (mm) per unit incident flux, per channel.

- ``dipole``: Jensen et al. 2001 (classical diffusion, A from the first Fresnel moment);
- ``better_dipole``: d'Eon 2012 (Grosjean's D, A from both moments, exitance from fluence and flux);
- ``normalized_diffusion``: Christensen & Burley 2015, R(r) = A s (e^{−sr} + e^{−sr/3}) / (8π r), fitted to
  brute-force Monte Carlo; A is the total diffuse reflectance, s = (1.85 − A + 7|A − 0.8|³) / ℓ with ℓ = 1/σ_t
  (their "searchlight" fit); we take A from the better dipole's total reflectance so that the three profiles
  carry comparable energy and need only σ_a, σ'_s, η;
- ``multiple_fit`` (the default): multiple scattering only — two or more events — fitted to volumetric Monte
  Carlo of a semi-infinite slab (multiple_fit.py), so that the single-scattering term is not counted twice.

The table (corrected from the document, see the note's errata — the real source lies inside the medium, the
better dipole's C_E is ½(1 − 3C_2), not "1/42"):

    R_d(r) = C_n [ (C_E z_r (σ_tr d_r + 1)/d_r² + C_φ/D) e^{−σ_tr d_r}/d_r
                 − (C_E z_v (σ_tr d_v + 1)/d_v² + C_φ/D) e^{−σ_tr d_v}/d_v ]

with z_r = 1/σ'_t, z_v = −z_r − 2 z_b, z_b = 2AD, d = sqrt(r² + z²), σ_tr = sqrt(σ_a / D).
"""

from __future__ import annotations

import functools

import numpy as np

from . import multiple_fit
from .medium import Medium
from .optics import fresnel_moment_fit

PROFILES = ("dipole", "better_dipole", "normalized_diffusion", "multiple_fit")


def _dipole_terms(medium: Medium, better: bool) -> dict[str, np.ndarray]:
    c1 = fresnel_moment_fit(1, medium.eta)
    c2 = fresnel_moment_fit(2, medium.eta)
    st_p = medium.sigma_t_prime
    alpha_p = medium.albedo_prime
    if better:
        D = (2.0 * medium.sigma_a + medium.sigma_s_prime) / (3.0 * st_p * st_p)
        A = (1.0 + 3.0 * c2) / (1.0 - 2.0 * c1)
        c_phi, c_e, c_n = 0.25 * (1.0 - 2.0 * c1), 0.5 * (1.0 - 3.0 * c2), alpha_p * alpha_p / (4.0 * np.pi)
    else:
        D = 1.0 / (3.0 * st_p)
        A = (1.0 + 2.0 * c1) / (1.0 - 2.0 * c1)
        c_phi, c_e, c_n = 0.0, 1.0, alpha_p / (4.0 * np.pi)
    z_r = 1.0 / st_p
    z_b = 2.0 * A * D
    return {
        "D": D,
        "z_r": z_r,
        "z_v": -z_r - 2.0 * z_b,
        "sigma_tr": np.sqrt(medium.sigma_a / D),
        "c_phi": c_phi,
        "c_e": c_e,
        "c_n": c_n,
        "A": A,
    }


def dipole_rd(r, medium: Medium, *, better: bool = False) -> np.ndarray:
    """R_d(r) of the classical (``better=False``) or better dipole; r in mm, broadcasts against the channels."""
    t = _dipole_terms(medium, better)
    r = np.asarray(r, dtype=np.float64)
    out = 0.0
    for z, sign in ((t["z_r"], 1.0), (t["z_v"], -1.0)):
        d = np.sqrt(r * r + z * z)
        flux = t["c_e"] * z * (t["sigma_tr"] * d + 1.0) / (d * d)
        out = out + sign * (flux + t["c_phi"] / t["D"]) * np.exp(-t["sigma_tr"] * d) / d
    return t["c_n"] * out


def dipole_total_reflectance(medium: Medium) -> np.ndarray:
    """Closed form of ∫ 2πr R_d dr for the classical dipole:
    (α'/2)(1 + e^{−(4/3)A sqrt(3(1−α'))}) e^{−sqrt(3(1−α'))}."""
    a = medium.albedo_prime
    A = _dipole_terms(medium, better=False)["A"]
    s = np.sqrt(3.0 * (1.0 - a))
    return 0.5 * a * (1.0 + np.exp(-4.0 / 3.0 * A * s)) * np.exp(-s)


def normalized_diffusion_parameters(medium: Medium) -> tuple[np.ndarray, np.ndarray]:
    """(A, s) of Christensen–Burley's profile: A the better dipole's total reflectance, s in 1/mm."""
    A = total_reflectance("better_dipole", medium)
    return A, (1.85 - A + 7.0 * np.abs(A - 0.8) ** 3) * medium.sigma_t


def normalized_diffusion_rd(r, medium: Medium) -> np.ndarray:
    """Christensen–Burley R(r) = A s (e^{−sr} + e^{−sr/3}) / (8π r)."""
    A, s = normalized_diffusion_parameters(medium)
    r = np.maximum(np.asarray(r, dtype=np.float64), 1e-12)
    return A * s * (np.exp(-s * r) + np.exp(-s * r / 3.0)) / (8.0 * np.pi * r)


def profile_rd(profile: str, r, medium: Medium) -> np.ndarray:
    """R_d(r) of a named profile (``PROFILES``)."""
    if profile == "dipole":
        return dipole_rd(r, medium)
    if profile == "better_dipole":
        return dipole_rd(r, medium, better=True)
    if profile == "normalized_diffusion":
        return normalized_diffusion_rd(r, medium)
    if profile == "multiple_fit":
        return multiple_fit.multiple_fit_rd(r, medium, better_dipole_reduced_total)
    raise ValueError(f"unknown profile {profile!r}; allowed: {', '.join(PROFILES)}")


def total_reflectance(profile: str, medium: Medium) -> np.ndarray:
    """∫₀^∞ 2πr R_d(r) dr per channel, by adaptive quadrature in u = log r (the profiles span decades); cached
    per medium, since normalised diffusion needs it inside every evaluation of its profile."""
    a, s = np.atleast_1d(medium.sigma_a), np.atleast_1d(medium.sigma_s)
    key = (profile, tuple(map(float, a)), tuple(map(float, s)), float(medium.g), float(medium.eta))
    out = np.array(_total_reflectance(*key))
    return out.reshape(np.shape(medium.sigma_a)) if np.ndim(medium.sigma_a) else out


@functools.lru_cache(maxsize=256)
def _total_reflectance(profile: str, sigma_a: tuple, sigma_s: tuple, g: float, eta: float) -> tuple:
    if profile == "normalized_diffusion":  # normalised by construction: ∫ = A, the better dipole's
        return _total_reflectance("better_dipole", sigma_a, sigma_s, g, eta)
    if profile == "multiple_fit":  # normalised by construction: ∫ = A, the Monte Carlo's (no shape fit needed)
        medium = Medium(np.array(sigma_a), np.array(sigma_s), g, eta)
        albedos = np.atleast_1d(medium.albedo_prime)
        return tuple(multiple_fit.energy(float(a), eta, better_dipole_reduced_total) for a in albedos)
    out = []
    for a, s in zip(sigma_a, sigma_s, strict=True):
        m = Medium(np.float64(a), np.float64(s), g, eta)
        mfp = float(m.mean_free_path)

        def integrand(u, m=m):
            r = np.exp(u)
            return 2.0 * np.pi * r * r * float(profile_rd(profile, r, m))

        lo, hi = np.log(1e-7 * mfp), np.log(1e5 * mfp)
        from scipy import integrate  # imported when used: scipy.integrate is a third of `import reflets`

        value, _ = integrate.quad(integrand, lo, hi, limit=400, epsabs=1e-12, epsrel=1e-10)
        out.append(value)
    return tuple(out)


def better_dipole_reduced_total(albedo_prime: float, eta: float) -> float:
    """The better dipole's ∫2πr R_d dr at reduced albedo α' (σ'_t = 1): what multiple_fit's energy table is
    interpolated relative to."""
    medium = Medium(np.float64(1.0 - albedo_prime), np.float64(albedo_prime), 0.0, eta)
    return float(np.ravel(total_reflectance("better_dipole", medium))[0])


def multiple_fit_parameters(medium: Medium) -> dict[str, np.ndarray]:
    """Per channel A, w, s1, s2 (1/mm), z1, z2 (mm) of ``multiple_fit`` (multiple_fit.py)."""
    return multiple_fit.parameters(medium, better_dipole_reduced_total)


def far_field_reflectance(profile: str, medium: Medium) -> np.ndarray:
    """What a uniformly lit flat sample re-emits per unit transmitted flux, all orders: the profile's total, plus
    single scattering at normal incidence for ``multiple_fit`` (the far-field BRDF has no separate term)."""
    total = total_reflectance(profile, medium)
    if profile == "multiple_fit":
        return total + multiple_fit.single_scattering_albedo(medium)
    return total


def glsl_uniforms(profile: str, medium: Medium) -> dict[str, tuple]:
    """Per-channel constants of ``profile_rd`` in shaders/profiles.glsl (vec3 uniforms ``p_*``, mm units)."""

    def vec(a) -> tuple:
        return tuple(float(x) for x in np.broadcast_to(np.asarray(a, dtype=np.float64), (3,)))

    if profile == "normalized_diffusion":
        A, s = normalized_diffusion_parameters(medium)
        return {"p_A": vec(A), "p_s": vec(s)}
    if profile == "multiple_fit":
        p = multiple_fit_parameters(medium)
        cosines, factors = multiple_fit.incidence_table(medium)
        return {
            **{f"p_{key}": vec(value) for key, value in p.items()},
            "p_incidence_cos": cosines.astype(np.float32).tobytes(),
            "p_incidence": factors.astype(np.float32).tobytes(),
        }
    t = _dipole_terms(medium, better=profile == "better_dipole")
    return {
        "p_zr": vec(t["z_r"]),
        "p_zv": vec(t["z_v"]),
        "p_str": vec(t["sigma_tr"]),
        "p_ce": vec(t["c_e"]),
        "p_cphi_over_d": vec(t["c_phi"] / t["D"]),
        "p_cn": vec(t["c_n"]),
    }


def capture_radii(profile: str, medium: Medium, fraction: float = 0.99) -> np.ndarray:
    """Per channel, the radius (mm) within which ``fraction`` of that channel's total reflectance R_total lies:
    the sampling radius a ring integral needs (low-absorption media such as marble spread over tens of mean
    free paths)."""
    mfp = float(np.max(medium.mean_free_path))
    r = np.geomspace(1e-6 * mfp, 1e4 * mfp, 4001)
    f = 2.0 * np.pi * r[:, None] * profile_rd(profile, r[:, None], medium).reshape(len(r), -1)
    cumulative = np.concatenate(
        [np.zeros((1, f.shape[1])), np.cumsum(0.5 * (f[1:] + f[:-1]) * np.diff(r)[:, None], axis=0)]
    )
    cumulative /= cumulative[-1]
    return np.array([np.interp(fraction, cumulative[:, c], r) for c in range(f.shape[1])])
