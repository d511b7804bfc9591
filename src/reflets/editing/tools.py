"""The editing tools of 001 §4.3: bend and expand (warps of the highlight inside a brush, solved for by
``solver.solve``), the stencil and the light tool (functions at the end). A brush is a
disc on the surface (centre, radius, stroke direction); its vertices get a planar parameterisation (the tangent
plane at the centre, scaled to the unit disc, y along the stroke), a warp W moves the highlight pattern inside
it, and the targets are ℓ*_i = J_W(q) ℓ(q) with q = W⁻¹(p_i) (the original ℓ carried along by the warp). The
warps vanish with their derivatives on the brush's boundary (falloff w = (1 − x² − y²)²), so targets there are
the original ℓ: the highlight enters and leaves the brush where it did.

- bend: W(x, y) = (x, y + w/2);
- expand: W(x, y) = (x, y + w sign(y) √|sin y| / 2) [erratum: the document's √(sin y) is undefined for y < 0].
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.interpolate import LinearNDInterpolator, NearestNDInterpolator
from scipy.spatial import QhullError

from .surface import SurfaceMesh

#: the smallest part of a stroke's direction along the surface, relative to its length, that orients a brush
#: (below it the stroke runs along the normal: its y axis would be rounding noise, or NaN for the zero vector)
MIN_TANGENTIAL = 1e-3


class BrushError(ValueError):
    """A brush that cannot be placed on the mesh (its centre off the surface, its stroke along the normal): the
    caller names the stroke it came from (``strokes.EditSession.brush``)."""


def _vector(v) -> str:
    """A point or direction as a message shows it: [x, y, z], six digits each."""
    return "[" + ", ".join(f"{x:.6g}" for x in np.asarray(v, np.float64)) + "]"


@dataclass
class Brush:
    """A disc on the surface: its centre (a point near the mesh), radius, and stroke direction (the y axis of
    its parameterisation; projected on the tangent plane at the vertex nearest the centre)."""

    centre: np.ndarray
    radius: float
    stroke: np.ndarray

    def frame(self, mesh: SurfaceMesh, oriented: bool = True) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        """(origin, x axis, y axis, normal) of the brush's plane, at the vertex nearest the centre (a brush
        smaller than the triangles there holds that vertex alone). A centre off the mesh (farther from that vertex
        than the radius and its longest edge), or (``oriented``: a warp's) a stroke along the normal, is a
        BrushError; unoriented (the stencil reads only distances), a stroke along the normal takes the vertex's
        tangent instead."""
        distances = np.linalg.norm(mesh.positions - np.asarray(self.centre), axis=1)
        nearest = int(np.argmin(distances))
        ring = mesh.positions[mesh.edges[mesh.edges[:, 0] == nearest, 1]] - mesh.positions[nearest]
        reach = self.radius + float(np.linalg.norm(ring, axis=1).max(initial=0.0))
        if distances[nearest] > reach:
            raise BrushError(
                f"centre {_vector(self.centre)} is off the mesh: {distances[nearest]:.4g} from its nearest vertex, "
                f"more than the radius and the edges there ({reach:.4g}); give a point on the surface"
            )
        n = mesh.normals[nearest]
        stroke = np.asarray(self.stroke, np.float64)
        stroke = stroke / max(float(np.abs(stroke).max(initial=0.0)), 1e-300)  # no overflow nor underflow below
        y = stroke - np.dot(stroke, n) * n
        length = float(np.linalg.norm(y))
        if length <= MIN_TANGENTIAL * float(np.linalg.norm(stroke)):  # the zero vector too
            if oriented:
                along = "is the zero vector" if not stroke.any() else f"runs along the surface normal {_vector(n)}"
                raise BrushError(f"stroke {_vector(self.stroke)} {along}; give a direction along the surface")
            y, length = mesh.t[nearest], 1.0
        y = y / length
        return mesh.positions[nearest], np.cross(y, n), y, n

    def coordinates(
        self, mesh: SurfaceMesh, margin: float = 1.0, oriented: bool = True
    ) -> tuple[np.ndarray, np.ndarray]:
        """The vertices within ``margin`` × radius of the centre, and their (x, y) in the unit-disc plane."""
        origin, ex, ey, _ = self.frame(mesh, oriented)
        d = mesh.positions - origin
        xy = np.stack([d @ ex, d @ ey], axis=1) / self.radius
        inside = np.linalg.norm(d, axis=1) < margin * self.radius
        return inside, xy


def falloff(x: np.ndarray, y: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """w = (1 − x² − y²)² inside the unit disc (0 outside), and its derivatives ∂w/∂x, ∂w/∂y."""
    s = np.clip(1.0 - x * x - y * y, 0.0, None)
    return s * s, -4.0 * x * s, -4.0 * y * s


def bend(x: np.ndarray, y: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The bend warp's vertical offset f (W = (x, y + f)) and ∂f/∂x, ∂f/∂y."""
    w, wx, wy = falloff(x, y)
    return 0.5 * w, 0.5 * wx, 0.5 * wy


def expand(x: np.ndarray, y: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The expand warp's offset f = w sign(y) √|sin y| / 2, and its derivatives (∂/∂y infinite at y = 0:
    clipped, the pattern tears open along the stroke's axis there)."""
    w, wx, wy = falloff(x, y)
    g = np.sign(y) * np.sqrt(np.abs(np.sin(y)))
    dg = 0.5 * np.cos(y) / np.maximum(np.sqrt(np.abs(np.sin(y))), 1e-6)
    return 0.5 * w * g, 0.5 * wx * g, 0.5 * (wy * g + w * dg)


WARPS = {"bend": bend, "expand": expand}
#: every tool a stroke may name: the warps, and the stencil (which sets the field under the brush directly)
TOOLS = (*WARPS, "stencil")


def _inverse(warp, x: np.ndarray, y: np.ndarray) -> np.ndarray:
    """q_y with q_y + f(x, q_y) = y (x is kept): bisection (the warps are monotonic in y)."""
    lo, hi = np.full_like(y, -2.0), np.full_like(y, 2.0)
    for _ in range(60):
        mid = 0.5 * (lo + hi)
        above = mid + warp(x, mid)[0] > y
        hi, lo = np.where(above, mid, hi), np.where(above, lo, mid)
    return 0.5 * (lo + hi)


def warp_targets(mesh: SurfaceMesh, ell: np.ndarray, brush: Brush, warp: str = "bend") -> tuple[np.ndarray, np.ndarray]:
    """Targets ℓ* (V, 3; zero outside the brush) and the brush's vertices (V,) for warping the highlight
    tangents ``ell`` (V, 3) by ``warp`` ("bend" or "expand")."""
    f = WARPS[warp]
    origin, ex, ey, _ = brush.frame(mesh)
    support, xy = brush.coordinates(mesh, margin=1.5)  # ℓ is interpolated from a little beyond the brush
    inside = support & (np.linalg.norm(xy, axis=1) < 1.0)
    # ℓ in the brush's plane, by its doubled angle (ℓ and −ℓ are the same highlight), interpolated linearly
    lx, ly = ell[support] @ ex, ell[support] @ ey
    angle2 = 2.0 * np.arctan2(ly, lx)
    doubled_ell = np.stack([np.cos(angle2), np.sin(angle2)], axis=1)
    try:
        interp = LinearNDInterpolator(xy[support], doubled_ell)
    except QhullError:  # fewer than 3 vertices, or all on a line (a brush about a triangle's size): no triangles
        interp = NearestNDInterpolator(xy[support], doubled_ell)
    x, y = xy[inside, 0], xy[inside, 1]
    qy = _inverse(f, x, y)
    doubled = interp(np.stack([x, qy], axis=1))
    carried = ~np.isnan(doubled).any(axis=1)  # q beyond the mesh's border: no ℓ to carry, so no target there
    theta = 0.5 * np.arctan2(doubled[:, 1], doubled[:, 0])
    d = np.stack([np.cos(theta), np.sin(theta)], axis=1)
    _, fx, fy = f(x, qy)
    pushed = np.stack([d[:, 0], fx * d[:, 0] + (1.0 + fy) * d[:, 1]], axis=1)  # J_W(q) ℓ(q)
    # back on each vertex's tangent plane by the inverse of the projection onto the brush's plane (the map the
    # parameterisation used: a direction that the warp leaves alone comes back exactly)
    t, b = mesh.t[inside], mesh.b[inside]
    m = np.stack([np.stack([t @ ex, b @ ex], 1), np.stack([t @ ey, b @ ey], 1)], axis=1)  # P [t b], (N, 2, 2)
    carried &= np.abs(np.linalg.det(m)) > 1e-9  # a tangent plane edge-on to the brush's: nothing maps back
    m[~carried], pushed[~carried] = np.eye(2), 0.0  # so a zero row
    a = np.linalg.solve(m, pushed[..., None])[..., 0]
    world = a[:, :1] * t + a[:, 1:] * b
    targets = np.zeros_like(mesh.positions)
    targets[inside] = world / np.maximum(np.linalg.norm(world, axis=1, keepdims=True), 1e-300)  # 0: no target
    return targets, inside


def stencil(mesh: SurfaceMesh, phi: np.ndarray, h: np.ndarray, brush: Brush, smoothing: int = 10) -> np.ndarray:
    """The stencil (§4.3): inside the brush u = h × n (h·u = 0 everywhere: a highlight *region*, the shape of
    the brush), then ``smoothing`` Laplacian steps on a band at the brush's border (the region is unstable
    there: the field jumps from the stencil to the surrounding one). Returns the new angles."""
    from .analysis import laplacian_step

    near, xy = brush.coordinates(mesh, margin=1.15, oriented=False)
    r = np.linalg.norm(xy, axis=1)
    inside = near & (r < 1.0)
    u = np.cross(h, mesh.normals)
    phi = phi.copy()
    ok = inside & (np.linalg.norm(u, axis=1) > 1e-9)  # h ∥ n: a critical point, any u
    phi[ok] = mesh.angles(u)[ok]
    band = near & (r > 0.85) & (r < 1.15)
    for _ in range(smoothing):
        phi = laplacian_step(mesh, phi, band, 0.5)
    return phi


def light_tool(
    mesh: SurfaceMesh, phi: np.ndarray, vertex: int, ell_target: np.ndarray, eye, samples: int = 721, k: int = 2
) -> tuple[np.ndarray, float]:
    """The light tool (§4.3): with the field fixed, the direction towards a light for which the highlight
    through ``vertex`` runs along ``ell_target``. The half vectors with h·u = 0 form a one-parameter family
    h(θ) = cos θ n + sin θ v; each gives an incoming direction ω_in = 2 (h·ω_out) h − ω_out, kept when
    n·ω_in > ε (ε = π/8, the document's cosine threshold), and its ℓ (eq 4.10); the best match of an exhaustive
    search wins. Returns (ω_in, the angle in degrees between its ℓ and the target)."""
    from .analysis import highlight_g, phi_gradient, weingarten

    n, u = mesh.normals[vertex], mesh.field(phi)[vertex]
    v = np.cross(n, u)
    out = np.asarray(eye, np.float64) - mesh.positions[vertex]
    out /= np.linalg.norm(out)
    theta = np.linspace(-np.pi / 2, np.pi / 2, samples)
    h = np.cos(theta)[:, None] * n + np.sin(theta)[:, None] * v
    incoming = 2.0 * (h @ out)[:, None] * h - out
    valid = incoming @ n > np.pi / 8
    if not valid.any():
        raise ValueError("no light direction above the surface makes a highlight there from this view")
    m = len(h)  # eq 4.10 at the vertex, once per candidate half vector
    h_tb = np.stack([h @ mesh.t[vertex], h @ mesh.b[vertex]], axis=1)
    grad = np.broadcast_to(phi_gradient(mesh, phi, k)[vertex], (m, 2))
    g = highlight_g(np.full(m, phi[vertex]), grad, np.broadcast_to(weingarten(mesh)[vertex], (m, 2, 2)), h_tb, h @ n)
    ell = g[:, :1] * mesh.b[vertex] - g[:, 1:] * mesh.t[vertex]
    target = np.asarray(ell_target, np.float64)
    cos = np.abs(ell @ target) / np.maximum(np.linalg.norm(ell, axis=1) * np.linalg.norm(target), 1e-300)
    cos[~valid] = -1.0
    best = int(np.argmax(cos))
    return incoming[best], float(np.degrees(np.arccos(np.clip(cos[best], 0.0, 1.0))))
