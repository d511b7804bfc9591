"""The layered scratched SV-BRDF of chapter 3 (§3.6, eqs 3.3, 3.4, 3.8) as a scene material, ``type = "scratched"``.

A scratched surface is a free **base** BRDF ρ_b covered by K **layers** of parallel scratches. Layer k has one
direction u_k = R(Θ_k) u in the tangent plane (u = the surface tangent, the direction of increasing texture u)
and a characteristic function 1_{S_k} whose footprint average α_k(x) weights the layer's scratch BRDF ρ_{s,k}
(the profile's table, :mod:`reflets.scratches.table`, in the layer's cone frame). Eq 3.4 combines them:
ρ̄ = Σ α_k ρ_{s,k}, ᾱ = Σ α_k; ρ = ρ̄/ᾱ if ᾱ > 1, else ρ̄ + (1 − ᾱ) ρ_b.

Layer generation (eq 3.8, erratum fixed: rotate into the layer's frame first, then scale, so Θ = 360° gives
every orientation): 1_{S_k}(x) = [N(diag(l, w)⁻¹ R(Θ_k)ᵀ x + ξ_k) ≤ d] with x = ``uv_scale`` · (u, v).
**Decision — the noise**: N is Worley's cellular noise F1 (distance to the nearest feature point of a Poisson
process of unit density, Worley 1996 — "bruit basé cellule"). Thresholded at d it is a union of discs of
radius d, i.e. in texture space ellipses of half-length d·l along u_k and half-width d·w along v_k: isolated
thin scratches for small d (3.14d, 3.11f), dense brushing for d ≳ 0.5 (3.14b). Expected coverage of a layer:
1 − exp(−π d²). The process is stationary, so the offsets ξ_k of the document are implicit (each layer draws
its own points).

α maps (eq 3.3): baked per layer at ``alpha_size``² texels over uv ∈ [0, 1]² by splatting every scratch's exact
area πd²lw along its axis (midpoint rule, two samples per texel; the width d·w is far below a texel for every
Table 3.1 row, so the lateral extent is ignored) and taking the Boolean-model union 1 − exp(−A/T²) of the
areas A falling into a texel of area T² (exact for isolated scratches to first order, the expected union of
overlapping ones). Layers denser than ``SPLAT_BUDGET`` splat samples keep a random subset of their scratches
with areas scaled up to keep the same expected coverage (coarser grain, same mean). Coarser levels are 2×2
means (the GPU's mip-maps): the footprint average is exact under mip-mapping because α is linear.

``coverage`` replaces the generated pattern by a constant α for every layer (uniform brushing; tests).

The finite part (``eval``, the GLSL ``brdf_eval`` every other technique sees): the scratch lobes are singular
(δ(θ_i + θ_o) in the solid-angle form) and have no finite value, like a mirror's delta lobe; what is left is
the base weighted by its mean share of the surface, w̄_b = mean over the α map of max(0, 1 − ᾱ(x)). The
``scratches`` technique shades the lobes.

Tables and α maps are cached in memory and on disk under ``$XDG_CACHE_HOME/reflets/scratches`` (default
``~/.cache``), keyed by a hash of the parameters they depend on and of the code that computes them.
"""

from __future__ import annotations

import functools
from pathlib import Path
from typing import Annotated, ClassVar, Literal, Union

import numpy as np
from pydantic import BaseModel, ConfigDict, Field, field_validator, model_validator

from ..brdf.ashikhmin_shirley import AshikhminShirley
from ..brdf.base import LIGHT_TYPES, RGB, Material, Oriented, PointsBRDF, register_material
from ..brdf.blinn_phong import BlinnPhong
from ..brdf.gltf import Gltf
from ..brdf.lafortune import Lafortune
from ..brdf.lambert import Lambert
from ..brdf.measured import Measured
from ..brdf.microfacet import Microfacet
from ..brdf.phong import Phong
from ..brdf.ward import Ward
from ..cache import Cache, Memo, content_key, file_stamp, source_hash
from ..errors import RefletsError
from ..quantities import Positive

#: Table 3.1 of the document: (layers N, spread Θ in degrees, length l, width w, density d)
PRESETS: dict[str, tuple[int, float, float, float, float]] = {
    "3.14b": (4, 7, 0.2, 2e-4, 0.6),
    "3.14c": (16, 360, 0.1, 1e-5, 0.3),
    "3.14d": (32, 360, 0.3, 3e-4, 0.05),
    "3.11bde": (6, 5, 0.1, 5e-4, 0.16),
    "3.11f": (32, 360, 0.1, 2e-4, 0.05),
    "3.15a": (4, 4, 0.1, 5e-5, 0.5),
    "3.15b": (16, 360, 0.1, 2e-4, 0.1),
    "3.15c": (16, 360, 0.02, 2e-5, 0.1),
    "3.15d": (32, 360, 0.1, 1e-5, 0.2),
    "3.17a": (4, 7, 0.02, 7e-4, 0.5),
    "3.17b": (16, 360, 0.02, 1e-5, 0.2),
}
DEFAULT_PRESET = "3.14b"
#: iron at 650 nm (the document's Fig 3.7 values), used for every RGB channel
IRON_ETA, IRON_K = 2.91, 3.09
MAX_LAYERS = 64
#: splat samples per layer (scratches × samples along each); denser layers keep a random subset (module docstring)
SPLAT_BUDGET = 4_000_000
#: layers whose α is below this are skipped (the document's α-culling)
ALPHA_CULL = 1e-6

PositiveRGB = tuple[Positive, Positive, Positive]

#: the base BRDF: any material of the library except scratched, translucent and mirror
BaseSpec = Annotated[
    Union[Lambert, Phong, BlinnPhong, Lafortune, Ward, AshikhminShirley, Microfacet, Measured, Gltf],  # noqa: UP007
    Field(discriminator="type"),
]


def _iron_base() -> Microfacet:
    return Microfacet(distribution="ggx", alpha=0.08, fresnel="conductor", eta=(IRON_ETA,) * 3, k=(IRON_K,) * 3)


class Conductor(BaseModel):
    """Complex index η + i k of the scratch walls, one number or one per RGB channel."""

    model_config = ConfigDict(extra="forbid")
    eta: Positive | PositiveRGB = IRON_ETA
    k: Annotated[float, Field(ge=0, allow_inf_nan=False)] | RGB = IRON_K


@register_material
class Scratched(Oriented, Material):
    """Layered scratched SV-BRDF (chapter 3 of the scratches document; docs/techniques/scratches.md).

    A base BRDF covered by K layers of parallel scratches whose profile BRDF is precomputed by the 2D tracer.
    ``eval`` / the GLSL twin return only the finite part, the base weighted by its mean uncovered share; the
    scratch lobes (singular on the Kajiya–Kay cone) are shaded by ``--method scratches``.

    Parameters
    ----------
    profile : str, default "quartic:0.5"
        Scratch profile: ``vgroove:D``, ``quartic:D`` (depth D for width 1), ``flat`` or ``file:PATH`` (a
        profilometer table; the path is taken as given, not relative to the scene file).
    conductor : { eta, k }, default iron (2.91, 3.09 at 650 nm, every channel)
        Complex index of the walls (Lazányi–Szirmay-Kalos Fresnel, ``fresnel = "exact"``: exact).
    ior : float or [r, g, b] > 0, default none
        Real index of dielectric walls instead (Schlick, or exact with ``fresnel = "exact"``).
    fresnel : "auto" | "exact" | "none", default "auto"
        "none": F = 1 (the mirror BRDF ρ_m, the document's Fig 3.7e).
    table_size : int in [8, 512], default 128
        M: the table has M × M bins over (φ_out, φ_in) (the document uses 256).
    rays : int in [100, 10⁶], default 10000
        Rays per φ_in column of the table.
    base : material table, default GGX α = 0.08 with iron's conductor Fresnel
        The base BRDF ρ_b: any type but scratched, translucent and mirror (a measured file is not resolved
        against the scene folder); its textures are read per pixel (a ``gltf`` base's, a library base's maps, normal
        map and emission).
    preset : "3.14b" | "3.14c" | "3.14d" | "3.11bde" | "3.11f" | "3.15a" | "3.15b" | "3.15c" | "3.15d" | "3.17a"
        | "3.17b", default "3.14b" when no layer parameter is given
        A row of the document's Table 3.1; the explicit parameters below override it.
    count : int in [1, 64]
        N, the number of layers.
    spread : degrees in [0, 360]
        Θ: layer k is rotated by Θ_k ~ U[−Θ/2, Θ/2] from the tangent.
    length, width : > 0, texture units (after ``uv_scale``)
        l and w, the scale of the cellular noise along u_k and v_k (scratches are d·2l long and d·2w wide).
    density : in (0, 1]
        d, the noise threshold (coverage of one layer: 1 − exp(−π d²)).
    coverage : in [0, 1], default none
        A constant α for every layer instead of the generated pattern.
    seed : int ≥ 0, default 0
        Random layer angles and scratch positions.
    uv_scale : > 0, default 1
        Texture coordinates are multiplied by it before the layers are evaluated.
    alpha_size : power of two in [16, 4096], default 512
        Resolution of the baked α maps (per layer, over uv ∈ [0, 1]², mip-mapped).
    """

    type: Literal["scratched"] = "scratched"
    profile: str = "quartic:0.5"
    conductor: Conductor | None = None
    ior: Positive | PositiveRGB | None = None
    fresnel: Literal["auto", "exact", "none"] = "auto"
    table_size: int = Field(128, ge=8, le=512)
    rays: int = Field(10000, ge=100, le=1_000_000)
    base: BaseSpec = Field(default_factory=_iron_base)
    preset: Literal[tuple(PRESETS)] | None = None
    count: int | None = Field(None, ge=1, le=MAX_LAYERS)
    spread: float | None = Field(None, ge=0, le=360)
    length: Positive | None = None
    width: Positive | None = None
    density: float | None = Field(None, gt=0, le=1)
    coverage: float | None = Field(None, ge=0, le=1)
    seed: int = Field(0, ge=0)
    uv_scale: Positive = 1.0
    alpha_size: int = Field(512, ge=16, le=4096)
    #: the finite part over the base's twin (``brdf_source`` puts them together)
    glsl: ClassVar[str] = "reflets/scratches/shaders/scratched_finite.glsl"

    @field_validator("profile")
    @classmethod
    def _profile_parses(cls, value: str) -> str:
        from .profiles import parse_profile

        try:
            parse_profile(value)
        except RefletsError as exc:
            raise ValueError(str(exc)) from None  # with the profile's file, when it names one
        return value

    @field_validator("alpha_size")
    @classmethod
    def _power_of_two(cls, value: int) -> int:
        if value & (value - 1):
            raise ValueError(f"alpha_size must be a power of two (mip-mapping), got {value}")
        return value

    @model_validator(mode="after")
    def _check(self) -> Scratched:
        if self.conductor is not None and self.ior is not None:
            raise ValueError("give conductor (eta, k) or ior, not both")
        if self.fresnel == "none" and (self.conductor is not None or self.ior is not None):
            raise ValueError('fresnel = "none" takes neither conductor nor ior')
        if self.base.cutout:  # the scratches pass neither cuts nor blends
            raise ValueError(f'a glTF base must be opaque (alpha_mode "{self.base.alpha_mode}" is not taken here)')
        if getattr(self.base, "transmissive", False):  # nor draws what lies behind
            raise ValueError("a glTF base must be opaque (a transmission factor is not taken here)")
        return self

    # ------------------------------------------------------------------------------------------ parameters
    @property
    def layer_parameters(self) -> tuple[int, float, float, float, float]:
        """(N, Θ degrees, l, w, d): the preset's row (``DEFAULT_PRESET`` without one) with explicit overrides."""
        row = PRESETS[self.preset or DEFAULT_PRESET]
        own = (self.count, self.spread, self.length, self.width, self.density)
        n, spread, length, width, density = (r if o is None else o for r, o in zip(row, own, strict=True))
        return int(n), float(spread), float(length), float(width), float(density)

    @property
    def layer_count(self) -> int:
        return self.layer_parameters[0]

    def layer_angles(self) -> np.ndarray:
        """Θ_k in radians, (K,): uniform in [−Θ/2, Θ/2] from the seed."""
        n, spread, *_ = self.layer_parameters
        rng = np.random.default_rng([self.seed, 0x5C7A])
        return np.radians(rng.uniform(-0.5 * spread, 0.5 * spread, n))

    def fresnel_arguments(self) -> dict:
        """Keyword arguments of :func:`~reflets.scratches.table.build_table` for the walls' Fresnel."""
        if self.fresnel == "none":
            return {"ior": None, "conductor": None, "fresnel": "auto"}
        model = "exact" if self.fresnel == "exact" else "auto"
        if self.ior is not None:
            return {"ior": self.ior, "conductor": None, "fresnel": model}
        c = self.conductor or Conductor()
        return {"ior": None, "conductor": (c.eta, c.k), "fresnel": model}

    @property
    def reciprocal(self) -> bool:
        return self.base.reciprocal

    @property
    def energy_conserving(self) -> bool:
        return self.base.energy_conserving

    # ------------------------------------------------------------------------------------------ precomputation
    def table(self, ctx=None, backend: str | None = None):
        """The profile's :class:`~reflets.scratches.table.ScratchTable` (memory, then disk cache, then traced).

        ``backend``: "numpy" or "gpu"; by default "gpu" when a context is given (faster here, see
        docs/techniques/scratches.md), else "numpy". Tables from different backends differ by Monte
        Carlo noise, so the backend is part of the cache key."""
        backend = backend or ("gpu" if ctx is not None else "numpy")
        return cached_table(self.profile, self.fresnel_arguments(), self.table_size, self.rays, backend, ctx)

    def alpha_maps(self) -> np.ndarray:
        """Base level of the α maps, (K, R, R) float32, row 0 at v = 0 (the GL texture's first row)."""
        return cached_alpha(self)

    @property
    def bends_normals(self) -> bool:
        return self.base.bends_normals  # the forward pass draws its finite part with the base's normal map

    def base_weight(self) -> float:
        """w̄_b = mean over the α map of max(0, 1 − ᾱ): the base's share of the surface (the finite part)."""
        if self.coverage is not None:
            return max(0.0, 1.0 - self.layer_count * self.coverage)
        def weight() -> float:  # (the reference asks at every hit: the maps' sum once per set of maps)
            return float(np.mean(np.maximum(0.0, 1.0 - self.alpha_maps().astype(np.float64).sum(axis=0))))

        return _BASE_WEIGHTS.get(alpha_key(self), weight)

    # ------------------------------------------------------------------------------------------ evaluation
    def eval(self, wo: np.ndarray, wi: np.ndarray) -> np.ndarray:
        return self.base_weight() * self.base.eval(wo, wi)

    def constant_dump(self) -> dict:
        """As the base class, with the base's own constant dump (its maps left out: per-material integrals — albedo
        curves, LTC fits — do not depend on the textures)."""
        return {**super().constant_dump(), "base": self.base.constant_dump()}

    @property
    def brdf_source(self) -> str:
        """The base's own twin (a library base's maps and hooks, glTF's material_surface) with its brdf_eval (and
        per-fragment split sum, if any) named base_* — what the scratches pass lights —, then the finite part:
        s_base_weight × the base's."""
        from ..gpu.programs import register_source

        base = self.base.brdf_source
        text = "\n".join([
            f"// Provides brdf_eval(wo, wi) of a scratched material over a {self.base.type} base (twin of "
            "reflets/scratches/material.py), and base_brdf_eval, the base itself.",
            "#define brdf_eval base_brdf_eval", "#define material_ibl base_material_ibl",
            "#define material_coat_ibl base_material_coat_ibl", f'#include "{base}"',
            "#undef brdf_eval", "#undef material_ibl", "#undef material_coat_ibl", f'#include "{self.glsl}"',
        ])  # fmt: skip
        return register_source(f"{self.glsl}#over-{base}", text)

    def lobe_nodes(self):
        """The base's mapped lobe at its nodes (``maps.Mapped.lobe_nodes``): the finite part's split sum weights the
        base's curves in its twin (scratched_finite.glsl)."""
        return self.base.lobe_nodes()

    def affine_zeros(self):
        """The finite part with its base's mapped affine colours at 0 (``maps.Mapped.affine_zeros``): curves weighted
        like the finite part's own, which the base's ``material_ibl_scale`` mixes with."""
        zeros = self.base.affine_zeros()
        return None if zeros is None else [self.model_copy(update={"base": zero}) for zero in zeros]

    def lambertian_split(self):
        """The finite part's Lambertian albedo (the base's × its share) and the rest: a method that integrates the
        Lambertian part exactly — the environment's irradiance — does so for the base's."""
        diffuse, rest = self.base.lambertian_split()
        weight = self.base_weight()
        return tuple(weight * d for d in diffuse), None if rest is None else self.model_copy(update={"base": rest})

    def lobe_summary(self):
        diffuse, kind, exponent = self.base.lobe_summary()
        return tuple(self.base_weight() * d for d in diffuse), kind, exponent

    def sample(self, wo, u1, u2):
        return self.base.sample(wo, u1, u2)

    def pdf(self, wo, wi):
        return self.base.pdf(wo, wi)

    # a textured base (a glTF material): its parameters at each point, as the GLSL twin's material_surface reads them
    @property
    def textured(self) -> bool:
        return self.base.textured

    @property
    def tabulated(self) -> bool:
        return self.base.tabulated

    def at(self, uv: np.ndarray, frames=None):
        """The finite part at mesh uv: the base there (its textures), weighted by its uncovered share."""
        if not self.base.textured:
            return self
        base, weight = self.base.at(uv, frames), self.base_weight()
        return PointsBRDF(lambda wo, wi: weight * base.eval(wo, wi), base)

    def shading_frame(self, frame: np.ndarray, uv: np.ndarray) -> np.ndarray:
        return self.base.shading_frame(frame, uv)

    def emitted(self, uv: np.ndarray) -> np.ndarray:
        return self.base.emitted(uv)

    def techniques(self, mesh) -> dict[str, str]:
        """The ``scratches`` pass under every light: the scratch lobes (thickened delta lights, midpoint samples of
        area lights, importance-sampled environment) over the base."""
        return dict.fromkeys(LIGHT_TYPES, "scratches")

    def lighting_warnings(self, light_types: set[str]) -> list[str]:
        """A profile without a flat part has no mirror peak: a point or directional light reflects off its walls
        only far from the mirror direction, and where the base is covered the highlight is missing."""
        from .profiles import parse_profile

        delta = sorted(light_types & {"point", "directional"})
        if not delta or parse_profile(self.profile).flat_fraction() > 1e-3:
            return []
        return [
            f"its scratch profile '{self.profile}' has no flat part, hence no mirror peak: {' / '.join(delta)} "
            "lights reflect off the scratch walls only, away from the mirror direction (the highlight may be "
            "missing or black); use a profile with a flat part (quartic) or an area / environment light"
        ]

    def uniforms(self) -> dict[str, object]:
        return {**self.base.uniforms(), "s_base_weight": self.base_weight()}

    def flags(self) -> dict[str, object]:
        return self.base.flags()

    def textures(self, ctx) -> dict[str, object]:
        return self.base.textures(ctx)


# ---------------------------------------------------------------------------------------------- caches
def _load_table(path: Path):
    from .table import load_table

    return load_table(path)


def _load_alpha(path: Path) -> np.ndarray:
    with np.load(path) as data:
        return data["alpha"]


TABLES = Cache("scratches", _load_table, lambda table, path: table.save(path))
ALPHAS = Cache("scratches", _load_alpha, lambda maps, path: np.savez_compressed(path, alpha=maps))


@functools.cache
def _code_hash(*modules: str) -> str:
    """Hash of the source files a cached result depends on (a changed tracer recomputes)."""
    here = Path(__file__).parent
    return source_hash(*(here / name for name in modules))


def table_key(profile: str, fresnel: dict, size: int, rays: int, backend: str) -> str:
    code = _code_hash("table.py", "tracer2d.py", "profiles.py", "gpu.py", "shaders/scratch_trace.comp")
    stamp = file_stamp(profile[5:]) if profile.startswith("file:") else None
    data = {"profile": profile, "stamp": stamp, "fresnel": fresnel, "size": size}
    return "table-" + content_key({**data, "rays": rays, "backend": backend, "code": code})


def cached_table(profile: str, fresnel: dict, size: int, rays: int, backend: str, ctx=None):
    """A scratch table from the memory cache, the disk cache, or :func:`build_table` (then stored in both)."""
    from .table import build_table

    key = table_key(profile, fresnel, size, rays, backend)
    names = ("table_size", "rays")  # the material's fields
    return TABLES.get(
        key, lambda: build_table(profile, **fresnel, size=size, rays=rays, backend=backend, ctx=ctx, names=names)
    )


#: base_weight by alpha_key
_BASE_WEIGHTS = Memo()


def alpha_key(material: Scratched) -> str:
    data = {
        "layers": material.layer_parameters,
        "seed": material.seed,
        "uv_scale": material.uv_scale,
        "size": material.alpha_size,
        "budget": SPLAT_BUDGET,
        "code": _code_hash("material.py"),
    }
    return "alpha-" + content_key(data)


#: bytes per layer texel of the α maps, baked or read and uploaded (float64 layers, their stack and float32 copy;
#: then the padded, transposed and mip-mapped texture array: measured 19.4–21.3 at 32 layers of 1024² and 2048²),
#: and the splatting's fixed working set
ALPHA_BYTES_PER_TEXEL = 24
ALPHA_FIXED_BYTES = 160_000_000


def check_alpha_size(material: Scratched) -> None:
    """Refuse an ``alpha_size`` whose K layers of R² texels (K · R² · ALPHA_BYTES_PER_TEXEL + ALPHA_FIXED_BYTES)
    exceed the available memory (reflets.resources), before baking or uploading them."""
    from ..resources import check

    k, r = material.layer_count, material.alpha_size

    def estimate(side: int) -> int:
        return k * side * side * ALPHA_BYTES_PER_TEXEL + ALPHA_FIXED_BYTES

    def fits(budget: int) -> int | None:
        side = r
        while side >= 16 and estimate(side) > budget:
            side //= 2
        return side if side >= 16 else None

    check("alpha_size", estimate(r), value=r, what=f"{k} layers of {r}² texels", fits=fits)


def cached_alpha(material: Scratched) -> np.ndarray:
    if material.coverage is not None:
        return np.full((material.layer_count, 1, 1), material.coverage, np.float32)
    key = alpha_key(material)
    if ALPHAS.peek(key) is None:  # before it is read or baked; not on every lookup of maps already in memory
        check_alpha_size(material)
    return ALPHAS.get(key, lambda: bake_alpha(material))


# ---------------------------------------------------------------------------------------------- α maps
def bake_alpha(material: Scratched) -> np.ndarray:
    """The α maps' base level (K, R, R) (rows along v, columns along u; algorithm in the module docstring)."""
    n, _, length, width, density = material.layer_parameters
    angles = material.layer_angles()
    return np.stack([bake_layer(k, angles[k], material) for k in range(n)]).astype(np.float32)


def bake_layer(k: int, angle: float, material: Scratched) -> np.ndarray:
    """α of one layer: Poisson scratches splatted along their axes, Boolean union per texel."""
    _, _, length, width, density = material.layer_parameters
    R, s = material.alpha_size, material.uv_scale
    rng = np.random.default_rng([material.seed, k + 1])
    half = density * length / s  # half-length of a scratch in uv
    samples = int(np.clip(np.ceil(4.0 * half * R), 1, 512))  # two per texel along the axis
    margin = half
    side = 1.0 + 2.0 * margin
    expected = (side * s) ** 2 / (length * width)  # unit density in noise space: 1/(l w) per unit x-area
    keep = min(1.0, SPLAT_BUDGET / (expected * samples))
    count = rng.poisson(expected * keep)
    t = -1.0 + (2.0 * np.arange(samples) + 1.0) / samples
    weights = np.sqrt(np.maximum(0.0, 1.0 - t * t))
    weights /= weights.sum()
    area = np.pi * density**2 * length * width / (s * s) / keep  # uv area of one (kept) scratch
    direction = np.array([np.cos(angle), np.sin(angle)])
    total = np.zeros(R * R)
    chunk = max(1, 2_000_000 // samples)
    for start in range(0, count, chunk):
        m = min(chunk, count - start)
        centres = rng.random((m, 2)) * side - margin
        pts = centres[:, None, :] + (half * t)[None, :, None] * direction  # (m, samples, 2)
        inside = np.all((pts >= 0.0) & (pts < 1.0), axis=-1)
        ij = np.minimum((pts * R).astype(np.int64), R - 1)
        index = ij[..., 1] * R + ij[..., 0]  # row = v, column = u
        w = np.broadcast_to(weights * area, (m, samples))
        total += np.bincount(index[inside], weights=w[inside], minlength=R * R)
    texel = 1.0 / (R * R)
    return (1.0 - np.exp(-total / texel)).reshape(R, R)


def mip_levels(base: np.ndarray) -> list[np.ndarray]:
    """2×2 means down to 1×1 (what the GPU's mip-maps hold for a power-of-two texture), over the last two axes."""
    levels = [np.asarray(base, np.float64)]
    while levels[-1].shape[-1] > 1:
        a = levels[-1]
        levels.append(0.25 * (a[..., 0::2, 0::2] + a[..., 1::2, 0::2] + a[..., 0::2, 1::2] + a[..., 1::2, 1::2]))
    return levels
