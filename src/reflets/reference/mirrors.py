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
"""

from __future__ import annotations

import numpy as np

from ..errors import SceneError
from ..scene.model import CylinderMesh, PlaneMesh, Scene, SphereMesh, TorusMesh

NEWTON_STEPS = 12


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
                "reflector shapes are sphere (any transform: ellipsoids), torus, cylinder (caps = false) and plane",
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


class MirrorBounce:
    """Which mesh triangles are reflectors, their exact surfaces and materials."""

    def __init__(self, scene: Scene, face_mesh: np.ndarray):
        self.face_mesh = face_mesh
        self.surfaces = {
            i: ImplicitReflector(mesh, i) for i, mesh in enumerate(scene.mesh) if getattr(mesh, "reflector", False)
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
            o = np.broadcast_to(origin, d.shape)
            x, n = surface.refine(o, d, hits.t[rows])
            cos = -np.sum(d * n, -1)
            r = d + 2.0 * cos[:, None] * n
            start = x + ref.geometry.epsilon * n
            out[sel] = self.materials[i].specular_reflectance(cos) * ref.trace(start, r, u[rows])
        return out
