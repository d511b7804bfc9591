"""``scratches``: the layered scratched SV-BRDF of chapter 3 rendered progressively on the forward pass.

Meshes of other materials are shaded by the forward pass; a ``scratched`` mesh gets ``shaders/scratches.frag``
(NumPy twin: :mod:`reflets.scratches.shading`, the formulas are there):

- α of every layer from a mip-mapped texture array (4 layers per RGBA texel), sampled with the pixel footprint
  (trilinear, anisotropic where the driver offers it) — or a constant with the material's ``coverage``;
- the base BRDF weighted by max(0, 1 − ᾱ), lit as by the forward pass (its environment grid included);
- the environment: ``samples`` importance samples per pixel and frame on the reflection half-cones, layers
  chosen ∝ α_k (stratified), φ_in drawn by exact inversion of the table's per-row CDF (a binary search of
  log₂ M texel fetches: the GPU draws exactly the twin's density, not an interpolated inverse CDF);
- point and directional lights "thickened" to f_H(h) = (1 − (h/H)²)² of angular radius H = ``thickness``
  degrees, normalised by 3 / (π H² cos θ_ℓ) so the result converges to the δ-light answer as H → 0, with the
  document's culling (|θ_ℓ + θ_o| ≥ H) and ``light_samples`` stratified samples per live layer.

Frames: ``render(spp=…)`` accumulates spp / samples frames (spp a multiple of ``samples``), frame k seeded by
(pixel, k, seed). Compile-time flags keep what a scene lacks out of the program (llvmpipe runs both sides of
uniform branches): the layer count, table size, sample counts, light counts, the environment and constant α.
"""

from __future__ import annotations

import math
from typing import ClassVar, Literal

import moderngl
import numpy as np
from pydantic import Field

from ..equirect import rotation_y
from ..errors import ArgumentError
from ..gpu import ProgramSpec
from ..scene.environment import load_environment
from ..techniques.base import register_technique
from ..techniques.forward import LIGHT_FLAGS, Forward, ForwardParams
from .material import Scratched

_SHADERS = "reflets/scratches/shaders/"
SCRATCH_FLAGS = frozenset(
    {"S_LAYERS", "S_TABLE", "S_LOG2", "S_ENV_SAMPLES", "S_LIGHT_SAMPLES", "S_CONSTANT_ALPHA", "OUTPUT"}
)
SCRATCHES_PROGRAM = ProgramSpec(
    "scratches",
    vertex="reflets/techniques/shaders/mesh.vert",
    fragment=_SHADERS + "scratches.frag",
    flags=SCRATCH_FLAGS | LIGHT_FLAGS,
)
#: anisotropic filtering of the α maps (grazing views of a plate keep their detail along the view)
ANISOTROPY = 16.0


class ScratchesParams(ForwardParams):
    """Parameters of ``scratches``."""

    samples: int = Field(8, ge=0, le=256, description="environment samples per pixel and frame (split ∝ α_k)")
    light_samples: int = Field(4, ge=1, le=64, description="samples per thickened light and live layer per frame")
    thickness: float = Field(2.0, gt=0, le=10, description="H: angular radius of thickened lights, degrees")
    table_backend: Literal["auto", "numpy", "gpu"] = Field(
        "auto", description="scratch-table tracer (auto: the GPU compute shader, faster here)"
    )


@register_technique
class Scratches(Forward):
    """Scratched materials: the layered SV-BRDF, environment IS + thickened lights, progressive (docstring)."""

    name: ClassVar[str] = "scratches"
    progressive: ClassVar[bool] = True
    summary: ClassVar[str] = "scratched / brushed materials: layered SV-BRDF, cone importance sampling, progressive"
    Params: ClassVar = ScratchesParams
    auto_order: ClassVar[int] = 1

    def prepare(self, scene) -> None:
        self._gpu = {}
        self._env_image = load_environment(scene)
        super().prepare(scene)

    def program_for(self, material) -> ProgramSpec:
        return SCRATCHES_PROGRAM if isinstance(material, Scratched) else self.program_spec

    def table_of(self, material: Scratched):
        """The material's scratch table as this technique computes it (backend per ``table_backend``)."""
        backend = self.params.table_backend
        if backend == "auto":
            return material.table(self.ctx)
        return material.table(self.ctx if backend == "gpu" else None, backend=backend)

    def flags(self, material) -> dict[str, object]:
        base = super().flags(material)
        if not isinstance(material, Scratched):
            return base
        table = self.table_of(material)
        env = self._env_image is not None
        return {
            **base,
            "S_LAYERS": material.layer_count,
            "S_TABLE": table.size,
            "S_LOG2": max(1, math.ceil(math.log2(table.size))),
            "S_ENV_SAMPLES": self.params.samples if env else 0,
            "S_LIGHT_SAMPLES": self.params.light_samples,
            "S_CONSTANT_ALPHA": int(material.coverage is not None),
        }

    def material_uniforms(self, material) -> dict[str, object]:
        if not isinstance(material, Scratched):
            return {}
        angles = material.layer_angles()
        rot = rotation_y(self.scene.environment.rotate_y) if self.scene.environment is not None else np.eye(3)
        return {
            "s_dir": np.stack([np.cos(angles), np.sin(angles)], axis=1).astype(np.float32).tobytes(),
            "s_thickness": math.radians(self.params.thickness),
            "s_coverage": float(material.coverage or 0.0),
            "s_env_from_world": rot.astype(np.float32).tobytes(),  # R^T: column-major bytes of row-major R
        }

    def material_textures(self, material) -> dict[str, object]:
        if not isinstance(material, Scratched):
            return {}
        key = material.model_dump_json()
        if key not in self._gpu:
            self._gpu[key] = self._upload(material)
        return self._gpu[key]

    def _texture(self, data: np.ndarray, nearest: bool = True):
        data = np.ascontiguousarray(data, dtype=np.float32)
        h, w = data.shape[:2]
        tex = self.ctx.texture((w, h), 1 if data.ndim == 2 else data.shape[2], data.tobytes(), dtype="f4")
        if nearest:
            tex.filter = (moderngl.NEAREST, moderngl.NEAREST)
        tex.repeat_x = tex.repeat_y = False
        self._objects.append(tex)
        return tex

    def _upload(self, material: Scratched) -> dict[str, object]:
        table = self.table_of(material)
        M = table.size
        rgb = lambda a: a if a.ndim == 3 else np.repeat(a[..., None], 3, axis=-1)  # noqa: E731
        textures = {
            "s_table_a": self._texture(np.concatenate([rgb(table.rho_s0), table.rho_m[..., None]], axis=-1)),
            "s_table_b": self._texture(np.concatenate([rgb(table.gamma), table.pdf[..., None]], axis=-1)),
            "s_cdf": self._texture(table.cdf.reshape(M, M + 1)),
        }
        if material.coverage is None:
            maps = material.alpha_maps()
            K, R = maps.shape[0], maps.shape[1]
            packs = -(-K // 4)
            padded = np.zeros((4 * packs, R, R), np.float32)
            padded[:K] = maps
            data = np.ascontiguousarray(padded.reshape(packs, 4, R, R).transpose(0, 2, 3, 1))
            tex = self.ctx.texture_array((R, R, packs), 4, data.tobytes(), dtype="f4")
            tex.build_mipmaps()  # 2×2 means of a power-of-two texture: the footprint averages (material.mip_levels)
            tex.filter = (moderngl.LINEAR_MIPMAP_LINEAR, moderngl.LINEAR)
            tex.anisotropy = ANISOTROPY
            tex.repeat_x = tex.repeat_y = True
            self._objects.append(tex)
            textures["s_alpha"] = tex
        if self._env_image is not None:
            env = self._env_image
            tex = self.ctx.texture((env.shape[1], env.shape[0]), 3, env.tobytes(), dtype="f4")
            tex.repeat_x, tex.repeat_y = True, False
            self._objects.append(tex)
            textures["s_env"] = tex
        return textures

    @property
    def default_spp(self) -> int:
        return max(self.params.samples, 1)  # one frame

    def frames(self, spp: int) -> tuple[int, int]:
        n = max(self.params.samples, 1)
        if spp < 1 or spp % n:
            raise ArgumentError(
                f"spp={spp} is not a positive multiple of samples={n}: scratches accumulates spp/samples frames of "
                f"{n} environment samples each (use spp={n}, {2 * n}, {4 * n}, … or set samples)",
                field="spp",
            )
        return spp // n, 1

    def frame_uniforms(self, frame: int, seed: int) -> dict[str, object]:
        s = int(seed) % (1 << 64)
        return {"u_frame": int(frame) & 0xFFFFFFFF, "u_seed": (s ^ (s >> 32)) & 0xFFFFFFFF}
