"""Scene triangles for ray casting (Embree through embreex), with float64 shading at the hits.

The reference sees exactly the triangles the GPU draws (``reflets.scene.geometry.mesh_data``) plus the
area-light polygons (emitters are visible and occlude, as in Mitsuba). Embree intersects in float32; hit
points, normals and tangents are then rebuilt in float64 from the barycentrics. A cut-out material's holes (glTF
alphaMode MASK: coverage under the cut-off) let rays through: a ray that hits one goes on from just past it
(:data:`MAX_CUTOUT_LAYERS` times at most), shadow rays likewise.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..errors import RefletsError
from ..scene.geometry import bounding_sphere, mesh_data
from ..scene.model import PolygonLight, QuadLight, Scene

MESHES, EMITTERS = 0, 1  # Embree geometry ids
#: holes a ray may pass through before the rest is taken as blocked (foliage cards stack a few deep)
MAX_CUTOUT_LAYERS = 64


def _embree():
    try:
        import embreex.mesh_construction as mesh_construction
        import embreex.rtcore_scene as rtcore_scene
    except ImportError as exc:  # pragma: no cover - embreex is a dependency
        raise RefletsError("the reference renderer needs embreex: pip install embreex") from exc
    return rtcore_scene, mesh_construction


@dataclass
class Hits:
    """First hits of a batch of rays: ``kind`` is -1 (miss), MESHES or EMITTERS; ``prim`` indexes the
    triangles of that kind; ``u``, ``v`` are Embree's barycentrics (p = (1−u−v) p0 + u p1 + v p2)."""

    kind: np.ndarray
    prim: np.ndarray
    u: np.ndarray
    v: np.ndarray
    t: np.ndarray


@dataclass
class Surface:
    """Shading data at mesh hits (float64): position, frame (t, b, n as columns of local→world), material."""

    position: np.ndarray
    frame: np.ndarray  # (..., 3, 3): columns t, b, n
    geometric_normal: np.ndarray
    material: np.ndarray  # index into SceneGeometry.material_names


def _hit_uniforms(hits, sel: np.ndarray, salt: np.ndarray | None) -> np.ndarray:
    """A number in [0, 1) per hit, hashed from where it lies (triangle, barycentrics, distance) and the ray's
    ``salt`` (FNV-1a over their bits, then a murmur-style finaliser): a blended surface's stochastic coverage —
    independent between rays, the same for a ray traced twice."""
    words = [hits.prim[sel].astype(np.uint32)]
    extra = () if salt is None else (salt,)
    words += [np.ascontiguousarray(np.asarray(a, np.float32)).view(np.uint32)
              for a in (hits.u[sel], hits.v[sel], hits.t[sel], *extra)]  # fmt: skip
    h = np.full(len(sel), 2166136261, np.uint32)
    for word in words:
        h = (h ^ word) * np.uint32(16777619)
    for shift, factor in ((16, 0x7FEB352D), (15, 0x846CA68B)):
        h = (h ^ (h >> np.uint32(shift))) * np.uint32(factor)
    h ^= h >> np.uint32(16)
    return h.astype(np.float64) / 2.0**32


class SceneGeometry:
    """All triangles of a scene in one Embree scene (meshes + emitters) and one with emitters only."""

    def __init__(self, scene: Scene):
        rtcore_scene, mesh_construction = _embree()
        positions, normals, tangents, uvs, faces, materials, meshes = [], [], [], [], [], [], []
        names = list(scene.materials)
        offset = 0
        for index, mesh in enumerate(scene.mesh):
            data = mesh_data(scene, index)
            positions.append(data.positions.astype(np.float64))
            normals.append(data.normals.astype(np.float64))
            tangents.append(data.tangents.astype(np.float64))
            uvs.append(data.uv_sets.astype(np.float64))
            faces.append(data.indices.astype(np.int64) + offset)
            materials.append(np.full(data.n_triangles, names.index(mesh.material)))
            meshes.append(np.full(data.n_triangles, index))
            offset += data.n_vertices
        self.material_names = names
        #: material index → the cut-out material (its holes let rays through)
        self._cutouts = {k: scene.materials[name] for k, name in enumerate(names) if scene.materials[name].cutout}
        self.vertices = np.concatenate(positions) if positions else np.zeros((0, 3))
        self.normals = np.concatenate(normals) if normals else np.zeros((0, 3))
        self.tangents = np.concatenate(tangents) if tangents else np.zeros((0, 4))
        #: both uv sets (V, 4): textures read either, parametric mirrors start Newton's search at the first
        self.uvs = np.concatenate(uvs) if uvs else np.zeros((0, 4))
        self.faces = np.concatenate(faces) if faces else np.zeros((0, 3), np.int64)
        self.face_material = np.concatenate(materials) if materials else np.zeros(0, np.int64)
        self.face_mesh = np.concatenate(meshes) if meshes else np.zeros(0, np.int64)  # index into scene.mesh

        # Emitters: fan triangles of every quad / polygon light, remembering the light index.
        self.lights = [(i, light) for i, light in enumerate(scene.light) if isinstance(light, QuadLight | PolygonLight)]
        tris, owner = [], []
        for j, (_, light) in enumerate(self.lights):
            poly = light.polygon()
            for k in range(1, len(poly) - 1):
                tris.append([poly[0], poly[k], poly[k + 1]])
                owner.append(j)
        self.emitter_triangles = np.asarray(tris, dtype=np.float64).reshape(-1, 3, 3)
        self.emitter_owner = np.asarray(owner, dtype=np.int64)

        points = np.concatenate([self.vertices, self.emitter_triangles.reshape(-1, 3)])
        centre, radius = bounding_sphere(points) if len(points) else (np.zeros(3), 1.0)
        self.centre, self.radius = centre, max(radius, 1e-6)
        self.epsilon = 1e-5 * self.radius  # ray offset against self-intersection

        self._all = rtcore_scene.EmbreeScene()
        self._emitters_only = rtcore_scene.EmbreeScene()
        # Geometry ids follow creation order; an empty mesh still needs a placeholder to keep ids stable.
        dummy = np.full((1, 3, 3), 1e30, dtype=np.float32)
        mesh_tris = self.vertices[self.faces].astype(np.float32) if len(self.faces) else dummy
        emit_tris = self.emitter_triangles.astype(np.float32) if len(self.emitter_triangles) else dummy
        mesh_construction.TriangleMesh(self._all, mesh_tris)
        mesh_construction.TriangleMesh(self._all, emit_tris)
        mesh_construction.TriangleMesh(self._emitters_only, dummy)
        mesh_construction.TriangleMesh(self._emitters_only, emit_tris)
        self._has = (len(self.faces) > 0, len(self.emitter_triangles) > 0)

    def intersect(self, origins: np.ndarray, directions: np.ndarray, emitters_only: bool = False,
                  salt: np.ndarray | None = None) -> Hits:  # fmt: skip
        """The first hits along rays, through cut-out holes; ``salt`` (N,) in [0, 1): a number per ray that makes a
        blended surface's coverage test differ between rays that are otherwise the same (a pixel's samples through
        its centre)."""
        hits = self._first_hits(origins, directions, emitters_only)
        if emitters_only or not self._cutouts:
            return hits
        origins = np.broadcast_to(origins, np.shape(directions))  # a pinhole's one origin
        pending = self._in_hole(hits, salt)
        for _ in range(MAX_CUTOUT_LAYERS):
            if not pending.any():
                return hits
            idx = np.flatnonzero(pending)
            start = hits.t[idx] + self.epsilon  # on from just past the hole, along the same ray
            again = self._first_hits(origins[idx] + directions[idx] * start[:, None], directions[idx])
            for name in ("kind", "prim", "u", "v"):
                getattr(hits, name)[idx] = getattr(again, name)
            hits.t[idx] = np.where(again.kind >= 0, start + again.t, again.t)
            pending[idx] = self._in_hole(again, None if salt is None else salt[idx])
        hits.kind[pending] = MESHES  # deeper than MAX_CUTOUT_LAYERS: blocked there
        return hits

    def _in_hole(self, hits: Hits, salt: np.ndarray | None) -> np.ndarray:
        """Where a mesh hit lands in a cut-out material's hole."""
        out = np.zeros(len(hits.kind), dtype=bool)
        on_mesh = np.flatnonzero(hits.kind == MESHES)
        materials = self.face_material[hits.prim[on_mesh]]
        for k, material in self._cutouts.items():
            sel = on_mesh[materials == k]
            if len(sel):
                uv = self.uv_sets(hits.prim[sel], hits.u[sel], hits.v[sel])
                out[sel] = material.holes(uv, _hit_uniforms(hits, sel, None if salt is None else salt[sel]))
        return out

    def _first_hits(self, origins: np.ndarray, directions: np.ndarray, emitters_only: bool = False) -> Hits:
        scene = self._emitters_only if emitters_only else self._all
        out = scene.run(
            np.ascontiguousarray(origins, dtype=np.float32),
            np.ascontiguousarray(directions, dtype=np.float32),
            output=1,
        )
        kind = np.where(out["primID"] >= 0, out["geomID"], -1).astype(np.int64)
        kind[(kind == MESHES) & (not self._has[0])] = -1
        kind[(kind == EMITTERS) & (not self._has[1])] = -1
        return Hits(
            kind=kind,
            prim=out["primID"].astype(np.int64),
            u=out["u"].astype(np.float64),
            v=out["v"].astype(np.float64),
            t=out["tfar"].astype(np.float64),
        )

    def occluded(self, origins: np.ndarray, directions: np.ndarray, distances: np.ndarray,
                 salt: np.ndarray | None = None) -> np.ndarray:  # fmt: skip
        """True where something (mesh or emitter) lies between origin and origin + distance · direction (``salt``:
        :meth:`intersect`'s)."""
        if len(origins) == 0:
            return np.zeros(0, dtype=bool)
        res = self._all.run(
            np.ascontiguousarray(origins, dtype=np.float32),
            np.ascontiguousarray(directions, dtype=np.float32),
            dists=np.ascontiguousarray(distances, dtype=np.float32),
            query="OCCLUDED",
        )
        blocked = np.asarray(res) != -1
        if self._cutouts and blocked.any():  # perhaps by a hole only: the first opaque hit decides
            idx = np.flatnonzero(blocked)
            origins = np.broadcast_to(origins, np.shape(directions))
            hits = self.intersect(origins[idx], directions[idx], salt=None if salt is None else salt[idx])
            blocked[idx] = (hits.kind >= 0) & (hits.t < np.broadcast_to(distances, blocked.shape)[idx])
        return blocked

    def uv_sets(self, prim: np.ndarray, u: np.ndarray, v: np.ndarray) -> np.ndarray:
        """The meshes' texture coordinates interpolated at hits (barycentrics ``u``, ``v`` of ``prim``): (N, 4),
        both uv sets (``MeshData.uv_sets``: what ``Material.at`` reads)."""
        w = np.stack([1.0 - u - v, u, v], axis=-1)[..., None]
        return np.sum(w * self.uvs[self.faces[prim]], axis=-2)

    def uv(self, prim: np.ndarray, u: np.ndarray, v: np.ndarray) -> np.ndarray:
        """The first uv set at hits, (N, 2)."""
        return self.uv_sets(prim, u, v)[:, :2]

    def surface(self, prim: np.ndarray, u: np.ndarray, v: np.ndarray, ray_dir: np.ndarray) -> Surface:
        """Interpolated shading frame at mesh hits, flipped to face the ray origin (two-sided surfaces, like
        the GPU's gl_FrontFacing), built exactly like GLSL ``shading_frame``."""
        face = self.faces[prim]
        w = np.stack([1.0 - u - v, u, v], axis=-1)[..., None]
        p = self.vertices[face]
        position = np.sum(w * p, axis=-2)
        n = np.sum(w * self.normals[face], axis=-2)
        n /= np.linalg.norm(n, axis=-1, keepdims=True)
        ng = np.cross(p[:, 1] - p[:, 0], p[:, 2] - p[:, 0])
        ng /= np.maximum(np.linalg.norm(ng, axis=-1, keepdims=True), 1e-300)
        back = np.sum(ng * ray_dir, axis=-1) > 0
        n = np.where(back[:, None], -n, n)
        ng = np.where(back[:, None], -ng, ng)
        tan4 = np.sum(w * self.tangents[face], axis=-2)
        t = tan4[:, :3] - n * np.sum(n * tan4[:, :3], axis=-1, keepdims=True)
        length = np.linalg.norm(t, axis=-1, keepdims=True)
        from ..brdf.base import orthonormal_basis

        fallback, _ = orthonormal_basis(n)
        t = np.where(length > 1e-6, t / np.maximum(length, 1e-300), fallback)
        sign = np.where(tan4[:, 3:4] < 0, -1.0, 1.0)
        b = sign * np.cross(n, t)
        return Surface(
            position=position,
            frame=np.stack([t, b, n], axis=-1),
            geometric_normal=ng,
            material=self.face_material[prim],
        )
