"""Mirror reflections for the reference: one specular bounce on ``reflector = true`` meshes.

The GPU method ``fermat`` renders one reflection of the scene in each smooth reflector; the reference traces
the same light paths independently: a camera ray that hits a reflector is reflected about the **exact**
surface — the hit on the tessellated mesh is refined to the analytic surface by Newton steps on its implicit
equation, and the normal is the implicit gradient there, not the mesh's interpolated normal — and the
reflected ray is shaded like a camera ray (direct lighting with MIS, emitters, background), weighted by the
mirror's reflectance at that incidence. Reflected rays that hit a reflector see its non-specular part only
(one reflection level, as ``fermat``).

The implicit forms (object space, before the mesh transform A x + t; world gradients are A⁻ᵀ ∇g):
sphere |p|² − r², torus (|p|² + R² − r²)² − 4R²(x² + z²), open cylinder x² + z² − r², plane y.
Reflectors known only as f(u, v) (Bézier patches, height fields) are refined parametrically instead: Newton on
o + t d = f(u, v) for (t, u, v) from the mesh hit's interpolated uv (the meshes' uv is the surface parameter),
the normal unit(f_u × f_v) there.
"""

from __future__ import annotations

import numpy as np

from ..errors import SceneError
from ..reflections.scene import reflector_surface
from ..scene.model import BezierMesh, CylinderMesh, HeightFieldMesh, PlaneMesh, Scene, SphereMesh, TorusMesh
from ..scene.surfaces import _solve3

NEWTON_STEPS = 12
#: the parametric refinement: largest (u, v) step (the mesh uv is within a cell of the answer), step halvings,
#: and the distance |o + t d − f(u, v)| / (1 + t) below which a ray has reached the exact surface
MAX_UV_STEP = 0.05
BACKTRACK = 6
HIT_TOL = 1e-9


class ImplicitReflector:
    """The exact surface of one reflector mesh, g(x) = 0 in world space."""

    def __init__(self, mesh, index: int):
        m = mesh.transform.matrix()
        self.linear, self.offset = m[:3, :3], m[:3, 3]
        self.inverse = np.linalg.inv(self.linear)
        if isinstance(mesh, SphereMesh):
            r = mesh.radius
            self._g = lambda p: (np.sum(p * p, -1) - r * r, 2.0 * p)
        elif isinstance(mesh, TorusMesh):
            big, small = mesh.major, mesh.minor

            def torus(p):
                s = np.sum(p * p, -1) + big * big - small * small
                grad = 4.0 * s[:, None] * p - 8.0 * big * big * p * np.array([1.0, 0.0, 1.0])
                return s * s - 4.0 * big * big * (p[:, 0] ** 2 + p[:, 2] ** 2), grad

            self._g = torus
        elif isinstance(mesh, CylinderMesh):
            r = mesh.radius
            self._g = lambda p: (p[:, 0] ** 2 + p[:, 2] ** 2 - r * r, 2.0 * p * np.array([1.0, 0.0, 1.0]))
        elif isinstance(mesh, PlaneMesh):
            self._g = lambda p: (p[:, 1], np.broadcast_to(np.array([0.0, 1.0, 0.0]), p.shape))
        else:
            raise SceneError(
                "reflector shapes are sphere (any transform: ellipsoids), torus, cylinder (caps = false), plane, "
                "bezier and heightfield",
                field=f"mesh[{index}].shape",
            )

    def value_gradient(self, x: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """g(x) and its world-space gradient."""
        p = (x - self.offset) @ self.inverse.T
        g, grad = self._g(p)
        return g, grad @ self.inverse  # A⁻ᵀ ∇g as rows

    def refine(self, origins: np.ndarray, dirs: np.ndarray, t: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Newton on g(o + t d) = 0 from the mesh hit; (exact hit point, unit normal facing the ray)."""
        t = t.copy()
        for _ in range(NEWTON_STEPS):
            g, grad = self.value_gradient(origins + t[:, None] * dirs)
            slope = np.sum(grad * dirs, -1)
            step = np.where(np.abs(slope) > 1e-300, g / np.where(slope == 0, 1.0, slope), 0.0)
            t -= np.clip(step, -1e-2 * (1.0 + t), 1e-2 * (1.0 + t))  # the mesh hit is already close
        x = origins + t[:, None] * dirs
        _, n = self.value_gradient(x)
        n /= np.linalg.norm(n, axis=-1, keepdims=True)
        n = np.where(np.sum(n * dirs, -1, keepdims=True) > 0, -n, n)
        return x, n


class ParametricReflector:
    """The exact surface of a reflector with no implicit form (Bézier patch, height field), as world-space
    f(u, v) (``reflets.reflections.scene.reflector_surface``: the surface the mesh samples)."""

    def __init__(self, scene: Scene, index: int):
        self.surface = reflector_surface(scene, index)

    def solve(
        self, origins: np.ndarray, dirs: np.ndarray, t: np.ndarray, uv: np.ndarray
    ) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        """Newton on F(t, u, v) = o + t d − f(u, v) = 0 (Jacobian [d, −f_u, −f_v]) from the mesh hit (t, uv).

        Damped so that it cannot wander off: (u, v) steps are capped (``MAX_UV_STEP``) and kept in [0, 1]², and
        a step is halved (up to ``BACKTRACK`` times) until |F| decreases, else the point stays put. Returns
        t, u, v and |F|: above ``HIT_TOL`` the ray meets no exact surface near its mesh hit (it grazes a bump
        the tessellation cut through, or passes just outside the patch's curved border)."""
        origins = np.broadcast_to(origins, dirs.shape)
        t, u, v = t.astype(np.float64).copy(), uv[:, 0].astype(np.float64).copy(), uv[:, 1].astype(np.float64).copy()
        err = np.linalg.norm(origins + t[:, None] * dirs - self.surface.position(u, v), axis=-1)
        for _ in range(NEWTON_STEPS):
            f, fu, fv = self.surface.evaluate(u, v, 1)
            step, _ = _solve3(np.stack([dirs, -fu, -fv], axis=-1), f - origins - t[:, None] * dirs)
            step *= np.minimum(1.0, MAX_UV_STEP / np.maximum(np.linalg.norm(step[:, 1:], axis=-1), 1e-300))[:, None]
            pending = err > 0.0
            for _ in range(BACKTRACK):
                if not pending.any():
                    break
                t1 = t + step[:, 0]
                u1, v1 = self.surface.clamp(u + step[:, 1], v + step[:, 2])
                e1 = np.linalg.norm(origins + t1[:, None] * dirs - self.surface.position(u1, v1), axis=-1)
                take = pending & (e1 < err)
                t, u, v, err = (np.where(take, new, old) for new, old in ((t1, t), (u1, u), (v1, v), (e1, err)))
                pending &= ~take
                step *= 0.5
        return t, u, v, err

    def refine(
        self, origins: np.ndarray, dirs: np.ndarray, t: np.ndarray, uv: np.ndarray
    ) -> tuple[np.ndarray, np.ndarray]:
        """(exact hit f(u, v), unit normal unit(f_u × f_v) facing the ray); where no exact hit is near, the mesh
        hit and the surface normal at the mesh uv (the best local guess, as the implicit refinement's)."""
        t1, u, v, err = self.solve(origins, dirs, t, uv)
        ok = err <= HIT_TOL * (1.0 + np.abs(t1))
        u, v = np.where(ok, u, uv[:, 0]), np.where(ok, v, uv[:, 1])
        x, fu, fv = self.surface.evaluate(u, v, 1)
        x = np.where(ok[:, None], x, origins + t[:, None] * dirs)
        n = np.cross(fu, fv)
        n /= np.maximum(np.linalg.norm(n, axis=-1, keepdims=True), 1e-300)
        n = np.where(np.sum(n * dirs, -1, keepdims=True) > 0, -n, n)
        return x, n


def reflector(scene: Scene, index: int) -> ImplicitReflector | ParametricReflector:
    """The reference's exact surface of reflector ``index``: implicit where a closed form exists."""
    mesh = scene.mesh[index]
    if isinstance(mesh, BezierMesh | HeightFieldMesh):
        return ParametricReflector(scene, index)
    return ImplicitReflector(mesh, index)


def _above_mesh(geometry, prim: np.ndarray, mesh_hit: np.ndarray, x: np.ndarray, dirs: np.ndarray) -> np.ndarray:
    """Where the reflected ray leaves: the exact point x, lifted onto the hit triangle's plane when it lies
    behind it (plus the usual epsilon). On concave parts the exact surface is behind the chords, and a ray
    leaving from x would hit its own tessellation at about the chord sag (measured: over half of a bumpy
    patch's pixels); the lift is at most that sag."""
    p = geometry.vertices[geometry.faces[prim]]
    ng = np.cross(p[:, 1] - p[:, 0], p[:, 2] - p[:, 0])
    ng /= np.maximum(np.linalg.norm(ng, axis=-1, keepdims=True), 1e-300)
    ng = np.where(np.sum(ng * dirs, -1, keepdims=True) > 0, -ng, ng)  # towards the viewer
    lift = np.maximum(np.sum((mesh_hit - x) * ng, -1), 0.0)
    return x + (lift + geometry.epsilon)[:, None] * ng


class MirrorBounce:
    """Which mesh triangles are reflectors, their exact surfaces and materials."""

    def __init__(self, scene: Scene, face_mesh: np.ndarray):
        self.face_mesh = face_mesh
        self.surfaces = {
            i: reflector(scene, i) for i, mesh in enumerate(scene.mesh) if getattr(mesh, "reflector", False)
        }
        self.materials = {i: scene.materials[scene.mesh[i].material] for i in self.surfaces}

    def __bool__(self) -> bool:
        return bool(self.surfaces)

    def radiance(self, ref, idx: np.ndarray, hits, origin: np.ndarray, dirs: np.ndarray, u: np.ndarray) -> np.ndarray:
        """Reflected radiance × reflectance for the camera samples ``idx`` (mesh hits), zero off reflectors."""
        out = np.zeros((len(idx), 3))
        mesh_of = self.face_mesh[hits.prim[idx]]
        for i, surface in self.surfaces.items():
            sel = np.nonzero(mesh_of == i)[0]
            if len(sel) == 0:
                continue
            rows = idx[sel]
            d = dirs[rows]
            o = origin[rows] if np.ndim(origin) == 2 else np.broadcast_to(origin, d.shape)  # per ray: orthographic
            uvs = ref.geometry.uv_sets(hits.prim[rows], hits.u[rows], hits.v[rows])  # (a mapped reflectance reads them)
            if isinstance(surface, ParametricReflector):
                x, n = surface.refine(o, d, hits.t[rows], uvs[:, :2])
                start = _above_mesh(ref.geometry, hits.prim[rows], o + hits.t[rows, None] * d, x, d)
            else:
                x, n = surface.refine(o, d, hits.t[rows])
                start = x + ref.geometry.epsilon * n
            cos = -np.sum(d * n, -1)
            r = d + 2.0 * cos[:, None] * n
            out[sel] = self.materials[i].specular_reflectance(cos, uvs) * ref.trace(start, r, u[rows])
        return out
