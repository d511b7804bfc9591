"""The document's lighting of a virtual object and of its shadow (004 §4.2–4.4), from the captured cube map:

- diffuse: face-constant, E(n) = (P_V / π) Σ_F L̄_F W_F(n) with the face means L̄_F (the coarsest mip) and the
  weights W_F exact (Σ_F W_F = π), the document's fit, or the fit renormalised (``lighting.py``), per vertex and
  Gouraud-interpolated (as its code), times the self-occlusion P_V (``occlusion.py``);
- specular: k_s times the cube map along the reflected direction at McGuire et al.'s mip level of the exponent
  (``capture.specular_level``), on the GPU (``shaders/document.frag``);
- the shadow on the ground: the sphere decomposition's occlusion weighted by the light behind each sphere,
  a_i = cos ω sin²α · min(‖ℓ_i‖ / ‖A‖, π) (the document's code: ℓ_i the cube map toward the sphere at the mip
  level of its solid angle, A the ambient radiance E(+y)/π, RGB lengths, so the shadow is grey; [erratum] the
  text's formula drops the π of the cap's cosine-weighted solid angle, the code has it right), spheres
  combined as Π (1 − a_i), tabulated over 3 × the object's footprint as the document's shadow texture.

The document shades Lambert and Phong-like materials only (k_d, k_s, N_s): reflets' ``lambert`` and normalised
``phong`` map onto them exactly, a ``microfacet`` lobe without Fresnel by its Blinn-Phong exponent (Walter et al.
2007: 2/α² − 2, a quarter of it about the reflected direction); anything else is an error naming the material
(use the differential mode).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..brdf.base import blinn_phong_exponent
from ..errors import ArgumentError
from ..gpu import GLObjects, HDRTarget, ProgramSpec, depth, get_context, get_program, set_uniforms
from ..scene import Scene
from ..scene.geometry import mesh_data
from . import capture
from .lighting import face_weights_exact, face_weights_fit, face_weights_normalised

DOCUMENT_PROGRAM = ProgramSpec(
    "ar_document", vertex="reflets/ar/shaders/document.vert", fragment="reflets/ar/shaders/document.frag"
)
#: the sphere shadows' texture, a fragment per texel (a full-screen triangle)
SHADOW_PROGRAM = ProgramSpec(
    "ar_shadow", vertex="reflets/techniques/shaders/background.vert", fragment="reflets/ar/shaders/shadow.frag"
)
WEIGHTS = {"exact": face_weights_exact, "fit": face_weights_fit, "normalised": face_weights_normalised}
#: GL_TEXTURE_CUBE_MAP_SEAMLESS (the document's seamless cube filtering)
_SEAMLESS = 0x884F
#: the shadow texture spans this many times the object's footprint (the document's)
SHADOW_EXTENT = 3.0
SHADOW_TEXELS = 128


@dataclass
class ObjectGeometry:
    """The object's triangles in world space (all its meshes), with a material index per vertex."""

    positions: np.ndarray
    normals: np.ndarray
    faces: np.ndarray
    material: list[str]  # per mesh
    mesh_of_vertex: np.ndarray

    @classmethod
    def of(cls, scene: Scene) -> ObjectGeometry:
        positions, normals, faces, owner, offset = [], [], [], [], 0
        for i in range(len(scene.mesh)):
            data = mesh_data(scene, i)
            positions.append(data.positions.astype(np.float64))
            normals.append(data.normals.astype(np.float64))
            faces.append(data.indices.reshape(-1, 3).astype(np.int64) + offset)
            owner.append(np.full(len(data.positions), i))
            offset += len(data.positions)
        if not positions:
            raise ArgumentError("the scene has no mesh to insert", field="mesh")
        return cls(np.concatenate(positions), np.concatenate(normals), np.concatenate(faces),
                   [m.material for m in scene.mesh], np.concatenate(owner))  # fmt: skip


def phong_terms(scene: Scene, name: str) -> tuple[np.ndarray, np.ndarray, float]:
    """(k_d, k_s, N_s) of a material the document can shade."""
    material = scene.materials[name]
    kind = getattr(material, "type", "")
    if kind == "lambert":
        return np.asarray(material.albedo, np.float64), np.zeros(3), 1.0
    if kind == "phong" and material.normalized:
        return np.asarray(material.kd, np.float64), np.asarray(material.ks, np.float64), float(material.exponent)
    if kind == "microfacet" and material.fresnel == "none":  # its Blinn-Phong exponent, a quarter about r
        return (np.asarray(material.diffuse, np.float64), np.asarray(material.specular, np.float64),
                blinn_phong_exponent(material.alpha) / 4.0)  # fmt: skip
    raise ArgumentError(
        f"the document's mode shades 'lambert', normalised 'phong' and 'microfacet' (fresnel none) materials, not "
        f"{kind!r} (use --mode differential)",
        field=f"materials.{name}",
    )


def face_weights(geometry: ObjectGeometry, weights: str = "exact") -> np.ndarray:
    """W_F(n) per vertex (V, 6), once per object (the normals do not change with the environment)."""
    if weights not in WEIGHTS:
        raise ArgumentError(f"unknown face weights {weights!r}; allowed: {', '.join(WEIGHTS)}", field="weights")
    return WEIGHTS[weights](geometry.normals)


def vertex_diffuse(geometry: ObjectGeometry, scene: Scene, cube, occlusion: np.ndarray, weights: np.ndarray):
    """k_d P_V Σ_F L̄_F W_F(n) / π per vertex (V, 3), from the per-vertex face weights (V, 6)."""
    irradiance = weights @ capture.face_means(cube) / np.pi
    kd = np.array([phong_terms(scene, name)[0] for name in geometry.material])[geometry.mesh_of_vertex]
    return kd * occlusion[:, None] * irradiance


def render_object(geometry, scene, cube, diffuse, view_proj, eye, size) -> np.ndarray:
    """The object shaded by the document's model: RGBA float32 (H, W, 4), alpha = coverage, row 0 the top."""
    ctx = get_context()
    program = get_program(ctx, DOCUMENT_PROGRAM)
    faces = capture._faces_of(cube)
    n = faces.shape[1]
    owned = GLObjects(ctx)
    target = HDRTarget(ctx, *size)
    try:
        ctx.enable_direct(_SEAMLESS)
        texture = owned.own(ctx.texture_cube((n, n), 3, np.ascontiguousarray(faces, np.float32).tobytes(), dtype="f4"))
        texture.build_mipmaps()
        texture.use(0)
        target.use()
        ctx.enable(ctx.DEPTH_TEST)
        ctx.disable(ctx.CULL_FACE)
        set_uniforms(program, {"u_view_proj": view_proj.T.astype(np.float32).tobytes(), "u_environment": 0,
                               "u_eye": tuple(float(c) for c in eye)})  # fmt: skip
        with depth.camera_depth(ctx):
            _draw_meshes(ctx, program, owned, geometry, scene, diffuse, n)
        return target.read(components=4)
    finally:
        ctx.disable(ctx.DEPTH_TEST)
        ctx.disable_direct(_SEAMLESS)
        owned.release()
        target.release()


def _draw_meshes(ctx, program, owned, geometry, scene, diffuse, n: int) -> None:
    """Each material's triangles with its Phong terms (buffers owned by ``owned``)."""
    for index, name in enumerate(geometry.material):
        _, ks, exponent = phong_terms(scene, name)
        triangles = geometry.faces[np.all(geometry.mesh_of_vertex[geometry.faces] == index, axis=1)]
        set_uniforms(program, {"u_ks": tuple(ks), "u_level": float(capture.specular_level(exponent, n))})
        buffers = [
            owned.own(ctx.buffer(np.ascontiguousarray(a, np.float32).tobytes()))
            for a in (geometry.positions, geometry.normals, diffuse)
        ]
        indices = owned.own(ctx.buffer(np.ascontiguousarray(triangles, np.int32).tobytes()))
        vao = owned.own(ctx.vertex_array(
            program, [(buffers[0], "3f", "in_position"), (buffers[1], "3f", "in_normal"),
                      (buffers[2], "3f", "in_diffuse")], index_buffer=indices, index_element_size=4))  # fmt: skip
        vao.render()


def ambient(cube) -> np.ndarray:
    """A: the ground's unoccluded irradiance over π, Σ_F L̄_F W_F(+y) / π (the document's weights 0.56 and 0.11
    are these W_F / π)."""
    return (face_weights_exact(np.array([[0.0, 1.0, 0.0]])) @ capture.face_means(cube))[0] / np.pi


def _shadow_grid(centres: np.ndarray, radii: np.ndarray, texels: int) -> tuple[np.ndarray, float]:
    """(x, z) of texel centre 0 and the spacing of a texels² grid over SHADOW_EXTENT × the spheres' footprint."""
    lo = (centres - radii[:, None]).min(axis=0)[[0, 2]]
    hi = (centres + radii[:, None]).max(axis=0)[[0, 2]]
    middle, half = 0.5 * (lo + hi), 0.5 * SHADOW_EXTENT * float(np.max(hi - lo))
    spacing = 2.0 * half / texels
    return middle - half + 0.5 * spacing, spacing


def shadow_texture(centres: np.ndarray, radii: np.ndarray, cube, texels: int = SHADOW_TEXELS):
    """The ground's remaining light fraction Π_i (1 − a_i) (grey), on a texels² grid over SHADOW_EXTENT × the
    spheres' footprint: (grid (T, T), origin (x, z) of texel centre 0, spacing). One fragment per texel on the
    GPU (shaders/shadow.frag; the map's mips and seamless filtering are GL's): what the document does on a phone,
    and 0.9 s a frame in NumPy (:func:`shadow_texture_numpy`, its reference) where the map changes every frame."""
    origin, spacing = _shadow_grid(centres, radii, texels)
    faces = np.ascontiguousarray(capture._faces_of(cube), np.float32)
    ctx = get_context()
    owned = GLObjects(ctx)
    try:
        ctx.enable_direct(_SEAMLESS)
        texture = owned.own(ctx.texture_cube(faces.shape[1:3][::-1], 3, faces.tobytes(), dtype="f4"))
        texture.build_mipmaps()
        texture.use(0)
        spheres = np.concatenate([centres, radii[:, None]], axis=1).astype(np.float32)
        owned.own(ctx.buffer(spheres.tobytes())).bind_to_storage_buffer(0)
        target = owned.own(ctx.texture((texels, texels), 1, dtype="f4"))
        fbo = owned.own(ctx.framebuffer(color_attachments=[target]))
        fbo.use()
        ctx.viewport = (0, 0, texels, texels)
        program = get_program(ctx, SHADOW_PROGRAM)
        set_uniforms(program, {"u_environment": 0, "u_origin": tuple(map(float, origin)), "u_spacing": spacing,
                               "u_count": len(radii), "u_size": float(faces.shape[1]),
                               "u_ambient": max(float(np.linalg.norm(ambient(cube))), 1e-12)})  # fmt: skip
        owned.own(ctx.vertex_array(program, [])).render(vertices=3)
        remaining = np.frombuffer(fbo.read(components=1, dtype="f4"), np.float32).reshape(texels, texels)
    finally:
        ctx.disable_direct(_SEAMLESS)
        owned.release()
    return remaining.astype(np.float64), origin, spacing


def shadow_texture_numpy(centres: np.ndarray, radii: np.ndarray, cube, texels: int = SHADOW_TEXELS):
    """:func:`shadow_texture` in NumPy (float64, ``capture.lookup``): its reference."""
    origin, spacing = _shadow_grid(centres, radii, texels)
    x = origin[0] + spacing * np.arange(texels)
    z = origin[1] + spacing * np.arange(texels)
    points = np.stack(np.broadcast_arrays(x[None, :], 0.0, z[:, None]), axis=-1).reshape(-1, 3)
    chain = capture.mips(cube)
    n = chain[0].shape[1]
    a_ambient = max(float(np.linalg.norm(ambient(cube))), 1e-12)
    remaining = np.ones(len(points))
    for centre, radius in zip(centres, radii, strict=True):  # per sphere: small arrays, faster than all at once
        d = centre - points
        distance = np.linalg.norm(d, axis=1)
        direction = d / distance[:, None]
        sin2 = np.clip(radius / distance, 0.0, 1.0) ** 2
        cos_w = np.clip(direction[:, 1], 0.0, 1.0)
        level = np.log2(np.maximum(n * radius / distance, 1e-6))
        local = np.linalg.norm(capture.lookup(cube, direction, level, chain=chain), axis=1)
        remaining *= 1.0 - np.clip(sin2 * cos_w * np.minimum(local / a_ambient, np.pi), 0.0, 1.0)
    return remaining.reshape(texels, texels), origin, spacing


def sample_shadow(grid: np.ndarray, origin: np.ndarray, spacing: float, points: np.ndarray) -> np.ndarray:
    """Bilinear lookup of the (grey) shadow texture at ground points (N, 3): (N,), 1 outside it."""
    texels = grid.shape[0]
    fx = (points[:, 0] - origin[0]) / spacing
    fz = (points[:, 2] - origin[1]) / spacing
    inside = (fx >= 0) & (fx <= texels - 1) & (fz >= 0) & (fz <= texels - 1)
    out = np.ones(len(points))
    x0 = np.clip(np.floor(fx[inside]).astype(int), 0, texels - 2)
    z0 = np.clip(np.floor(fz[inside]).astype(int), 0, texels - 2)
    tx, tz = fx[inside] - x0, fz[inside] - z0
    out[inside] = ((1 - tz) * ((1 - tx) * grid[z0, x0] + tx * grid[z0, x0 + 1])
                   + tz * ((1 - tx) * grid[z0 + 1, x0] + tx * grid[z0 + 1, x0 + 1]))  # fmt: skip
    return out
