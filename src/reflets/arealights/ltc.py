"""``ltc``: Linearly Transformed Cosines (Heitz, Dupuy, Hill & Neubelt, SIGGRAPH 2016) for polygon lights.

For a view angle θ and roughness the material's lobe f·cos is approximated by ``A · D_M``: A = ∫ f cos dω (the
directional albedo) and D_M the clamped cosine transformed by a 3×3 matrix M; the polygon integral of D_M
is Lambert's formula (after clipping to z ≥ 0) on the polygon transformed by M⁻¹. M⁻¹ and A come from a table
(``ltc_fit.py``: the fitter, the file format and the lookup parameterisation). Per draw, the table is chosen
from the material:

- microfacet GGX / Beckmann, ``fresnel = "none"``, separable masking: the shipped family table
  (``data/ltc/ggx.npz``, ``beckmann.npz``) at α — for an anisotropic α the geometric mean sqrt(α_x α_y), an
  isotropic approximation of the lobe (its width is right on average, its elongation is lost) — times
  ``specular``;
- normalised Phong / Blinn-Phong: the shipped table at the equivalent α = sqrt(2/(e + 2)), times ``ks``
  (the table spans e ∈ [0, 10⁶], the whole parameter range);
- Ward ``variant = "duer"``: the shipped table at sqrt(α_x α_y), times ``ks``;
- a material that gives its parameters per fragment (``Material.fragment_ltc``: glTF's, textured or not, save a
  constant sheen): the GGX table read at each fragment's roughness — α after the normal map's Toksvig widening and
  the specular anti-aliasing —, its magnitude the exact directional albedo of the material's height-correlated,
  Schlick lobe (F₀ A + B of the split-sum table, per fragment: base colour, metallic, specular), the Lambertian
  part its Fresnel-weighted diffuse albedo averaged over the hemisphere at the view (as the split sum has it), a
  sheen as a Lambertian lobe of its albedo, and a clear coat as a second GGX lobe about its own normal, c F_c(v) over
  1 − c F_c(v) of the base: one more polygon integral. The table's shape is the separable-Smith GGX fit; an
  anisotropic lobe is read as the isotropic one of the same area (``auto`` lights it by ``forward``);
- every other material (Fresnel modes, correlated masking, un-normalised Phong / Blinn-Phong, original Ward,
  Lafortune, Ashikhmin–Shirley, measured): a one-material table over θ only, fitted at ``prepare`` with the
  exact material (~1 s), cached in memory and in ``$XDG_CACHE_HOME/reflets/ltc`` (default ``~/.cache``) under
  a hash of the material's parameters (and, for a measured file, its size and modification time).

**Base distribution** (``base``). Heitz et al. transform the clamped cosine z/π. Seen through M it falls off
as a power law (∝ ψ⁻⁴ at an angle ψ from its axis), while Phong's cos^e ψ ≈ exp(−e ψ²/2), Beckmann's and
Ward's lobes fall off like Gaussians: the best clamped-cosine fit of such a lobe misplaces 18 % of it (L1
0.359), which leaves a highlight's plateau ~10 % too dark and spreads its tail over the dark plane around it.
``base = "power"`` (default) transforms the mixture (1 − β) z/π + β (n + 1)/(2π) zⁿ, n = 31, β fitted per
table cell with M (stored in the magnitude texture's alpha): cosⁿ seen through M is nearly Gaussian. Its
polygon integral stays closed-form — Arvo's (1995) recurrence of axial moments adds (n − 1)/2 = 15 steps per
edge —, and where the whole transformed polygon lies outside the cone that holds all but 10⁻⁴ of the cosⁿ lobe
(z < 10^(−4/32) = 0.75) the cosⁿ part is cut to 0 instead of fading as a power law. The family tables
``phong_power.npz``, ``blinn_phong_power.npz``, ``beckmann_power.npz`` and ``ward_power.npz`` hold the
mixture; GGX has none (its fitted β stays below 1 %: the clamped cosine is its shape) and reads ``ggx.npz``;
one-material tables fit the mixture and keep the clamped-cosine fit when no cell uses it. ``base = "cosine"``
is Heitz et al.'s LTC, the tables of before; ``horizon = "sphere"`` always takes it (its closed form is the
clamped cosine's).

Measured (issue 18) on the area-light document's scene of ``reflets bench arealights`` (light at height 1,
200×150), by ``python tools/bench_arealights_part.py OUT`` — the ``ltc``, ``ltc base=cosine`` and brute 8² rows
of the suite, same reference and metrics; max error = the largest |error| on the plane as a fraction of the
peak, against brute 64² (converged; the 256-spp reference's own noise reaches 4 % of the peak); FLIP and
relative MSE against the reference. Each cell: max error / FLIP / relative MSE.

| material | base = "power" (default) | base = "cosine" (Heitz et al.) | brute 8² |
|---|---|---|---|
| Phong e = 150, un-normalised | 0.51 % / 0.064 / 3.7e-5 | 11.35 % / 0.442 / 5.2e-4 | 1.90 % / 0.040 / 5.2e-5 |
| Phong e = 200, un-normalised | 0.61 % / 0.054 / 2.2e-5 | 10.72 % / 0.459 / 3.5e-4 | 2.58 % / 0.039 / 3.8e-5 |
| Phong e = 500, un-normalised | 0.70 % / 0.029 / 3.6e-6 | 9.89 % / 0.422 / 6.4e-5 | 8.96 % / 0.030 / 2.2e-5 |
| Beckmann α = 0.1 | 0.73 % / 0.088 / 1.3e-3 | 13.84 % / 0.438 / 8.7e-2 | 1.07 % / 0.045 / 1.1e-3 |
| Phong normalised, α = 0.1 (e = 198) | 0.57 % / 0.072 / 9.4e-4 | 10.63 % / 0.458 / 5.2e-2 | 2.63 % / 0.046 / 1.3e-3 |
| Blinn-Phong normalised, α = 0.1 | 0.62 % / 0.086 / 7.3e-4 | 13.40 % / 0.440 / 2.4e-2 | 1.12 % / 0.044 / 7.1e-4 |
| Ward (duer) α = 0.1 | 0.74 % / 0.088 / 1.3e-3 | 13.82 % / 0.439 / 8.4e-2 | 1.08 % / 0.045 / 1.1e-3 |
| the four at α = 0.3 | 0.17–1.63 % / 0.21–0.26 / 5e-4–2e-3 | 8.0–11.9 % / 0.33–0.38 / 0.01–0.05 | ≤ 0.53 % / ≤ 0.042 |
| GGX α = 0.1 / 0.3 / 0.6 | the same table in both bases: 0.76 / 3.77 / 2.50 % | | |

Where the clamped cosine's error came from (same scene, Phong e = 150): not the table's θ sampling — the
one-material table fitted with 128 view angles instead of 32 has the same per-cell L1 error (median 0.354,
``reflets fit-ltc --brdf phong --param exponent=150 --param normalized=false --param "kd=[0,0,0]" --size 128``)
and renders the same image —, not the optimiser — 0.354 (0.359 at e = 500) is the clamped cosine's floor on a
Gaussian —, but the shape: the largest error is the highlight's plateau coming out too dark, the plane just
outside its rim comes out too bright, and the power-law tail lights the plane where the exact image is 0.
That tail is most of the FLIP: HDR-FLIP's exposure range runs up to the image's median, which is 0 here, so
light where there should be none is seen. The mixture fit reaches a median L1 of 0.022 (0.027 at e = 500; the
same command with ``--param base_power=31``) and the support cut-off removes the tail. At mid roughness
(α ≈ 0.3) the families gain less FLIP: a mixture of the powers 1 and 31 has no intermediate shape, and the
few per cent of clamped cosine left in those cells' fits still glow over the dark plane. Cost: (n − 1)/2 = 15
more recurrence steps per polygon edge. On llvmpipe the mixture shader ran no slower than the clamped-cosine
one in every interleaved measurement (Phong e = 500 at 800×600 in the committed run: 50.9 ms against 74.5 ms,
benchmarks/results/arealights.md; the host was shared, so compare within the run only).

Per fragment, against the NumPy reference with shadows (4 × 4-pixel block means, relative MSE): two textured
spheres (checker base colour, roughness 0.15 / 0.7 and metallic 0 / 1 in stripes, one clear-coated) under two quad
lights 4.4 × 10⁻⁴ (``forward``'s 8 × 8 midpoint rule 3.7 × 10⁻⁴; tests/arealights/test_ltc_textured.py); the
gallery's DamagedHelmet (320 × 240, 16 spp) 0.34 % per pixel, 0.10 % on blocks (forward 1.64 % / 0.25 %) in 0.6×
forward's frame time (``python tools/ltc_gltf_spheres.py --helmet``). Constant glTF spheres under two quad lights
(``python tools/ltc_gltf_spheres.py``), per fragment / the one-material table / ``forward``: dielectric roughness
0.2: 0.02 / 0.39 / 0.02 %; 0.5: 0.03 / 0.08 / 0.02 %; metal roughness 0.02: 0.04 / 0.03 / 0.13 %; 0.3: 0.04 / 0.04 /
0.02 %; clear coat over roughness 0.6: 0.04 / 0.60 / 0.03 %; sheen 0.73 / 0.06 / 0.02 % (hence the constant
sheen's exception).

A Lambertian term (``kd`` / ``diffuse`` / ``albedo``) is split off and integrated exactly (identity matrix);
the table fits the rest of the BRDF. Ashikhmin–Shirley's coupled diffuse term and measured data are not
Lambertian and stay in the fitted lobe (one LTC for the whole BRDF). A coloured lobe (conductor Fresnel,
measured) shares one shape (fitted to its luminance) with a magnitude per RGB channel.

One- and two-sided lights: a one-sided light seen from behind contributes nothing; the absolute value of the
edge sum makes a two-sided light right from either side. The unoccluded integral (as every area-light method;
shadows: the soft-shadow ratio, docs/techniques/shadows.md); compare unoccluded scenes with
``reflets.reference(..., visibility=False)``.

Accuracy with ``base = "cosine"`` (benchmark scene of tests/arealights/test_ltc.py, relative MSE against the
unoccluded reference; more in data/ltc/README.md): GGX α = 0.1 / 0.3 / 0.6: 0.02 / 0.11 / 0.04 %; normalised
Phong e = 150: 0.9 %; Beckmann, Blinn-Phong, Ward, Lafortune at similar widths 1.2–1.3 % (their Gaussian-like
lobes come out ~5 % too dark: the LTC's tails are heavier — what the mixture base fixes); Ashikhmin–Shirley
2.8 %; anisotropic GGX (0.1, 0.4): 23 % — the isotropic approximation fails for strongly anisotropic lobes.

Cost (shader ltc.glsl): per fragment two bilinear fetches and a 3×3 transform; per light and polygon vertex
a transform and a normalisation; per edge one clipped edge term (with a mixture table, plus 15 recurrence
steps and the edge's highest point for the support test) — horizon clipping is done edge by edge
without building the clipped polygon (no local arrays, no data-dependent branches: a software rasteriser
runs both sides of every branch), and the edge term θ/sinθ comes from a rational fit instead of acos/atan.
The light records (the light buffer's layout, ``polygon_record``) are also uploaded as a uniform array for
up to ``UNIFORM_LIGHTS`` polygon lights: on llvmpipe uniform loads are broadcasts while buffer loads gather
per pixel (−6 % frame time with one light, −19 % with eight); more lights read the buffer. When every polygon
light of the scene has the same vertex count (quads), the edge loops get it as a constant and unroll (−10 %).
Benchmark scene at 800×600 on llvmpipe (2 cores), one quad light, GGX α = 0.3 (``reflets bench ltc-cost``,
interleaved rounds): 4.7 ms per two-thread frame against 3.5 ms for ``forward`` with one point light (1.36×);
where the time goes is in that report (``profile`` parameter: the shader with one stage dropped).
``horizon = "sphere"`` trades exact clipping for production engines' clipped-sphere approximation (faster,
exact where the transformed polygon stays above the horizon; accuracy in the same report, with the
clamped-cosine tables it takes).
"""

from __future__ import annotations

import functools
import math
from dataclasses import dataclass
from importlib import resources
from pathlib import Path
from typing import ClassVar, Literal

import moderngl
import numpy as np
from pydantic import Field

from ..cache import Cache, content_key, file_stamp, source_hash
from ..gpu import ProgramSpec
from ..techniques.base import register_technique
from . import ltc_fit
from .base import AREA_PROGRAM, POLY_STRIDE, SHADERS, AreaLightParams, AreaLightTechnique
from .ltc_fit import FAMILIES, LtcTable

LTC_FLAGS = {
    "LTC_SIZE_THETA",
    "LTC_SIZE_ROUGH",
    "LTC_EDGE_P",
    "LTC_EDGE_Q",
    "LTC_DIFFUSE",
    "LTC_LOBE",
    "LTC_POWER",
    "LTC_CUT",
    "LTC_FRAGMENT",
    "LTC_SQRT_ALPHA_MIN",
}
LTC_PROGRAM = ProgramSpec(
    "arealight_ltc",
    vertex=AREA_PROGRAM.vertex,
    fragment=AREA_PROGRAM.fragment,
    flags=AREA_PROGRAM.flags | LTC_FLAGS | {"LTC_UNIFORM_LIGHTS", "LTC_VERTICES", "LTC_PROFILE", "LTC_HORIZON"},
)
#: θ entries of the one-material tables fitted at prepare time
INSTANCE_SIZE = 32
#: the cosine power of the mixture base (base = "power") for the one-material tables
INSTANCE_BASE_POWER = 31
#: the lobe's base distribution: "power" (the clamped cosine mixed with cosⁿ per cell, the default) or
#: "cosine" (the clamped cosine alone, Heitz et al.'s LTC)
BASES = ("power", "cosine")
#: scenes with up to this many polygon lights also get their records as a uniform array (faster to read on
#: llvmpipe than the light buffer); more lights read the buffer
UNIFORM_LIGHTS = 16


def shipped_table(family: str, base: str = "cosine") -> LtcTable:
    """The table shipped for a family: ``reflets/data/ltc/<family>.npz`` (the clamped cosine), or with base
    "power" ``<family>_power.npz`` where the mixture fits the family better (else the clamped-cosine one)."""
    power = f"{family}_power.npz"
    if base == "power" and resources.files("reflets").joinpath("data", "ltc", power).is_file():
        return _shipped_file(power)
    return _shipped_file(f"{family}.npz")


@functools.cache
def _shipped_file(name: str) -> LtcTable:
    with resources.files("reflets").joinpath("data", "ltc", name).open("rb") as fh:
        return LtcTable.load(fh)


@dataclass(frozen=True)
class LtcChoice:
    """How the ltc method shades one material: the table, the roughness coordinate in it, the RGB factor on
    its magnitude, the Lambertian albedo, and where the table came from ("ggx", …, or "material")."""

    table: LtcTable | None
    roughness: float
    scale: tuple[float, float, float]
    diffuse: tuple[float, float, float]
    source: str


def _family_of(lobe) -> str | None:
    t = lobe.type
    if t == "microfacet" and lobe.fresnel == "none" and lobe.masking == "separable":
        return lobe.distribution
    if t in ("phong", "blinn_phong") and lobe.normalized:
        return t
    if t == "ward" and lobe.variant == "duer":
        return "ward"
    return None


def choose_table(material, base: str = "power") -> LtcChoice:
    """The table, roughness coordinate and factors for a material (rules in the module docstring)."""
    if material.fragment_ltc:  # parameters per fragment (textures): the GGX table at each fragment's roughness
        return LtcChoice(shipped_table("ggx", "cosine"), 0.0, (1.0, 1.0, 1.0), (1.0, 1.0, 1.0), "fragment")
    diffuse, lobe = material.lambertian_split()  # the Lambertian part is integrated exactly
    if lobe is None:
        return LtcChoice(None, 0.0, (0.0, 0.0, 0.0), diffuse, "none")
    family = _family_of(lobe)
    if family is not None:
        spec = FAMILIES[family]
        scale = lobe.specular if lobe.type == "microfacet" else lobe.ks
        table = shipped_table(family, base)
        r = float(ltc_fit.roughness_coordinate(spec.alpha(lobe), table.meta["alpha_min"]))
        return LtcChoice(table, r, tuple(float(c) for c in scale), diffuse, family)
    base_power = INSTANCE_BASE_POWER if base == "power" else 1
    return LtcChoice(fitted_table(lobe, base_power=base_power), 0.0, (1.0, 1.0, 1.0), diffuse, "material")


# ------------------------------------------------------------------------------ one-material tables


TABLES = Cache("ltc", LtcTable.load, lambda table, path: table.save(path))


@functools.cache
def _fitter_hash() -> str:
    return source_hash(Path(ltc_fit.__file__))


def material_key(material, n_theta: int = INSTANCE_SIZE, base_power: int = 1) -> str:
    """Hash of everything a one-material table depends on (the fitter's source included: a changed fitter
    refits)."""
    data = {
        "material": material.constant_dump(),
        "fitter": _fitter_hash(),
        "n_theta": n_theta,
        "settings": ltc_fit.FitSettings(base_power=base_power).__dict__,
    }
    if material.type == "measured":
        data["file_stat"] = file_stamp(material.file)
    return content_key(data)


def fitted_table(material, n_theta: int = INSTANCE_SIZE, base_power: int = 1) -> LtcTable:
    """The one-material table of ``material`` (memory cache, then disk cache, then a fit)."""
    settings = ltc_fit.FitSettings(base_power=base_power)
    return TABLES.get(
        material_key(material, n_theta, base_power), lambda: ltc_fit.fit_material(material, n_theta, settings)
    )


# ------------------------------------------------------------------------------ the technique


#: LTC_PROFILE values of ltc.glsl, in order
PROFILE_STAGES = ("full", "no_clip", "no_fetch", "no_edges", "frame_only")
#: LTC_HORIZON values of ltc.glsl, in order
HORIZONS = ("exact", "sphere")


class LtcParams(AreaLightParams):
    """Parameters of ``ltc``."""

    base: Literal[BASES] = Field(
        "power",
        description="the lobe's base distribution: power (the clamped cosine mixed with cos^n per table cell: "
        "sharp highlights without the clamped cosine's heavy tails) or cosine (the clamped cosine alone, as in "
        "Heitz et al. 2016); horizon = sphere always uses cosine",
    )
    horizon: Literal[HORIZONS] = Field(
        "exact",
        description="horizon clipping: exact (edge by edge) or sphere (the cap with the polygon's vector form "
        "factor, clipped in closed form: what production engines do; exact where nothing is clipped)",
    )
    profile: Literal[PROFILE_STAGES] = Field(
        "full",
        description="cost breakdown only (wrong images): drop a stage of the shader to time it — no_clip "
        "(no horizon clipping), no_fetch (no table fetches), no_edges (no polygon integral), frame_only",
    )


@register_technique
class Ltc(AreaLightTechnique):
    """Polygon lights by Linearly Transformed Cosines, fitted tables per BRDF (see the module docstring)."""

    name: ClassVar[str] = "ltc"
    summary: ClassVar[str] = "area lights: linearly transformed cosines (fitted tables for every BRDF)"
    area_glsl: ClassVar[str] = SHADERS + "ltc.glsl"
    program_spec: ClassVar[ProgramSpec] = LTC_PROGRAM

    Params: ClassVar = LtcParams

    def _choice(self, material) -> LtcChoice:
        cache = self.__dict__.setdefault("_choices", {})
        key = material.model_dump_json()
        if key not in cache:
            # the sphere horizon's closed form holds for the clamped cosine only
            cache[key] = choose_table(material, "cosine" if self.params.horizon == "sphere" else self.params.base)
        return cache[key]

    def flags(self, material) -> dict[str, object]:
        choice = self._choice(material)
        size = choice.table.size if choice.table is not None else (1, 1)
        rows = self._polygon_rows
        counts = {int(rows[i + 1][3]) for i in range(0, len(rows), POLY_STRIDE)}  # record row 1: vertex count
        defines = ltc_fit.glsl_defines(
            size,
            diffuse=max(choice.diffuse) > 0.0,
            lobe=choice.table is not None,
            uniform_lights=len(rows) // POLY_STRIDE if self._lights_in_uniforms() else 0,
            vertices=counts.pop() if len(counts) == 1 else 0,
            base_power=choice.table.base_power if choice.table is not None else 1,
        )
        profile = PROFILE_STAGES.index(self.params.profile)
        horizon = HORIZONS.index(self.params.horizon)
        fragment = {
            "LTC_FRAGMENT": int(choice.source == "fragment"),
            "LTC_SQRT_ALPHA_MIN": f"{math.sqrt(choice.table.meta['alpha_min']) if choice.table else 0.0:.8g}",
        }
        return {**super().flags(material), **defines, **fragment, "LTC_PROFILE": profile, "LTC_HORIZON": horizon}

    def polygon_rows(self, scene) -> list[tuple]:
        """The light buffer's rows, kept: the uniform copy and the vertex-count flag are made from them."""
        self._polygon_rows = super().polygon_rows(scene)
        return self._polygon_rows

    def _lights_in_uniforms(self) -> bool:
        return 0 < len(self._polygon_rows) <= UNIFORM_LIGHTS * POLY_STRIDE

    def material_uniforms(self, material) -> dict[str, object]:
        choice = self._choice(material)
        lights = (
            {"a_ltc_lights": np.asarray(self._polygon_rows, np.float32).tobytes()} if self._lights_in_uniforms() else {}
        )
        return {
            **super().material_uniforms(material),
            "a_ltc_roughness": choice.roughness,
            "a_ltc_scale": choice.scale,
            "a_ltc_diffuse": choice.diffuse,
            **lights,
        }

    def release(self) -> None:
        self._table_textures = {}  # the textures go with the other GPU objects
        super().release()

    def material_textures(self, material) -> dict[str, object]:
        table = self._choice(material).table
        if table is None:
            return {}
        uploaded = self.__dict__.setdefault("_table_textures", {})  # one upload per table, shared by meshes
        key = id(table)
        if key in uploaded:
            return uploaded[key]
        textures = {}
        size = table.size
        magnitude = np.concatenate([table.magnitude, table.power_weight[..., None]], axis=-1)  # alpha: β
        for name, data in (("a_ltc_minv", table.minv), ("a_ltc_magnitude", magnitude)):  # RGBA: faster than RGB
            data = np.ascontiguousarray(data, dtype=np.float32)
            tex = self.ctx.texture(size, data.shape[-1], data.tobytes(), dtype="f4")
            tex.filter = (moderngl.LINEAR, moderngl.LINEAR)
            tex.repeat_x = tex.repeat_y = False
            self._objects.append(tex)
            textures[name] = tex
        uploaded[key] = textures
        return textures
