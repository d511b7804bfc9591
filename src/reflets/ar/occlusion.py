"""The object's self-occlusion P_V (004 §5.1), precomputed once per object on the GPU:

    P_V(p) = (1/π) ∫ max(0, n·ω) visible(p, ω) dω   [erratum: visible(p, n) in the text]

The document's estimator: N uniformly distributed sphere directions (default 1,000), each holding a solid
angle 4π/N, so P_V ≈ (4/N) Σ_k max(0, n·ω_k) visible(p, ω_k), clamped to [0, 1]. Directions: a spherical
Fibonacci set (deterministic and uniform; ``fibonacci_directions``). Visibility along ω_k: one orthographic
depth map of the mesh looking along −ω_k, fitted to the mesh's bounding sphere
(``techniques.shadows.directional_view``).

Bias. The document's form c ↦ b tan(acos c) at lookup, b = 0.75 texel (the largest depth step between a point
and its texel's centre on its own plane; the document's b = 0.005 of the depth range is 2.6 texels at 512²),
tan capped at 10, plus half a texel, the point moved half a texel along its normal. Added: the depth maps
push each occluder back by its own slope (polygon offset 1 × slope + 4 units). Without it a surface through
the vertex seen nearly edge-on — a wall at whose foot the vertex stands, a concave crease — hides it: the
foot of a wall came out up to 0.06 darker than its exact 1/2 (512², tests/ar/test_self_occlusion.py).

Closed meshes (welded by position, every edge walked as often each way) get their back faces culled: along
any line, what lies in front of a point is first met by a face turned to the viewer, so this is exact and
rasterises half the triangles. Open meshes occlude from both faces; a vertex lying on another sheet (a zero-
thickness contact) is then seen through within the bias, as in the document.

Deviation: P_V is stored **per vertex**, not in a 1024² texture. Our meshes have no UV atlas, and the
document's own code Gouraud-interpolates its per-vertex diffuse weights; so there is no texture-space
rasterisation and no dilation. The pass is "vertex space": every vertex is a point (GL_POINTS) on its own texel
of a square float32 accumulation texture (ceil(√V)² texels), carrying its weighted sum over a batch of
directions (up to 64 depth maps tiled in one atlas), summed over batches by additive blending; read
back once at the end.
"""

from __future__ import annotations

import math

import moderngl
import numpy as np

from ..gpu import GLObjects, ProgramSpec, get_context, get_program, set_uniforms
from ..scene.geometry import bounding_sphere
from ..techniques.shadows import DEPTH_PROGRAM, MAX_ATLAS, directional_view

#: directions per batch at most: their depth maps tiled in one atlas (at most MAX_ATLAS² texels), their views in
#: one uniform block of BATCH × RECORD vec4 (4 KiB)
BATCH = 64
#: vec4 per view in occlusion.vert's uniform block: three affine rows and the direction
RECORD = 4
OCCLUSION_PROGRAM = ProgramSpec(
    "self_occlusion",
    vertex="reflets/ar/shaders/occlusion.vert",
    fragment="reflets/ar/shaders/occlusion.frag",
    constants=(("OCCLUSION_BATCH", str(BATCH)),),
)
#: the document's Monte Carlo: directions over the whole sphere
DIRECTIONS = 1000
#: texels per side of one direction's depth map
RESOLUTION = 512
#: lookup bias in texels: per unit tan θ (θ between the normal and ω), constant; the point's offset along its
#: normal; tan θ capped at MAX_TAN (c < 0.1: grazing directions, of small weight c)
SLOPE_TEXELS, CONSTANT_TEXELS, NORMAL_TEXELS, MAX_TAN = 0.75, 0.5, 0.5, 10.0
#: glPolygonOffset(factor, units) of the depth maps: an occluder pushed back by its own largest depth step
#: across a texel — what separates a point from its texel's centre on that occluder's plane
POLYGON_OFFSET = (1.0, 4.0)


def fibonacci_directions(count: int) -> np.ndarray:
    """``count`` unit directions of a spherical Fibonacci lattice (equal-area bands in z, golden-angle azimuths):
    deterministic and uniform, each standing for a solid angle 4π / count. (count, 3) float64."""
    i = np.arange(count) + 0.5
    z = 1.0 - 2.0 * i / count
    phi = i * math.pi * (3.0 - math.sqrt(5.0))
    r = np.sqrt(np.maximum(0.0, 1.0 - z * z))
    return np.stack([r * np.cos(phi), r * np.sin(phi), z], axis=-1)


def occlusion_estimate(normals: np.ndarray, directions: np.ndarray) -> np.ndarray:
    """The estimator with every direction visible, (4/N) Σ_k max(0, n·ω_k) (unclamped): what a convex object
    gets, 1 up to the directions' quadrature error."""
    n = np.asarray(normals, np.float64)
    return 4.0 / len(directions) * np.maximum(n @ np.asarray(directions, np.float64).T, 0.0).sum(axis=1)


def closed_orientation(positions: np.ndarray, faces: np.ndarray) -> int:
    """+1 where the mesh, its vertices welded by position, bounds solids with its faces wound outwards (every
    directed edge a → b matched by as many b → a: closed, touching parts allowed; positive volume), −1 where it
    is wound inwards, 0 where it is open. A closed mesh in front of a point along a line is first met by a
    surface facing the viewer (the line enters a solid there), so its depth maps may cull the faces turned away:
    exact, and half the triangles rasterised."""
    p = np.asarray(positions, np.float64)
    faces = np.asarray(faces, np.int64)
    if len(faces) == 0:
        return 0
    scale = max(float(np.ptp(p, axis=0).max()), 1e-30) * 1e-6
    _, weld = np.unique(np.round(p / scale), axis=0, return_inverse=True)
    f = weld.reshape(-1)[faces]
    f = f[(f[:, 0] != f[:, 1]) & (f[:, 1] != f[:, 2]) & (f[:, 2] != f[:, 0])]
    a, b = f.ravel(), np.roll(f, -1, axis=1).ravel()  # directed edges a → b
    n = int(weld.max()) + 1
    if len(f) == 0 or not np.array_equal(np.sort(a * n + b), np.sort(b * n + a)):
        return 0  # an open edge, or one walked more often one way than the other
    t = p[faces]
    volume = float(np.einsum("ij,ij->i", t[:, 0], np.cross(t[:, 1], t[:, 2])).sum())
    return int(np.sign(volume))


def _records(directions: np.ndarray, view_projs: list[np.ndarray], resolution: int) -> np.ndarray:
    """Per direction the view's affine map (p, 1) → (tile texel x, y, window depth) and (ω, world-to-depth)."""
    records = np.zeros((len(directions), RECORD, 4))
    for k, (omega, vp) in enumerate(zip(directions, view_projs, strict=True)):
        rows = vp[:3].copy()
        rows[:2] *= 0.5 * resolution  # ndc → texels: ½ res (ndc + 1)
        rows[:2, 3] += 0.5 * resolution
        rows[2] *= 0.5  # ndc → window depth: ½ ndc + ½
        rows[2, 3] += 0.5
        records[k, :3] = rows
        records[k, 3] = (*omega, np.linalg.norm(rows[2, :3]))
    return records.astype(np.float32)


def self_occlusion(
    positions: np.ndarray,
    normals: np.ndarray,
    faces: np.ndarray,
    directions: int | np.ndarray = DIRECTIONS,
    resolution: int = RESOLUTION,
) -> np.ndarray:
    """P_V at every vertex, (V,) float32 in [0, 1] (see the module docstring).

    ``positions`` (V, 3) and unit ``normals`` (V, 3) of a triangle mesh ``faces`` (F, 3), in one frame;
    ``directions``: how many Fibonacci directions, or the unit directions themselves (M, 3); ``resolution``:
    texels per side of each direction's depth map.
    """
    positions = np.ascontiguousarray(positions, np.float32)
    normals = np.asarray(normals, np.float64)
    length = np.linalg.norm(normals, axis=1, keepdims=True)
    normals = np.ascontiguousarray(np.where(length > 0, normals / np.maximum(length, 1e-30), 0.0), np.float32)
    faces = np.ascontiguousarray(faces, np.uint32)
    if isinstance(directions, int | np.integer):
        directions = fibonacci_directions(int(directions))
    directions = np.asarray(directions, np.float64)
    directions = directions / np.linalg.norm(directions, axis=1, keepdims=True)
    count = len(positions)
    if count == 0 or len(directions) == 0:
        return np.zeros(count, np.float32)
    if len(faces) == 0:  # nothing occludes: the estimator alone
        return np.clip(occlusion_estimate(normals, directions), 0.0, 1.0).astype(np.float32)

    centre, radius = bounding_sphere(positions.astype(np.float64))
    radius = max(radius, 1e-6)
    texel = 2.0 * radius / resolution
    bias = (SLOPE_TEXELS * texel, CONSTANT_TEXELS * texel, NORMAL_TEXELS * texel, MAX_TAN)
    tiles = max(1, MAX_ATLAS // resolution)  # tiles per atlas side: a batch is up to tiles² directions
    batch = min(len(directions), tiles * tiles, BATCH)
    columns = min(tiles, math.ceil(math.sqrt(batch)))
    rows = math.ceil(batch / columns)
    side = math.ceil(math.sqrt(count))
    # each view looks along −ω: the sky side of the mesh is nearest
    view_projs = [directional_view(-omega, centre, radius)["view_proj"] for omega in directions]

    orientation = closed_orientation(positions, faces)
    ctx = get_context()
    gl = GLObjects(ctx)
    try:
        depth_program = get_program(ctx, DEPTH_PROGRAM)
        program = get_program(ctx, OCCLUSION_PROGRAM)
        vbo = gl.own(ctx.buffer(positions.tobytes()))
        nbo = gl.own(ctx.buffer(normals.tobytes()))
        ibo = gl.own(ctx.buffer(faces.tobytes()))
        records = _records(directions, view_projs, resolution)
        views = gl.own(ctx.buffer(reserve=BATCH * RECORD * 16))
        mesh = gl.own(ctx.vertex_array(depth_program, [(vbo, "3f", "in_position")], ibo, skip_errors=True))
        points = gl.own(ctx.vertex_array(program, [(vbo, "3f", "in_position"), (nbo, "3f", "in_normal")]))
        atlas = gl.own(ctx.depth_texture((columns * resolution, rows * resolution)))
        atlas.compare_func = ""  # raw depths for texelFetch
        atlas_fbo = gl.own(ctx.framebuffer(depth_attachment=atlas))
        accumulation = gl.own(ctx.texture((side, side), 1, dtype="f4"))
        accumulation_fbo = gl.own(ctx.framebuffer(color_attachments=[accumulation]))
        accumulation_fbo.clear(0.0, 0.0, 0.0, 0.0)
        set_uniforms(
            program,
            {
                "u_side": side,
                "u_depth": 0,
                "u_columns": columns,
                "u_resolution": resolution,
                "u_weight": 4.0 / len(directions),
                "u_bias": tuple(float(b) for b in bias),
            },
        )
        if orientation:  # closed: the surfaces facing the view hide whatever the others would
            ctx.enable(ctx.CULL_FACE)
            ctx.cull_face = "back" if orientation > 0 else "front"
        else:  # open meshes occlude from both sides
            ctx.disable(ctx.CULL_FACE)
        ctx.blend_func = moderngl.ONE, moderngl.ONE
        ctx.point_size = 1.0
        for first in range(0, len(directions), batch):
            size = min(batch, len(directions) - first)
            atlas_fbo.use()
            atlas_fbo.clear(depth=1.0)
            ctx.enable(ctx.DEPTH_TEST)
            ctx.polygon_offset = POLYGON_OFFSET
            for k in range(size):
                ctx.viewport = ((k % columns) * resolution, (k // columns) * resolution, resolution, resolution)
                matrix = view_projs[first + k].T.astype(np.float32).tobytes()  # column-major
                set_uniforms(depth_program, {"u_view_proj": matrix})
                mesh.render()
            ctx.disable(ctx.DEPTH_TEST)
            ctx.polygon_offset = 0.0, 0.0
            accumulation_fbo.use()
            ctx.viewport = (0, 0, side, side)
            ctx.enable(ctx.BLEND)
            views.write(records[first : first + size].tobytes())
            views.bind_to_uniform_block(0)
            atlas.use(0)
            set_uniforms(program, {"u_count": size})
            points.render(moderngl.POINTS, vertices=count)
            ctx.disable(ctx.BLEND)
        values = np.frombuffer(accumulation_fbo.read(components=1, dtype="f4"), np.float32)[:count]
    finally:
        ctx.disable(ctx.BLEND | ctx.DEPTH_TEST | ctx.CULL_FACE)
        ctx.polygon_offset = 0.0, 0.0
        gl.release()
    return np.clip(values, 0.0, 1.0).astype(np.float32)
