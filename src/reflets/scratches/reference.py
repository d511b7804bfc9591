"""Explicit-geometry ground truth of scratched surfaces: what a pixel sees when its footprint covers many scratches.

A pixel much wider than a scratch averages the radiance leaving the extruded, periodic profile over one period
(scratches are parallel and identical, so every period looks the same). The reference traces that average
from the eye, independently of the 2D tables:

- for the pixel's view direction ω_o (world), rays travel along −ω_o into the profile, entering the lid at
  x0 = (k + ξ_k)/N, k < N (stratified over the period; the exit direction is a deterministic, piecewise smooth
  function of x0, so stratification leaves an O(N^-3/2)-per-discontinuity error rather than O(N^-1/2));
- :func:`~reflets.scratches.tracer3d.trace_directions` follows every mirror bounce in 3D with the exact Fresnel
  factor at the 3D incidence cosine (conductor or dielectric, per RGB channel), until the ray leaves through
  the lid;
- the pixel value is the mean of (Fresnel path weight × incoming radiance along the exit direction). Mirror
  paths are reversible and their Fresnel weights are the same both ways, so this eye-side average equals the
  light-side definition of the tables, ∫ ρ_s(φ_o, φ_i) cos φ_i L(−θ_o, φ_i) dφ_i.

Lighting (:class:`Lighting`) is an equirectangular environment plus an optional :class:`ConeLight`: a
directional light of small angular radius H and constant radiance — a *thin* source so both the reference
(whose exit directions lie on the 1D half-cone θ = −θ_o and would never hit a true delta light) and the
models can integrate it. The shipped sky's own sun is painted out by :func:`sky_lighting` and replaced by such
a cone, which the models sample explicitly.

Partial coverage (eq. 3.4's linear mixing): a footprint covering a fraction c of scratch geometry and 1 − c of
flat base. The reference stratifies one period of that pattern: stratum s = (k + ξ)/N < c lands inside a scratch
at x0 = s/c, the rest on the base, shaded by one MIS sample of the base BRDF (:func:`shade_brdf`).

Standard errors use pairs of neighbouring strata: Var ≈ Σ_pairs (g_2i − g_2i+1)² / N² (conservative).
"""

from __future__ import annotations

import time
from dataclasses import dataclass, field
from importlib import resources
from pathlib import Path

import numpy as np

from ..brdf.base import Material
from ..equirect import equirect_uv, rotation_y
from .profiles import Profile, parse_profile
from .tracer2d import FresnelSpec
from .tracer3d import trace_directions

_CHUNK = 1 << 17


# -- frames --------------------------------------------------------------------------------------------------
@dataclass(frozen=True)
class ScratchFrame:
    """Scratch direction **u**, base normal **n** and **v** = **n** × **u**, world vectors (chapter 3, §3.2)."""

    u: np.ndarray
    n: np.ndarray

    @property
    def v(self) -> np.ndarray:
        return np.cross(self.n, self.u)

    @classmethod
    def plate(cls, angle_deg: float = 0.0) -> ScratchFrame:
        """A horizontal plate (n = +y, the environments' up) brushed along u = (cos β, 0, −sin β)."""
        b = np.radians(angle_deg)
        return cls(np.array([np.cos(b), 0.0, -np.sin(b)]), np.array([0.0, 1.0, 0.0]))

    def tracer(self, w: np.ndarray) -> np.ndarray:
        """World → tracer3d coordinates (x, y, z) = (ω·v, ω·n, ω·u)."""
        return np.stack([w @ self.v, w @ self.n, w @ self.u], axis=-1)

    def from_tracer(self, d: np.ndarray) -> np.ndarray:
        return d[..., :1] * self.v + d[..., 1:2] * self.n + d[..., 2:3] * self.u

    def shading(self, w: np.ndarray) -> np.ndarray:
        """World → the BRDF library's local frame (x = tangent = u, y = v, z = n)."""
        return np.stack([w @ self.u, w @ self.v, w @ self.n], axis=-1)

    def from_shading(self, w: np.ndarray) -> np.ndarray:
        return w[..., :1] * self.u + w[..., 1:2] * self.v + w[..., 2:3] * self.n

    def cone(self, w: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """(θ, φ) = (asin ω·u, atan2(ω·v, ω·n))."""
        return np.arcsin(np.clip(w @ self.u, -1.0, 1.0)), np.arctan2(w @ self.v, w @ self.n)

    def from_cone(self, theta, phi) -> np.ndarray:
        theta, phi = np.broadcast_arrays(np.asarray(theta, float), np.asarray(phi, float))
        c = np.cos(theta)[..., None]
        return np.sin(theta)[..., None] * self.u + c * (
            np.sin(phi)[..., None] * self.v + np.cos(phi)[..., None] * self.n
        )


# -- lighting ------------------------------------------------------------------------------------------------
@dataclass
class ConeLight:
    """A distant light of angular radius ``half_angle`` (radians) and constant ``radiance`` around ``direction``
    (unit, towards the light): a thickened directional light, integrable by eye rays and by 1D cone integrals."""

    direction: np.ndarray
    half_angle: float
    radiance: np.ndarray

    def __post_init__(self):
        self.direction = np.asarray(self.direction, float) / np.linalg.norm(self.direction)
        self.radiance = np.broadcast_to(np.asarray(self.radiance, float), (3,)).copy()

    @property
    def cos_half(self) -> float:
        return float(np.cos(self.half_angle))

    @property
    def solid_angle(self) -> float:
        return 2.0 * np.pi * (1.0 - self.cos_half)

    def inside(self, w: np.ndarray) -> np.ndarray:
        return w @ self.direction >= self.cos_half

    def sample(self, u1, u2) -> tuple[np.ndarray, np.ndarray]:
        """Uniform directions in the cone; pdf = 1 / solid angle."""
        cos_a = 1.0 - np.asarray(u1) * (1.0 - self.cos_half)
        sin_a = np.sqrt(np.maximum(0.0, 1.0 - cos_a * cos_a))
        phi = 2.0 * np.pi * np.asarray(u2)
        a = self.direction
        t = np.cross(a, [0.0, 1.0, 0.0] if abs(a[1]) < 0.9 else [1.0, 0.0, 0.0])
        t /= np.linalg.norm(t)
        b = np.cross(a, t)
        w = (sin_a * np.cos(phi))[..., None] * t + (sin_a * np.sin(phi))[..., None] * b + cos_a[..., None] * a
        return w, np.full(cos_a.shape, 1.0 / self.solid_angle)


@dataclass
class Lighting:
    """An equirectangular environment (Mitsuba 3 layout, bilinear like the GPU) and an optional cone light."""

    env: np.ndarray | None = None  # (H, W, 3) radiance
    rotate_y: float = 0.0
    sun: ConeLight | None = None
    name: str = "lighting"

    def env_radiance(self, w: np.ndarray) -> np.ndarray:
        if self.env is None:
            return np.zeros(w.shape[:-1] + (3,))
        u, v = equirect_uv(w @ rotation_y(self.rotate_y))
        h, wd, _ = self.env.shape
        x = u * wd - 0.5
        y = np.clip(v * h - 0.5, 0.0, h - 1.0)
        x0 = np.floor(x).astype(np.int64)
        y0 = np.minimum(np.floor(y).astype(np.int64), max(h - 2, 0))
        fx, fy = (x - x0)[..., None], (y - y0)[..., None]
        x0w, x1w, y1 = x0 % wd, (x0 + 1) % wd, np.minimum(y0 + 1, h - 1)
        img = self.env
        top = img[y0, x0w] * (1 - fx) + img[y0, x1w] * fx
        bottom = img[y1, x0w] * (1 - fx) + img[y1, x1w] * fx
        return top * (1 - fy) + bottom * fy

    def sun_radiance(self, w: np.ndarray) -> np.ndarray:
        if self.sun is None:
            return np.zeros(w.shape[:-1] + (3,))
        return np.where(self.sun.inside(w)[..., None], self.sun.radiance, 0.0)

    def radiance(self, w: np.ndarray) -> np.ndarray:
        return self.env_radiance(w) + self.sun_radiance(w)


def sky_lighting(sun: ConeLight | None = None, rotate_y: float = 0.0) -> Lighting:
    """The shipped procedural sky (``data/environments/sky.hdr``) with its painted sun removed (pixels above 20
    replaced by their row's median), plus an optional explicit :class:`ConeLight` sun."""
    from ..imageio import read_image

    path = resources.files("reflets").joinpath("data", "environments", "sky.hdr")
    with resources.as_file(path) as p:
        image = read_image(Path(p)).astype(np.float64)
    bright = image.max(axis=-1) > 20.0
    for row in np.nonzero(bright.any(axis=1))[0]:
        image[row, bright[row]] = np.median(image[row, ~bright[row]], axis=0)
    return Lighting(image, rotate_y, sun, name="sky" + (" + cone sun" if sun else ""))


def sun_for_highlight(
    frame: ScratchFrame, wo: np.ndarray, elevation_deg: float = 40.0, phi: float | None = None, **cone
) -> ConeLight:
    """A cone light on the reflection half-cone of ``wo`` (θ_sun = −θ_o), so its brushed highlight passes through
    that view direction: at cone angle ``phi`` if given, else on the opposite side in φ at ``elevation_deg``."""
    half, radiance = cone.get("half_angle", np.radians(2.5)), cone.get("radiance", (300.0, 270.0, 230.0))
    if phi is not None:
        return ConeLight(frame.from_cone(-np.arcsin(np.clip(wo @ frame.u, -1, 1)), phi), half, radiance)
    a = -float(wo @ frame.u)
    c = np.sin(np.radians(elevation_deg))
    c = min(c, 0.98 * np.sqrt(max(1.0 - a * a, 0.0)))
    b = -np.sign(wo @ frame.v or 1.0) * np.sqrt(max(1.0 - a * a - c * c, 0.0))
    return ConeLight(a * frame.u + b * frame.v + c * frame.n, half, radiance)


# -- views of a plate ----------------------------------------------------------------------------------------
@dataclass
class PlateView:
    """A pinhole camera looking at the plate y = 0: per-pixel view directions ``wo`` (H, W, 3) of the plate point
    seen at the pixel centre (distant lighting, no shadows: a pixel depends on its ω_o only)."""

    width: int = 96
    height: int = 64
    eye: tuple = (0.0, 1.6, 1.5)
    target: tuple = (0.0, 0.0, -0.3)
    fov_deg: float = 55.0
    angle_deg: float = 30.0  # brushing direction in the plate
    wo: np.ndarray = field(init=False, repr=False)
    points: np.ndarray = field(init=False, repr=False)

    def __post_init__(self):
        eye, target = np.asarray(self.eye, float), np.asarray(self.target, float)
        f = (target - eye) / np.linalg.norm(target - eye)
        r = np.cross(f, [0.0, 1.0, 0.0])
        r /= np.linalg.norm(r)
        up = np.cross(r, f)
        t = np.tan(np.radians(self.fov_deg) / 2.0)
        aspect = self.width / self.height
        xs = ((np.arange(self.width) + 0.5) / self.width * 2.0 - 1.0) * t * aspect
        ys = (1.0 - (np.arange(self.height) + 0.5) / self.height * 2.0) * t
        d = f + xs[None, :, None] * r + ys[:, None, None] * up
        d /= np.linalg.norm(d, axis=-1, keepdims=True)
        if np.any(d[..., 1] >= -1e-3):
            raise ValueError("every pixel must see the plate (y = 0): tilt the camera down")
        tt = -eye[1] / d[..., 1]
        self.points = eye + tt[..., None] * d
        self.wo = -d

    @property
    def frame(self) -> ScratchFrame:
        return ScratchFrame.plate(self.angle_deg)

    def coverage_ramp(self) -> np.ndarray:
        """A coverage map c ∈ [0, 1] rising linearly from the left to the right column (H, W)."""
        return np.broadcast_to(np.linspace(0.0, 1.0, self.width)[None, :], (self.height, self.width)).copy()


# -- shading of a smooth BRDF (the base of partial coverage; Ashikhmin–Shirley in models.py) ----------------
def _power(a, b):
    a2, b2 = a * a, b * b
    with np.errstate(invalid="ignore", divide="ignore"):
        return np.where(a2 + b2 > 0, a2 / (a2 + b2), 0.0)


def shade_brdf(material: Material, frame: ScratchFrame, wo: np.ndarray, lighting: Lighting, u: np.ndarray):
    """One MIS sample per row of ∫ f L cos: a BRDF sample (environment + cone light, power heuristic) and a cone
    light sample. ``wo`` (n, 3) world, ``u`` (n, 4) uniform numbers. Returns (n, 3)."""
    wo_l = frame.shading(wo)
    wi_l, pdf_b = material.sample(wo_l, u[:, 0], u[:, 1])
    ok = (pdf_b > 0) & (wi_l[:, 2] > 0) & (wo_l[:, 2] > 0)
    f = material.eval(wo_l, wi_l)
    wi = frame.from_shading(wi_l)
    out = np.zeros((wo.shape[0], 3))
    sun = lighting.sun
    pdf_s = np.where(sun.inside(wi), 1.0 / sun.solid_angle, 0.0) if sun is not None else np.zeros(len(wo))
    w_b = _power(pdf_b, pdf_s)
    L = lighting.env_radiance(wi) + w_b[:, None] * lighting.sun_radiance(wi)
    with np.errstate(invalid="ignore", divide="ignore"):
        term = f * (wi_l[:, 2] / np.where(ok, pdf_b, 1.0))[:, None] * L
    out += np.where(ok[:, None], term, 0.0)
    if sun is not None:
        ws, ps = sun.sample(u[:, 2], u[:, 3])
        ws_l = frame.shading(ws)
        fs = material.eval(wo_l, ws_l)
        pb = material.pdf(wo_l, ws_l)
        w_s = _power(ps, pb)
        oks = (ws_l[:, 2] > 0) & (wo_l[:, 2] > 0)
        term = fs * (ws_l[:, 2] * w_s / ps)[:, None] * sun.radiance
        out += np.where(oks[:, None], term, 0.0)
    return out


def stratified_stats(values: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Mean over axis 1 (N strata, N even or not) and the paired-strata standard error of that mean."""
    n = values.shape[1]
    mean = values.mean(axis=1)
    m = n - n % 2
    diff = values[:, 0:m:2] - values[:, 1:m:2]
    var = np.sum(diff * diff, axis=1) / (n * n) if m else np.zeros_like(mean)
    return mean, np.sqrt(var)


# -- the reference -------------------------------------------------------------------------------------------
@dataclass
class ReferenceResult:
    mean: np.ndarray  # (..., 3) radiance
    stderr: np.ndarray  # (..., 3)
    rays: int  # rays per pixel
    lost: int
    seconds: float
    max_bounces: int = 0


def reference_radiance(
    profile: Profile | str,
    fresnel: FresnelSpec,
    frame: ScratchFrame,
    wo: np.ndarray,
    lighting: Lighting,
    *,
    rays: int = 256,
    seed: int = 0,
    coverage=None,
    base: Material | None = None,
) -> ReferenceResult:
    """Outgoing radiance of a scratched footprint for view directions ``wo`` (..., 3) (world, unit).

    ``coverage`` (shape of wo[..., 0], or a scalar) is the area fraction of scratch geometry; the rest is the flat
    ``base`` material (required when some coverage < 1). See the module docstring for the estimator."""
    t0 = time.perf_counter()
    profile = parse_profile(profile)
    wo = np.asarray(wo, dtype=np.float64)
    shape = wo.shape[:-1]
    wo = wo.reshape(-1, 3)
    P, N = wo.shape[0], int(rays)
    cov = np.broadcast_to(np.asarray(1.0 if coverage is None else coverage, float), shape).reshape(-1)
    if np.any(cov < 1.0) and base is None:
        raise ValueError("a coverage below 1 needs a base material")
    rng = np.random.default_rng(seed)
    mean = np.zeros((P, 3))
    err = np.zeros((P, 3))
    lost = 0
    most = 0
    per = max(1, _CHUNK // N)
    for start in range(0, P, per):
        sl = slice(start, min(P, start + per))
        p = sl.stop - sl.start
        s = (np.arange(N)[None, :] + rng.random((p, N))) / N  # stratified position in the pattern period
        c = cov[sl][:, None]
        scr = s < c
        values = np.zeros((p, N, 3))
        w_pix = np.broadcast_to(wo[sl][:, None, :], (p, N, 3))
        if scr.any():
            ww = w_pix[scr]
            x0 = s[scr] / c.repeat(N, axis=1)[scr]
            D, weight, bounces, bad = trace_directions(
                profile, frame.tracer(ww), x0, rng.random(x0.size), fresnel=fresnel
            )
            exit_w = frame.from_tracer(D)
            L = lighting.radiance(exit_w) * weight  # (n, 3) × (n, C) broadcast (C = 1 or 3)
            values[scr] = np.where(bad[:, None], 0.0, L)
            lost += int(bad.sum())
            if (~bad).any():
                most = max(most, int(bounces[~bad].max()))
        flat = ~scr
        if flat.any():
            uu = rng.random((int(flat.sum()), 4))
            cf = c.repeat(N, axis=1)[flat]
            uu[:, 0] = np.clip((s[flat] - cf) / np.maximum(1.0 - cf, 1e-300), 0.0, 1.0 - 1e-12)
            values[flat] = shade_brdf(base, frame, w_pix[flat], lighting, uu)
        mean[sl], err[sl] = stratified_stats(values)
    return ReferenceResult(
        mean.reshape(shape + (3,)), err.reshape(shape + (3,)), N, lost, time.perf_counter() - t0, most
    )


def mirror_radiance(fresnel: FresnelSpec, frame: ScratchFrame, wo: np.ndarray, lighting: Lighting) -> np.ndarray:
    """F(ω_o·n) L(reflect(ω_o, n)): the exact answer for a flat profile (a Fresnel mirror)."""
    wo = np.asarray(wo, float)
    c = wo @ frame.n
    wr = 2.0 * c[..., None] * frame.n - wo
    return fresnel(c) * lighting.radiance(wr)


def render_plate_reference(
    profile, fresnel: FresnelSpec, view: PlateView, lighting: Lighting, *, rays=256, seed=0, coverage=None, base=None
) -> ReferenceResult:
    """The reference image of a plate fully (or ``coverage``-partially) covered by one layer of scratches."""
    return reference_radiance(
        profile, fresnel, view.frame, view.wo, lighting, rays=rays, seed=seed, coverage=coverage, base=base
    )
