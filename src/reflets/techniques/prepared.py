"""The GPU state of one scene that every pass of a frame shares, built once.

A frame composed by ``auto`` runs several passes over the same scene (the BRDF pass, translucent light views,
scratch lobes, Fermat reflections). What they all read — the meshes' vertex and index buffers, the quad-light
masks, the environment map and its texture, the emitters' geometry, the bounding sphere that fixes the clip
planes, the lights' shadow maps — lives here once instead of once per pass; each pass keeps only what is its
own (programs, vertex arrays binding these buffers to them, light buffers shaped for its method, its tables).
A whole-frame method makes one for itself; ``auto`` makes one and hands it to every pass (``Technique.shared``).
Whoever made it releases it.
"""

from __future__ import annotations

import moderngl
import numpy as np

from ..gpu import GLObjects, ProgramSpec, get_program
from ..scene.environment import load_environment
from ..scene.geometry import bounding_boxes, mesh_data
from ..scene.lightmask import load_masks, quad_uv
from ..scene.map_emitters import is_split, split_map
from ..scene.meshdata import MeshData
from ..scene.model import PolygonLight, QuadLight, Scene
from .ibl import PrefilteredEnvironment
from .shadows import DEFAULT_SHADOWS, ShadowMaps, ShadowSettings, light_index

_SHADERS = "reflets/techniques/shaders/"
EMITTER_PROGRAM = ProgramSpec(
    "emitter", vertex=_SHADERS + "emitter.vert", fragment=_SHADERS + "emitter.frag", flags=frozenset({"EMITTER_MASK"})
)
#: the vertex layout of mesh.vert (and every program that draws scene meshes)
MESH_LAYOUT = ("3f 3f 4f 2f 2f", "in_position", "in_normal", "in_tangent", "in_uv", "in_uv1")


class PreparedScene:
    """Meshes, masks, environment and emitters of one scene on one context (see the module docstring)."""

    def __init__(self, ctx, scene: Scene, shadow_settings: ShadowSettings = DEFAULT_SHADOWS):
        self.ctx = ctx
        self.scene = scene
        self._gl = GLObjects(ctx)
        self._own = self._gl.own
        self._mesh_buffers: dict[tuple, tuple] = {}  # mesh → (vbo, ibo, data), uploaded when a pass first draws it
        #: world-space triangles of every mesh (the content-keyed cache's objects: read-only)
        self.meshes: list[MeshData] = [mesh_data(scene, i) for i in range(len(scene.mesh))]
        self._masks = load_masks(scene)  # by light index in this scene; passes ask by light (``mask_of``)
        #: the environment map (H, W, 3) float32 × its scale, or None — its residual when its compact emitters are
        #: lights of ``scene`` (``map_emitters.with_map_emitters``) —, and its texture (repeat in u) or None: what
        #: lights (the prefiltered maps, the occlusion views, the scratch lobes' samples)
        whole = load_environment(scene)
        self.environment = split_map(scene)[1] if is_split(scene) else whole
        self.environment_texture = self._env_texture(self.environment)
        #: what is seen (the background, a mirror's reflection along its direction): the whole map, its sun in it
        self.background_texture = (self._env_texture(whole) if whole is not self.environment
                                   else self.environment_texture)  # fmt: skip
        self.emitters = [self._emitter(i, light) for i, light in enumerate(scene.light) if _is_area(light)]
        points = [m.positions for m in self.meshes] + [light.polygon() for light in scene.light if _is_area(light)]
        #: (N, 2, 3) bounding boxes of each mesh and emitter: the camera's automatic near plane
        self.boxes = bounding_boxes(points)
        self._ibl = None
        #: the lights' shadow maps (every mesh casts)
        self.shadows = ShadowMaps(self, shadow_settings)

    def _env_texture(self, image: np.ndarray | None):
        if image is None:
            return None
        tex = self.ctx.texture((image.shape[1], image.shape[0]), 3, np.ascontiguousarray(image).tobytes(), dtype="f4")
        tex.repeat_x, tex.repeat_y = True, False
        return self._own(tex)

    def prefiltered_environment(self) -> PrefilteredEnvironment:
        """The environment's prefiltered maps, made when a pass first asks (the GPU prefiltering runs once)."""
        if self._ibl is None:
            self._ibl = PrefilteredEnvironment(self.environment_texture, self.environment, self.scene.environment)
        return self._ibl

    def mask_of(self, light) -> np.ndarray | None:
        """The mask of a light of this scene (a pass's scene may hold a subset of the lights)."""
        return self._masks.get(light_index(self.scene, light))

    def vertex_array(self, program, mesh: int | MeshData, extra: tuple = (), indexed: bool = True):
        """A vertex array binding mesh ``mesh`` (an index: the shared buffers; or any ``MeshData``, e.g. a
        subdivided copy: uploaded once, released with this scene) to a program of mesh.vert's layout, with
        ``extra`` buffer formats after it (moderngl's (buffer, format, names…)); ``indexed=False`` leaves the index
        buffer out (one vertex per vertex: transform feedback). The caller owns the vertex array."""
        vbo, ibo = self.buffers(mesh)
        layout, *names = MESH_LAYOUT
        content = [(vbo, layout, *names), *extra]
        return self.ctx.vertex_array(program, content, ibo if indexed else None, skip_errors=True)

    def buffers(self, mesh: int | MeshData) -> tuple:
        """(vertex buffer, index buffer) of a scene mesh or of a ``MeshData``, uploaded on first use."""
        key = ("mesh", mesh) if isinstance(mesh, int) else ("data", id(mesh))
        if key not in self._mesh_buffers:
            data = self.meshes[mesh] if isinstance(mesh, int) else mesh
            vbo = self._own(self.ctx.buffer(data.interleaved().tobytes()))
            ibo = self._own(self.ctx.buffer(data.indices.tobytes()))
            self._mesh_buffers[key] = (vbo, ibo, data)  # the data kept: its id is not reused while it is a key
        return self._mesh_buffers[key][:2]

    def _emitter(self, index: int, light) -> tuple:
        """(program, vertex array, light, mask texture or None) drawing an area light's emitting face."""
        ctx = self.ctx
        poly = light.polygon()
        tri = np.array([[poly[0], poly[k], poly[k + 1]] for k in range(1, len(poly) - 1)]).reshape(-1, 3)
        uv = np.stack(quad_uv(light, tri), axis=-1) if isinstance(light, QuadLight) else np.zeros((len(tri), 2))
        vbo = self._own(ctx.buffer(np.concatenate([tri, uv], axis=1).astype(np.float32).tobytes()))
        mask = self._masks.get(index)
        program = get_program(ctx, EMITTER_PROGRAM, EMITTER_MASK=int(mask is not None))
        vao = self._own(ctx.vertex_array(program, [(vbo, "3f 2f", "in_position", "in_uv")], skip_errors=True))
        texture = None
        if mask is not None:
            texture = ctx.texture((mask.shape[1], mask.shape[0]), 1, mask.tobytes(), dtype="f4")
            texture.filter = (moderngl.NEAREST, moderngl.NEAREST)
            texture.repeat_x = texture.repeat_y = False
            self._own(texture)
        return program, vao, light, texture

    def release(self) -> None:
        self.shadows.release()
        if self._ibl is not None:
            self._ibl.release()
            self._ibl = None
        self._gl.release()
        self._mesh_buffers = {}


def _is_area(light) -> bool:
    return isinstance(light, QuadLight | PolygonLight)
