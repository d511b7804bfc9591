"""Comparison models of a brushed / scratched surface, rendered by NumPy Monte Carlo under the reference's lighting.

Every model shades a view direction ω_o (world) under a :class:`~.reference.Lighting` and reports its own
standard error (paired strata, like the reference). Four models (figure 3.7 of the document):

- **full** — the scratch table with Fresnel through γ (eq. 3.2): ρ_s = F_γ(θ_o) ρ_m + (1 − F_γ) ρ_s(0),
  F_γ = (2|θ_o|/π)^γ, integrated on the Kajiya–Kay half-cone, L_o = ∫ ρ_s(φ_o, φ_i) cos φ_i L(−θ_o, φ_i) dφ_i;
- **1-bounce** — the same table traced with at most one reflection (``trace_table(max_bounces=1)``: a path
  needing a second bounce is dropped, its energy lost);
- **NDF** — a "cylindrical" microfacet model built from the profile's normals (derivation below);
- **AS00** — Ashikhmin–Shirley (the library's ``ashikhmin_shirley``) with n_u = 1e4 along the scratch direction
  and n_v = 2 across it, R_s = the metal's exact Fresnel reflectance at normal incidence per channel (its
  Schlick term then follows the conductor's curve closely), R_d = 0 (a bare metal has no diffuse term).

The three cone models share one estimator: φ_i is drawn from the row φ_o of the table by inverting its CDF
(pdf ∝ ρ_m cos φ_i, eq. 3.5), and the cone light from the exact interval where the half-cone θ = −θ_o crosses
it — ω(θ_i, φ)·s = sin θ_i s_u + cos θ_i (s_v sin φ + s_n cos φ) ≥ cos H is one interval around
φ_s = atan2(s_v, s_n) — uniformly (the document's thickened light, §3.7, with the exact support); the two are
combined with the power heuristic. Tables are evaluated at the nearest bin (the pdf's own resolution).

NDF model derivation. The extruded profile's normals all lie in the plane ⊥ **u**: m = (sin α, cos α) in the
profile plane (x along **v**, y along **n**), α = −atan h'(x). Its 1D normal distribution D(α) is the microsurface
length per unit base length with normal angle in dα: D(α) dα = ∫ 1[α(x) ∈ dα] √(1 + h'²) dx, so
∫ D(α) cos α dα = 1. For a view at cone angle φ the visible-normal density is
D_v(α) = G₁(φ) D(α) ⟨cos(φ − α)⟩ / cos φ (Heitz 2014), with the Smith masking of the same distribution,
G₁(φ) = cos φ / ∫ D(α) ⟨cos(φ − α)⟩ dα (masking by an extruded profile depends on the projected direction only:
the 3D cosines carry the same factor cos θ). A facet α mirrors φ into 2α − φ and the 3D incidence cosine is
cos θ cos(φ − α) — the same geometry as the tables, but with one bounce, Smith masking/shadowing (G₁(φ_o) G₁(φ_i),
separable) instead of the profile's exact visibility, and no inter-reflection. Changing variables to
φ_i = 2α − φ_o (dα = dφ_i / 2) gives the cone-form BRDF

    ρ_ndf(φ_o, φ_i) = F(cos θ_o cos d) D(φ_h) cos d G₁(φ_o) G₁(φ_i) / (2 cos φ_o cos φ_i),
    φ_h = (φ_o + φ_i)/2, d = (φ_o − φ_i)/2,

reciprocal and ≤ 1 in albedo. It is tabulated like a scratch table (same bins, same normalisation and sampling)
by drawing x uniformly along the profile for each φ_in (weight ⟨cos(φ_in − α)⟩ G₁(φ_in) / (cos α cos φ_in), exit
φ_out = 2α − φ_in times G₁(φ_out)); the Fresnel factor is then applied exactly per sample at render time.
"""

from __future__ import annotations

import time
from dataclasses import dataclass

import numpy as np

from ..brdf.ashikhmin_shirley import AshikhminShirley
from ..brdf.base import Material
from .profiles import Profile, parse_profile
from .reference import Lighting, ScratchFrame, _power, shade_brdf, stratified_stats
from .table import ScratchTable, build_table, table_from_tallies
from .tracer2d import THETAS, FresnelSpec, Tallies, bin_of, column_weight, stratified_phi, trace_table

_CHUNK = 1 << 18


@dataclass
class ModelResult:
    mean: np.ndarray  # (..., 3)
    stderr: np.ndarray  # (..., 3)
    samples: int  # per pixel
    seconds: float  # rendering (the precomputation is timed by the caller)


# -- the cone models -----------------------------------------------------------------------------------------
@dataclass
class ConeModel:
    """A BRDF on the reflection half-cone, tabulated [φ_o, φ_i] and sampled by its rows (eq. 3.5).

    ``fresnel_mode``: ``"gamma"`` (ρ_s of eq. 3.2 from the table's ρ_m, ρ_s(0), γ) or ``"exact"`` (ρ_m × the
    fresnel of the single bounce at cos θ_o cos((φ_o − φ_i)/2), the NDF model)."""

    name: str
    table: ScratchTable
    fresnel_mode: str = "gamma"
    fresnel: FresnelSpec | None = None

    def rho(self, theta_o, phi_o, phi_i) -> np.ndarray:
        """ρ_s(θ_o; φ_o, φ_i) at the nearest bin, (n, 3)."""
        t = self.table
        b, j = bin_of(phi_o, t.size), bin_of(phi_i, t.size)
        rm = t.rho_m[b, j].astype(np.float64)
        if self.fresnel_mode == "exact":
            c = np.cos(theta_o) * np.cos(0.5 * (phi_o - phi_i))
            return rm[:, None] * np.broadcast_to(self.fresnel(c), (rm.size, 3))
        x = np.clip(2.0 * np.abs(theta_o) / np.pi, 0.0, 1.0)
        g = t.gamma[b, j].astype(np.float64)
        s0 = t.rho_s0[b, j].astype(np.float64)
        if g.ndim == 1:
            g, s0 = g[:, None], s0[:, None]
        with np.errstate(divide="ignore"):
            F = np.where(x[:, None] > 0, np.power(x[:, None], g), np.where(g > 0, 0.0, 1.0))
        return np.broadcast_to(F * rm[:, None] + (1.0 - F) * s0, (rm.size, 3))


def sun_interval(sun, frame: ScratchFrame, theta_i: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """[φ−, φ+] ∩ (−π/2, π/2) where the half-cone θ = θ_i lies inside the cone light (empty: φ+ ≤ φ−)."""
    su, sv, sn = sun.direction @ frame.u, sun.direction @ frame.v, sun.direction @ frame.n
    A = np.sin(theta_i) * su
    B = np.cos(theta_i) * np.hypot(sv, sn)
    with np.errstate(divide="ignore", invalid="ignore"):
        c = (sun.cos_half - A) / B
    half = np.where(c < 1.0, np.arccos(np.clip(c, -1.0, 1.0)), -1.0)
    phi_s = np.arctan2(sv, sn)
    lo = np.maximum(phi_s - half, -0.5 * np.pi)
    hi = np.minimum(phi_s + half, 0.5 * np.pi)
    return lo, np.where(half >= 0, hi, lo)


def render_cone_model(
    model: ConeModel, frame: ScratchFrame, wo: np.ndarray, lighting: Lighting, *, spp: int = 64, seed: int = 0
) -> ModelResult:
    """L_o(ω_o) = ∫ ρ_s cos φ_i L(−θ_o, φ_i) dφ_i by stratified table sampling + cone-light sampling (MIS)."""
    t0 = time.perf_counter()
    wo = np.asarray(wo, float)
    shape = wo.shape[:-1]
    wo = wo.reshape(-1, 3)
    P, S = wo.shape[0], int(spp)
    theta_o, phi_o = frame.cone(wo)
    theta_i = -theta_o
    rng = np.random.default_rng(seed)
    mean, err = np.zeros((P, 3)), np.zeros((P, 3))
    sun = lighting.sun
    if sun is not None:
        lo_all, hi_all = sun_interval(sun, frame, theta_i)
    per = max(1, _CHUNK // S)
    for start in range(0, P, per):
        sl = slice(start, min(P, start + per))
        p = sl.stop - sl.start
        th = np.repeat(theta_o[sl], S)
        po = np.repeat(phi_o[sl], S)
        u = ((np.arange(S)[None, :] + rng.random((p, S))) / S).ravel()
        phi_i, pdf_t = model.table.sample(po, u)
        rho = model.rho(th, po, phi_i)
        w_i = frame.from_cone(-th, phi_i)
        if sun is not None:
            lo, hi = np.repeat(lo_all[sl], S), np.repeat(hi_all[sl], S)
            width = hi - lo
            has = width > 0
            p_s = np.where(has & (phi_i >= lo) & (phi_i <= hi), 1.0 / np.where(has, width, 1.0), 0.0)
            L = lighting.env_radiance(w_i) + _power(pdf_t, p_s)[:, None] * lighting.sun_radiance(w_i)
        else:
            L = lighting.env_radiance(w_i)
        ok = pdf_t > 0
        with np.errstate(divide="ignore", invalid="ignore"):
            val = np.where(ok[:, None], rho * (np.cos(phi_i) / np.where(ok, pdf_t, 1.0))[:, None] * L, 0.0)
        if sun is not None and has.any():
            us = ((np.arange(S)[None, :] + rng.random((p, S))) / S).ravel()
            phi_s = lo + us * width
            rho_s = model.rho(th, po, phi_s)
            pt = model.table.pdf_at(po, phi_s).astype(np.float64)
            ps = 1.0 / np.where(has, width, 1.0)
            contrib = rho_s * (np.cos(phi_s) * _power(ps, pt) / ps)[:, None] * sun.radiance
            val += np.where(has[:, None], contrib, 0.0)
        mean[sl], err[sl] = stratified_stats(val.reshape(p, S, 3))
    return ModelResult(mean.reshape(shape + (3,)), err.reshape(shape + (3,)), S, time.perf_counter() - t0)


# -- building the models -------------------------------------------------------------------------------------
def full_model(profile, fresnel: FresnelSpec, *, size=256, rays=10000, seed=0, backend="numpy", ctx=None) -> ConeModel:
    """The document's model: the multi-bounce table with ρ_s(0), ρ_m and γ (exact Fresnel at each bounce)."""
    table = build_table(profile, **_fresnel_kwargs(fresnel), size=size, rays=rays, seed=seed, backend=backend, ctx=ctx)
    return ConeModel("full", table)


def one_bounce_model(profile, fresnel: FresnelSpec, *, size=256, rays=10000, seed=0) -> ConeModel:
    """The same table with paths of more than one reflection dropped (the 2D tracer's ``max_bounces=1``)."""
    profile = parse_profile(profile)
    tallies = trace_table(profile, size=size, rays=rays, fresnel=fresnel, seed=seed, max_bounces=1)
    return ConeModel("1-bounce", table_from_tallies(tallies, profile, fresnel, meta={"max_bounces_limit": 1}))


def _fresnel_kwargs(fresnel: FresnelSpec) -> dict:
    if fresnel.model in ("conductor", "lazanyi"):
        return {"conductor": (fresnel.eta, fresnel.k), "fresnel": "exact" if fresnel.model == "conductor" else "auto"}
    if fresnel.model in ("dielectric", "schlick"):
        return {"ior": fresnel.eta, "fresnel": "exact" if fresnel.model == "dielectric" else "auto"}
    return {"ior": None}


def profile_normals(profile: Profile, samples: int = 8192) -> tuple[np.ndarray, np.ndarray]:
    """Normal angles α(x) = −atan h'(x) at stratified x (midpoints) and the micro-length weight 1/cos α."""
    x = (np.arange(samples) + 0.5) / samples
    alpha = -np.arctan(profile.slope(x))
    return alpha, 1.0 / np.cos(alpha)


def smith_g1(profile: Profile, phi, samples: int = 8192) -> np.ndarray:
    """G₁(φ) = cos φ / ∫ D(α) ⟨cos(φ − α)⟩ dα, the Smith masking of the profile's normal distribution."""
    alpha, length = profile_normals(profile, samples)
    phi = np.atleast_1d(np.asarray(phi, float))
    out = np.empty(phi.shape)
    for s in range(0, phi.size, 256):
        p = phi.ravel()[s : s + 256]
        proj = np.mean(np.maximum(np.cos(p[:, None] - alpha[None, :]), 0.0) * length[None, :], axis=1)
        out.ravel()[s : s + 256] = np.cos(p) / np.maximum(proj, 1e-300)
    return np.minimum(out, 1.0)


def ndf_model(profile, fresnel: FresnelSpec, *, size=256, rays=10000, seed=0) -> ConeModel:
    """The tabulated-NDF ("cylindrical") microfacet model of the profile (see the module docstring)."""
    profile = parse_profile(profile)
    M, N = int(size), int(rays)
    grid = np.linspace(-0.5 * np.pi, 0.5 * np.pi, 4097)
    g1_grid = smith_g1(profile, grid)

    def g1(p):
        return np.interp(p, grid, g1_grid)

    rng = np.random.default_rng(seed)
    T, C = len(THETAS), fresnel.channels
    cos_t = np.cos(np.asarray(THETAS))
    counts, csq = np.zeros(M * M), np.zeros(M * M)
    wsum, wsq = np.zeros((T, C, M * M)), np.zeros((T, C, M * M))
    lost = np.zeros(M)
    cols_per = max(1, _CHUNK // N)
    for c0 in range(0, M, cols_per):
        j = np.repeat(np.arange(c0, min(M, c0 + cols_per)), N)
        rank = np.tile(np.arange(N), j.size // N)
        phi_in = stratified_phi(j, rank, N, M, rng.random(j.size))
        alpha = -np.arctan(profile.slope(rng.random(j.size)))
        c2 = np.cos(phi_in - alpha)
        phi_out = 2.0 * alpha - phi_in
        w = np.maximum(c2, 0.0) / (np.cos(alpha) * np.cos(phi_in)) * g1(phi_in) * g1(phi_out)
        ok = (c2 > 0) & (np.abs(phi_out) < 0.5 * np.pi)
        w = np.where(ok, w, 0.0)
        lost += np.bincount(j[(c2 > 0) & ~ok], minlength=M)  # reflected below the horizon
        flat = bin_of(phi_out, M) * M + j
        cw = column_weight(phi_in, j, M) * w
        counts += np.bincount(flat, weights=cw, minlength=M * M)
        csq += np.bincount(flat, weights=cw * cw, minlength=M * M)
        F = fresnel(np.clip(c2, 0.0, 1.0)[:, None] * cos_t[None, :])  # (n, T, C)
        for t in range(T):
            for ch in range(C):
                wt = cw * F[:, t, ch]
                wsum[t, ch] += np.bincount(flat, weights=wt, minlength=M * M)
                wsq[t, ch] += np.bincount(flat, weights=wt * wt, minlength=M * M)
    tallies = Tallies(
        size=M,
        rays=N,
        thetas=tuple(float(t) for t in THETAS),
        counts=counts.reshape(M, M),
        weights=np.moveaxis(wsum.reshape(T, C, M, M), 1, -1),
        counts_sq=csq.reshape(M, M),
        weights_sq=np.moveaxis(wsq.reshape(T, C, M, M), 1, -1),
        lost=lost,
        max_bounces=1,
    )
    table = table_from_tallies(tallies, profile, fresnel, meta={"model": "ndf"})
    return ConeModel("NDF", table, fresnel_mode="exact", fresnel=fresnel)


# -- Ashikhmin–Shirley and other smooth BRDFs -----------------------------------------------------------------
def as00_material(fresnel: FresnelSpec, nu: float = 1e4, nv: float = 2.0) -> AshikhminShirley:
    """AS00 matched to the metal: R_s = F(1) per channel (exact Fresnel at normal incidence), R_d = 0."""
    f0 = np.broadcast_to(fresnel(1.0), (3,))
    return AshikhminShirley(rs=tuple(float(v) for v in np.clip(f0, 0, 1)), rd=(0.0, 0.0, 0.0), nu=nu, nv=nv)


def render_material(
    material: Material, frame: ScratchFrame, wo: np.ndarray, lighting: Lighting, *, spp: int = 64, seed: int = 0
) -> ModelResult:
    """∫ f L cos for a library BRDF (local frame x = u, y = v, z = n): stratified BRDF samples + cone-light samples,
    power-heuristic MIS."""
    t0 = time.perf_counter()
    wo = np.asarray(wo, float)
    shape = wo.shape[:-1]
    wo = wo.reshape(-1, 3)
    P, S = wo.shape[0], int(spp)
    rng = np.random.default_rng(seed)
    mean, err = np.zeros((P, 3)), np.zeros((P, 3))
    per = max(1, _CHUNK // S)
    for start in range(0, P, per):
        sl = slice(start, min(P, start + per))
        p = sl.stop - sl.start
        u = rng.random((p, S, 4))
        u[..., 0] = (np.arange(S)[None, :] + u[..., 0]) / S
        w = np.repeat(wo[sl], S, axis=0)
        val = shade_brdf(material, frame, w, lighting, u.reshape(-1, 4))
        mean[sl], err[sl] = stratified_stats(val.reshape(p, S, 3))
    return ModelResult(mean.reshape(shape + (3,)), err.reshape(shape + (3,)), S, time.perf_counter() - t0)


def mix(scratch: ModelResult, base: ModelResult, alpha) -> ModelResult:
    """Eq. 3.4 with one layer (ᾱ = α ≤ 1): α L_s + (1 − α) L_b, errors combined as independent."""
    a = np.asarray(alpha, float)[..., None]
    mean = a * scratch.mean + (1.0 - a) * base.mean
    err = np.sqrt((a * scratch.stderr) ** 2 + ((1.0 - a) * base.stderr) ** 2)
    return ModelResult(mean, err, scratch.samples + base.samples, scratch.seconds + base.seconds)
