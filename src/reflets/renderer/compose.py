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
                       its BRDF — translucent meshes by their far-field BRDF, scratched ones with their scratch lobes)
=====================  ===========================================================================================

The table is not written here: each material declares which technique takes each light type
(``Material.techniques(mesh)``: ``Translucent`` → ``translucent`` for point / directional lights, ``Scratched`` →
``scratches``, a reflector ``Mirror`` → ``fermat``, the BRDF library → nothing, i.e. the BRDF pass), and each
technique where its pass goes and whether it takes one light per pass (``Technique.auto_order``,
``one_light_per_pass``); ``pass_plan`` builds the passes from those declarations. A new material type with its
own technique needs no change here.

``reflets info`` prints this table (``evaluation_table``); docs/architecture.md says how accurate each row is.
The last pass also draws the emitters and the background.
"""

from __future__ import annotations

import time
from typing import ClassVar, Literal

import numpy as np
from pydantic import Field

from ..diagnostics import lit_by_constants
from ..gpu.frames import copy_image
from ..gpu.targets import TargetCache
from ..scene.map_emitters import with_map_emitters
from ..scene.model import PolygonLight, QuadLight, Scene
from ..techniques.base import Technique, TechniqueParams, get_technique, register_technique, samples_per_pixel_side
from ..techniques.forward import (
    CASCADES_HELP,
    EnvironmentOcclusion,
    GridSide,
    PassRole,
    TextureAnisotropy,
    shadow_settings,
)
from ..techniques.prepared import PreparedScene
from ..techniques.shadows import CASCADES

#: the method of a scene that names none
DEFAULT_METHOD = "auto"
AREA_METHODS = ("ltc", "forward", "brute", "adaptive", "biased", "analytic", "mc")
LIGHT_KINDS = ("point", "directional", "quad", "polygon", "environment")


class AutoParams(TechniqueParams):
    """Parameters of ``auto`` (``area_samples``, ``env_grid``, ``environment``, ``environment_occlusion`` and
    ``texture_anisotropy`` go to every pass, as in ``forward``; the shadow settings to the prepared scene they
    share)."""

    area_method: Literal["ltc", "forward", "brute", "adaptive", "biased", "analytic", "mc"] = Field(
        "ltc", description="how BRDF-library materials (and translucent ones' far field) take quad / polygon lights"
    )
    area_samples: int = Field(
        8, ge=1, le=64, description="n: n×n midpoint samples per quad light where passes use them"
    )
    env_grid: tuple[GridSide, GridSide] = Field((32, 16), description="environment map as nu × nv distant lights")
    environment: Literal["prefiltered", "grid"] = Field(
        "prefiltered", description="environment lighting: prefiltered split sum or the env_grid lights"
    )
    environment_occlusion: EnvironmentOcclusion = "checkerboard"
    texture_anisotropy: TextureAnisotropy = 16.0
    soft_shadows: Literal["ratio", "pcss"] = Field(
        "ratio", description="area lights' soft shadows: the ratio estimator over sample views, or PCSS"
    )
    shadow_samples: int = Field(4, ge=1, le=8, description="ratio: n×n shadow views per quad light")
    shadow_cascades: int = Field(CASCADES, ge=1, le=8, description=CASCADES_HELP)


def pass_plan(scene: Scene, area_method: str) -> list[tuple[str, Scene, frozenset[int], bool]]:
    """(method, the scene that pass prepares — lit by the lights it takes —, the meshes it shades, additive) per
    pass, in drawing order.

    Each material says which technique shades it under each light type (``Material.techniques``); meshes with the
    same answer form a group. A group's own technique draws it once (or once per light, for a technique with one
    light view per pass), and the lights it leaves go to the area-light method on the material's BRDF, added
    where that group's depth is equal. The BRDF pass (meshes that leave every light to it, the emitters, the
    background) always runs; passes are ordered by ``Technique.auto_order`` (a pass that reflects the others,
    ``fermat``, last). Blended surfaces (glTF BLEND) are drawn over everything: by the BRDF pass after its
    background, or — when a pass follows it — by a pass of their own after all the others (the pass before it
    draws the extras). A reflector seen through a blended surface shows no reflection there (its G-buffer holds
    the blended surface)."""
    groups: dict[tuple, set[int]] = {}
    for i, mesh in enumerate(scene.mesh):
        key = tuple(sorted(scene.materials[mesh.material].techniques(mesh).items()))
        groups.setdefault(key, set()).add(i)
    entries: list[tuple[float, str, Scene, frozenset[int], bool]] = []
    for key, indices in groups.items():
        if not key:
            continue
        mapping, meshes, drawn = dict(key), frozenset(indices), False
        for method in sorted(set(mapping.values()), key=lambda m: get_technique(m).auto_order):
            technique = get_technique(method)
            lights = [light for light in scene.light if mapping.get(light.type) == method]
            scenes = (
                [_with_lights(scene, [light]) for light in lights]
                if technique.one_light_per_pass
                else [scene if len(lights) == len(scene.light) else _with_lights(scene, lights)]
            )
            for pass_scene in scenes:
                entries.append((technique.auto_order, method, pass_scene, meshes, drawn))
                drawn = True
        rest = [light for light in scene.light if light.type not in mapping]
        if rest or not drawn:
            order = min(get_technique(m).auto_order for m in mapping.values()) + 0.5
            entries.append((order, area_method, _with_lights(scene, rest), meshes, drawn))
    brdf_meshes = frozenset(groups.get((), ()))
    blended = frozenset(i for i in brdf_meshes if scene.materials[scene.mesh[i].material].see_through)
    if blended and any(entry[0] > 2 for entry in entries):  # a later pass (Fermat's) must be behind them
        entries.append((4, area_method, scene, blended, False))
        brdf_meshes -= blended
    entries.append((2, area_method, scene, brdf_meshes, False))
    entries.sort(key=lambda entry: entry[0])  # stable: a group's passes keep their order
    return [(method, pass_scene, meshes, additive) for _, method, pass_scene, meshes, additive in entries]


def _with_lights(scene: Scene, lights: list) -> Scene:
    """The scene lit by some of its lights only (such a pass never draws the background: the last does)."""
    return scene.model_copy(update={"light": lights})


def evaluation_table(area_method: str = "ltc") -> list[tuple[str, str, str]]:
    """(material, light, how ``auto`` evaluates it) for every pair — printed by ``reflets info``."""
    area = f"{area_method} (exact polygon integral of the BRDF's LTC)" if area_method == "ltc" else area_method
    area += " × the soft-shadow ratio"
    rows = []
    for material in ("BRDF library", "translucent", "scratched", "mirror reflector"):
        for light in LIGHT_KINDS:
            delta = light in ("point", "directional")
            if material == "BRDF library":
                how = (
                    "exact, shadow maps with PCF"
                    if delta
                    else area
                    if light != "environment"
                    else "prefiltered image-based lighting (the material's own split sum), occluded by 32 shadow views"
                )
            elif material == "translucent":
                how = (
                    "single + multiple scattering through the light's own light view"
                    if delta
                    else "far-field BRDF (glossy interface + total diffuse reflectance): "
                    + ("area method" if light != "environment" else "prefiltered image-based lighting")
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
                    else "background along the mirror direction; diffuse part by prefiltered image-based lighting"
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
        scene = with_map_emitters(scene)  # an environment's sun as a light, planned as the scene's own
        self.scene = scene
        plan = pass_plan(scene, self._area_method(scene))
        p = self.params
        self.passes: list[tuple[str, Technique]] = []
        # meshes, masks, environment and emitters uploaded once for every pass (each pass's scene holds the same
        # meshes and materials, lit by some of the lights)
        self.prepared = PreparedScene(self.ctx, scene, shadow_settings(p))
        # the emitters and the background: the last pass but a pass of blended meshes only (it draws over them; a
        # reflecting pass before it does its reflections only as the extras' pass)
        blended = [bool(meshes) and all(scene.materials[scene.mesh[i].material].see_through for i in meshes)
                   for _, _, meshes, _ in plan]  # fmt: skip
        extras = max((k for k in range(len(plan)) if not blended[k]), default=len(plan) - 1)  # all blended: the one
        for k, (method, pass_scene, meshes, additive) in enumerate(plan):
            technique = get_technique(method)(
                self.ctx,
                area_samples=p.area_samples,
                env_grid=p.env_grid,
                environment=p.environment,
                environment_occlusion=p.environment_occlusion,
                texture_anisotropy=p.texture_anisotropy,
            )
            # the frame's clear is auto's own (a pass that changes every frame may come first)
            technique.role = PassRole(meshes=meshes, clear=False, extras=k == extras, additive=additive)
            technique.shared = self.prepared
            technique.prepare(pass_scene)
            self.passes.append((method, technique))
        self.final = self.passes[-1][1]  # full scene: its clip planes and camera serve every pass
        self.pass_ms: dict[int, float] = {}
        self._late = self._late_passes()
        # the frame's plan, fixed by the passes: does a pass change from frame to frame, and in which order the
        # changing parts are drawn (first those that read back an image they draw: a reflection — on llvmpipe the
        # read waits for what was drawn before it, so not for the others' new samples), then the late passes
        self._changes = any(t.frame_dependent for _, t in self.passes)
        self._changing_order = sorted((k for k in range(len(self.passes)) if k not in self._late),
                                      key=lambda k: not self.passes[k][1].reads_own_images)  # fmt: skip
        self._late_order = sorted(self._late)
        color = scene.background_color()
        self._clear = (*(color or (0.0, 0.0, 0.0)), 1.0)
        self._static_frame = TargetCache()  # the static parts of the frame, kept for the frames after the first
        self._static_view: tuple | None = None

    def _late_passes(self) -> frozenset[int]:
        """Passes drawn whole after every pass's static part, when some pass changes from frame to frame: a pass
        that adds to meshes such a pass draws, or that shows what lies behind its see-through meshes."""
        changing: set[int] = set()  # meshes drawn after the static parts
        late = set()
        for k, (_, technique) in enumerate(self.passes):
            meshes = technique.role.meshes or frozenset()
            see_through = any(self.scene.materials[self.scene.mesh[i].material].see_through for i in meshes)
            if changing and ((technique.role.additive and meshes & changing) or see_through):
                late.add(k)
            if technique.frame_dependent or k in late:
                changing |= meshes
        return frozenset(late)

    def _area_method(self, scene: Scene) -> str:
        has_area = any(isinstance(light, QuadLight | PolygonLight) for light in scene.light)
        method = self.params.area_method
        if not has_area:
            return "forward"
        masked = any(getattr(light, "mask", None) is not None for light in scene.light)
        if masked and method != "forward" and not getattr(get_technique(method), "supports_masks", False):
            return "forward"
        if any(lit_by_constants(method, m) for m in scene.materials.values()):
            return "forward"  # its integrals would take a material's constant parameters, not its textures
        return method

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
        if not self.prepared.shadows.set_camera(camera):  # the shared cascades, refitted once for every pass
            return False
        self.scene = self.scene.model_copy(update={"camera": camera})
        return all(technique.set_camera(camera) for _, technique in self.passes)

    def camera_matrices(self, width: int, height: int) -> tuple[np.ndarray, np.ndarray]:
        return self.final.camera_matrices(width, height)  # one camera matrix for every pass

    def screen_bytes_per_sample(self) -> int:
        """The passes' screen images, and the kept static frame (colour + depth, 20 B) when some pass changes from
        frame to frame."""
        kept = 20 if self._changes else 0
        return sum(t.screen_bytes_per_sample() for _, t in self.passes) + kept

    def _timed_draw(self, target, view_proj, vp_bytes, frame: int, seed: int) -> None:
        """Each pass into the shared target, timed by its own query (``Renderer.stats['gpu_ms']``). When some pass
        changes from frame to frame (new samples), the other passes' parts are drawn first and kept: a frame after
        the first from the same view restores them and draws the changing parts alone."""
        args = (target, view_proj, vp_bytes, frame, seed)
        self.pass_ms = {}
        if not self._changes:
            target.use(clear=self._clear)
            for k, (_, technique) in enumerate(self.passes):
                self._timed(k, technique._draw, args)
            return
        view = (vp_bytes, target.size, seed)
        kept = self._static_frame.get(self.ctx, *target.size)
        if frame > 0 and self._static_view == view:
            with self.timer.timed_pass("static parts kept"):
                copy_image(self.ctx, target.fbo, target.size, kept.color, kept.depth)
        else:
            target.use(clear=self._clear)
            for k, (_, technique) in enumerate(self.passes):
                if k not in self._late:
                    self._timed(k, technique._draw_static, args)
            copy_image(self.ctx, kept.fbo, target.size, target.color, target.depth)
            self._static_view = view
        for k in self._changing_order:
            self._timed(k, self.passes[k][1]._draw_dynamic, args)
        for k in self._late_order:
            self._timed(k, self.passes[k][1]._draw, args)

    def _timed(self, k: int, draw, args: tuple) -> None:
        start = time.perf_counter()
        with self.timer.timed_pass(f"{k} {self.passes[k][0]}"):
            draw(*args)
        if self.measure_passes:  # a finish per pass: only when asked (it costs a sync)
            self.ctx.finish()
            self.pass_ms[k] = self.pass_ms.get(k, 0.0) + 1e3 * (time.perf_counter() - start)

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
        if getattr(self, "prepared", None) is not None:
            self.prepared.release()
        self.prepared = None
        super().release()  # the frame target and the frame sum
        if hasattr(self, "_static_frame"):
            self._static_frame.release()
            self._static_view = None
