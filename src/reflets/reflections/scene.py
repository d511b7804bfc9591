"""Scene reflectors as NumPy surfaces: the CPU twin of what the ``fermat`` shaders solve on.

A reflector mesh is a canonical shape (sphere, torus, open cylinder, plane, Bézier patch, height field) under
its transform x → A x + t; :class:`AffineSurface` maps a canonical surface, its derivatives, charts and segment
hits through that map, exactly as solver.glsl does (setup in canonical space, Newton on world-space
derivatives), so the NumPy solvers and the GPU solver see the same problem. Bézier and height-field surfaces
are those scene.shapes samples for the mesh, so f(mesh uv) is the mesh vertex.
"""

from __future__ import annotations

import numpy as np

from ..errors import SceneError
from ..scene.model import BezierMesh, CylinderMesh, HeightFieldMesh, PlaneMesh, Scene, SphereMesh, TorusMesh
from ..scene.surfaces import Chart, Cylinder, Plane, Sphere, Surface, Torus, _unit


class AffineChart(Chart):
    """A chart of the canonical surface, evaluated through the affine map."""

    def __init__(self, chart: Chart, linear: np.ndarray, offset: np.ndarray):
        self.chart, self.linear, self.offset = chart, linear, offset
        self.periodic, self.a, self.b = chart.periodic, chart.a, chart.b

    def evaluate(self, s, t, order=2):
        out = self.chart.evaluate(s, t, order)
        return [out[0] @ self.linear.T + self.offset] + [d @ self.linear.T for d in out[1:]]

    def clamp(self, s, t):
        return self.chart.clamp(s, t)

    def to_uv(self, s, t):
        return self.chart.to_uv(s, t)

    def from_uv(self, u, v):
        return self.chart.from_uv(u, v)


class AffineSurface(Surface):
    """``A f(u, v) + t`` for a canonical surface f; normals map by A⁻ᵀ, segment hits are solved in canonical
    space (segments map to segments)."""

    def __init__(self, base: Surface, linear: np.ndarray, offset: np.ndarray):
        self.base = base
        self.linear = np.asarray(linear, dtype=np.float64)
        self.offset = np.asarray(offset, dtype=np.float64)
        self.inverse = np.linalg.inv(self.linear)
        self.periodic, self.closed, self.domain = base.periodic, base.closed, base.domain

    def _to_canonical(self, x) -> np.ndarray:
        return (np.asarray(x, dtype=np.float64) - self.offset) @ self.inverse.T

    def _eval(self, u, v, order):
        out = self.base.evaluate(u, v, order)
        return [out[0] @ self.linear.T + self.offset] + [d @ self.linear.T for d in out[1:]]

    def normal(self, u, v):
        return _unit(self.base.normal(u, v) @ self.inverse)  # A⁻ᵀ n as rows

    @property
    def interior(self):
        return self.base.interior @ self.linear.T + self.offset

    def interior_point(self, E, V):
        return self.base.interior_point(self._to_canonical(E), self._to_canonical(V)) @ self.linear.T + self.offset

    def segment_hit(self, P, O=None):
        O = self.interior if O is None else O
        return self.base.segment_hit(self._to_canonical(P), self._to_canonical(O))

    def implicit(self, x):
        return self.base.implicit(self._to_canonical(x))

    def chart(self, a_uv, b_uv):
        return AffineChart(self.base.chart(a_uv, b_uv), self.linear, self.offset)


def canonical_surface(mesh, index: int = 0) -> Surface:
    """The canonical (untransformed) surface of a reflector mesh, parameterised like scene.shapes."""
    if isinstance(mesh, SphereMesh):
        return Sphere((0.0, 0.0, 0.0), mesh.radius)
    if isinstance(mesh, TorusMesh):
        return Torus((0.0, 0.0, 0.0), mesh.major, mesh.minor)
    if isinstance(mesh, CylinderMesh):
        return Cylinder((0.0, 0.0, 0.0), mesh.radius, mesh.height)
    if isinstance(mesh, PlaneMesh):
        sx, sz = mesh.size
        return Plane((0.0, 0.0, 0.0), (sx, 0.0, 0.0), (0.0, 0.0, -sz))
    if isinstance(mesh, BezierMesh | HeightFieldMesh):
        from ..scene.shapes import bezier_surface, heightfield_surface

        try:
            if isinstance(mesh, BezierMesh):
                return bezier_surface(mesh.control_points)  # the very surface the mesh samples
            return heightfield_surface(mesh.heights, mesh.file, mesh.size, mesh.height_scale)
        except SceneError as exc:
            raise SceneError(exc.message, file=exc.file, field=f"mesh[{index}].{exc.field}") from None
    raise SceneError(
        "reflector shapes are sphere (any transform: ellipsoids), torus, cylinder (caps = false), plane, "
        "bezier and heightfield",
        field=f"mesh[{index}].shape",
    )


def reflector_surface(scene: Scene, index: int) -> AffineSurface:
    """The world-space surface of ``scene.mesh[index]`` (what the fermat shaders solve on)."""
    mesh = scene.mesh[index]
    m = mesh.transform.matrix()
    return AffineSurface(canonical_surface(mesh, index), m[:3, :3], m[:3, 3])
