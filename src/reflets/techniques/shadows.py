"""Shadow maps of the point and directional lights, in one depth atlas shared by every pass of a frame.

Every technique shades its lights through ``shaders/lights.glsl`` (or, for the scratch lobes and Fermat's
reflected pass, code that includes it), and there ``shaders/shadows.glsl`` multiplies each point / directional
light by the fraction of filtered shadow-map texels that see it:

- a point light: six 90° perspective views (a cube map unfolded into the atlas: faces +x, −x, +y, −y, +z, −z,
  picked by the major axis of the light-to-point vector); a directional light: one orthographic view fitted to
  the scene's bounding sphere. Views are drawn once per prepare (they depend on the lights and the meshes, not
  on the camera);
- percentage-closer filtering: 3 × 3 hardware-bilinear comparisons one texel apart;
- bias, chosen on the test scenes (``tests/techniques/test_shadows.py``): a slope-scaled polygon offset in the
  depth pass (``SLOPE_BIAS``, ``CONSTANT_BIAS``) and, at lookup, a normal offset of 0.5 + 1.5 sin θ texels
  (θ between the normal and the light) along the normal turned towards the light. No acne on lit surfaces
  (lit floor within 2 % of the reference), and shadows stay attached to their casters.

A light with ``shadows = false`` gets no view. All views share one resolution, chosen so that the atlas stays
within ``MAX_ATLAS`` texels per side (many lights: smaller maps, a warning-free degradation stated here).
"""

from __future__ import annotations

import math

import moderngl
import numpy as np

from ..gpu import ProgramSpec, get_program, release_objects, set_uniforms
from ..scene.model import DirectionalLight, PointLight, Scene
from ..scene.transform import look_at, perspective

_SHADERS = "reflets/techniques/shaders/"
DEPTH_PROGRAM = ProgramSpec("shadow_depth", vertex=_SHADERS + "mesh.vert", fragment=_SHADERS + "shadow_depth.frag")
#: texture unit of the atlas and storage binding of the views in every shading program
SHADOW_UNIT = 11
SHADOW_BINDING = 6
#: pixels per side of one view (a point light's cube face, a directional light's map)
RESOLUTION = 2048
#: the atlas's largest side in texels (a 4096² float depth atlas is 64 MiB)
MAX_ATLAS = 4096
#: glPolygonOffset(factor, units) of the depth pass: depth pushed back by the surface's slope plus a constant
SLOPE_BIAS, CONSTANT_BIAS = 2.0, 4.0
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

    def __init__(self, ctx, scene: Scene, meshes_vertex_array, bounds: tuple):
        """``meshes_vertex_array(program)``: vertex arrays of every mesh for a program (the prepared scene's);
        ``bounds``: the scene's bounding sphere (centre, radius)."""
        self.ctx = ctx
        self.scene = scene
        self._first_view: dict[int, int] = {}  # light index → its first view
        views: list[tuple[np.ndarray, float]] = []  # (view-projection, world texel size: per unit distance for 90°)
        centre, radius = bounds
        for index, light in enumerate(scene.light):
            if not getattr(light, "shadows", False) or centre is None:
                continue
            if isinstance(light, PointLight):
                self._first_view[index] = len(views)
                views += _cube_views(np.asarray(light.position, np.float64), centre, radius)
            elif isinstance(light, DirectionalLight):
                self._first_view[index] = len(views)
                views.append(_directional_view(np.asarray(light.direction, np.float64), centre, radius))
        self.view_count = len(views)
        self._objects: list = []
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
        records = []
        for k, (view_proj, texel) in enumerate(views):
            tile = ((k % columns) * self.resolution / size[0], (k // columns) * self.resolution / size[1])
            scale = (self.resolution / size[0], self.resolution / size[1])
            records.append(
                np.concatenate(
                    [
                        view_proj.T.ravel(),  # four columns (GLSL mat4 from column vectors)
                        [*tile, *scale],
                        [texel / self.resolution, 0.0, 0.0, 0.0],
                    ]
                )
            )
        self.buffer = self._own(ctx.buffer(np.asarray(records, np.float32).tobytes()))
        self._draw(meshes_vertex_array, views, columns, size)

    def view_index(self, light) -> int:
        """The first view of a light of this scene (found by identity: a pass's scene holds some of the lights),
        or −1 when it casts no shadow."""
        for index, candidate in enumerate(self.scene.light):
            if candidate is light:
                return self._first_view.get(index, -1)
        return -1

    def bind(self) -> None:
        """Bind the atlas and the views where the shading programs read them (a program without shadows
        ignores both)."""
        if self.atlas is not None:
            self.atlas.use(SHADOW_UNIT)
            self.buffer.bind_to_storage_buffer(SHADOW_BINDING)

    def _draw(self, meshes_vertex_array, views, columns: int, size: tuple[int, int]) -> None:
        ctx = self.ctx
        program = get_program(ctx, DEPTH_PROGRAM)
        vaos = [self._own(vao) for vao in meshes_vertex_array(program)]
        fbo = self._own(ctx.framebuffer(depth_attachment=self.atlas))
        fbo.use()
        fbo.clear(depth=1.0)
        ctx.enable(ctx.DEPTH_TEST)
        ctx.disable(ctx.CULL_FACE)  # two-sided surfaces cast from both sides
        ctx.polygon_offset = SLOPE_BIAS, CONSTANT_BIAS
        r = self.resolution
        for k, (view_proj, _) in enumerate(views):
            ctx.viewport = ((k % columns) * r, (k // columns) * r, r, r)
            set_uniforms(program, {"u_view_proj": view_proj.T.astype(np.float32).tobytes()})
            for vao in vaos:
                vao.render()
        ctx.polygon_offset = 0.0, 0.0
        ctx.disable(ctx.DEPTH_TEST)

    def _own(self, obj):
        self._objects.append(obj)
        return obj

    def release(self) -> None:
        release_objects(self.ctx, self._objects)
        self._objects = []
        self.atlas = self.buffer = None


def _cube_views(position: np.ndarray, centre: np.ndarray, radius: float) -> list[tuple[np.ndarray, float]]:
    """Six 90° views from a point light holding the scene's bounding sphere (near: as far as the sphere allows)."""
    dist = float(np.linalg.norm(centre - position))
    far = (dist + radius) * 1.01 + 1e-6
    near = max(far * 1e-4, 0.99 * (dist - radius)) if dist > radius else far * 1e-4
    proj = perspective(90.0, 1.0, near, far)
    return [(proj @ look_at(position, position + np.asarray(axis), up), 2.0) for axis, up in CUBE_FACES]


def _directional_view(direction: np.ndarray, centre: np.ndarray, radius: float) -> tuple[np.ndarray, float]:
    """An orthographic view along ``direction`` holding the scene's bounding sphere."""
    d = direction / np.linalg.norm(direction)
    radius = max(radius, 1e-6)
    eye = centre - d * 2.0 * radius
    up = (0.0, 1.0, 0.0) if abs(d[1]) < 0.99 else (1.0, 0.0, 0.0)
    near, far = 0.5 * radius, 3.5 * radius
    proj = np.diag([1.0 / radius, 1.0 / radius, -2.0 / (far - near), 1.0])
    proj[2, 3] = -(far + near) / (far - near)
    return proj @ look_at(eye, centre, up), 2.0 * radius
