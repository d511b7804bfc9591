"""Shadow maps of every light, in one depth atlas shared by every pass of a frame.

Every technique shades its lights through ``shaders/lights.glsl`` (or, for the scratch lobes and Fermat's
reflected pass, code that includes it), the area-light methods their polygons through ``arealight.frag``, and
there ``shaders/shadows.glsl`` weights each light by what its shadow views see:

- a point light: six 90° perspective views (a cube map unfolded into the atlas: faces +x, −x, +y, −y, +z, −z,
  picked by the major axis of the light-to-point vector); a directional light: one orthographic view fitted to
  the meshes' bounding sphere, preceded by cascades over the camera's view when that view is coarser than a
  pixel (``cascade_spheres``); percentage-closer filtering (3 × 3 hardware-bilinear comparisons one texel
  apart);
- a quad / polygon light: **soft shadows by the ratio estimator** (Heitz et al. 2018) with shadow maps for
  visibility: ``SOFT_SIDE``² points spread over the emitter by the midpoint rule (the forward pass's sample
  pattern), one perspective view from each along the emitting normal, fitted to the meshes' boxes in front
  of it (two views per point for a two-sided light); the light's unshadowed contribution — exact by LTC or
  whatever the area-light method computes — is multiplied by Σ_k w_k V_k / Σ_k w_k, with w_k = f cosθ_x cosθ_y
  dA / r² the unshadowed integrand at point k (a masked quad: × the mask there) and V_k one bilinear
  comparison in view k. Exact where the light is wholly seen or wholly hidden; in the penumbra a quadrature
  of the visible fraction with ``SOFT_SIDE``² nodes. Directions more than ``MAX_ANGLE`` from the emitting
  normal fall outside the views and count as visible (their cosθ_y < 0.18);
- the environment: ``ENV_SAMPLES`` orthographic views along directions drawn ∝ the map's power (the shader
  reads them from uniforms: ``environment_uniforms``);
- views are drawn once per prepare (they depend on the lights and the meshes), but for the cascades, drawn
  again by ``set_camera``;
- bias, chosen on the test scenes (``tests/techniques/test_shadows.py``): a slope-scaled polygon offset in the
  depth pass (``SLOPE_BIAS``, ``CONSTANT_BIAS``) and, at lookup, a normal offset of 0.5 + 1.5 sin θ texels
  (θ between the normal and the light) along the normal turned towards the light. No acne on lit surfaces
  (lit floor within 2 % of the reference), and shadows stay attached to their casters.

In a scene of a few meshes (``CULL_MESHES``), a mesh's draw leaves out the lookups no caster can darken
(``environment_occludes``, ``shadowed``: forward.py compiles them out), tested on boxes and the mesh's convexity
(``_cull_tests``, ``_shadow_needs``; docs/techniques/shadows.md).

A light with ``shadows = false`` gets no view. All views share one resolution, chosen so that the atlas stays
within ``MAX_ATLAS`` texels per side (many lights: smaller maps).

View record in the storage buffer (``RECORD`` vec4 each): [0..3] view-projection columns, [4] atlas tile (uv of
its corner, uv size), [5] (world texel size: per unit distance along the axis for a perspective view; near and
far of a soft-shadow view, 0),
[6] sample point y and its weight dA × mask, [7] the view's axis (the emitting normal, or its opposite); an
environment view: [6] its direction and weight, [7] its weight per channel (what ``environment_uniforms``
packs for the shader).
"""

from __future__ import annotations

import hashlib
import math
from dataclasses import dataclass
from typing import Literal

import moderngl
import numpy as np

from ..cache import Memo
from ..equirect import equirect_direction, rotation_y, row_solid_angles
from ..gpu import GLObjects, ProgramSpec, get_program, set_uniforms
from ..scene.emitters import area_light_samples, polygon_normal
from ..scene.geometry import bounding_sphere, camera_range, clip_planes_of_sphere, self_shadowing
from ..scene.lightmask import LUMINANCE, mask_lookup
from ..scene.model import DirectionalLight, EnvironmentLight, PointLight, PolygonLight, QuadLight, Scene
from ..scene.transform import look_at, perspective
from ..textures import texture_for

_SHADERS = "reflets/techniques/shaders/"
DEPTH_PROGRAM = ProgramSpec("shadow_depth", vertex=_SHADERS + "mesh.vert", fragment=_SHADERS + "shadow_depth.frag")
#: the depth pass of a cut-out material (glTF alphaMode MASK): its holes cast no shadow
CUTOUT_PROGRAM = ProgramSpec("shadow_cutout", vertex=_SHADERS + "mesh.vert", fragment=_SHADERS + "shadow_cutout.frag",
                             flags=frozenset({"BRDF_GLTF_BASE_MAP", "BRDF_GLTF_BLEND"}))  # fmt: skip
#: the texture unit of a cut-out's base colour while the maps are drawn (the frame's passes bind their own later)
CUTOUT_UNIT = 0
#: texture units of the atlas (depth comparisons; raw depths for PCSS) and storage binding of the views in every
#: shading program
SHADOW_UNIT, SHADOW_DEPTH_UNIT, SHADOW_NEAREST_UNIT = 11, 10, 16
SHADOW_SAMPLERS = {
    "u_shadow_atlas": SHADOW_UNIT,
    "u_shadow_depth": SHADOW_DEPTH_UNIT,
    "u_shadow_nearest": SHADOW_NEAREST_UNIT,
}
SHADOW_BINDING = 6
#: pixels per side of one view (a point light's cube face, a directional light's map)
RESOLUTION = 2048
#: the atlas's largest side in texels (a 4096² float depth atlas is 64 MiB)
MAX_ATLAS = 4096
#: glPolygonOffset(factor, units) of the depth pass: depth pushed back by the surface's slope plus a constant
SLOPE_BIAS, CONSTANT_BIAS = 2.0, 4.0
#: vec4 rows per view record (layout in the module docstring)
RECORD = 8
#: a quad light's soft shadows: SOFT_SIDE² sample views by default (a polygon: about as many over its fan)
SOFT_SIDE = 4
#: the environment's occlusion: ENV_SAMPLES directions drawn ∝ the map's power (stratified, deterministic;
#: a direction drawn k times is one view of weight k), one orthographic view each; the environment's light is
#: weighted by the visible fraction of them (a sun gets its own exact direction: its shadow lands in place)
ENV_SAMPLES = 32
#: a mesh's draw leaves out the shadow lookups no caster can darken — the environment's occlusion, or every
#: lookup (``ShadowMaps.environment_occludes``, ``ShadowMaps.shadowed``) —, checked in scenes of at most this many
#: meshes (pairs of boxes per light and view)
CULL_MESHES = 16
#: a box grown by this many texels of a whole-scene view for those tests (what a lookup may see of a caster: the
#: normal offset, the filter, the rasterised edge)
CULL_MARGIN = 4.0
#: a directional light's cascades (Engel 2006; Zhang et al. 2006) when the camera sees part of a large scene: at
#: most CASCADES views, the last the whole scene's, over depths at most CASCADE_RANGE far / near
CASCADES, CASCADE_RANGE = 4, 1000.0
#: only this many directional lights, the brightest (by the luminance of their irradiance), get cascades: a
#: map's many small lamps (``map_emitters``) each get the whole scene's view alone (the atlas's views share one
#: resolution: cascades for 30 lamps would coarsen every map of the frame)
CASCADED_LIGHTS = 2


@dataclass(frozen=True)
class ShadowSettings:
    """How area lights' soft shadows are made and how many cascades a directional light may get (the techniques'
    ``soft_shadows``, ``shadow_samples`` and ``shadow_cascades``)."""

    design: Literal["ratio", "pcss"] = "ratio"
    side: int = SOFT_SIDE  # ratio: side² sample views per quad light
    cascades: int = CASCADES  # a directional light's views at most (1: the whole scene's alone)


DEFAULT_SHADOWS = ShadowSettings()
#: soft-shadow views hold directions up to this angle from the emitting normal (degrees)
MAX_ANGLE = 80.0
#: the cube faces' (axis, up) pairs, in the order shadows.glsl picks them
CUBE_FACES = (
    ((1, 0, 0), (0, -1, 0)),
    ((-1, 0, 0), (0, -1, 0)),
    ((0, 1, 0), (0, 0, 1)),
    ((0, -1, 0), (0, 0, -1)),
    ((0, 0, 1), (0, -1, 0)),
    ((0, 0, -1), (0, -1, 0)),
)


class ShadowMaps:
    """The shadow views of a scene's lights, drawn into one depth atlas (see the module docstring)."""

    def __init__(self, prepared, settings: ShadowSettings = DEFAULT_SHADOWS):
        """The views of a ``PreparedScene``'s lights (its meshes cast; its environment map, if any, is sampled;
        not imported here: the prepared scene imports this module)."""
        ctx = self.ctx = prepared.ctx
        scene = self.scene = prepared.scene
        self.settings = settings
        self._first_view: dict[int, int] = {}  # light index → its first view
        self._soft: dict[int, tuple[int, int, int]] = {}  # area light index → (first view, points, views per point)
        self._cascades: dict[int, tuple[int, int]] = {}  # directional light index → (first view, cascades)
        self._scene_sphere = (np.zeros(3), 1e-6)
        #: the environment's occlusion views: (first view, count), or None
        self.environment_views: tuple[int, int] | None = None
        #: how many of them (the first) every pixel looks up: directions drawn more than once (shadows.glsl)
        self.environment_full = 0
        #: shadows.glsl's ``environment_visibility`` uniforms (empty without environment views)
        self.environment_uniforms: dict[str, bytes] = {}
        # where the culling tests apply: per mesh its box, self_shadowing, and whether another mesh's box meets
        # its rays towards the environment's views / towards a shadowed light (``_cull_tests``)
        self._cull: tuple[np.ndarray, list[str], list[tuple[bool, bool]]] | None = None
        self._needs: list[tuple[bool, bool]] = []  # per mesh: (environment_occludes, shadowed) for the camera
        views: list[dict] = []
        boxes = [(m.positions.min(axis=0), m.positions.max(axis=0)) for m in prepared.meshes if len(m.positions)]
        if boxes:  # the meshes' bounding-box corners: what the views must hold
            corners = np.array([[box[(k >> a) & 1][a] for a in range(3)] for box in boxes for k in range(8)])
            centre, radius = bounding_sphere(corners)
            radius = max(radius, 1e-6)
            self._scene_sphere = (centre, radius)
        self._cascaded = cascaded_lights(scene)
        for index, light in enumerate(scene.light):
            if not getattr(light, "shadows", False) or not boxes:
                continue
            first = len(views)
            if isinstance(light, PointLight):
                views += _cube_views(np.asarray(light.position, np.float64), centre, radius)
            elif isinstance(light, DirectionalLight):  # placeholders: a cascade's view snaps to the texel grid
                spheres = [*cascade_spheres(scene.camera, centre, radius, self._cascade_limit(index)), (centre, radius)]
                self._cascades[index] = (first, len(spheres))
                views += [None] * len(spheres)
            elif isinstance(light, QuadLight | PolygonLight):
                points, weights = _soft_samples(light, prepared.mask_of(light), settings)
                normal = polygon_normal(light.polygon())
                axes = (normal, -normal) if light.two_sided else (normal,)
                for y, w in zip(points, weights, strict=True):
                    views += [_sample_view(y, axis, w, corners) for axis in axes]
                self._soft[index] = (first, len(points), len(axes))
            elif isinstance(light, EnvironmentLight) and prepared.environment is not None:
                directions, counts, colours = environment_directions(prepared.environment, light)
                for k in np.argsort(-counts, kind="stable"):  # the directions drawn more than once first
                    view = directional_view(-directions[k], centre, radius)
                    view.update(point=tuple(directions[k]), weight=float(counts[k]), axis=tuple(colours[k]))
                    views.append(view)
                self.environment_views = (first, len(views) - first)
                self.environment_full = int(np.count_nonzero(counts > 1))
            else:
                continue
            self._first_view[index] = first
        self.view_count = len(views)
        self._gl = GLObjects(ctx)
        self._own = self._gl.own
        self.atlas = None
        self.buffer = None
        if not views:
            return
        columns = math.ceil(math.sqrt(len(views)))
        rows = math.ceil(len(views) / columns)
        self.resolution = min(RESOLUTION, MAX_ATLAS // columns)
        size = (columns * self.resolution, rows * self.resolution)
        self.atlas = self._own(ctx.depth_texture(size))
        self.atlas.compare_func = "<="  # sampler2DShadow: 1 where the point is not behind the stored depth
        self.atlas.filter = (moderngl.LINEAR, moderngl.LINEAR)  # bilinear comparisons (hardware 2×2 PCF)
        self.atlas.repeat_x = self.atlas.repeat_y = False
        self._raw = self._own(ctx.sampler(filter=(moderngl.NEAREST, moderngl.NEAREST), compare_func=""))
        self._raw.repeat_x = self._raw.repeat_y = False
        # one comparison of the nearest texel (the environment's many directions: the sum over them filters,
        # and a bilinear comparison costs four fetches on a software rasteriser)
        self._nearest = self._own(ctx.sampler(filter=(moderngl.NEAREST, moderngl.NEAREST), compare_func="<="))
        self._nearest.repeat_x = self._nearest.repeat_y = False
        self._columns, self._size = columns, size
        for index, (first, count) in self._cascades.items():
            views[first : first + count] = self._directional_views(index, scene.camera)
        self._views = views
        self.buffer = self._own(ctx.buffer(np.asarray([self._record(k) for k in range(len(views))]).tobytes()))
        if self.environment_views:
            first, count = self.environment_views
            self.environment_uniforms = _environment_uniforms(views[first : first + count], first, columns, size)
        if len(boxes) == len(prepared.meshes) <= CULL_MESHES:  # (an empty mesh has no box)
            env = self.environment_views
            directions = np.array([view["point"] for view in views[env[0] : env[0] + env[1]]] if env else [])
            boxes = np.array(boxes)
            tests = self._cull_tests(boxes, directions.reshape(-1, 3), radius)
            # the convex hull only where the answer matters: a mesh other meshes may shadow keeps its lookups
            shadowing = [mesh_self_shadowing(mesh) if test != (True, True) else "any"
                         for mesh, test in zip(prepared.meshes, tests, strict=True)]
            self._cull = (boxes, shadowing, tests)
            self._needs = self._shadow_needs(scene.camera)
        self._casters = [self._caster(prepared, i) for i in range(len(prepared.meshes))]
        # the distinct programs (the depth one, the cut-out variants: a program may serve several meshes)
        self._programs = list({id(caster[0]): caster[0] for caster in self._casters}.values())
        self._fbo = self._own(ctx.framebuffer(depth_attachment=self.atlas))
        self._draw(range(len(views)))

    def _caster(self, prepared, index: int) -> tuple:
        """(program, vertex array, uniforms, coverage texture or None) drawing mesh ``index`` into a map: depth only,
        or with a cut-out material's coverage test."""
        material = prepared.scene.materials[prepared.scene.mesh[index].material]
        if not material.cutout:
            program = get_program(self.ctx, DEPTH_PROGRAM)
            return program, self._own(prepared.vertex_array(program, index)), {}, None
        flags = material.flags()
        textured = flags["BRDF_GLTF_BASE_MAP"] > 0
        program = get_program(self.ctx, CUTOUT_PROGRAM, BRDF_GLTF_BASE_MAP=flags["BRDF_GLTF_BASE_MAP"],
                              BRDF_GLTF_BLEND=flags["BRDF_GLTF_BLEND"])  # fmt: skip
        texture = texture_for(self.ctx, material.texture_data("base_color_texture")) if textured else None
        uniforms = {k: v for k, v in {**material.uniforms(), "m_base_color_map": CUTOUT_UNIT}.items() if k in program}
        return program, self._own(prepared.vertex_array(program, index)), uniforms, texture

    def _cascade_limit(self, index: int) -> int:
        """How many views directional light ``index`` may have (``CASCADED_LIGHTS``)."""
        return self.settings.cascades if index in self._cascaded else 1

    def _directional_views(self, index: int, camera) -> list[dict]:
        """Directional light ``index``'s views for ``camera``: its cascades (finest first), then the whole
        scene's."""
        centre, radius = self._scene_sphere
        direction = np.asarray(self.scene.light[index].direction, np.float64)
        spheres = [*cascade_spheres(camera, centre, radius, self._cascade_limit(index)), (centre, radius)]
        return [
            directional_view(direction, *snap_to_texels(direction, c, r, self.resolution), centre, radius)
            for c, r in spheres[:-1]
        ] + [directional_view(direction, centre, radius)]

    def _record(self, k: int) -> np.ndarray:
        """View k's record (``RECORD`` vec4, float32; layout in the module docstring)."""
        view, (columns, size) = self._views[k], (self._columns, self._size)
        tile = ((k % columns) * self.resolution / size[0], (k // columns) * self.resolution / size[1])
        scale = (self.resolution / size[0], self.resolution / size[1])
        return np.concatenate(
            [
                view["view_proj"].T.ravel(),  # four columns (GLSL mat4 from column vectors)
                [*tile, *scale],
                [view["texel"] / self.resolution, *view.get("near_far", (0.0, 0.0)), 0.0],
                [*view.get("point", (0.0, 0.0, 0.0)), view.get("weight", 0.0)],
                [*view.get("axis", (0.0, 0.0, 0.0)), 0.0],
            ]
        ).astype(np.float32)

    def _cull_tests(self, boxes: np.ndarray, directions: np.ndarray, radius: float) -> list[tuple[bool, bool]]:
        """Per mesh: may a ray from its box towards one of the environment's views (along its direction) / towards a
        shadowed light or view (a direction: the box swept; a point or an area light: the box holding both; the
        environment's views included) meet another mesh's box? Boxes grown by ``CULL_MARGIN`` texels of the views
        looked up there: a whole-scene view's for directions, a cube face's or a soft-shadow view's at the farthest
        corner for a point or an area light."""
        whole = CULL_MARGIN * 2.0 * radius / self.resolution
        tests = []
        for i, raw in enumerate(boxes):
            # both boxes grown: the caster by a lookup's reach, the receiver by the normal offset of its lookups
            others, box = np.delete(boxes, i, axis=0) + [[-whole], [whole]], raw + [[-whole], [whole]]
            environment = len(directions) > 0 and any(np.any(swept_box_meets(box, directions, o)) for o in others)
            lights = environment
            for index, light in enumerate(self.scene.light):
                if lights or index not in self._first_view or isinstance(light, EnvironmentLight):
                    continue
                if isinstance(light, DirectionalLight):
                    towards = -np.asarray(light.direction, np.float64)[None] / np.linalg.norm(light.direction)
                    lights = any(bool(swept_box_meets(box, towards, other)[0]) for other in others)
                    continue
                corners = (np.asarray(light.position, np.float64)[None] if isinstance(light, PointLight)
                           else light.polygon())  # fmt: skip
                span = np.array([np.minimum(box[0], corners.min(axis=0)), np.maximum(box[1], corners.max(axis=0))])
                far = float(np.linalg.norm(span[1] - span[0]))  # no receiver is farther from the light
                texel = (2.0 if isinstance(light, PointLight) else 2.0 * math.tan(math.radians(MAX_ANGLE))) * far
                margin = CULL_MARGIN * texel / self.resolution
                span += [[-margin], [margin]]
                grown = np.delete(boxes, i, axis=0) + [[-margin], [margin]]
                lights = any(bool(np.all(span[0] <= o[1]) and np.all(span[1] >= o[0])) for o in grown)
            tests.append((environment, lights))
        return tests

    def _shadow_needs(self, camera) -> list[tuple[bool, bool]]:
        """Per mesh: (can a caster hide one of the environment's views from a point of it the camera sees, can
        one darken it from any light or view at all). Not where its rays towards them meet no other mesh's box
        (``_cull_tests``) and the mesh cannot hide itself — flat, or closed and convex, front sides out, with the
        camera's near plane outside it (geometry.self_shadowing: a point facing a light it sees from outside a
        convex hull is not hidden by it). An orthographic camera's near plane may cut anything: convex meshes
        count as open then."""
        boxes, shadowing, tests = self._cull  # (only asked where culling is on)
        eye = np.asarray(camera.position, np.float64)
        if camera.orthographic:
            reach = np.inf
        else:  # the near plane's corners lie within near × |(x, y, 1)| of the eye, (x, y) the view's half extents
            tan_y = math.tan(math.radians(camera.fov_y) / 2.0)  # at depth 1 (camera.projection_matrix's)
            ox, oy = (abs(o) for o in camera.principal_offset)
            half_x = tan_y * camera.size[0] / camera.size[1] / camera.pixel_aspect * (1.0 + 2.0 * ox)
            half_y = tan_y * (1.0 + 2.0 * oy)
            reach = camera_range(camera, boxes)[0] * math.sqrt(1.0 + half_x**2 + half_y**2)
        needs = []
        for box, kind, test in zip(boxes, shadowing, tests, strict=True):
            cut = bool(np.all(eye >= box[0] - reach) and np.all(eye <= box[1] + reach))
            needs.append((True, True) if kind == "any" or (kind == "inside" and cut) else test)
        return needs

    def environment_occludes(self, mesh: int) -> bool:
        """May the environment's views be hidden from some point of mesh ``mesh`` (its index among the prepared
        meshes) that the camera sees? (False: its draw leaves the occlusion out, exactly.)"""
        return self._needs[mesh][0] if mesh < len(self._needs) else True

    def shadowed(self, mesh: int) -> bool:
        """May any light's or view's shadow fall on a point of mesh ``mesh`` the camera sees? (False: its draw
        leaves every shadow lookup out, exactly.)"""
        return self._needs[mesh][1] if mesh < len(self._needs) else True

    def set_camera(self, camera) -> bool:
        """Fit the directional lights' cascades to a new camera (their records updated, their tiles drawn again:
        the other views do not depend on the camera); False when a light's number of cascades changes (the
        atlas's layout with it) or the near plane's reach enters or leaves a convex mesh's box (which then draws
        its shadows): prepare again."""
        # (a light without cascades keeps its one whole-scene view: nothing to fit)
        fitted = {index: self._directional_views(index, camera) for index in self._cascades
                  if index in self._cascaded}  # fmt: skip
        if any(len(views) != self._cascades[index][1] for index, views in fitted.items()):
            return False
        if self._cull is not None and self._shadow_needs(camera) != self._needs:
            return False
        redraw = []
        for index, views in fitted.items():
            first, count = self._cascades[index]
            if count == 1:
                continue  # the whole scene's view alone: the camera does not move it
            self._views[first : first + count] = views
            for k in range(first, first + count):
                self.buffer.write(self._record(k).tobytes(), offset=k * RECORD * 16)
            redraw += range(first, first + count)
        if redraw:
            self._draw(redraw)
        return True

    def cascade_count(self, light) -> int:
        """How many views a directional light of this scene has (cascades and the whole scene's; 0: no shadows)."""
        return self._cascades.get(light_index(self.scene, light), (0, 0))[1]

    def soft_range(self, light) -> tuple[int, int, int] | None:
        """(first view, sample points, views per point) of an area light of this scene, or None (no shadows)."""
        return self._soft.get(light_index(self.scene, light))

    def soft_code(self, light) -> float:
        """An area light's views as shadows.glsl's ``soft_visibility`` reads them: (first + 1) × 256 + points × 4
        + PCSS × 2 + views per point − 1, or 0 (no shadows); exact in float32 (below 2²⁴)."""
        soft = self.soft_range(light)
        if soft is None:
            return 0.0
        first, points, per_point = soft
        pcss = int(self.settings.design == "pcss")
        return float((first + 1) * 256 + points * 4 + pcss * 2 + per_point - 1)

    def view_index(self, light) -> int:
        """The first view of a light of this scene, or −1 when it casts no shadow."""
        return self._first_view.get(light_index(self.scene, light), -1)

    def bind(self) -> None:
        """Bind the atlas and the views where the shading programs read them (a program without shadows
        ignores both)."""
        if self.atlas is not None:
            self.atlas.use(SHADOW_UNIT)
            self.atlas.use(SHADOW_DEPTH_UNIT)
            self._raw.use(SHADOW_DEPTH_UNIT)  # that unit reads raw depths (no comparison)
            self.atlas.use(SHADOW_NEAREST_UNIT)
            self._nearest.use(SHADOW_NEAREST_UNIT)
            self.buffer.bind_to_storage_buffer(SHADOW_BINDING)

    def _draw(self, indices) -> None:
        """Draw views ``indices`` into their tiles (each tile cleared first)."""
        ctx = self.ctx
        self._fbo.use()
        ctx.enable(ctx.DEPTH_TEST)
        ctx.disable(ctx.CULL_FACE)  # two-sided surfaces cast from both sides
        ctx.polygon_offset = SLOPE_BIAS, CONSTANT_BIAS
        r, columns = self.resolution, self._columns
        for k in indices:
            viewport = ((k % columns) * r, (k // columns) * r, r, r)
            self._fbo.clear(depth=1.0, viewport=viewport)
            ctx.viewport = viewport
            view_proj = self._views[k]["view_proj"].T.astype(np.float32).tobytes()
            for program in self._programs:
                set_uniforms(program, {"u_view_proj": view_proj})
            for program, vao, uniforms, texture in self._casters:
                if texture is not None:
                    texture.use(CUTOUT_UNIT)
                if uniforms:  # a cut-out's own coverage (its program may serve several materials)
                    set_uniforms(program, uniforms)
                vao.render()
        ctx.polygon_offset = 0.0, 0.0
        ctx.disable(ctx.DEPTH_TEST)

    def release(self) -> None:
        self._gl.release()
        self.atlas = self.buffer = None


def cascaded_lights(scene: Scene) -> set[int]:
    """The indices of the ``CASCADED_LIGHTS`` brightest shadowed directional lights of a scene."""
    lights = [(float(np.dot(light.irradiance, LUMINANCE)), index) for index, light in enumerate(scene.light)
              if isinstance(light, DirectionalLight) and light.shadows]  # fmt: skip
    return {index for _, index in sorted(lights, key=lambda item: -item[0])[:CASCADED_LIGHTS]}


def light_index(scene: Scene, light) -> int | None:
    """The index of ``light`` in ``scene.light``, found by identity: a pass's scene holds some of the full
    scene's lights (the same objects), at other indices."""
    return next((i for i, candidate in enumerate(scene.light) if candidate is light), None)


def _environment_uniforms(views: list[dict], first: int, columns: int, size: tuple[int, int]) -> dict[str, bytes]:
    """The environment views as shadows.glsl reads them: per view the affine map from (x, 1) to its atlas uv and
    depth (an orthographic view-projection with the tile's placement folded in: three dot products a lookup),
    its direction and world texel size, its weight per channel, its tile's uv clamp box."""
    affine, dirs, rgb, boxes = [], [], [], []
    resolution = size[0] // columns
    scale = np.array([resolution / size[0], resolution / size[1]])
    half = 0.5 / np.asarray(size, np.float64)
    for k, view in enumerate(views, start=first):
        tile = np.array([(k % columns) * scale[0], (k // columns) * scale[1]])
        rows = 0.5 * view["view_proj"][:3].copy()  # ndc → [0, 1]: ½ ndc + ½
        rows[:, 3] += 0.5
        rows[:2] = rows[:2] * scale[:, None]
        rows[:2, 3] += tile
        affine += list(rows)
        dirs.append((*view["point"], view["texel"] / resolution))
        rgb.append((*view["axis"], 0.0))
        boxes.append((*(tile + half), *(tile + scale - half)))
    return {
        name: np.asarray(rows, np.float32).tobytes()
        for name, rows in (("u_env_affine", affine), ("u_env_dir", dirs), ("u_env_rgb", rgb), ("u_env_box", boxes))
    }


def swept_box_meets(box: np.ndarray, directions: np.ndarray, other: np.ndarray) -> np.ndarray:
    """Per direction d (K, 3): does the box swept along d (box + t d, t ≥ 0) meet ``other``? Boxes are (2, 3)
    lower and upper corners; per axis the t where the two overlap is an interval, and they meet where every
    axis's interval and t ≥ 0 share a t."""
    lo, hi = box
    other_lo, other_hi = other
    with np.errstate(divide="ignore", invalid="ignore"):
        a, b = (other_lo - hi) / directions, (other_hi - lo) / directions
    start, end = np.minimum(a, b), np.maximum(a, b)
    still = directions == 0.0  # no motion on this axis: always or never overlapping
    overlap = (lo <= other_hi) & (hi >= other_lo)
    start = np.where(still, np.where(overlap, -np.inf, np.inf), start)
    end = np.where(still, np.inf, end)
    return np.maximum(start.max(axis=1), 0.0) <= end.min(axis=1)


#: geometry.self_shadowing of the meshes last asked for, by content (a convex hull: 0.1–0.4 s for a
#: 65,000-triangle sphere)
_SHADOWING = Memo(256)


def mesh_self_shadowing(mesh) -> str:
    """geometry.self_shadowing of a prepared mesh (its normals included), remembered in memory by its content."""
    digest = hashlib.blake2b(digest_size=16)
    for array in (mesh.positions, mesh.indices, mesh.normals):
        digest.update(repr(array.shape).encode())
        digest.update(np.ascontiguousarray(array).tobytes())
    return _SHADOWING.get(digest.digest(), lambda: self_shadowing(mesh.positions, mesh.indices, mesh.normals))


def _cube_views(position: np.ndarray, centre: np.ndarray, radius: float) -> list[dict]:
    """Six 90° views from a point light holding the meshes' bounding sphere (near: as far as the sphere allows)."""
    dist = float(np.linalg.norm(centre - position))
    far = (dist + radius) * 1.01 + 1e-6
    near = max(far * 1e-4, 0.99 * (dist - radius)) if dist > radius else far * 1e-4
    proj = perspective(90.0, 1.0, near, far)
    return [
        {"view_proj": proj @ look_at(position, position + np.asarray(axis), up), "texel": 2.0}
        for axis, up in CUBE_FACES
    ]


def directional_view(
    direction: np.ndarray,
    centre: np.ndarray,
    radius: float,
    depth_centre: np.ndarray | None = None,
    depth_radius: float | None = None,
) -> dict:
    """An orthographic view along ``direction`` holding a sphere across and, along the direction, the sphere
    (``depth_centre``, ``depth_radius``) — by default the same: a cascade holds its slice of the camera's view
    across and every caster of the scene in depth. Its view-projection and the world size of its whole width
    (2 r; a texel is that over the resolution)."""
    d = direction / np.linalg.norm(direction)
    if depth_centre is None:
        depth_centre, depth_radius = centre, radius
    eye = centre + d * (float(np.dot(depth_centre - centre, d)) - 2.0 * depth_radius)
    up = (0.0, 1.0, 0.0) if abs(d[1]) < 0.99 else (1.0, 0.0, 0.0)
    near, far = 0.5 * depth_radius, 3.5 * depth_radius
    proj = np.diag([1.0 / radius, 1.0 / radius, -2.0 / (far - near), 1.0])
    proj[2, 3] = -(far + near) / (far - near)
    return {"view_proj": proj @ look_at(eye, eye + d, up), "texel": 2.0 * radius}


def cascade_spheres(camera, centre: np.ndarray, radius: float, count: int = CASCADES) -> list[tuple[np.ndarray, float]]:
    """Bounding spheres of slices of the camera's view frustum (finest first) where one view of the whole scene
    would be coarser than a pixel at the camera's point of interest (``look_at``); none otherwise. The depths
    the scene's sphere allows, at most ``CASCADE_RANGE`` far / near, are split logarithmically into ``count``
    slices (each as many pixels per texel), the last left to the whole scene's view, stopping at a slice half
    as wide as the scene. A scene deeper than ``CASCADE_RANGE`` times the point of interest's distance (a ground
    plane to the horizon) takes the range of that ratio centred on it (log scale) instead of its far end: the
    near objects keep fine slices."""
    if camera.orthographic:  # a constant pixel footprint: the whole scene in one view
        return []
    eye = np.asarray(camera.position, np.float64)
    forward = np.asarray(camera.look_at, np.float64) - eye
    focus = float(np.linalg.norm(forward))
    forward /= focus
    tan_half = math.tan(math.radians(camera.fov_y) / 2.0)
    width, height = camera.size
    if count < 2 or 2.0 * radius / RESOLUTION <= 2.0 * focus * tan_half / height:  # a texel ≤ a pixel: one view
        return []
    depth = float(np.dot(centre - eye, forward))
    z1 = depth + radius
    if z1 > CASCADE_RANGE * focus:  # a scene far deeper than the view's point of interest (ground to the horizon):
        z0, z1 = focus / math.sqrt(CASCADE_RANGE), focus * math.sqrt(CASCADE_RANGE)  # slices around the focus
    else:
        z0 = max(depth - radius, z1 / CASCADE_RANGE, clip_planes_of_sphere(eye, centre, radius)[0])
    if z1 <= z0:
        return []
    k2 = tan_half**2 * (1.0 + (width / height) ** 2)  # (distance of a corner from the axis / depth)²
    splits = z0 * (z1 / z0) ** (np.arange(count + 1) / count)
    spheres = []
    for a, b in zip(splits[:-2], splits[1:-1], strict=True):
        # the smallest sphere centred on the axis through the slice's eight corners (camera rotations keep it)
        z = min(b, 0.5 * (a + b) * (1.0 + k2))
        r = math.sqrt(max((z - a) ** 2 + a * a * k2, (b - z) ** 2 + b * b * k2))
        if r >= 0.5 * radius:
            break
        spheres.append((eye + forward * z, r))
    return spheres


def snap_to_texels(direction: np.ndarray, centre: np.ndarray, radius: float, resolution: int):
    """A cascade's sphere with its radius rounded up to an eighth of an octave and its centre moved onto the
    texel grid of its view: as the camera moves, texels stay where they were (no shimmering shadow edges)."""
    radius = 2.0 ** (math.ceil(8.0 * math.log2(radius)) / 8.0)
    texel = 2.0 * radius / resolution
    d = direction / np.linalg.norm(direction)
    across = look_at(np.zeros(3), d, (0.0, 1.0, 0.0) if abs(d[1]) < 0.99 else (1.0, 0.0, 0.0))[:2, :3]  # right, up
    offsets = across @ centre
    return centre + across.T @ (np.round(offsets / texel) * texel - offsets), radius


def environment_directions(image: np.ndarray, light, count: int = ENV_SAMPLES) -> tuple[np.ndarray, np.ndarray]:
    """World directions drawn ∝ the map's luminance × solid angle at stratified positions of its CDF (pixel
    centres), merged: (directions (K, 3), how many of the ``count`` samples each got, that × the pixel's colour
    over its luminance (K, 3): the sample's weight per channel, so that a yellow sun hidden leaves a blue sky)."""
    h, w, _ = image.shape
    power = (image.astype(np.float64) @ LUMINANCE) * row_solid_angles(h, w)[:, None]
    cdf = np.cumsum(power.ravel())
    if cdf[-1] <= 0:
        return np.zeros((0, 3)), np.zeros(0), np.zeros((0, 3))
    picks = np.searchsorted(cdf / cdf[-1], (np.arange(count) + 0.5) / count, side="right")
    pixels, counts = np.unique(np.minimum(picks, h * w - 1), return_counts=True)
    rows, cols = np.divmod(pixels, w)
    local = equirect_direction((cols + 0.5) / w, (rows + 0.5) / h)
    rgb = image[rows, cols].astype(np.float64)
    colour = rgb / np.maximum(rgb @ LUMINANCE, 1e-30)[:, None]
    return local @ rotation_y(light.rotate_y).T, counts.astype(np.float64), counts[:, None] * colour


def _soft_samples(light, mask, settings: ShadowSettings) -> tuple[np.ndarray, np.ndarray]:
    """The soft-shadow sample points of an area light and their weights dA × mask (zero-weight points dropped);
    PCSS: the emitter's centroid, weighted by its area."""
    poly = light.polygon()
    if settings.design == "pcss":
        points, areas = area_light_samples(poly, 1)
        return (areas @ points / areas.sum())[None], np.array([areas.sum()])
    triangles = len(poly) - 2
    side = settings.side if isinstance(light, QuadLight) else max(1, round(settings.side / math.sqrt(triangles)))
    points, areas = area_light_samples(poly, side)
    if mask is not None:  # a quad: the side × side grid in area_light_samples' order
        t = (np.arange(side) + 0.5) / side
        u, v = np.meshgrid(t, t, indexing="xy")
        areas = areas * mask_lookup(mask, u.ravel(), v.ravel())
    keep = areas > 0
    return points[keep], areas[keep]


def _sample_view(point: np.ndarray, axis: np.ndarray, weight: float, corners: np.ndarray) -> dict:
    """A perspective view from ``point`` along ``axis``, its off-axis frustum fitted to the mesh-box corners in
    front of it (directions clamped at ``MAX_ANGLE`` from the axis)."""
    up = (0.0, 1.0, 0.0) if abs(axis[1]) < 0.99 else (1.0, 0.0, 0.0)
    view = look_at(point, point + axis, up)
    local = corners @ view[:3, :3].T + view[:3, 3]  # view space: the axis is −z
    depth = -local[:, 2]
    far = max(float(depth.max()), 1e-6) * 1.01
    near = max(far * 1e-3, float(depth[depth > 0].min()) * 0.99 if np.any(depth > 0) else far * 1e-3)
    limit = math.tan(math.radians(MAX_ANGLE))
    tangents = np.clip(local[:, :2] / np.maximum(depth, far * 1e-6)[:, None], -limit, limit)
    left, bottom = tangents.min(axis=0)
    right, top = tangents.max(axis=0)
    if not np.any(depth > 0) or right - left < 1e-6 or top - bottom < 1e-6:  # nothing in front: any valid view
        left = bottom = -limit
        right = top = limit
    proj = np.array(
        [
            [2.0 / (right - left), 0.0, (right + left) / (right - left), 0.0],
            [0.0, 2.0 / (top - bottom), (top + bottom) / (top - bottom), 0.0],
            [0.0, 0.0, -(far + near) / (far - near), -2.0 * far * near / (far - near)],
            [0.0, 0.0, -1.0, 0.0],
        ]
    )
    return {
        "view_proj": proj @ view,
        "texel": max(right - left, top - bottom),
        "near_far": (near, far),
        "point": tuple(point),
        "weight": float(weight),
        "axis": tuple(axis),
    }
