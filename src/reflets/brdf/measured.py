"""Measured isotropic BRDFs in the MERL format (Matusik et al. 2003, "A Data-Driven Reflectance Model").

Using your own MERL files
-------------------------
Put the ``.binary`` files of the MERL 100 database (or any file in the same layout, e.g. one written by
:func:`write_merl`) next to the scene and name them in a material::

    [materials.gold]
    type = "measured"
    file = "brdfs/gold-metallic-paint.binary"   # relative to the scene file's folder
    scale = [1, 1, 1]                           # optional RGB multiplier
    precision = "fp32"                          # or "fp16": half the GPU memory, ~5e-4 relative rounding

The file is read when the material is first used (scene loading resolves the path and checks it); a missing,
truncated or malformed file is a :class:`~reflets.errors.SceneError` naming the file.

File layout
-----------
Header: three little-endian int32 (n_θh, n_θd, n_φd) = (90, 90, 180). Then three planes (R, G, B), each
90·90·180 little-endian float64, entry (i_θh, i_θd, i_φd) at ``(i_θh·90 + i_θd)·180 + i_φd``; f_r is the stored
value times the channel scale 1/1500, 1.15/1500, 1.66/1500 (R, G, B). Negative values mean "not measured":
they read as 0 and :attr:`Measured.missing` / :attr:`MerlTable.missing` count them (non-finite values too).

Coordinates (Rusinkiewicz 1998, as in MERL's ``BRDFRead.cpp``)
---------------------------------------------------------------
h = normalize(wi + wo) has polar angles (θh, φh); d = wi rotated by −φh about z, then by −θh about y, has
polar angles (θd, φd). wi is the direction to the light, wo to the viewer (the local frame of
:mod:`reflets.brdf.base`). Swapping wi and wo maps φd to φd ± π, so the table stores φd ∈ [0, π) only and
φd < 0 is folded to φd + π (reciprocity). Continuous table indices::

    c_θh = sqrt(θh / (π/2)) · 90      c_θd = θd / (π/2) · 90      c_φd = φd / π · 180

(MERL's reference code floors these and clamps to [0, n − 1], so entry i covers the continuous interval
[i, i + 1)).

Interpolation convention
------------------------
Entry i sits at continuous index **i + 0.5** — the centre of the interval it covers, which is exactly
OpenGL's texel-centre convention. :meth:`Measured.eval` interpolates trilinearly in continuous index space
with entries at i + 0.5, clamping at both ends of θh and θd (below 0.5 or above n − 0.5 the edge entry is
used) and wrapping φd with period 180 (entry 179 neighbours entry 0: φd = π is φd = 0 by reciprocity). The
GLSL twin does the same from a 3D float texture (x = φd, y = θd, z = θh, coordinate = continuous index / n),
interpolating in float32 itself from eight ``texelFetch`` (wrap and clamp as here), so NumPy and GPU agree to
float precision on every driver (``precision = "fp16"``: to half-float rounding, 2^-11 relative). The shader
computes the angles with its own atan (Cephes, 2e-7): GLSL leaves atan's accuracy to the driver, and
llvmpipe's (3e-6 rad) alone gives 1e-3 relative differences in steep table regions. Hardware LINEAR filtering
is not used: texture units filter with 8-bit weights (measured on an NVIDIA H200: 1e-2 relative off this
reference in steep table regions). Nearest-entry lookup as in MERL's code
is *not* used: it makes f_r piecewise constant, with visible steps in highlights. :func:`write_merl`
samples a function at the entry centres, so a written file reproduces it exactly there.

Near grazing angles interpolation mixes entries whose centres lie below the horizon (which MERL files
leave unmeasured or 0), so values within a table cell (1–2°) of the horizon are less reliable than the data.

Physical caveats
----------------
``reciprocal`` is True: the folding of φd makes f(wo, wi) = f(wi, wo) exactly. ``energy_conserving`` is
False: measured data contains noise, and values near grazing angles are extrapolated, so the directional
albedo of a table can exceed 1; no white-furnace guarantee is made.

Sampling: a one-sample mixture of cosine-weighted directions and a Blinn-style half-vector lobe
(density ∝ cos^e θh around the normal, reflected about wo), with the exponent e and the mixture weight fitted
to the table's θh profile when it is loaded. The weights are clamped to [0.1, 0.9], so the estimator's
second moment is at most 10× that of either strategy used alone (a defensive mixture).

Memory
------
The NumPy reference keeps the table as float64 (90·90·180·3·8 B = 35 MB per file; up to four files are
cached, keyed by resolved path, modification time and size, so repeated ``eval`` calls never re-read the
file). The GPU texture is RGB32F, 17.5 MB (``fp16``: RGB16F, 8.7 MB; drivers may pad RGB to RGBA,
+33 %), created once per (GL context, file, precision). fp16 stores values above 65504 as 65504.
"""

from __future__ import annotations

import functools
import stat
from dataclasses import dataclass
from pathlib import Path
from typing import Literal

import numpy as np

from ..errors import SceneError
from ..quantities import MAX_MAGNITUDE
from .base import (
    RGB,
    Material,
    finish_sample,
    mix_pdf,
    normalize,
    pdf_cosine,
    pdf_power_cosine,
    reflect_or_fail,
    register_material,
    sample_cosine,
    sample_half_vector_pdf_to_wi,
    sample_mixture,
    sample_power_cosine,
    upper,
)
from .blinn_phong import normalization

#: table dimensions (n_θh, n_θd, n_φd) of a MERL file, as in its header
MERL_SHAPE = (90, 90, 180)
#: f_r = stored value × scale, per channel (R, G, B)
CHANNEL_SCALES = np.array([1.0 / 1500.0, 1.15 / 1500.0, 1.66 / 1500.0])
_HEADER_BYTES = 12
_ENTRIES = MERL_SHAPE[0] * MERL_SHAPE[1] * MERL_SHAPE[2]
_FILE_BYTES = _HEADER_BYTES + 3 * _ENTRIES * 8
_HALF_PI = 0.5 * np.pi
_FP16_MAX = 65504.0
_LUMINANCE = np.array([0.2126, 0.7152, 0.0722])
_Z = np.array([0.0, 0.0, 1.0])


# ------------------------------------------------------------------------------------------ coordinates


def merl_coordinates(wo: np.ndarray, wi: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(θh, θd, φd) of direction pairs (shape (..., 3) each → three (...) arrays), φd folded into [0, π).

    Computed in a form that is exactly symmetric in wo and wi: θd = atan2(|wi − wo|, |wi + wo|) (half the
    angle between them) and φd is the azimuth of wi − wo = 2 sinθd (cosφd t + sinφd b) in the frame
    (t, b, h) obtained by rotating (x, y, z) by θh about y and then by φh about z. This equals MERL's
    rotation of wi but keeps full precision when wi ≈ wo. Inputs need not be above the surface, but the
    angles only mean something when wi + wo ≠ 0.
    """
    wo = np.asarray(wo, dtype=np.float64)
    wi = np.asarray(wi, dtype=np.float64)
    s = wo + wi
    u = wi - wo
    s_len = np.linalg.norm(s, axis=-1)
    h = s / np.maximum(s_len, 1e-300)[..., None]
    r = np.hypot(h[..., 0], h[..., 1])
    theta_h = np.arctan2(r, h[..., 2])
    theta_d = np.arctan2(np.linalg.norm(u, axis=-1), s_len)
    safe = r > 0
    r_safe = np.where(safe, r, 1.0)
    cos_phi = np.where(safe, h[..., 0] / r_safe, 1.0)
    sin_phi = np.where(safe, h[..., 1] / r_safe, 0.0)
    x = (u[..., 0] * cos_phi + u[..., 1] * sin_phi) * h[..., 2] - u[..., 2] * r
    y = u[..., 1] * cos_phi - u[..., 0] * sin_phi
    phi_d = np.mod(np.arctan2(y, x), np.pi)
    phi_d = np.where(phi_d >= np.pi, 0.0, phi_d)  # −tiny + π rounds to π
    return theta_h, theta_d, phi_d


def merl_directions(theta_h, theta_d, phi_d) -> tuple[np.ndarray, np.ndarray]:
    """Inverse of :func:`merl_coordinates` with φh = 0: ``(wo, wi)``, each of shape (..., 3).

    wi = cosθd h + sinθd (cosφd t + sinφd b) and wo its mirror image about h, with h = (sinθh, 0, cosθh),
    t = (cosθh, 0, −sinθh), b = (0, 1, 0). φd + π gives the same pair with wo and wi swapped.
    """
    th, td, pd = np.broadcast_arrays(*(np.asarray(a, dtype=np.float64) for a in (theta_h, theta_d, phi_d)))
    sh, ch = np.sin(th), np.cos(th)
    a = np.sin(td) * np.cos(pd)  # component along t
    b = np.sin(td) * np.sin(pd)  # along the bitangent
    c = np.cos(td)  # along h
    wi = np.stack([c * sh + a * ch, b, c * ch - a * sh], axis=-1)
    wo = np.stack([c * sh - a * ch, -b, c * ch + a * sh], axis=-1)
    return wo, wi


def continuous_indices(theta_h, theta_d, phi_d) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Continuous table indices (c_θh, c_θd, c_φd); entry i covers [i, i + 1) and sits at i + 0.5."""
    n_h, n_d, n_p = MERL_SHAPE
    c_h = np.sqrt(np.maximum(np.asarray(theta_h, dtype=np.float64), 0.0) / _HALF_PI) * n_h
    c_d = np.asarray(theta_d, dtype=np.float64) / _HALF_PI * n_d
    c_p = np.asarray(phi_d, dtype=np.float64) / np.pi * n_p
    return c_h, c_d, c_p


def entry_centres() -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(θh, θd, φd) at the entry centres (continuous index i + 0.5), each of shape (90,), (90,), (180,)."""
    n_h, n_d, n_p = MERL_SHAPE
    theta_h = ((np.arange(n_h) + 0.5) / n_h) ** 2 * _HALF_PI
    theta_d = (np.arange(n_d) + 0.5) / n_d * _HALF_PI
    phi_d = (np.arange(n_p) + 0.5) / n_p * np.pi
    return theta_h, theta_d, phi_d


def _axis(c: np.ndarray, n: int, wrap: bool) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Lower/upper neighbour indices and weight of the upper one for texel centres at i + 0.5."""
    x = np.nan_to_num(c, nan=0.0, posinf=n, neginf=0.0) - 0.5
    lo = np.floor(x)
    t = x - lo
    i0 = lo.astype(np.int64)
    i1 = i0 + 1
    if wrap:
        return np.mod(i0, n), np.mod(i1, n), t
    return np.clip(i0, 0, n - 1), np.clip(i1, 0, n - 1), t


def interpolate(values: np.ndarray, c_h, c_d, c_p) -> np.ndarray:
    """Trilinear interpolation of a (90, 90, 180, 3) table at continuous indices (entries at i + 0.5),
    clamped in θh and θd, periodic in φd; returns (..., 3)."""
    n_h, n_d, n_p = values.shape[:3]
    h0, h1, th = _axis(np.asarray(c_h), n_h, wrap=False)
    d0, d1, td = _axis(np.asarray(c_d), n_d, wrap=False)
    p0, p1, tp = _axis(np.asarray(c_p), n_p, wrap=True)
    flat = values.reshape(-1, values.shape[-1])
    out = np.zeros(th.shape + (values.shape[-1],))
    for hi, wh in ((h0, 1.0 - th), (h1, th)):
        for di, wd in ((d0, 1.0 - td), (d1, td)):
            row = (hi * n_d + di) * n_p
            w_hd = wh * wd
            for pi, wp in ((p0, 1.0 - tp), (p1, tp)):
                out += (w_hd * wp)[..., None] * np.take(flat, row + pi, axis=0)  # take: 3× faster than []
    return out


# ---------------------------------------------------------------------------------------------- files


@dataclass(frozen=True, eq=False)
class MerlTable:
    """A loaded MERL file. ``values``: read-only float64 (n_θh, n_θd, n_φd, 3) = (90, 90, 180, 3) array of
    f_r with the channel scales applied and missing entries set to 0."""

    path: Path
    values: np.ndarray
    #: number of negative (or non-finite) stored values — "not measured" — over all three channels
    missing: int
    #: (modification time in ns, size in bytes) of the file when it was read
    stamp: tuple[int, int]
    #: exponent e of the half-vector lobe cos^e θh used for importance sampling (fitted to the data)
    lobe_exponent: float
    #: probability of sampling that lobe rather than the cosine-weighted hemisphere, in [0.1, 0.9]
    lobe_weight: float


def load_merl(path: str | Path) -> MerlTable:
    """Read a MERL BRDF file (cached per resolved path, modification time and size).

    Raises :class:`SceneError` naming the file (made absolute) when it is missing, unreadable, not 90×90×180
    or not the exact size of such a file. A relative path is taken relative to the working directory; scene
    files resolve theirs against the scene's folder first.
    """
    resolved = Path(path).expanduser().resolve()
    try:
        info = resolved.stat()
    except FileNotFoundError:
        raise SceneError("MERL BRDF file not found", file=resolved) from None
    except OSError as exc:
        raise SceneError(f"cannot read MERL BRDF file ({exc.strerror or exc})", file=resolved) from None
    if not stat.S_ISREG(info.st_mode):
        raise SceneError("is not a regular file (expected a MERL BRDF .binary file)", file=resolved)
    return _load_cached(str(resolved), info.st_mtime_ns, info.st_size)


@functools.lru_cache(maxsize=4)
def _load_cached(path: str, mtime_ns: int, size: int) -> MerlTable:
    try:
        with open(path, "rb") as fh:
            header = fh.read(_HEADER_BYTES)
            if len(header) < _HEADER_BYTES:
                raise SceneError(
                    f"truncated MERL BRDF file: {len(header)} bytes, shorter than the 12-byte header", file=path
                )
            dims = tuple(int(v) for v in np.frombuffer(header, dtype="<i4"))
            if dims != MERL_SHAPE:
                raise SceneError(
                    f"not a MERL BRDF file: header says {dims[0]}×{dims[1]}×{dims[2]} (n_θh×n_θd×n_φd), expected "
                    f"90×90×180 as three little-endian int32",
                    file=path,
                )
            raw = np.fromfile(fh, dtype="<f8", count=3 * _ENTRIES)
            extra = len(fh.read(1))
    except OSError as exc:
        raise SceneError(f"cannot read MERL BRDF file ({exc.strerror or exc})", file=path) from None
    if raw.size < 3 * _ENTRIES:
        got = _HEADER_BYTES + raw.size * 8
        raise SceneError(f"truncated MERL BRDF file: {got} bytes, expected {_FILE_BYTES}", file=path)
    if extra:
        raise SceneError(
            f"not a MERL BRDF file: {size} bytes, expected {_FILE_BYTES} (data continues after the 3 planes)",
            file=path,
        )
    valid = np.isfinite(raw) & (raw >= 0)
    missing = int(raw.size - np.count_nonzero(valid))
    planes = np.where(valid, raw, 0.0).reshape(3, *MERL_SHAPE) * CHANNEL_SCALES[:, None, None, None]
    if planes.max() > MAX_MAGNITUDE:
        raise SceneError(f"BRDF values up to {planes.max():.3g}, over {MAX_MAGNITUDE:.0e}: not a MERL table of a real "
                         "material", file=path)  # fmt: skip
    values = np.ascontiguousarray(np.moveaxis(planes, 0, -1))
    values.flags.writeable = False
    exponent, weight = _fit_lobe(values)
    return MerlTable(Path(path), values, missing, (mtime_ns, size), exponent, weight)


def _fit_lobe(values: np.ndarray) -> tuple[float, float]:
    """Sampling lobe from the luminance θh profile (median over θd < 30°, all φd, for θh < 60°): the floor of
    the profile is taken as diffuse, the excess above it fitted by peak · cos^e θh (least squares in log
    space over the points above 5 % of the peak); the lobe's weight is its share of the estimated albedo."""
    theta_h = entry_centres()[0]
    rows = theta_h < np.radians(60.0)
    lum = values[rows, :30, :, :] @ _LUMINANCE
    profile = np.median(lum.reshape(lum.shape[0], -1), axis=1)
    floor = max(float(profile.min()), 0.0)
    excess = profile - floor
    peak = float(excess[0])
    if not peak > 0:
        return 1.0, 0.1
    log_cos = np.log(np.cos(theta_h[rows]))
    use = (excess > 0.05 * peak) & (np.arange(len(excess)) > 0)
    if np.count_nonzero(use) >= 2:
        exponent = float(np.sum(np.log(excess[use] / peak) * log_cos[use]) / np.sum(log_cos[use] ** 2))
    else:  # the lobe falls below 5 % within the first entry
        exponent = float(np.log(0.05) / log_cos[1])
    exponent = float(np.clip(exponent, 1.0, 1e5))
    specular = peak / normalization(exponent)
    diffuse = np.pi * floor
    return exponent, float(np.clip(specular / (specular + diffuse), 0.1, 0.9))


def write_merl(path: str | Path, brdf_fn) -> Path:
    """Write a MERL-layout file from an isotropic BRDF ``brdf_fn(wo, wi) -> (..., 3)`` (local frame, wo to the
    viewer, wi to the light), evaluated at every entry's centre (continuous index i + 0.5 on each axis, φh = 0)
    and divided by the channel scales. Return a negative value to mark an entry as not measured."""
    path = Path(path)
    wo, wi = merl_directions(*np.meshgrid(*entry_centres(), indexing="ij"))
    f = np.broadcast_to(np.asarray(brdf_fn(wo, wi), dtype=np.float64), (*MERL_SHAPE, 3))
    planes = np.moveaxis(f, -1, 0) / CHANNEL_SCALES[:, None, None, None]
    with open(path, "wb") as fh:
        fh.write(np.asarray(MERL_SHAPE, dtype="<i4").tobytes())
        fh.write(np.ascontiguousarray(planes, dtype="<f8").tobytes())
    return path


# ------------------------------------------------------------------------------------------- textures


def _texture(ctx, table: MerlTable, precision: str):
    """The table as a 3D texture (x = φd, y = θd, z = θh), created once per (context, file, precision)."""
    import moderngl

    from ..gpu.context import context_store

    textures = context_store(ctx, "merl-textures")
    key = (str(table.path), precision)
    cached = textures.get(key)
    if cached is not None and cached[0] == table.stamp:
        return cached[1]
    if cached is not None:
        cached[1].release()
    if precision == "fp16":
        data, dtype = np.minimum(table.values, _FP16_MAX).astype(np.float16), "f2"
    else:
        data, dtype = table.values.astype(np.float32), "f4"
    n_h, n_d, n_p = MERL_SHAPE
    texture = ctx.texture3d((n_p, n_d, n_h), 3, data.tobytes(), dtype=dtype)
    texture.filter = (moderngl.NEAREST, moderngl.NEAREST)  # read by texelFetch: the shader interpolates
    textures[key] = (table.stamp, texture)
    return texture


# ------------------------------------------------------------------------------------------- material


@register_material
class Measured(Material):
    """Tabulated isotropic BRDF read from a MERL ``.binary`` file, trilinearly interpolated.

    Parameters
    ----------
    file : path, required
        The MERL file (relative paths in a scene file are relative to the scene's folder).
    scale : [r, g, b] ≥ 0, default [1, 1, 1]
        Multiplier applied to the measured f_r.
    precision : "fp32" | "fp16", default "fp32"
        Storage of the GPU texture. fp16 halves its memory (8.7 MB instead of 17.5 MB) at 2^-11 relative
        rounding of the stored values; the NumPy reference always uses the float64 data.
    """

    type: Literal["measured"] = "measured"
    file: Path
    scale: RGB = (1.0, 1.0, 1.0)
    precision: Literal["fp32", "fp16"] = "fp32"

    def lobe_summary(self):  # a generic glossy lobe: the cone methods' sampling guess, not a fit
        return (0.0, 0.0, 0.0), 2, 50.0

    glsl = "reflets/brdf/glsl/measured.glsl"

    def load(self) -> MerlTable:
        """The loaded table (read on first use, then cached); SceneError naming the file if it is bad."""
        return load_merl(self.file)

    @property
    def table(self) -> MerlTable:
        return self.load()

    @property
    def missing(self) -> int:
        """How many stored values (over the three channels) were negative, i.e. not measured, and read as 0."""
        return self.load().missing

    @property
    def reciprocal(self) -> bool:
        return True  # φd is folded into [0, π), which maps (wo, wi) and (wi, wo) to the same point

    @property
    def energy_conserving(self) -> bool:
        return False  # measured data is noisy and some MERL materials exceed albedo 1 at grazing angles

    def eval(self, wo: np.ndarray, wi: np.ndarray) -> np.ndarray:
        wo = np.asarray(wo, dtype=np.float64)
        wi = np.asarray(wi, dtype=np.float64)
        f = interpolate(self.load().values, *continuous_indices(*merl_coordinates(wo, wi)))
        return np.where(upper(wo, wi), f * np.asarray(self.scale), 0.0)

    def _weights(self) -> list[float]:
        w = self.load().lobe_weight
        return [1.0 - w, w]

    def sample(self, wo: np.ndarray, u1: np.ndarray, u2: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Mixture of cosine sampling and half vectors with density (e + 1)/(2π) cos^e θh (e fitted)."""
        wo = np.broadcast_to(np.asarray(wo, dtype=np.float64), np.shape(u1) + (3,))
        exponent = self.load().lobe_exponent

        def lobe(a, b, chosen):
            return reflect_or_fail(wo[chosen], sample_power_cosine(_Z, exponent, a, b))

        wi = sample_mixture(self._weights(), [lambda a, b, _: sample_cosine(a, b), lobe], u1, u2)
        return finish_sample(self, wo, wi)

    def pdf(self, wo: np.ndarray, wi: np.ndarray) -> np.ndarray:
        wo = np.asarray(wo, dtype=np.float64)
        h = normalize(wo + wi)
        lobe = sample_half_vector_pdf_to_wi(pdf_power_cosine(_Z, self.load().lobe_exponent, h), wo, h)
        return mix_pdf(self._weights(), [pdf_cosine(wi), lobe])

    def uniforms(self) -> dict[str, object]:
        return {"m_scale": tuple(float(s) for s in self.scale)}

    def textures(self, ctx) -> dict[str, object]:
        return {"m_table": _texture(ctx, self.load(), self.precision)}
