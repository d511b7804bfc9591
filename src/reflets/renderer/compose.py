"""``auto``: every material with its own real-time technique, in one frame.

The whole-frame methods each shade one kind of material well (``translucent`` the subsurface terms, ``scratches``
the scratch lobes, ``fermat`` exact reflections, ``ltc`` area lights on every BRDF). ``auto`` prepares one of them
per kind of material present and lets each draw the meshes it owns into one shared float32 target, with one
camera matrix (so the same mesh has bit-identical depth in every pass):

=====================  ===========================================================================================
material / mesh        passes
=====================  ===========================================================================================
BRDF library           the area-light method (``area_method``, default ``ltc``; ``forward``'s midpoint rule when the
                       scene has no quad / polygon light, or a masked one the method does not take): every light
translucent            ``translucent`` once per point / directional light, each with its own light view (the first
                       pass writes, the others add where the depth is equal); quad / polygon / environment lights
                       through the material's far-field BRDF by the area-light method, added the same way
scratched              ``scratches``: point / directional lights thickened, quad / polygon lights as their midpoint
                       samples thickened, the environment importance-sampled; progressive
mirror reflector       ``fermat`` last: its non-specular part, then the reflections of every other mesh (shaded with
                       its BRDF — translucent meshes by their far-field BRDF, scratched ones by their base BRDF)
=====================  ===========================================================================================

``reflets info`` prints this table (``evaluation_table``); docs/architecture.md says how accurate each row is.
The last pass also draws the emitters and the background.
"""

from __future__ import annotations

import time
from typing import ClassVar, Literal

import numpy as np
from pydantic import Field

from ..brdf.mirror import Mirror
from ..gpu import FrameTimer, HDRTarget
from ..scene.model import DirectionalLight, PointLight, PolygonLight, QuadLight, Scene
from ..scratches.material import Scratched
from ..techniques.base import Technique, TechniqueParams, get_technique, register_technique
from ..techniques.forward import Forward, GridSide, PassRole, check_target_size, samples_per_pixel_side
from ..translucency.material import Translucent

#: the method of a scene that names none
DEFAULT_METHOD = "auto"
AREA_METHODS = ("ltc", "forward", "brute", "adaptive", "biased", "analytic", "mc")
LIGHT_KINDS = ("point", "directional", "quad", "polygon", "environment")


class AutoParams(TechniqueParams):
    """Parameters of ``auto`` (``area_samples`` and ``env_grid`` go to every pass, as in ``forward``)."""

    area_method: Literal["ltc", "forward", "brute", "adaptive", "biased", "analytic", "mc"] = Field(
        "ltc", description="how BRDF-library materials (and translucent ones' far field) take quad / polygon lights"
    )
    area_samples: int = Field(
        8, ge=1, le=64, description="n: n×n midpoint samples per quad light where passes use them"
    )
    env_grid: tuple[GridSide, GridSide] = Field((32, 16), description="environment map as nu × nv distant lights")


def material_kind(scene: Scene, index: int) -> str:
    """The pass that shades ``scene.mesh[index]``: brdf, translucent, scratched or reflector."""
    mesh = scene.mesh[index]
    material = scene.materials[mesh.material]
    if mesh.reflector and isinstance(material, Mirror):
        return "reflector"
    if isinstance(material, Translucent):
        return "translucent"
    if isinstance(material, Scratched):
        return "scratched"
    return "brdf"


def evaluation_table(area_method: str = "ltc") -> list[tuple[str, str, str]]:
    """(material, light, how ``auto`` evaluates it) for every pair — printed by ``reflets info``."""
    area = f"{area_method} (exact polygon integral of the BRDF's LTC)" if area_method == "ltc" else area_method
    rows = []
    for material in ("BRDF library", "translucent", "scratched", "mirror reflector"):
        for light in LIGHT_KINDS:
            delta = light in ("point", "directional")
            if material == "BRDF library":
                how = (
                    "exact"
                    if delta
                    else area
                    if light != "environment"
                    else "grid of distant lights (env_grid), integrating the map exactly"
                )
            elif material == "translucent":
                how = (
                    "single + multiple scattering through the light's own light view"
                    if delta
                    else "far-field BRDF (glossy interface + total diffuse reflectance): "
                    + ("area method" if light != "environment" else "environment grid")
                )
            elif material == "scratched":
                how = (
                    "thickened light (H = thickness) on every live layer"
                    if delta
                    else "midpoint samples of the emitter, each thickened"
                    if light != "environment"
                    else "importance sampling of the reflection half-cones"
                )
            else:
                how = (
                    "Fermat reflection of every other mesh lit by it; diffuse part exact"
                    if delta
                    else "Fermat reflection of the emitter and the meshes it lights; diffuse part by midpoint samples"
                    if light != "environment"
                    else "background along the mirror direction; diffuse part by the environment grid"
                )
            rows.append((material, light, how))
    return rows


@register_technique
class Auto(Technique):
    """Each material with its own technique, all in one frame (module docstring)."""

    name: ClassVar[str] = "auto"
    summary: ClassVar[str] = "the default: every material with its own real-time technique, in one frame"
    Params: ClassVar = AutoParams

    def prepare(self, scene: Scene) -> None:
        self.release()
        self.scene = scene
        kinds = [material_kind(scene, i) for i in range(len(scene.mesh))]
        owned = {k: frozenset(i for i, kind in enumerate(kinds) if kind == k) for k in set(kinds)}
        delta = [light for light in scene.light if isinstance(light, PointLight | DirectionalLight)]
        others = [light for light in scene.light if not isinstance(light, PointLight | DirectionalLight)]
        area_method = self._area_method(scene)

        plan: list[tuple[str, Scene, frozenset[int], bool]] = []  # (method, scene, meshes, additive)
        if "translucent" in owned:
            meshes = owned["translucent"]
            for k, light in enumerate(delta):
                plan.append(("translucent", self._with_lights(scene, [light]), meshes, k > 0))
            if others:
                plan.append((area_method, self._with_lights(scene, others), meshes, bool(delta)))
        if "scratched" in owned:
            plan.append(("scratches", scene, owned["scratched"], False))
        # the BRDF pass always runs (with no mesh of its own, it still draws the emitters and the background)
        plan.append((area_method, scene, owned.get("brdf", frozenset()), False))
        if "reflector" in owned:
            plan.append(("fermat", scene, owned["reflector"], False))

        p = self.params
        self.passes: list[tuple[str, Technique]] = []
        for k, (method, pass_scene, meshes, additive) in enumerate(plan):
            technique = get_technique(method)(self.ctx, area_samples=p.area_samples, env_grid=p.env_grid)
            technique.role = PassRole(meshes=meshes, clear=k == 0, extras=k == len(plan) - 1, additive=additive)
            technique.prepare(pass_scene)
            self.passes.append((method, technique))
        self.final = self.passes[-1][1]  # full scene: its clip planes and camera serve every pass
        self.pass_ms: dict[int, float] = {}
        self.timer = FrameTimer(self.ctx)

    def _area_method(self, scene: Scene) -> str:
        has_area = any(isinstance(light, QuadLight | PolygonLight) for light in scene.light)
        method = self.params.area_method
        if not has_area:
            return "forward"
        masked = any(getattr(light, "mask", None) is not None for light in scene.light)
        if masked and method != "forward" and not getattr(get_technique(method), "supports_masks", False):
            return "forward"
        return method

    @staticmethod
    def _with_lights(scene: Scene, lights: list) -> Scene:
        """The scene lit by some of its lights only (such a pass never draws the background: the last does)."""
        return scene.model_copy(update={"light": lights})

    @property
    def progressive(self) -> bool:  # type: ignore[override]
        return any(t.progressive for _, t in self.passes)

    @property
    def default_spp(self) -> int:
        return max((t.default_spp for _, t in self.passes if t.progressive), default=1)

    def frames(self, spp: int) -> tuple[int, int]:
        for _, technique in self.passes:
            if technique.progressive:
                return technique.frames(spp)
        return 1, samples_per_pixel_side(spp)

    def set_camera(self, camera) -> bool:
        self.scene = self.scene.model_copy(update={"camera": camera})
        return all(technique.set_camera(camera) for _, technique in self.passes)

    def accumulate(self, *, size=None, seed: int = 0, spp: int | None = None, first_frame: int = 0):
        if self.scene is None:
            raise RuntimeError("call prepare(scene) before render()")
        n_frames, s = self.frames(self.default_spp if spp is None else spp)
        width, height = size or self.scene.camera.size
        check_target_size(self.ctx, width, height, s)
        view, proj = self.final.camera_matrices(width, height)
        view_proj = proj @ view
        vp_bytes = view_proj.T.astype(np.float32).tobytes()
        target = HDRTarget(self.ctx, width * s, height * s)
        total = None
        try:
            for frame in range(first_frame, first_frame + n_frames):
                with self.timer.frame():
                    for k, (_, technique) in enumerate(self.passes):
                        start = time.perf_counter()
                        technique._draw(target, view_proj, vp_bytes, frame, seed)
                        if self.measure_passes:  # a finish per pass: only when asked (it costs a sync)
                            self.ctx.finish()
                            self.pass_ms[k] = 1e3 * (time.perf_counter() - start)
                image = target.read()
                total = image.astype(np.float64) if total is None else total + image
        finally:
            target.release()
        self._supersample = s
        return total, n_frames

    resolve = Forward.resolve  # the mean of the frames, box-filtered by the supersampling

    #: time each pass of a frame (``pass_costs``): a ``ctx.finish()`` after each, so only when asked
    measure_passes: bool = False

    def pass_costs(self) -> list[tuple[str, int, float]]:
        """(method, meshes it shades, wall ms of its part of the last frame) per pass, with ``measure_passes``."""
        return [
            (method, len(t.role.meshes or ()), self.pass_ms.get(k, float("nan")))
            for k, (method, t) in enumerate(self.passes)
        ]

    def release(self) -> None:
        for _, technique in getattr(self, "passes", []):
            technique.release()
        self.passes = []
