"""Prefiltered image-based lighting: the environment as a split-sum approximation instead of a grid of lights.

For a material lit by the environment map L, the reflected radiance is split (Karis 2013's split sum, as in
Filament and Unreal) into

- a diffuse part ρ_d / π · E(n), E the irradiance map: the map's exact cosine convolution, computed in NumPy on
  a downsampled copy of the map (``IRRADIANCE_SIZE`` normals × ``SOURCE_SIZE`` source texels, one matrix
  product) and looked up bilinearly;
- a specular part A(μ) · P(r, α): P the map prefiltered with GGX lobes of roughness α (``shaders/
  ibl_prefilter.comp``: ``PREFILTER_SAMPLES`` importance samples per texel with N = V = R, each read at the
  source mip matching its solid angle — filtered importance sampling), one mip level per roughness
  (level k: α = (k / (LEVELS − 1))²), read along the mirror direction r at the material's equivalent α; and
  A(μ) the **material's own** specular directional albedo — ∫ f cos θ_i dω_i minus its Lambertian albedo, by
  importance sampling of its NumPy ``eval`` / ``sample`` at ``ALBEDO_NODES`` values of μ = n·v — so that the
  split sum applies to every BRDF of the library, not only GGX (the lobe's shape enters through α only:
  ``Material.lobe_summary``'s Phong / Blinn-Phong exponent mapped to GGX α, see ``equivalent_alpha``).

The prefiltering runs on the GPU once per environment (a persistent renderer keeps it); the albedo curves once
per material. What the approximation costs is measured by ``reflets bench ibl`` against the reference.
"""

from __future__ import annotations

import functools
import math
import sys
from pathlib import Path

import moderngl
import numpy as np

from ..cache import Cache, content_key, file_stamp, source_hash
from ..equirect import equirect_direction, rotation_y, row_solid_angles
from ..gpu import GLObjects, ProgramSpec, get_program, set_uniforms

_SHADERS = "reflets/techniques/shaders/"
PREFILTER_PROGRAM = ProgramSpec("ibl_prefilter", compute=_SHADERS + "ibl_prefilter.comp")
#: prefiltered map: level 0 size and mip levels (level k holds α = (k / (LEVELS − 1))²)
PREFILTER_SIZE = (256, 128)
LEVELS = 7
PREFILTER_SAMPLES = 256
#: irradiance map (normals) and the downsampled source it integrates
IRRADIANCE_SIZE = (64, 32)
SOURCE_SIZE = (128, 64)
#: μ = n·v nodes of a material's specular albedo curve
ALBEDO_NODES = 32
ALBEDO_SAMPLES = 4096
#: texture units of the prefiltered and irradiance maps
IBL_UNITS = (18, 17)  # among the fixed units (forward.MATERIAL_UNITS go around them)
#: compile-time flags of the IBL code in lights.glsl
IBL_FLAGS = frozenset({"ENV_IBL", "IBL_LEVELS", "IBL_NODES"})


def _downsample(image: np.ndarray, size: tuple[int, int]) -> np.ndarray:
    """Box-filter an equirectangular map to (width, height) (exact when the sizes divide; else nearest blocks); a
    map smaller than that along an axis keeps its own size there (spread over more texels, a bright texel's
    power would land in one of them and leave the others empty)."""
    h, w, _ = image.shape
    size = (min(size[0], w), min(size[1], h))
    rows = np.minimum((np.arange(h) * size[1]) // h, size[1] - 1)
    cols = np.minimum((np.arange(w) * size[0]) // w, size[0] - 1)
    theta = (np.arange(h) + 0.5) / h * np.pi
    weight = np.sin(theta)[:, None] * np.ones((1, w))  # solid angle ∝ sin θ
    out = np.zeros((size[1], size[0], 3))
    norm = np.zeros((size[1], size[0], 1))
    np.add.at(out, (rows[:, None], cols[None, :]), image.astype(np.float64) * weight[..., None])
    np.add.at(norm, (rows[:, None], cols[None, :]), weight[..., None])
    return out / np.maximum(norm, 1e-30)


def irradiance_map(image: np.ndarray) -> np.ndarray:
    """E(n) = ∫ L(ω) max(0, n·ω) dω on an equirectangular grid of normals (the map's own frame), float32."""
    source = _downsample(image, SOURCE_SIZE)
    sh, sw = source.shape[:2]
    omega = row_solid_angles(sh, sw)
    u, v = (np.arange(sw) + 0.5) / sw, (np.arange(sh) + 0.5) / sh
    dirs = equirect_direction(u[None, :], v[:, None]).reshape(-1, 3)
    power = (source * omega[:, None, None]).reshape(-1, 3)
    w, h = IRRADIANCE_SIZE
    normals = equirect_direction(((np.arange(w) + 0.5) / w)[None, :], ((np.arange(h) + 0.5) / h)[:, None])
    cosines = np.maximum(normals.reshape(-1, 3) @ dirs.T, 0.0)
    return (cosines @ power).reshape(h, w, 3).astype(np.float32)


def equivalent_alpha(material) -> float:
    """The GGX roughness whose prefiltered lobe stands for the material's main specular lobe: a Blinn-Phong
    exponent e ↦ α = √(2 / (e + 2)) (Walter et al. 2007's correspondence), a Phong lobe about the mirror
    direction as the Blinn-Phong lobe of exponent 4e (the half-vector lobe is four times wider); no lobe: 1."""
    _, kind, exponent = material.lobe_summary()
    if kind == 0 or exponent <= 0:
        return 1.0
    e = 4.0 * exponent if kind == 1 else exponent
    return float(min(1.0, math.sqrt(2.0 / (e + 2.0))))


def specular_albedo(material, nodes: int = ALBEDO_NODES, samples: int = ALBEDO_SAMPLES) -> np.ndarray:
    """(nodes, 3): ∫ f(ω_o, ω_i) cos θ_i dω_i at μ = cos θ_o = (k + ½) / nodes, minus the Lambertian albedo,
    by stratified importance sampling of the material's own ``sample`` (deterministic)."""
    diffuse = np.asarray(material.lambertian_split()[0], np.float64)
    side = int(math.isqrt(samples))
    t = (np.arange(side) + 0.5) / side
    u1, u2 = (a.ravel() for a in np.meshgrid(t, t, indexing="ij"))
    out = np.zeros((nodes, 3))
    for k in range(nodes):
        mu = (k + 0.5) / nodes
        wo = np.broadcast_to(np.array([math.sqrt(max(0.0, 1.0 - mu * mu)), 0.0, mu]), (len(u1), 3))
        wi, pdf = material.sample(np.ascontiguousarray(wo), u1, u2)
        ok = (pdf > 0) & (wi[..., 2] > 0)
        f = material.eval(np.ascontiguousarray(wo[ok]), wi[ok])
        out[k] = np.sum(f * (wi[ok, 2] / pdf[ok])[:, None], axis=0) / len(u1)
    return np.maximum(out - diffuse, 0.0)


ALBEDOS = Cache("ibl", lambda path: np.load(path)["albedo"], lambda albedo, path: np.savez(path, albedo=albedo))


def cached_specular_albedo(material) -> np.ndarray:
    """``specular_albedo`` of a material through the cache (memory, then disk): a persistent renderer prepares
    again on every edit, and a curve costs 15–120 ms of NumPy per material. Keyed by the material, the sample
    counts and the source of its model, of the BRDF base and of this module (a measured table: its file stamp)."""
    module = sys.modules[type(material).__module__].__file__
    data = {
        "material": material.constant_dump(),
        "nodes": ALBEDO_NODES,
        "samples": ALBEDO_SAMPLES,
        "code": _source_hash(module),
    }
    if getattr(material, "type", None) == "measured":
        data["file_stat"] = file_stamp(material.file)
    return ALBEDOS.get("albedo-" + content_key(data), lambda: specular_albedo(material))


@functools.cache
def _source_hash(module: str) -> str:
    from ..brdf import base

    return source_hash(Path(module), Path(base.__file__), Path(__file__))


class PrefilteredEnvironment:
    """The prefiltered radiance and irradiance maps of one environment on one context (module docstring)."""

    def __init__(self, source, image: np.ndarray, light):
        """``source``: the map's texture (the prepared scene's; its mips are built here, its own filter is left
        as it is), ``image`` the same map in memory."""
        ctx = self.ctx = source.ctx
        self._gl = GLObjects(ctx)
        self._own = self._gl.own
        self.env_from_world = rotation_y(light.rotate_y).astype(np.float32).tobytes()  # R^T, column-major
        source.build_mipmaps()
        # the prefiltering reads the source's mips through a sampler of its own (the background and the scratch
        # lobes keep reading level 0 through the texture's filter)
        mips = self._own(ctx.sampler(filter=(moderngl.LINEAR_MIPMAP_LINEAR, moderngl.LINEAR)))
        mips.repeat_x, mips.repeat_y = True, False
        w, h = PREFILTER_SIZE
        self.radiance = self._own(ctx.texture((w, h), 4, dtype="f4"))
        self.radiance.build_mipmaps(0, LEVELS - 1)  # allocates levels 0 … LEVELS − 1
        self.radiance.repeat_x, self.radiance.repeat_y = True, False
        program = get_program(ctx, PREFILTER_PROGRAM)
        source.use(0)
        mips.use(0)
        texel_omega = 4.0 * math.pi / (image.shape[0] * image.shape[1])
        for level in range(LEVELS):
            lw, lh = max(1, w >> level), max(1, h >> level)
            self.radiance.bind_to_image(0, read=False, write=True, level=level)
            alpha = (level / (LEVELS - 1)) ** 2
            set_uniforms(
                program,
                {
                    "u_source": 0,
                    "u_alpha": float(alpha),
                    "u_samples": PREFILTER_SAMPLES,
                    "u_size": (lw, lh),
                    "u_source_texel_omega": float(texel_omega),
                    "u_copy_lod": float(max(0.0, math.log2(image.shape[1] / lw))),
                },
            )
            program.run(group_x=-(-lw // 8), group_y=-(-lh // 8))
        ctx.memory_barrier()
        mips.clear(0)
        self.radiance.filter = (moderngl.LINEAR_MIPMAP_LINEAR, moderngl.LINEAR)
        irradiance = irradiance_map(image)
        self.irradiance = self._own(ctx.texture(IRRADIANCE_SIZE, 3, irradiance.tobytes(), dtype="f4"))
        self.irradiance.repeat_x, self.irradiance.repeat_y = True, False
        self.irradiance.filter = (moderngl.LINEAR, moderngl.LINEAR)

    def flags(self) -> dict[str, int]:
        return {"ENV_IBL": 1, "IBL_LEVELS": LEVELS, "IBL_NODES": ALBEDO_NODES}

    def uniforms(self, material) -> dict[str, object]:
        """The material's split-sum inputs (its albedo curve from the cache: computed once per material; none for a
        material that gives them per fragment)."""
        maps = {
            "u_ibl_env_from_world": self.env_from_world,
            "u_ibl_radiance": IBL_UNITS[0],
            "u_ibl_irradiance": IBL_UNITS[1],
        }
        if material.fragment_ibl:
            return maps
        untinted = material.ibl_interface
        lobes = material.lobe_nodes()
        if lobes is not None:  # a mapped lobe shape: the curves at maps.lobe_node_texels (its MATERIAL_IBL reads them)
            curves = np.concatenate([cached_specular_albedo(m) for m in lobes])
            if material.affine_zeros() is not None:  # and a mapped affine colour: each node's curve at its 0 too
                zeros = np.concatenate([cached_specular_albedo(m.affine_zeros()[0]) for m in lobes])
                maps["u_map_ibl_zero_nodes"] = zeros.astype(np.float32).tobytes()
            return {"u_map_ibl_albedo": curves.astype(np.float32).tobytes(),
                    "u_map_ibl_alpha": np.array([equivalent_alpha(m) for m in lobes], np.float32).tobytes(), **maps}
        zeros = material.affine_zeros()
        for j, zero in enumerate(zeros or ()):  # mapped affine colours: the curves at 0 (maps.Mapped._affine_ibl)
            maps[f"u_map_ibl_zero{j}"] = cached_specular_albedo(zero).astype(np.float32).tobytes()
        return {
            "u_ibl_albedo": cached_specular_albedo(material).astype(np.float32).tobytes(),
            "u_ibl_diffuse": tuple(float(c) for c in material.lambertian_split()[0]),
            "u_ibl_alpha": equivalent_alpha(material),
            "u_ibl_untinted": (np.zeros((ALBEDO_NODES, 3)) if untinted is None
                               else cached_specular_albedo(untinted)).astype(np.float32).tobytes(),
            **maps,
        }

    def bind(self) -> None:
        self.radiance.use(IBL_UNITS[0])
        self.irradiance.use(IBL_UNITS[1])

    def release(self) -> None:
        self._gl.release()
