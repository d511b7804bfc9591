"""Forward renderer: every mesh × its material × every light, in one pass, into a float32 HDR target.

What it computes, exactly or not:

- point and directional lights: exact direct lighting, shadowed by shadow maps with PCF (``shadows.py``);
- quad and polygon area lights: the midpoint rule of the area-light document (eq 2.8) with ``area_samples``²
  points per quad (per triangle of a polygon fan), shadowed by the light's soft-shadow ratio; converges as
  O(1/n²); the dedicated area-light methods (adaptive, cone, LTC, exact diffuse) come with ``reflets.arealights``;
- environment maps: by default the prefiltered split sum (``ibl.py``: GGX-prefiltered radiance, the irradiance
  map, each material's own specular albedo); ``environment = "grid"``: ``env_grid`` distant lights whose
  powers integrate the map exactly (diffuse-accurate, blurry for sharp lobes; not occluded by the scene);
- the image is one sample per pixel at the pixel centre; ``spp`` = s² gives an s×s stratified supersample;
- a depth pre-pass first for textured meshes (``depth_prepass``): each of their pixels is shaded once, at the
  nearest surface, not once per surface that covers it — same image (tested). Measured on llvmpipe (frame
  time, persistent renderer): the helmet of ``reflets bench assets`` 34 → 26 ms, the gallery's helmet under
  quad lights 147 → 102 ms, the water bottle 25 → 15 ms; on scenes of untextured spheres it cost up to 20 %
  (llvmpipe shades vertices on one thread: a second pass over 150k triangles is not free), so their meshes
  are drawn once as before.

Buffer layouts (std430, vec4 each): points (position, cone scale), (intensity, shadow view + 1), (cone axis, cone
offset) — the cone's t = clamp(cos θ · scale + offset, 0, 1), squared (scale 0, offset 1 without a cone);
directional (unit vector towards the light, irradiance); area samples (point, dA), (light normal, two_sided),
(radiance, 0); environment (direction, radiance × solid angle).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Annotated, ClassVar, Literal, NamedTuple

import moderngl
import numpy as np
from pydantic import Field

from ..equirect import rotation_y
from ..gpu import ProgramSpec, depth, get_program, release_objects, set_uniforms
from ..gpu.frames import copy_image
from ..gpu.targets import TargetCache
from ..scene.camera import projection_matrix, view_eye
from ..scene.emitters import area_light_samples, polygon_normal
from ..scene.environment import environment_grid
from ..scene.geometry import camera_range, mesh_scale
from ..scene.lightmask import mask_lookup
from ..scene.map_emitters import with_map_emitters
from ..scene.meshdata import MeshData
from ..scene.model import DirectionalLight, PointLight, PolygonLight, QuadLight, Scene
from ..scene.transform import look_at
from .base import (
    Technique,
    TechniqueParams,
    register_technique,
    samples_per_pixel_side,
)
from .ibl import IBL_FLAGS
from .prepared import PreparedScene
from .shading import MaterialShading, shading_for
from .shadows import CASCADES, DEPTH_PROGRAM, SHADOW_SAMPLERS, ShadowSettings

_SHADERS = "reflets/techniques/shaders/"
#: compile-time light counts of lights.glsl (every program that includes it declares them)
LIGHT_FLAGS = (
    frozenset(
        {
            "N_POINT",
            "N_DIR",
            "N_AREA",
            "N_AREA_LIGHTS",
            "N_ENV",
            "SHADOW_VIEWS",
            "ENV_VIEWS",
            "ENV_FULL",
            "ENV_CHECKERBOARD",
        }
    )
    | IBL_FLAGS
)
MESH_VERT = _SHADERS + "mesh.vert"
MESH_PROGRAM = ProgramSpec(
    "forward",
    vertex=MESH_VERT,
    fragment=_SHADERS + "forward.frag",
    flags=frozenset({"OUTPUT"}) | LIGHT_FLAGS,
)
BACKGROUND_PROGRAM = ProgramSpec(
    "background", vertex=_SHADERS + "background.vert", fragment=_SHADERS + "background.frag"
)
#: one side of the environment grid (nu or nv): 1…1024 distant lights
GridSide = Annotated[int, Field(ge=1, le=1024)]
#: the prefiltered environment's occlusion: each pixel looks up half the directions and borrows the other half
#: from its neighbours (shaders/shadows.glsl), or looks up every one
EnvironmentOcclusion = Annotated[
    Literal["checkerboard", "every-pixel", "none"],
    Field(
        description="the environment's shadow lookups: half per pixel (checkerboard), all of them, or none (the "
        "map unoccluded by the scene, as Filament and three.js light it)"
    ),
]
TextureAnisotropy = Annotated[
    float,
    Field(
        ge=1.0,
        le=16.0,
        allow_inf_nan=False,
        description="material textures' anisotropic filtering (1: trilinear only, as Filament and three.js leave "
        "glTF textures; free on GPUs, about a third of a textured frame on llvmpipe)",
    ),
]
CASCADES_HELP = "directional lights: at most n shadow views, cascades over the camera's view and the whole scene's"
_OUTPUTS = {"radiance": 0, "position": 1, "normal": 2, "uv": 3, "samples": 4}  # samples: the area-light methods


class ForwardParams(TechniqueParams):
    """Parameters of the forward renderer."""

    area_samples: int = Field(8, ge=1, le=64, description="n: n×n midpoint samples per quad light")
    soft_shadows: Literal["ratio", "pcss"] = Field(
        "ratio", description="area lights' soft shadows: the ratio estimator over sample views, or PCSS"
    )
    shadow_samples: int = Field(4, ge=1, le=8, description="ratio: n×n shadow views per quad light")
    shadow_cascades: int = Field(CASCADES, ge=1, le=8, description=CASCADES_HELP)
    env_grid: tuple[GridSide, GridSide] = Field((32, 16), description="environment map as nu × nv distant lights")
    environment: Literal["prefiltered", "grid"] = Field(
        "prefiltered", description="environment lighting: prefiltered split sum (ibl.py) or the env_grid lights"
    )
    environment_occlusion: EnvironmentOcclusion = "checkerboard"
    texture_anisotropy: TextureAnisotropy = 16.0
    output: Literal["radiance", "position", "normal", "uv"] = "radiance"


def shadow_settings(params) -> ShadowSettings:
    """The soft-shadow settings of a technique's (or ``auto``'s) parameters."""
    return ShadowSettings(params.soft_shadows, params.shadow_samples, params.shadow_cascades)


#: the texture units of a transmissive draw's frame copy (colour, depth): above the shadow maps (10, 11, 16), Fermat's
#: G-buffer (12–15) and the prefiltered environment (17, 18)
BEHIND_UNITS = (19, 20)
#: the units of a material's own textures (its maps, tables…), around the fixed ones above: a glTF material may
#: have 15 textures and its tables (unit 0: the environment or a cut-out's base colour)
MATERIAL_UNITS = (*range(1, 10), *range(21, 48))


def bind_material_textures(textures: dict) -> dict[str, int]:
    """Bind a draw's material textures to :data:`MATERIAL_UNITS`; their sampler uniforms."""
    if len(textures) > len(MATERIAL_UNITS):  # a glTF material has at most 15 textures and 3 tables
        raise RuntimeError(f"{len(textures)} textures in one draw; at most {len(MATERIAL_UNITS)} units")
    for unit, texture in zip(MATERIAL_UNITS, textures.values(), strict=False):
        texture.use(unit)
    return dict(zip(textures, MATERIAL_UNITS, strict=False))


@dataclass(frozen=True)
class PassRole:
    """What a technique draws when a composed frame (``reflets.renderer.compose``) shares the target with
    other techniques; the default is a whole frame."""

    meshes: frozenset[int] | None = None  # meshes this technique shades (None: all)
    clear: bool = True  # clear colour and depth first
    extras: bool = True  # draw the emitters and the background after the meshes (and a technique's own passes)
    additive: bool = False  # add onto surfaces already drawn (more lights on the same meshes): depth ≤, blend +

    def shades(self, index: int) -> bool:
        return self.meshes is None or index in self.meshes


WHOLE_FRAME = PassRole()


class MeshDraw(NamedTuple):
    """How one mesh is shaded: its program and vertex array, uniforms, textures (the material's, ``filtered``
    those whose sampling the renderer's ``texture_anisotropy`` sets; the shading's own), its shading, and its
    depth pre-pass vertex array (None: drawn once, writing its depths)."""

    program: object
    vao: object
    uniforms: dict
    material_textures: dict
    own_textures: dict
    shading: MaterialShading | None
    depth_vao: object
    filtered: list
    centre: np.ndarray | None = None  # a see-through mesh's bounding-box centre (the back-to-front order); else None
    transmission: int = 0  # its material's BRDF_GLTF_TRANSMISSION (1: thin-walled, 2: a volume; 0: none)


@register_technique
class Forward(Technique):
    """Direct lighting by forward shading (the engine's baseline; see the module docstring)."""

    name: ClassVar[str] = "forward"
    summary: ClassVar[str] = "forward shading: point/directional exact, area lights by midpoint grid"
    Params: ClassVar[type[TechniqueParams]] = ForwardParams

    #: the part of a frame this technique draws (a composed frame sets it before ``prepare``)
    role: PassRole = WHOLE_FRAME

    #: depths first, then each pixel shaded once at the nearest surface (EQUAL-or-nearer, no depth writes): the
    #: textured meshes whose program has mesh.vert's positions (the same vertex stage, ``invariant``) and no
    #: cut-out (module docstring: where it pays)
    depth_prepass: ClassVar[bool] = True

    #: GPU state shared with the other passes of a composed frame (``auto`` sets it before ``prepare``; None: the
    #: technique prepares and releases its own)
    shared: PreparedScene | None = None

    def __init__(self, ctx, **params):
        super().__init__(ctx, **params)
        self._behind = TargetCache()  # the frame copy transmissive surfaces read (``_behind_copy``)

    def prepare(self, scene: Scene) -> None:
        ctx = self.ctx
        self.release()
        scene = with_map_emitters(scene)  # an environment's sun as a light (a composed frame's passes: done already)
        self.scene = scene
        self._objects = []
        self.prepared = (
            self.shared if self.shared is not None else PreparedScene(ctx, scene, shadow_settings(self.params))
        )
        self._owns_prepared = self.shared is None

        points_l, dirs, area = [], [], []
        runs = []  # per area light with samples: (first sample, sample count, soft-shadow code, 0)
        shadows = self.prepared.shadows
        for light in scene.light:  # w of a delta light's second row: its first shadow view + 1 (0: no shadow)
            if isinstance(light, PointLight):
                cone = light.spot  # an isotropic light: scale 0, offset 1 (a factor of 1 everywhere)
                scale, offset = cone.scale_offset() if cone is not None else (0.0, 1.0)
                axis = cone.axis if cone is not None else (0.0, 0.0, 0.0)
                points_l += [(*light.position, scale), (*light.intensity, shadows.view_index(light) + 1.0),
                             (*axis, offset)]  # fmt: skip
            elif isinstance(light, DirectionalLight):
                d = -np.asarray(light.direction, dtype=np.float64)
                dirs += [
                    (*(d / np.linalg.norm(d)), shadows.cascade_count(light)),
                    (*light.irradiance, shadows.view_index(light) + 1.0),
                ]
            elif isinstance(light, QuadLight | PolygonLight):
                rows = self.area_light_rows(light)
                if rows:
                    runs.append((len(area) // 3, len(rows) // 3, shadows.soft_code(light), 0.0))
                area += rows
        env = []
        self._ibl = None
        if scene.environment is not None and self.params.environment == "prefiltered":
            self._ibl = self.prepared.prefiltered_environment()
        elif scene.environment is not None:
            env_dirs, env_power = environment_grid(self.prepared.environment, scene.environment, self.params.env_grid)
            keep = np.any(env_power > 0, axis=1)
            for d, pw in zip(env_dirs[keep], env_power[keep], strict=True):
                env += [(*d, 0.0), (*pw, 0.0)]
        polygons = self.polygon_rows(scene)
        # Light counts are compile-time constants: llvmpipe executes a loop's body (masked) even for zero
        # iterations, so a loop over an absent light type cost as much as one light (measured: 3 empty loops
        # with a GGX BRDF doubled the frame time of one point light).
        self._light_flags = {
            "N_POINT": len(points_l) // 3,
            "N_DIR": len(dirs) // 2,
            "N_AREA": len(area) // 3,
            "N_AREA_LIGHTS": len(runs),
            "N_ENV": len(env) // 2,
            "SHADOW_VIEWS": shadows.view_count,
            **(self._ibl.flags() if self._ibl is not None else {"ENV_IBL": 0}),
            "ENV_VIEWS": shadows.environment_views[1]
            if self._ibl is not None and shadows.environment_views and self.params.environment_occlusion != "none"
            else 0,
            "ENV_FULL": shadows.environment_full,
            "ENV_CHECKERBOARD": int(self.params.environment_occlusion == "checkerboard"),
            **self.extra_light_flags(polygons),
        }
        self._light_buffers = [self._ssbo(rows) for rows in (points_l, dirs, area, env, polygons)]
        self._light_uniforms = {"u_area_runs": np.asarray(runs, np.float32).tobytes()} if runs else {}
        if self._light_flags["ENV_VIEWS"]:
            self._light_uniforms.update(shadows.environment_uniforms)

        self.shadings = self.material_shadings(scene)
        self._draws = []
        for index, mesh in enumerate(scene.mesh):
            if not self.role.shades(index):
                self._draws.append(None)  # another pass of a composed frame shades this mesh
                continue
            self._draws.append(self._mesh_draw(index, scene.materials[mesh.material]))
        self._shaded = [draw for draw in self._draws if draw is not None]
        self._early = {k for k, draw in enumerate(self._shaded) if draw.depth_vao is not None}
        self._blended = [k for k, draw in enumerate(self._shaded) if draw.centre is not None]
        self._depth_program = get_program(ctx, DEPTH_PROGRAM) if self._early else None

        self._background = get_program(ctx, BACKGROUND_PROGRAM)
        self._background_vao = ctx.vertex_array(self._background, [])
        self._objects.append(self._background_vao)
        self._near, self._far = camera_range(scene.camera, self.prepared.boxes)

    def _mesh_draw(self, index: int, material) -> MeshDraw:
        """How one mesh is drawn: with the shading of its material's type, or this technique's own BRDF shading."""
        ctx = self.ctx
        shading = shading_for(material, self.shadings)
        spec = self.program_spec if shading is None else shading.program
        # no caster can darken this mesh (from a light, from a view of the environment): those lookups compiled out —
        # for an opaque surface of the technique's own shading, lit from its side of the geometry only (a
        # see-through or cut-out one shows its inside, light crosses a transmissive or translucent one, a normal
        # map or scratches' walls take light from past the geometric horizon: a convex mesh can shadow itself there)
        shadows = self.prepared.shadows
        opaque = shading is None and not material.see_through and not material.cutout and not material.bends_normals
        unoccluded = ({} if not opaque else {"SHADOW_VIEWS": 0, "ENV_VIEWS": 0} if not shadows.shadowed(index)
                      else {"ENV_VIEWS": 0} if not shadows.environment_occludes(index) else {})  # fmt: skip
        if shading is None:
            program = get_program(ctx, self.program_spec, slots=self.slots(material),
                                  **{**self.flags(material), **unoccluded})  # fmt: skip
            uniforms = {**material.uniforms(), **self.material_uniforms(material)}
            own_textures = self.material_textures(material)
        else:
            flags = {**self.pass_flags(), **material.flags(), **shading.flags(material)}  # (no culling: not opaque)
            program = get_program(ctx, shading.program, slots=shading.slots(material), **flags)
            uniforms = {**material.uniforms(), **shading.uniforms(material)}
            own_textures = shading.textures(material)
        vao = self.mesh_vertex_array(program, index)
        if self._ibl is not None:
            uniforms.update(self._ibl.uniforms(material if shading is None else shading.ibl_material(material)))
        textures = material.textures(ctx)
        # the images (not the split-sum table): their anisotropy is set at each draw, the textures being shared by
        # a context's renderers, each with its own texture_anisotropy
        filtered = [texture for texture in textures.values() if texture.filter[0] == moderngl.LINEAR_MIPMAP_LINEAR]
        early = (self.depth_prepass and material.textured and spec.vertex == MESH_VERT and not material.cutout
                 and not material.see_through and not self.role.additive)  # fmt: skip
        depth_vao = self.mesh_vertex_array(get_program(ctx, DEPTH_PROGRAM), index) if early else None
        centre = self.prepared.boxes[index].mean(axis=0) if material.see_through else None
        transmission = material.flags().get("BRDF_GLTF_TRANSMISSION", 0) if shading is None else 0
        if transmission:
            uniforms["u_thickness_scale"] = mesh_scale(self.scene, index)
        return MeshDraw(program, vao, uniforms, textures, own_textures, shading, depth_vao, filtered, centre,
                        transmission)  # fmt: skip

    # ------------------------------------------------------------------ how this technique shades
    def material_shadings(self, scene: Scene) -> list[MaterialShading]:
        """The shadings of the material types this technique exists for (translucent, scratched…); every
        other material gets the technique's own BRDF shading (``program_spec``, ``slots``, ``flags``,
        ``material_uniforms``, ``material_textures``). None here."""
        return []

    #: the program of the technique's own BRDF shading (the area-light methods swap the fragment stage)
    program_spec: ClassVar[ProgramSpec] = MESH_PROGRAM

    def slots(self, material) -> dict[str, str]:
        """GLSL include slots of the BRDF shading's program for one material."""
        return {"BRDF": material.brdf_source}

    def pass_flags(self) -> dict[str, object]:
        """Flags every mesh program of this pass takes: the output and the light counts."""
        return {"OUTPUT": _OUTPUTS[self.params.output], **self._light_flags}

    def flags(self, material) -> dict[str, object]:
        return {**self.pass_flags(), **material.flags()}

    def material_uniforms(self, material) -> dict[str, object]:
        """Per-draw uniforms a technique adds for a material (besides the material's own)."""
        return {}

    def material_textures(self, material) -> dict[str, object]:
        """Per-draw textures the BRDF shading adds for a material, by sampler uniform name (bound after the
        material's own, from texture unit 1 on); the technique releases them (e.g. via ``self._objects``)."""
        return {}

    def area_light_rows(self, light) -> list[tuple]:
        """Rows of the area-sample buffer (binding 2) for one area light: the midpoint rule here."""
        poly = light.polygon()
        nl = polygon_normal(poly)
        n = self.params.area_samples
        pts, dA = area_light_samples(poly, n)
        weight = np.ones(len(pts))
        mask = self.prepared.mask_of(light)
        if mask is not None:  # a quad: the n × n grid in area_light_samples' order; masked-out samples dropped
            t = (np.arange(n) + 0.5) / n
            u, v = np.meshgrid(t, t, indexing="xy")
            weight = mask_lookup(mask, u.ravel(), v.ravel())
        rows = []
        for y, a, m in zip(pts, dA, weight, strict=True):
            if m > 0.0:
                rows += [(*y, a), (*nl, float(light.two_sided)), (*(m * np.asarray(light.radiance)), 0.0)]
        return rows

    def polygon_rows(self, scene: Scene) -> list[tuple]:
        """Rows of the polygon-light buffer (binding 4), used by the area-light techniques; none here."""
        return []

    def extra_light_flags(self, polygon_rows: list[tuple]) -> dict[str, int]:
        """Compile-time light counts a technique adds (the area-light methods: N_POLYGONS)."""
        return {}

    def frame_uniforms(self, frame: int, seed: int) -> dict[str, object]:
        """Uniforms that change per frame (progressive techniques: frame index and seed)."""
        return {}

    def frames(self, spp: int) -> tuple[int, int]:
        """(frames to accumulate, supersampling side s) for a requested spp; deterministic techniques
        anti-alias with s×s samples."""
        return 1, samples_per_pixel_side(spp)

    def screen_bytes_per_sample(self) -> int:
        """Bytes per target sample of this pass's own images at the target size, beyond the frame's
        (FRAME_BYTES_PER_SAMPLE): its shadings' screen maps (a technique adds its G-buffer)."""
        return sum(getattr(shading, "screen_bytes_per_sample", 0) for shading in getattr(self, "shadings", []))

    def mesh_vertex_array(self, program, mesh: int | MeshData, extra: tuple = (), indexed: bool = True):
        """A vertex array of mesh ``mesh`` (a scene index: the prepared scene's buffers; or any ``MeshData``) for a
        program of mesh.vert's layout, owned by this technique (``PreparedScene.vertex_array``)."""
        vao = self.prepared.vertex_array(program, mesh, extra, indexed)
        self._objects.append(vao)
        return vao

    def _ssbo(self, rows: list[tuple]):
        data = np.asarray(rows, dtype=np.float32).reshape(-1, 4) if rows else np.zeros((1, 4), np.float32)
        buf = self.ctx.buffer(data.tobytes())
        self._objects.append(buf)
        return buf

    def camera_matrices(self, width: int, height: int) -> tuple[np.ndarray, np.ndarray]:
        """(view, projection) for the scene camera at the given image size (row-major NumPy)."""
        cam = self.scene.camera
        view = look_at(cam.position, cam.look_at, cam.up)
        proj = projection_matrix(cam, width, height, self._near, self._far)
        return view, proj

    def set_camera(self, camera) -> bool:
        """Move the camera without preparing again: only the clip planes depend on it, and the directional
        lights' shadow cascades (refitted by whoever made the prepared scene)."""
        if self._owns_prepared and not self.prepared.shadows.set_camera(camera):
            return False
        self.scene = self.scene.model_copy(update={"camera": camera})
        self._near, self._far = camera_range(camera, self.prepared.boxes)
        return True

    def _draw(self, target, view_proj, vp_bytes, frame: int, seed: int) -> None:
        for shading in self.shadings:  # what the meshes read: light views, screen-space maps
            shading.draw_inputs(target, vp_bytes)
        with depth.camera_depth(self.ctx):
            self._draw_camera(target, vp_bytes, view_proj, frame, seed)

    def _bind_lighting(self) -> None:
        """This pass's lights, shadow views and prefiltered environment where its programs read them (another
        pass of the same frame binds its own there)."""
        for i, buf in enumerate(self._light_buffers):
            buf.bind_to_storage_buffer(i)
        self.prepared.shadows.bind()
        if self._ibl is not None:
            self._ibl.bind()

    def _draw_camera(self, target, vp_bytes, view_proj, frame: int, seed: int) -> None:
        """The meshes, emitters and background from the camera (reversed-Z: ``reflets.gpu.depth``)."""
        ctx = self.ctx
        role = self.role
        radiance = self.params.output == "radiance"  # AOVs keep 0 where no surface is seen
        color = self.scene.background_color() if radiance else (0.0, 0.0, 0.0)
        if role.clear:
            target.use(clear=(*(color if color is not None else (0.0, 0.0, 0.0)), 1.0))  # a constant background
        else:
            target.bind()
        ctx.enable(ctx.DEPTH_TEST)
        ctx.disable(ctx.CULL_FACE)
        if role.additive:  # the same surfaces again, lit by other lights: add where the depth is equal
            ctx.depth_func = depth.NEARER_OR_EQUAL
            target.fbo.depth_mask = False
            ctx.enable(ctx.BLEND)
            ctx.blend_func = moderngl.ONE, moderngl.ONE
        self._bind_lighting()
        early = self._depth_prepass(target, vp_bytes)
        eye = view_eye(self.scene.camera)
        per_frame = {"u_view_proj": vp_bytes, "u_eye": eye, **self.frame_uniforms(frame, seed), **SHADOW_SAMPLERS,
                     **self._light_uniforms}  # fmt: skip
        for k, draw in enumerate(self._shaded):
            if draw.centre is not None:
                continue  # blended: over everything else, last
            if early:  # a pre-passed mesh: its depths are there, shade the nearest only
                target.fbo.depth_mask = k not in early
                ctx.depth_func = depth.NEARER_OR_EQUAL if k in early else depth.NEARER
            self._draw_mesh(draw, per_frame, frame, seed)
        if early:
            target.fbo.depth_mask = True
            ctx.depth_func = depth.NEARER
        if role.additive:
            ctx.disable(ctx.BLEND)
            target.fbo.depth_mask = True
            ctx.depth_func = depth.NEARER
        if role.extras:
            self._draw_extras(vp_bytes, view_proj, radiance and color is None)
        if self._blended:
            self._draw_blended(target, eye, view_proj, per_frame, frame, seed)
        ctx.disable(ctx.DEPTH_TEST)

    def _draw_mesh(self, draw: MeshDraw, per_frame: dict, frame: int, seed: int) -> None:
        for texture in draw.filtered:  # shared textures: set once (each set binds the texture)
            if texture.anisotropy != self.params.texture_anisotropy:
                texture.anisotropy = self.params.texture_anisotropy
        samplers = bind_material_textures({**draw.material_textures, **draw.own_textures})
        shading_frame = draw.shading.frame_uniforms(frame, seed) if draw.shading is not None else {}
        set_uniforms(draw.program, {**draw.uniforms, **samplers, **per_frame, **shading_frame})
        draw.vao.render()

    def _draw_blended(self, target, eye, view_proj, per_frame: dict, frame: int, seed: int) -> None:
        """See-through surfaces over everything drawn (the background included), farthest first by their bounding
        boxes' centres (a mesh's own triangles unsorted, as three.js and Filament draw them), their depths written
        as three.js does: glTF BLEND ones blended by their coverage; transmissive ones (transmission.glsl) reading
        a copy of the frame drawn so far — a thin-walled mesh's far side first, copied again, then its near side
        (both are surfaces the light crosses); a volume's near side only (its far side is the volume's exit)."""
        ctx = self.ctx  # never an additive pass: a see-through (glTF) material's meshes are the BRDF pass's
        distance = {k: float(np.linalg.norm(self._shaded[k].centre - eye)) for k in self._blended}
        inverse = None  # the inverse view-projection the transmissive draws read depths with
        ctx.enable(ctx.BLEND)  # a L + (1 - a) L_behind (a transmissive surface: a = 1 unless it is BLEND too)
        ctx.blend_func = moderngl.SRC_ALPHA, moderngl.ONE_MINUS_SRC_ALPHA, moderngl.ZERO, moderngl.ONE
        for k in sorted(self._blended, key=distance.get, reverse=True):
            draw = self._shaded[k]
            if not draw.transmission:
                self._draw_mesh(draw, per_frame, frame, seed)
                continue
            inverse = inverse or np.linalg.inv(view_proj).T.astype(np.float32).tobytes()
            ctx.enable(ctx.CULL_FACE)
            for culled in ("front", "back") if draw.transmission == 1 else ("back",):
                behind = self._behind_copy(target)
                behind.color.use(BEHIND_UNITS[0])
                behind.depth.use(BEHIND_UNITS[1])
                ctx.cull_face = culled
                self._draw_mesh(draw, {**per_frame, "u_inv_view_proj": inverse, "u_behind": BEHIND_UNITS[0],
                                       "u_behind_depth": BEHIND_UNITS[1]}, frame, seed)  # fmt: skip
            ctx.cull_face = "back"
            ctx.disable(ctx.CULL_FACE)
        ctx.disable(ctx.BLEND)

    def _behind_copy(self, target):
        """The frame drawn so far (colour with its mips, and depth), for a transmissive surface to read."""
        fresh = self._behind.target is None or self._behind.target.size != target.size
        behind = self._behind.get(self.ctx, *target.size)
        if fresh:
            behind.color.filter = moderngl.LINEAR_MIPMAP_LINEAR, moderngl.LINEAR
            behind.depth.compare_func = ""  # read as numbers, not compared
            behind.depth.filter = moderngl.NEAREST, moderngl.NEAREST
            for texture in (behind.color, behind.depth):  # off the screen: its edge, not the other side
                texture.repeat_x = texture.repeat_y = False
        ctx = self.ctx
        copy_image(ctx, behind.fbo, target.size, target.color, target.depth)  # a depth blit: a CPU copy on llvmpipe
        behind.color.build_mipmaps()
        target.bind()  # and the state of _draw_blended's transmissive draws again
        ctx.enable(ctx.BLEND | ctx.DEPTH_TEST | ctx.CULL_FACE)
        ctx.blend_func = moderngl.SRC_ALPHA, moderngl.ONE_MINUS_SRC_ALPHA, moderngl.ZERO, moderngl.ONE
        ctx.depth_func = depth.NEARER
        return behind

    def _draw_extras(self, vp_bytes: bytes, view_proj: np.ndarray, background: bool) -> None:
        """The area lights' emitting faces and the environment behind everything."""
        ctx = self.ctx
        for emitter_program, vao, light, mask in self.prepared.emitters if self.params.output == "radiance" else []:
            if mask is not None:
                mask.use(1)
            set_uniforms(
                emitter_program,
                {
                    "u_view_proj": vp_bytes,
                    "u_radiance": tuple(light.radiance),
                    "u_two_sided": bool(light.two_sided),
                    "u_mask": 1,
                },
            )
            vao.render()
        if background:
            # The environment last, only where the depth buffer is still clear (llvmpipe then skips the
            # covered pixels: a full-screen background pass first cost 4× the clear at 800×600).
            ctx.depth_func = depth.NEARER_OR_EQUAL
            self._draw_background(view_proj)
            ctx.depth_func = depth.NEARER

    def _depth_prepass(self, target, vp_bytes: bytes) -> set[int]:
        """Draw the depths of the meshes that take a pre-pass (colour writes off); their indices in ``_shaded``."""
        if not self._early:
            return self._early
        set_uniforms(self._depth_program, {"u_view_proj": vp_bytes})
        target.fbo.color_mask = (False, False, False, False)
        for k in self._early:
            self._shaded[k].depth_vao.render()
        target.fbo.color_mask = (True, True, True, True)
        return self._early

    def _draw_background(self, view_proj: np.ndarray) -> None:
        """The environment map along every camera ray (a full-screen triangle at the far plane)."""
        rot = rotation_y(self.scene.environment.rotate_y)
        self.prepared.background_texture.use(0)
        # the projection of directions only (the eye moved to the origin): rays without the cancellation of a
        # near-plane point minus the eye in float32
        to_eye = np.eye(4)
        to_eye[:3, 3] = self.scene.camera.position
        if self.scene.camera.orthographic:  # every ray looks along the view: a pinhole 1e-4° wide shows it
            cam = self.scene.camera.model_copy(update={"projection": "perspective", "fov_y": 1e-4})
            width, height = cam.size
            view_proj = projection_matrix(cam, width, height, 1.0) @ look_at(cam.position, cam.look_at, cam.up)
        uniforms = {
            "u_inv_view_proj": np.linalg.inv(view_proj @ to_eye).T.astype(np.float32).tobytes(),
            "u_env_from_world": rot.astype(np.float32).tobytes(),  # R^T: column-major bytes of row-major R
            "u_env": 0,
        }
        set_uniforms(self._background, uniforms)
        self._background_vao.render(vertices=3)

    def release(self) -> None:
        for shading in getattr(self, "shadings", []):
            shading.release()
        self.shadings = []
        release_objects(self.ctx, getattr(self, "_objects", []))
        self._objects = []
        if getattr(self, "_owns_prepared", False):
            self.prepared.release()
        self._owns_prepared = False
        super().release()  # the frame target and the frame sum
        self._behind.release()


def _aov(name: str, summary: str) -> type[Forward]:
    """A forward variant that writes a geometry buffer instead of radiance (tests, debugging)."""

    def __init__(self, ctx, **params):
        Forward.__init__(self, ctx, **{**params, "output": name})

    cls = type(
        f"{name.capitalize()}AOV",
        (Forward,),
        {"name": name, "summary": summary, "__init__": __init__, "__doc__": summary},
    )
    return register_technique(cls)


PositionAOV = _aov("position", "AOV: world-space position per pixel")
NormalAOV = _aov("normal", "AOV: shading normal per pixel (facing the camera)")
UvAOV = _aov("uv", "AOV: texture coordinates per pixel")
