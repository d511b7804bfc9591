"""``fermat``: exact specular reflections in curved smooth reflectors, per vertex (Roger & Holzschuch 2005).

Instead of an environment map (exact only for objects at infinity), every scene vertex V is moved to its
reflection point P on the reflector — the stationary point of the path length |E − f(u, v)| + |V − f(u, v)|
(Fermat's principle) — and the rasteriser draws the mirror image of the scene between reflected vertices.
Exact at vertices, with correct parallax at any distance; edges between vertices stay straight on screen
(``subdivide`` splits every reflected triangle into k² so that they bend).

Passes per frame (the document's §3.2, with its silhouette problem fixed):

1. the scene as ``forward`` renders it (reflectors show their non-specular part);
2. a G-buffer of the nearest surface per pixel: world position, reflector id, normal;
3. per reflector, the scene without reflectors drawn at each vertex's reflection point, found by the solver
   (``solve.vert``, by transform feedback once per eye position; ``reflected.vert`` draws from it;
   ``solver = "robust"``: Newton steps with the analytic Hessian in a local chart, residual check
   and rejection of back-facing / non-existent reflections; ``"document"``: the document's triangle-secant
   iteration), depth |PV| (level-1 visibility: the object nearest to the mirror wins); fragments are kept only
   on this reflector's visible pixels (an exact id test: linearly interpolated triangles spill past the
   silhouette, which the document's "behind" test alone does not reject) and when P is not behind the
   visible surface (level 2); they are lit with the eye at P;
4. composite: reflectance (constant or conductor Fresnel) × the reflected image — or the background along the
   mirror direction where no reflected geometry was drawn — added onto pass 1.

Reflectors: ``reflector = true`` meshes with a ``mirror`` material, of shape sphere (with any transform: an
ellipsoid), torus, open cylinder (``caps = false``) or plane, solved on their exact parametric surface.
Limits (as in the document): one reflection per vertex (a vertex with several reflection points shows one),
reflectors do not appear in reflections. Shadows: the forward pass's shadow maps light the reflected objects too.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import ClassVar, Literal, NamedTuple

import moderngl
import numpy as np
from pydantic import Field

from ..errors import ArgumentError
from ..gpu import ProgramSpec, depth, get_program, release_objects, set_uniforms
from ..gpu.frames import copy_image
from ..resources import check, largest_fitting
from ..scene.emitters import polygon_normal
from ..scene.geometry import bounding_sphere, mesh_data
from ..scene.lightmask import quad_uv
from ..scene.map_emitters import with_map_emitters
from ..scene.meshdata import MeshData
from ..scene.model import CylinderMesh, PlaneMesh, PolygonLight, QuadLight, Scene, SphereMesh, TorusMesh
from ..scene.surfaces import SampledSurface
from ..scratches.lobes import LOBE_FLAGS, ScratchLobes
from ..techniques.base import register_technique
from ..techniques.forward import LIGHT_FLAGS, Forward, ForwardParams, bind_material_textures
from ..techniques.shading import shading_for
from ..techniques.shadows import SHADOW_SAMPLERS
from .scene import canonical_surface
from .solver import SOLVERS, SURFACE_KINDS, glsl_constants

SHADERS = "reflets/reflections/shaders/"
MESH_VERT = "reflets/techniques/shaders/mesh.vert"
SOLVER_FLAGS = frozenset({"SURFACE_KIND", "SOLVER", "ITERATIONS", "COUNT_ITERATIONS"})
GBUFFER_PROGRAM = ProgramSpec("fermat_gbuffer", vertex=MESH_VERT, fragment=SHADERS + "gbuffer.frag")
REFLECTED_PROGRAM = ProgramSpec(
    "fermat_reflected",
    vertex=SHADERS + "reflected.vert",
    fragment=SHADERS + "reflected.frag",
    flags=LIGHT_FLAGS | LOBE_FLAGS | {"REFLECTED_EMITTER", "EMITTER_MASK", "SCRATCHED"},
    constants=glsl_constants(),
)
SOLVE_PROGRAM = ProgramSpec(
    "fermat_solve",
    vertex=SHADERS + "solve.vert",
    flags=SOLVER_FLAGS,
    constants=glsl_constants(),
    varyings=("t_mirror",),
)
COMPOSITE_PROGRAM = ProgramSpec(
    "fermat_composite",
    vertex="reflets/techniques/shaders/background.vert",
    fragment=SHADERS + "composite.frag",
    flags=frozenset({"BACKGROUND_ENV"}),
)
POINTS_PROGRAM = ProgramSpec(
    "fermat_points",
    vertex=SHADERS + "points.vert",
    flags=SOLVER_FLAGS,
    constants=glsl_constants(),
    varyings=("t_position", "t_normal", "t_valid", "t_residual", "t_iterations"),
)
#: SURFACE_KIND values of solver.glsl
DEFAULT_ITERATIONS = {"robust": 8, "document": 5}
#: texture units of the G-buffer and reflection images (materials use 1…, the environment 0); the uvs' after the
#: material units (forward.MATERIAL_UNITS): the composite reads a mirror's maps
GBUFFER_UNITS = (12, 13, 14, 48)
#: texture unit of a sampled reflector's node grid
GRID_UNIT = 15


#: the coarse grid of the segment hit on sampled reflectors (NumPy twin: SampledSurface.hit_grid)
SAMPLED_HIT_GRID = 8
#: node grid of a reflector sampled into a texture when the scene does not say
DEFAULT_SAMPLES = 64


@dataclass(frozen=True)
class Reflector:
    """One reflector mesh as the solver sees it: canonical shape (kind, parameters, or a sampled grid) and
    world transform x → A x + t."""

    index: int
    kind: str
    params: tuple[float, float, float, float]
    linear: np.ndarray
    offset: np.ndarray
    sampled: SampledSurface | None = None

    def uniforms(self) -> dict[str, object]:
        out = {
            "r_linear": self.linear.T.astype(np.float32).tobytes(),  # column-major
            "r_inverse": np.linalg.inv(self.linear).T.astype(np.float32).tobytes(),
            "r_offset": tuple(float(c) for c in self.offset),
            "r_params": self.params,
        }
        if self.sampled is not None:
            s = self.sampled
            out.update(
                {
                    "r_nodes": (int(s.positions.shape[1]), int(s.positions.shape[0])),
                    "r_periodic": tuple(int(p) for p in s.periodic),
                    "r_interior": tuple(float(c) for c in s.interior),
                    "r_orientation": float(s.orientation),
                    "r_hit_grid": int(s.hit_grid),
                }
            )
        return out

    def grid_texture(self, ctx):
        """The padded node grid (GridInterpolator's) as an RGB float texture, or None for analytic kinds."""
        if self.sampled is None:
            return None
        grid = np.ascontiguousarray(self.sampled._f.grid, dtype=np.float32)  # (n_v + 3, n_u + 3, 3)
        texture = ctx.texture((grid.shape[1], grid.shape[0]), 3, grid.tobytes(), dtype="f4")
        texture.filter = (moderngl.NEAREST, moderngl.NEAREST)
        return texture


def sampled_surface(surface, samples: int) -> SampledSurface:
    """A canonical surface sampled on ``samples``² nodes as the GPU stores it (bicubic, coarse hit grid)."""
    out = SampledSurface.from_surface(surface, samples, "bicubic")
    out.hit_grid = SAMPLED_HIT_GRID
    return out


def reflector_of(scene: Scene, index: int, samples: int | None = None) -> Reflector:
    """The parametric surface of ``scene.mesh[index]``: analytic for sphere, torus, cylinder and plane unless
    ``samples`` asks for a sampled texture; sampled for every other shape reflets.reflections knows (Bézier
    and height-field patches); a clear error otherwise."""
    mesh = scene.mesh[index]
    m = mesh.transform.matrix()
    linear, offset = m[:3, :3].copy(), m[:3, 3].copy()
    params = None
    if isinstance(mesh, SphereMesh):
        kind, params = "sphere", (mesh.radius, 0.0, 0.0, 0.0)
    elif isinstance(mesh, TorusMesh):
        kind, params = "torus", (mesh.major, mesh.minor, 0.0, 0.0)
    elif isinstance(mesh, CylinderMesh):
        kind, params = "cylinder", (mesh.radius, mesh.height, 0.0, 0.0)
    elif isinstance(mesh, PlaneMesh):
        kind, params = "plane", (mesh.size[0], mesh.size[1], 0.0, 0.0)
    if params is None or samples is not None:
        surface = canonical_surface(mesh, index)  # the scene error for shapes no surface describes
        grid = sampled_surface(surface, samples or DEFAULT_SAMPLES)
        return Reflector(index, "sampled", (0.0, 0.0, 0.0, 0.0), linear, offset, grid)
    return Reflector(index, kind, tuple(float(p) for p in params), linear, offset)


def emitter_mesh(light: QuadLight | PolygonLight) -> MeshData:
    """A polygon light as a fan mesh of mesh.vert's layout (normal = the emitting side; uv = a quad's (u, v), where
    its mask is read)."""
    poly = light.polygon()
    n = polygon_normal(poly)
    t = poly[1] - poly[0]
    t /= np.linalg.norm(t)
    k = np.arange(1, len(poly) - 1)
    uv = np.zeros((len(poly), 2), np.float32)
    return MeshData(
        positions=poly.astype(np.float32),
        normals=np.tile(n, (len(poly), 1)).astype(np.float32),
        tangents=np.tile([*t, 1.0], (len(poly), 1)).astype(np.float32),
        uvs=np.stack(quad_uv(light, poly), axis=-1).astype(np.float32) if isinstance(light, QuadLight) else uv,
        indices=np.stack([np.zeros_like(k), k, k + 1], axis=1).astype(np.uint32),
    )


#: what drawing the reflected meshes adds, whatever their size (llvmpipe's binned scene is bounded)
RASTER_BYTES = 64_000_000


def split_size(triangles: int, vertices: int, k: int) -> tuple[int, int]:
    """(vertices, triangles) of a mesh split k: T (k + 1)(k + 2) / 2 and T k² (edges duplicated per triangle), or
    the mesh itself for k ≤ 1."""
    return (triangles * (k + 1) * (k + 2) // 2, triangles * k * k) if k > 1 else (vertices, triangles)


def subdivision_bytes(meshes: list[tuple[int, int, int]], reflectors: int) -> int:
    """Peak bytes ``Fermat.prepare`` allocates for the reflected meshes, each (T triangles, N vertices, split k),
    drawn once per reflector — an upper bound from the arrays it makes. A mesh split k > 1 has
    V = T (k + 1)(k + 2) / 2 vertices (shared edges duplicated per triangle) and F = T k² triangles; k ≤ 1 draws
    the mesh itself (V = N, F = T, nothing new in NumPy). In bytes:

    - R = 48 V + 12 F: the subdivided ``MeshData`` kept (float32 position 12, normal 12, tangent 16, uv 8; uint32
      indices 12 per triangle);
    - S = max(164 V + 24 F, 140 V + 36 F) + 96 T + 64 (k + 1)²: the peak of ``MeshData.subdivided``, its result
      included (float64 interpolated attributes 88 V, handedness 4 V, int64 indices 24 F, the float64 tangent +
      handedness 32 V before the float32 copies; int64 corners and one attribute's float64 corner values per
      triangle; the barycentric grid) — tracemalloc measures 206–209 B per vertex where this gives 208–231;
    - G = 48 V + 12 F: the vertex and index buffers the GL driver keeps (llvmpipe copies them), uploaded once
      for every reflector, and 16 V per reflector: its solved reflection points (``_solve``);
    - an upload's transients beyond its buffers: max(48 V − 12 F, 12 F) (the interleaved array and its bytes);
    - drawing them: RASTER_BYTES (llvmpipe bins a bounded scene: measured ≤ 51 MB more at any k).

    The peak is the larger of the subdivision phase, max over j of Σ_{i<j} R_i + S_j (meshes split in order), and
    Σ R + Σ G + reflectors · 16 Σ V + max(the largest upload's transients, RASTER_BYTES). Calibrated on the teapot
    scene (``python tools/calibrate_memory.py``): estimate / measured growth of the peak resident memory over k = 1
    is 5.73 / 1.75 / 1.14 at k = 10 / 20 / 40 (93 / 170 / 465 MB estimated; docs/inputs-and-outputs.md)."""
    kept = phase_a = upload = buffers = points = 0
    for t, n, k in meshes:
        v, f = split_size(t, n, k)
        if k > 1:
            phase_a = max(phase_a, kept + max(164 * v + 24 * f, 140 * v + 36 * f) + 96 * t + 64 * (k + 1) ** 2)
            kept += 48 * v + 12 * f
        buffers += 48 * v + 12 * f
        points += 16 * v
        upload = max(upload, 48 * v - 12 * f, 12 * f)
    return max(phase_a, kept + buffers + reflectors * points + max(upload, RASTER_BYTES))


class FermatParams(ForwardParams):
    """Parameters of ``fermat``."""

    solver: Literal["robust", "document"] = Field(
        "robust", description="robust: Newton in a local chart with checks; document: the triangle-secant iteration"
    )
    iterations: int | None = Field(None, ge=1, le=64, description="solver iterations (default 8 robust, 5 document)")
    subdivide: int | Literal["auto"] = Field(
        "auto",
        description="reflected triangles split into k² so reflected edges bend; auto: per mesh, the smallest k "
        "that makes every triangle span at most max_angle seen from the reflector",
    )
    max_angle: float = Field(4.0, gt=0.0, le=90.0, description="subdivide = auto: degrees per reflected triangle")
    sampled: int | None = Field(
        None,
        ge=4,
        le=1024,
        description="solve on every reflector sampled into an N×N float texture (bicubic) instead of its analytic "
        "form; Bézier and height-field reflectors are always sampled (64² unless given)",
    )
    hidden_tolerance: float = Field(
        0.02, ge=0.0, le=1.0, description="how far (× the reflector's radius) P may lie behind the visible surface"
    )


class _Images(NamedTuple):
    """A frame's screen images: the G-buffer, each reflector's reflection image (framebuffer, colour) of the
    reflected meshes that are the same every frame, and a working copy completed each frame (or None)."""

    gbuffer: object
    position: object
    normal: object
    uvs: object
    reflections: list[tuple]
    working: tuple | None


@register_technique
class Fermat(Forward):
    """Per-vertex Fermat reflections in smooth curved reflectors (see the module docstring)."""

    name: ClassVar[str] = "fermat"
    summary: ClassVar[str] = "exact reflections in curved mirrors: per-vertex Fermat search on the GPU"
    Params: ClassVar = FermatParams
    auto_order: ClassVar[int] = 3
    reads_own_images: ClassVar[bool] = True  # each reflection image, composited onto the frame

    def prepare(self, scene: Scene) -> None:
        scene = with_map_emitters(scene)  # as Forward.prepare does: the reflected objects' lights too
        if not any(mesh.reflector for mesh in scene.mesh):
            raise ArgumentError(
                "the fermat method needs a mesh with reflector = true (and a mirror material)", field="mesh"
            )
        if scene.camera.orthographic:  # its reflection paths end at the eye point
            raise ArgumentError("the fermat method needs a perspective camera (its paths end at the eye)",
                                field="camera.projection")  # fmt: skip
        splits = iter(self._check_memory(scene))  # k per reflected mesh, emitters last, in the order drawn below
        super().prepare(scene)
        ctx = self.ctx
        self._lobes = ScratchLobes(self.prepared, scene)  # reflected scratched meshes: their lobes, default sampling
        self._reflectors = [
            reflector_of(scene, i, self.params.sampled) for i, mesh in enumerate(scene.mesh) if mesh.reflector
        ]
        self._grids = [r.grid_texture(ctx) for r in self._reflectors]
        self._objects += [g for g in self._grids if g is not None]
        self._gbuffer_size = None
        meshes = self.prepared.meshes
        ids = {r.index: k + 1 for k, r in enumerate(self._reflectors)}
        bounds = [bounding_sphere(meshes[r.index].positions.astype(np.float64)) for r in self._reflectors]
        gbuffer = get_program(ctx, GBUFFER_PROGRAM)
        self._gbuffer_draws = []  # (vao, reflector id)
        self._reflected_meshes = []  # (mesh data subdivided, material)
        self.subdivisions = []  # k per reflected mesh (emitters last), for reports
        for index, (mesh, data) in enumerate(zip(scene.mesh, meshes, strict=True)):
            self._gbuffer_draws.append((self.mesh_vertex_array(gbuffer, index), float(ids.get(index, 0))))
            if index not in ids:
                k = next(splits)
                self.subdivisions.append(k)
                self._reflected_meshes.append((data.subdivided(k), scene.materials[mesh.material]))
        self._reflected_emitters = []
        points = [data.positions for data in meshes]
        for light in scene.light:
            if isinstance(light, QuadLight | PolygonLight):
                data = emitter_mesh(light)
                points.append(data.positions)
                self._gbuffer_draws.append((self.mesh_vertex_array(gbuffer, data), 0.0))
                k = next(splits)
                self.subdivisions.append(k)
                self._reflected_emitters.append((data.subdivided(k), light))
        self._depth_range = 4.0 * bounding_sphere(np.concatenate(points))[1]
        # per reflector: its draws through the solver (vertex arrays bound to that reflector's programs)
        self._reflection_draws, self._solve_programs, self._solves = [], [], []
        for r in self._reflectors:
            draws, solve_program, solves = self._reflector_draws(r)
            self._reflection_draws.append(draws)
            self._solve_programs.append(solve_program)
            self._solves.append(solves)
        # per reflector: does it reflect a scratched material (new samples each frame)?
        self._scratched = [any(scratched for *_, scratched in draws) for draws in self._reflection_draws]
        self._solved: list[tuple | None] = [None] * len(self._reflectors)  # the eye each one's points are for
        self._composites = []
        for r, (_, size) in zip(self._reflectors, bounds, strict=True):
            material = scene.materials[scene.mesh[r.index].material]
            program = get_program(
                ctx,
                COMPOSITE_PROGRAM,
                slots={"BRDF": material.brdf_source},
                BACKGROUND_ENV=int(scene.background_color() is None),
                **material.flags(),
            )
            vao = ctx.vertex_array(program, [])
            self._objects.append(vao)
            self._composites.append((program, vao, material.uniforms(), material.textures(ctx), size))

    def _check_memory(self, scene: Scene) -> list[int]:
        """Refuse a ``subdivide`` whose reflected meshes would not fit in the available memory (reflets.resources:
        one line naming it, the estimate of :func:`subdivision_bytes`, the limit and the largest k that fits),
        before anything is allocated: the meshes come from the content-keyed cache the prepared scene reads.
        Returns the k of each reflected mesh (the scene's in order, then the emitters'), for ``prepare``."""
        meshes = [mesh_data(scene, i) for i in range(len(scene.mesh))]
        reflectors = [i for i, mesh in enumerate(scene.mesh) if mesh.reflector]
        centres = [bounding_sphere(meshes[i].positions.astype(np.float64))[0] for i in reflectors]
        reflected = [data for i, data in enumerate(meshes) if i not in reflectors]
        reflected += [emitter_mesh(light) for light in scene.light if isinstance(light, QuadLight | PolygonLight)]
        counts = [(data.n_triangles, data.n_vertices, self._subdivision(data, centres)) for data in reflected]
        if not counts:
            return []
        vertices = sum(split_size(t, n, k)[0] for t, n, k in counts)

        def fits(budget: int) -> int | None:
            def estimate(k: int) -> int:
                return subdivision_bytes([(t, n, k) for t, n, _ in counts], len(reflectors))

            return largest_fitting(estimate, 1, max(k for _, _, k in counts), budget)

        check(
            "subdivide",
            subdivision_bytes(counts, len(reflectors)),
            value=self.params.subdivide,
            what=f"{vertices:,} reflected vertices, drawn for {len(reflectors)} reflector(s)",
            fits=fits,
            advice="lower it" if self.params.subdivide != "auto" else "raise max_angle, or give subdivide = k",
        )
        return [k for _, _, k in counts]

    def _subdivision(self, data: MeshData, centres: list[np.ndarray]) -> int:
        """k for one mesh: the given one, or (auto) the smallest making every triangle's longest edge span at
        most ``max_angle`` seen from each reflector's centre — a reflected triangle is flat between its
        vertices, so its straight edges and its chord below the curved mirror shrink with that angle."""
        if self.params.subdivide != "auto":
            return int(self.params.subdivide)
        p = data.positions.astype(np.float64)[data.indices]
        edge = np.max(np.linalg.norm(p - np.roll(p, 1, axis=1), axis=-1), axis=1)
        angle = max(
            float(np.max(edge / np.maximum(np.linalg.norm(p.mean(axis=1) - c, axis=-1), 1e-9))) for c in centres
        )
        return int(np.clip(np.ceil(angle / np.radians(self.params.max_angle)), 1, 16))

    def _solver_flags(self, reflector: Reflector, count: bool = False) -> dict[str, int]:
        solver = self.params.solver
        return {
            "SURFACE_KIND": SURFACE_KINDS[reflector.kind],
            "SOLVER": SOLVERS[solver],
            "ITERATIONS": self.params.iterations or DEFAULT_ITERATIONS[solver],
            "COUNT_ITERATIONS": int(count),
        }

    def _reflector_draws(self, reflector: Reflector) -> tuple[list[tuple], object, list[tuple]]:
        """(the draws of the meshes and emitters reflected in it, the solver's program, its solves: (vertex array,
        buffer of the reflection points, vertices) per draw, run by ``_solve``)."""
        ctx = self.ctx
        solve_program = get_program(ctx, SOLVE_PROGRAM, **self._solver_flags(reflector))
        solves = []

        def vertex_array(program, data):  # the mesh's buffers, and its reflection points as seen from the eye
            points = ctx.buffer(reserve=data.n_vertices * 16)
            self._objects.append(points)
            solves.append((self.mesh_vertex_array(solve_program, data, indexed=False), points, data.n_vertices))
            return self.mesh_vertex_array(program, data, extra=((points, "4f", "in_mirror"),))

        # every environment lookup: the checkerboard needs the whole 2×2 quad alive, and this pass discards
        light_flags = {**self._light_flags, "ENV_CHECKERBOARD": 0}
        draws = []
        for data, material in self._reflected_meshes:
            scratched = shading_for(material, [self._lobes]) is not None  # its lobes, as in direct view
            program = get_program(
                ctx,
                REFLECTED_PROGRAM,
                slots={"BRDF": material.brdf_source},
                REFLECTED_EMITTER=0,
                EMITTER_MASK=0,
                SCRATCHED=int(scratched),
                **light_flags,
                **material.flags(),
                **(self._lobes.flags(material) if scratched else {}),
            )
            uniforms = {**material.uniforms(), **reflector.uniforms()}
            if self._ibl is not None:  # the environment lights reflected objects as in direct view
                uniforms.update(self._ibl.uniforms(self._lobes.ibl_material(material) if scratched else material))
            textures = material.textures(ctx)
            if scratched:
                uniforms.update(self._lobes.uniforms(material))
                textures = {**textures, **self._lobes.textures(material)}
            draws.append((program, vertex_array(program, data), uniforms, textures, scratched))
        masks = {id(light): mask for _, _, light, mask in self.prepared.emitters}  # the emitters' mask textures
        for data, light in self._reflected_emitters:
            mask = masks.get(id(light))
            program = get_program(
                ctx,
                REFLECTED_PROGRAM,
                slots={"BRDF": "reflets/brdf/glsl/lambert.glsl"},  # compiled out: an emitter is not shaded
                REFLECTED_EMITTER=1,
                EMITTER_MASK=int(mask is not None),
                **light_flags,
            )
            uniforms = {
                "u_radiance": tuple(light.radiance),
                "u_two_sided": bool(light.two_sided),
                **reflector.uniforms(),
            }
            textures = {"u_mask": mask} if mask is not None else {}
            draws.append((program, vertex_array(program, data), uniforms, textures, False))
        return draws, solve_program, solves

    def _solve(self, k: int, eye: tuple[float, float, float]) -> None:
        """Reflector ``k``'s reflection points of every reflected vertex seen from ``eye`` (transform feedback),
        unless they are those of this eye already: a frame from the same camera solves nothing."""
        if self._solved[k] == eye:
            return
        program = self._solve_programs[k]
        if self._grids[k] is not None:
            self._grids[k].use(GRID_UNIT)
        set_uniforms(program, {**self._reflectors[k].uniforms(), "r_grid": GRID_UNIT, "u_eye": eye})
        for vao, points, count in self._solves[k]:
            vao.transform(points, mode=moderngl.POINTS, vertices=count)
        self._solved[k] = eye

    # ------------------------------------------------------------------ per-size images
    def screen_bytes_per_sample(self) -> int:
        """The G-buffer's position, normal and uvs (float32 RGBA, 16 B each) and depth (4 B), and per reflector its
        reflection image and depth (20 B) — with a working copy of them (20 B) where a reflected material samples
        anew each frame: 72 B per target sample for one reflector (measured 54.5 before the uvs: fermat 134.5 B
        per sample at 2048², forward 80)."""
        reflectors = len(getattr(self, "_reflectors", ())) or 1
        return super().screen_bytes_per_sample() + 52 + 20 * reflectors + 20 * int(self.frame_dependent)

    def _images(self, size: tuple[int, int]) -> _Images:
        """The G-buffer and reflection images at a render size, re-created on change."""
        if self._gbuffer_size == size:
            return self._gbuffer
        ctx = self.ctx

        def colour():
            texture = ctx.texture(size, 4, dtype="f4")
            texture.filter = (moderngl.NEAREST, moderngl.NEAREST)
            self._objects.append(texture)
            return texture

        def reflection_image():
            texture, depth_r = colour(), depth.float_depth_texture(ctx, size)  # copied exactly (copy_image)
            fbo = ctx.framebuffer(color_attachments=[texture], depth_attachment=depth_r)
            self._objects += [depth_r, fbo]
            return fbo, texture

        position, normal, uvs = colour(), colour(), colour()
        depth_g = depth.float_depth_texture(ctx, size)  # camera: reversed-Z
        gbuffer_fbo = ctx.framebuffer(color_attachments=[position, normal, uvs], depth_attachment=depth_g)
        self._objects += [depth_g, gbuffer_fbo]
        reflections = [reflection_image() for _ in self._reflectors]
        working = reflection_image() if self.frame_dependent else None
        self._gbuffer = _Images(gbuffer_fbo, position, normal, uvs, reflections, working)
        self._gbuffer_size = size
        return self._gbuffer

    # ------------------------------------------------------------------ frame
    @property
    def frame_dependent(self) -> bool:
        """A reflected scratched material samples its lobes anew each frame."""
        return any(getattr(self, "_scratched", ()))

    def _eye(self) -> tuple[float, float, float]:
        return tuple(float(c) for c in self.scene.camera.position)

    def _reflects(self) -> bool:
        """Does this pass draw the reflections (the extras pass of a radiance frame)?"""
        return self.params.output == "radiance" and bool(self.role.extras)

    def _draw(self, target, view_proj, vp_bytes, frame: int, seed: int) -> None:
        self._draw_static(target, view_proj, vp_bytes, frame, seed)
        self._draw_dynamic(target, view_proj, vp_bytes, frame, seed)

    def _draw_static(self, target, view_proj, vp_bytes, frame: int, seed: int) -> None:
        """The mirrors' own shading (and the background), the G-buffer and each reflector's image of the reflected
        meshes whose shading is the same every frame."""
        super()._draw(target, view_proj, vp_bytes, frame, seed)
        if not self._reflects():
            return
        ctx = self.ctx
        images = self._images(target.size)
        ctx.enable(ctx.DEPTH_TEST)
        ctx.disable(ctx.CULL_FACE)
        images.gbuffer.use()
        ctx.viewport = (0, 0, *target.size)
        images.gbuffer.clear(0.0, 0.0, 0.0, 0.0, depth=depth.CLEAR)
        program = get_program(ctx, GBUFFER_PROGRAM)
        with depth.camera_depth(ctx):
            for vao, reflector_id in self._gbuffer_draws:
                set_uniforms(program, {"u_view_proj": vp_bytes, "u_reflector_id": reflector_id})
                vao.render()
        eye = self._eye()
        for k in range(len(self._reflectors)):
            self._solve(k, eye)
            fbo = images.reflections[k][0]
            fbo.use()
            ctx.viewport = (0, 0, *target.size)
            fbo.clear(0.0, 0.0, 0.0, 0.0, depth=1.0)
            self._draw_reflected(k, images, vp_bytes, frame, seed, scratched=False)
        ctx.disable(ctx.DEPTH_TEST)

    def _draw_dynamic(self, target, view_proj, vp_bytes, frame: int, seed: int) -> None:
        """Each reflector's image completed by the reflected meshes that sample anew each frame (on a copy of the
        static image), composited onto the frame."""
        if not self._reflects():
            return
        ctx = self.ctx
        images = self._images(target.size)
        for k in range(len(self._reflectors)):
            fbo, reflection = images.reflections[k]
            if images.working is not None and self._scratched[k]:
                copy_image(ctx, images.working[0], target.size, reflection, fbo.depth_attachment)
                fbo, reflection = images.working
                fbo.use()
                ctx.enable(ctx.DEPTH_TEST)
                ctx.disable(ctx.CULL_FACE)
                self._draw_reflected(k, images, vp_bytes, frame, seed, scratched=True)
            self._composite(k, target, images, reflection)
        ctx.disable(ctx.DEPTH_TEST)

    def _draw_reflected(self, k: int, images: _Images, vp_bytes, frame: int, seed: int, scratched: bool) -> None:
        """Reflector ``k``'s reflected draws of one kind (scratched or not) into the bound reflection image."""
        images.position.use(GBUFFER_UNITS[0])
        images.normal.use(GBUFFER_UNITS[1])
        self._bind_lighting()
        if self._grids[k] is not None:
            self._grids[k].use(GRID_UNIT)
        common = {
            "r_grid": GRID_UNIT,
            "u_view_proj": vp_bytes,
            "u_eye": self._eye(),
            "u_depth_range": self._depth_range,
            "u_gbuffer_position": GBUFFER_UNITS[0],
            "u_gbuffer_normal": GBUFFER_UNITS[1],
            "u_reflector_id": float(k + 1),
            "u_hidden_tolerance": self.params.hidden_tolerance * self._composites[k][4],
            **SHADOW_SAMPLERS,
            **self._light_uniforms,
            **(ScratchLobes.frame_uniforms(frame, seed) if scratched else {}),  # they sample per frame
        }
        for program, vao, uniforms, textures, is_scratched in self._reflection_draws[k]:
            if is_scratched == scratched:
                samplers = bind_material_textures(textures)
                set_uniforms(program, {**uniforms, **samplers, **common})
                vao.render()

    def _composite(self, k: int, target, images: _Images, reflection) -> None:
        """Reflector ``k``'s reflection image onto the frame: additive, no depth test."""
        ctx = self.ctx
        program_c, vao_c, material_uniforms, material_textures, _ = self._composites[k]
        target.fbo.use()
        ctx.viewport = (0, 0, *target.size)
        ctx.disable(ctx.DEPTH_TEST)
        ctx.enable(ctx.BLEND)
        ctx.blend_func = moderngl.ONE, moderngl.ONE
        images.position.use(GBUFFER_UNITS[0])
        images.normal.use(GBUFFER_UNITS[1])
        reflection.use(GBUFFER_UNITS[2])
        images.uvs.use(GBUFFER_UNITS[3])
        uniforms = {
            **material_uniforms,
            **bind_material_textures(material_textures),
            "u_gbuffer_position": GBUFFER_UNITS[0],
            "u_gbuffer_normal": GBUFFER_UNITS[1],
            "u_reflection": GBUFFER_UNITS[2],
            "u_gbuffer_uvs": GBUFFER_UNITS[3],
            "u_reflector_id": float(k + 1),
            "u_eye": self._eye(),
        }
        color = self.scene.background_color()
        if color is None:
            from ..equirect import rotation_y

            self.prepared.background_texture.use(0)
            uniforms["u_env"] = 0
            uniforms["u_env_from_world"] = rotation_y(self.scene.environment.rotate_y).astype(np.float32).tobytes()
        else:
            uniforms["u_background"] = tuple(color)
        set_uniforms(program_c, uniforms)
        vao_c.render(vertices=3)
        ctx.disable(ctx.BLEND)

    def release(self) -> None:
        if hasattr(self, "_lobes"):
            self._lobes.release()
        super().release()

    # ------------------------------------------------------------------ the solver alone
    def reflection_points(self, vertices: np.ndarray, eyes=None, reflector: int = 0) -> dict[str, np.ndarray]:
        """The GPU solver's result for points ``vertices`` (N, 3) seen from ``eyes`` (N, 3; default the scene
        camera), read back by transform feedback: position, normal, valid, residual, iterations per point
        (tests and benchmarks compare them with the NumPy solver and exact references)."""
        ctx = self.ctx
        r = self._reflectors[reflector]
        program = get_program(ctx, POINTS_PROGRAM, **self._solver_flags(r, count=True))
        vertices = np.ascontiguousarray(vertices, dtype=np.float32).reshape(-1, 3)
        eyes = np.broadcast_to(self.scene.camera.position if eyes is None else eyes, vertices.shape)
        data = np.ascontiguousarray(np.concatenate([vertices, eyes], axis=1), dtype=np.float32)
        vbo = ctx.buffer(data.tobytes())
        out = ctx.buffer(reserve=len(vertices) * 9 * 4)
        vao = ctx.vertex_array(program, [(vbo, "3f 3f", "in_position", "in_eye")])
        fbo = ctx.simple_framebuffer((1, 1))  # a draw needs a complete framebuffer, even with nothing rasterised
        try:
            fbo.use()
            if self._grids[reflector] is not None:
                self._grids[reflector].use(GRID_UNIT)
            set_uniforms(program, {**r.uniforms(), "r_grid": GRID_UNIT})
            vao.transform(out, mode=moderngl.POINTS, vertices=len(vertices))
            result = np.frombuffer(out.read(), dtype=np.float32).reshape(-1, 9).astype(np.float64)
        finally:
            release_objects(ctx, [vao, out, vbo, fbo])
        return {
            "position": result[:, 0:3],
            "normal": result[:, 3:6],
            "valid": result[:, 6] > 0.5,
            "residual": result[:, 7],
            "iterations": result[:, 8].astype(int),
        }
