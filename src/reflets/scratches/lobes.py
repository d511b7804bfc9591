"""The GPU side of a scratched material's lobes (``shaders/scratch_lobes.glsl``): its compile-time flags, uniforms
and textures (scratch table, per-row CDF, mip-mapped α maps; the environment from the prepared scene), made once
per material and scene. ``ScratchLobes`` is the shading of scratched materials: the ``scratches`` pass draws
scratched meshes with it, and the ``fermat`` pass shades their reflections with the same code, so a scratched
plate looks the same in a mirror as in direct view."""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import ClassVar

import moderngl
import numpy as np

from ..equirect import rotation_y
from ..gpu import ProgramSpec, release_objects
from ..techniques.forward import LIGHT_FLAGS
from ..techniques.prepared import PreparedScene
from ..techniques.shading import MaterialShading
from .material import Scratched

#: compile-time flags of scratch_lobes.glsl (a program that includes it declares them)
LOBE_FLAGS = frozenset({"S_LAYERS", "S_TABLE", "S_LOG2", "S_ENV_SAMPLES", "S_LIGHT_SAMPLES", "S_CONSTANT_ALPHA"})
#: a scratched mesh in a forward pass: the base BRDF lit as the forward pass does, plus the lobes
SCRATCHES_PROGRAM = ProgramSpec(
    "scratches",
    vertex="reflets/techniques/shaders/mesh.vert",
    fragment="reflets/scratches/shaders/scratches.frag",
    flags=LOBE_FLAGS | LIGHT_FLAGS | {"OUTPUT"},
)
#: anisotropic filtering of the α maps (grazing views of a plate keep their detail along the view)
ANISOTROPY = 16.0


@dataclass(frozen=True)
class LobeSettings:
    """How the lobes are sampled (the ``scratches`` method's parameters of the same names take these defaults)."""

    samples: int = 8  # environment samples per pixel and frame (split ∝ α_k)
    light_samples: int = 4  # samples per thickened light and live layer per frame
    thickness: float = 2.0  # H, degrees
    table_backend: str = "auto"  # "auto" (the GPU tracer with a context), "numpy" or "gpu"


class ScratchLobes(MaterialShading):
    """Flags, uniforms and textures of the scratched materials of one pass's scene (lit by its lights: the
    environment is sampled when that scene has one), on a prepared scene's context."""

    material_type: ClassVar[type] = Scratched
    program: ClassVar[ProgramSpec] = SCRATCHES_PROGRAM

    def __init__(self, prepared: PreparedScene, scene, settings: LobeSettings = LobeSettings()):
        self.ctx = prepared.ctx
        self.scene = scene
        self.settings = settings
        self._env_texture = prepared.environment_texture if scene.environment is not None else None
        self._textures: dict[str, dict[str, object]] = {}
        self._objects: list = []

    def ibl_material(self, material: Scratched):
        """The base: the pass lights it through lights.glsl (``base_brdf_eval``) and weights it by max(0, 1 − ᾱ)
        per pixel itself — the finite part's mean share, in the material's own albedo curve, would count twice."""
        return material.base

    def table_of(self, material: Scratched):
        """The material's scratch table as these settings compute it."""
        backend = self.settings.table_backend
        if backend == "auto":
            return material.table(self.ctx)
        return material.table(self.ctx if backend == "gpu" else None, backend=backend)

    def flags(self, material: Scratched) -> dict[str, object]:
        table = self.table_of(material)
        return {
            "S_LAYERS": material.layer_count,
            "S_TABLE": table.size,
            "S_LOG2": max(1, math.ceil(math.log2(table.size))),
            "S_ENV_SAMPLES": self.settings.samples if self._env_texture is not None else 0,
            "S_LIGHT_SAMPLES": self.settings.light_samples,
            "S_CONSTANT_ALPHA": int(material.coverage is not None),
        }

    def uniforms(self, material: Scratched) -> dict[str, object]:
        angles = material.layer_angles()
        env = self.scene.environment
        rot = rotation_y(env.rotate_y) if env is not None else np.eye(3)
        return {
            "s_dir": np.stack([np.cos(angles), np.sin(angles)], axis=1).astype(np.float32).tobytes(),
            "s_thickness": math.radians(self.settings.thickness),
            "s_coverage": float(material.coverage or 0.0),
            "s_env_from_world": rot.astype(np.float32).tobytes(),  # R^T: column-major bytes of row-major R
        }

    def textures(self, material: Scratched) -> dict[str, object]:
        key = material.model_dump_json()
        if key not in self._textures:
            self._textures[key] = self._upload(material)
        return self._textures[key]

    @staticmethod
    def frame_uniforms(frame: int, seed: int) -> dict[str, object]:
        """The random stream of frame ``frame`` (progressive accumulation: each frame draws new samples)."""
        s = int(seed) % (1 << 64)
        return {"u_frame": int(frame) & 0xFFFFFFFF, "u_seed": (s ^ (s >> 32)) & 0xFFFFFFFF}

    def release(self) -> None:
        release_objects(self.ctx, self._objects)
        self._objects = []
        self._textures = {}

    # ------------------------------------------------------------------ uploads
    def _texture(self, data: np.ndarray):
        data = np.ascontiguousarray(data, dtype=np.float32)
        h, w = data.shape[:2]
        tex = self.ctx.texture((w, h), 1 if data.ndim == 2 else data.shape[2], data.tobytes(), dtype="f4")
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
        if self._env_texture is not None:
            textures["s_env"] = self._env_texture  # the prepared scene's
        return textures
