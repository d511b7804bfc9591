"""Procedural meshes with exact analytic normals and tangents.

Every builder evaluates a parametric surface ``p(u, v)`` on a regular ``(u, v)`` grid and fills the shading
frame from the analytic derivatives rather than from the triangles, so that interpolated normals and
tangents are as accurate as the tessellation allows and anisotropic BRDFs get a smooth, well-defined
orientation. Conventions (right-handed world, y up):

* ``tangent.xyz`` is the normalised ``∂p/∂u``; ``w = ±1`` is chosen so that ``w * cross(n, t)`` is the
  normalised ``∂p/∂v`` direction (glTF convention). With ``v`` running from the top (+y) down, as on the
  sphere and the cylinder side, the frame is left-handed and ``w = -1``; the plane, the cube, the cylinder
  caps, the torus, the Bézier patch and the height field have ``w = +1``.
* uv lies in [0, 1]; seam vertices are duplicated so uv is continuous on every triangle.
* triangles are counter-clockwise seen from the side the normals point to; degenerate triangles at the
  sphere poles are dropped.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from pathlib import Path

import numpy as np

from reflets.errors import ARRAY_READ_ERRORS, SceneError
from reflets.quantities import MAX_MAGNITUDE
from reflets.scene.meshdata import MeshData, merged

from .surfaces import BezierPatch, HeightField

# 128 × 64 keeps adjacent vertex normals 2π/128 ≈ 2.8° apart: the chord sag is ≈ 3e-4 of the radius and the
# silhouette stays smooth at 1080p for an object filling the frame, at ~8k vertices per object.
DEFAULT_SEGMENTS = (128, 64)


# ----------------------------------------------------------------------------------------------- validation
def _positive(shape: str, field: str, value: object) -> float:
    """Return ``value`` as a float, or raise SceneError unless it is a finite number > 0."""
    try:
        x = float(value)  # type: ignore[arg-type]
    except (TypeError, ValueError):
        x = math.nan
    if not (math.isfinite(x) and x > 0.0):
        raise SceneError(f"must be a finite number > 0 for a {shape}, got {value!r}", field=field)
    return x


def _count(shape: str, field: str, value: object, minimum: int) -> int:
    """Return ``value`` as an int, or raise SceneError unless it is an integer >= ``minimum``."""
    ok = isinstance(value, int | np.integer) and not isinstance(value, bool) and value >= minimum
    if not ok:
        raise SceneError(f"must be an integer >= {minimum} for a {shape}, got {value!r}", field=field)
    return int(value)


def _pair(shape: str, field: str, value: object, minimum: tuple[int, int]) -> tuple[int, int]:
    """Validate a pair of segment counts such as ``(n_u, n_v)``."""
    if not (isinstance(value, list | tuple | np.ndarray) and len(value) == 2):
        raise SceneError(
            f"must be two integers [n_u, n_v] >= {list(minimum)} for a {shape}, got {value!r}", field=field
        )
    return (
        _count(shape, f"{field}[0]", value[0], minimum[0]),
        _count(shape, f"{field}[1]", value[1], minimum[1]),
    )


def _sizes(shape: str, field: str, value: object, n: int) -> np.ndarray:
    """A scalar or n-vector of finite positive extents, as an (n,) float64 array."""
    arr = np.atleast_1d(np.asarray(value, dtype=object))
    if arr.shape not in ((1,), (n,)):
        raise SceneError(
            f"must be a number or {n} numbers, each finite and > 0, for a {shape}, got {value!r}", field=field
        )
    return np.broadcast_to(np.array([_positive(shape, field, x) for x in arr]), (n,)).astype(np.float64)


# ------------------------------------------------------------------------------------------------- helpers
def _unit(v: np.ndarray) -> np.ndarray:
    return v / np.linalg.norm(v, axis=-1, keepdims=True)


def _grid_indices(nu: int, nv: int, flip: bool) -> np.ndarray:
    """Two triangles per cell of an ``(nv+1) × (nu+1)`` vertex grid stored row by row (u fastest).

    With corners a=(i,j), b=(i+1,j), c=(i+1,j+1), d=(i,j+1), (a,b,c),(a,c,d) is counter-clockwise seen from
    ``cross(∂p/∂u, ∂p/∂v)``; ``flip`` reverses it for grids where that cross product points inwards.
    """
    j, i = np.mgrid[0:nv, 0:nu]
    a = (j * (nu + 1) + i).ravel()
    b, c, d = a + 1, a + nu + 2, a + nu + 1
    return np.stack([a, d, c, a, c, b] if flip else [a, b, c, a, c, d], axis=1).reshape(-1, 3)


def _mesh(pos, nrm, tan, w, uv, idx) -> MeshData:
    """Pack float64 arrays into a MeshData, dropping vertices no triangle references."""
    pos, nrm, tan, uv = (np.asarray(x, dtype=np.float64).reshape(-1, x.shape[-1]) for x in (pos, nrm, tan, uv))
    w = np.broadcast_to(np.asarray(w, dtype=np.float64).reshape(-1, 1), (pos.shape[0], 1))
    used, remap = np.unique(idx, return_inverse=True)
    return MeshData(
        positions=pos[used].astype(np.float32),
        normals=_unit(nrm[used]).astype(np.float32),
        tangents=np.concatenate([_unit(tan[used]), w[used]], axis=1).astype(np.float32),
        uvs=uv[used].astype(np.float32),
        indices=remap.reshape(-1, 3).astype(np.uint32),
    )


def _uv_grid(nu: int, nv: int) -> tuple[np.ndarray, np.ndarray]:
    """(nv+1, nu+1) arrays of u and v in [0, 1], u varying fastest."""
    v, u = np.meshgrid(np.linspace(0.0, 1.0, nv + 1), np.linspace(0.0, 1.0, nu + 1), indexing="ij")
    return u, v


# -------------------------------------------------------------------------------------------------- shapes
def plane(size: tuple[float, float] | float = (1.0, 1.0), segments: tuple[int, int] = (1, 1)) -> MeshData:
    """A flat rectangle in the y = 0 plane, centred at the origin, facing +y.

    Parameters
    ----------
    size : (w, d) or scalar
        Extent along x and z: x ∈ [-w/2, w/2], z ∈ [-d/2, d/2].
    segments : (n_x, n_z)
        Grid cells along x and z (>= 1); more cells help per-vertex lighting only.

    Notes
    -----
    ``u`` runs along +x and ``v`` along -z, so uv (0, 0) is the corner (-w/2, 0, +d/2), as a texture laid on
    the floor and seen from a camera looking down -z. Tangent +x, ``w = +1``.
    """
    w, d = _sizes("plane", "size", size, 2)
    nx, nz = _pair("plane", "segments", segments, (1, 1))
    u, v = _uv_grid(nx, nz)
    pos = np.stack([(u - 0.5) * w, np.zeros_like(u), (0.5 - v) * d], axis=-1)
    ones = np.ones_like(u)[..., None]
    return _mesh(pos, ones * [0, 1, 0], ones * [1, 0, 0], 1.0, np.stack([u, v], -1), _grid_indices(nx, nz, False))


def sphere(radius: float = 1.0, segments: tuple[int, int] = DEFAULT_SEGMENTS) -> MeshData:
    """A UV sphere centred at the origin.

    Parameters
    ----------
    radius : float
        > 0.
    segments : (n_u, n_v)
        Cells around the y axis (>= 3) and from pole to pole (>= 2). The default 128 × 64 puts adjacent
        vertex normals 2.8° apart, so interpolated normals deviate from the true sphere by < 0.05° and the
        area is within 0.1 % of 4πr².

    Notes
    -----
    ``p(u, v) = r (sinθ sinφ, cosθ, sinθ cosφ)`` with azimuth ``φ = 2πu`` (u = 0 at +z, increasing towards
    +x, i.e. counter-clockwise about +y) and polar angle ``θ = πv`` (v = 0 at the north pole +y, v = 1 at the
    south pole). The seam column u = 1 duplicates u = 0. Tangent ``(cosφ, 0, -sinφ)`` is defined at the poles
    too, each pole vertex using the azimuth of the middle of its column (u = (i + ½)/n_u) so every pole
    triangle gets its own, non-zero frame. Going south is ``-cross(n, t)``, hence ``w = -1``.
    """
    r = _positive("sphere", "radius", radius)
    nu, nv = _pair("sphere", "segments", segments, (3, 2))
    u, v = _uv_grid(nu, nv)
    # Pole vertices sit mid-column: the north pole of cell i is vertex (i, 0), the south pole (i + 1, n_v).
    u[0] += 0.5 / nu
    u[-1] -= 0.5 / nu
    phi, theta = 2.0 * np.pi * u, np.pi * v
    nrm = np.stack([np.sin(theta) * np.sin(phi), np.cos(theta), np.sin(theta) * np.cos(phi)], axis=-1)
    tan = np.stack([np.cos(phi), np.zeros_like(phi), -np.sin(phi)], axis=-1)
    idx = _grid_indices(nu, nv, flip=True).reshape(nv, 2 * nu, 3)
    # Drop the zero-area triangle of each cell that touches a pole: (a, c, b) in the top row, (a, d, c) below.
    idx = np.concatenate([idx[0, 0::2], idx[1:-1].reshape(-1, 3), idx[-1, 1::2]])
    return _mesh(r * nrm, nrm, tan, -1.0, np.stack([u, v], -1), idx)


def cube(size: float | tuple[float, float, float] = 1.0) -> MeshData:
    """An axis-aligned box centred at the origin: 24 vertices, flat normals, a full [0, 1]² uv per face.

    Parameters
    ----------
    size : float or (sx, sy, sz)
        Edge lengths, > 0.

    Notes
    -----
    Each face has its own (n, t, b) with ``b = cross(n, t)`` (``w = +1``): the ±y faces follow
    :func:`plane` (t = +x), the side faces have v pointing up (+y) and u to the right seen from outside.
    """
    half = 0.5 * _sizes("cube", "size", size, 3)
    # Rows: normal, tangent (u direction); bitangent = cross(n, t).
    frames = np.array(
        [
            [[1, 0, 0], [0, 0, -1]],
            [[-1, 0, 0], [0, 0, 1]],
            [[0, 1, 0], [1, 0, 0]],
            [[0, -1, 0], [1, 0, 0]],
            [[0, 0, 1], [1, 0, 0]],
            [[0, 0, -1], [-1, 0, 0]],
        ],
        dtype=np.float64,
    )
    n, t = frames[:, None, 0], frames[:, None, 1]  # (6, 1, 3)
    b = np.cross(n, t)
    uv = np.array([[0, 0], [1, 0], [1, 1], [0, 1]], dtype=np.float64)  # (4, 2) per face
    pos = (n + (2 * uv[None, :, :1] - 1) * t + (2 * uv[None, :, 1:] - 1) * b) * half  # (6, 4, 3)
    quad = np.array([[0, 1, 2], [0, 2, 3]])
    idx = (quad[None] + 4 * np.arange(6)[:, None, None]).reshape(-1, 3)
    ones = np.ones((6, 4, 1))
    return _mesh(pos, n * ones, t * ones, 1.0, np.broadcast_to(uv, (6, 4, 2)), idx)


def cylinder(radius: float = 1.0, height: float = 2.0, segments: int = 128, caps: bool = True) -> MeshData:
    """A cylinder along the y axis, centred at the origin, y ∈ [-h/2, h/2], closed unless ``caps`` is False.

    Parameters
    ----------
    radius, height : float
        > 0.
    segments : int
        Cells around the axis (>= 3); 128 keeps adjacent side normals 2.8° apart.

    Notes
    -----
    Side: ``p(u, v) = (r sinφ, h/2 - h v, r cosφ)``, ``φ = 2πu`` as on :func:`sphere`, v = 0 at the top rim;
    tangent ``(cosφ, 0, -sinφ)``, ``w = -1``. Caps: a fan with planar uv ``u = ½ + x/2r`` and v along -z
    (top) or +z (bottom), tangent +x, ``w = +1``, like :func:`plane` seen from outside.
    """
    r = _positive("cylinder", "radius", radius)
    h = _positive("cylinder", "height", height)
    n = _count("cylinder", "segments", segments, 3)
    u, v = _uv_grid(n, 1)
    phi = 2.0 * np.pi * u
    nrm = np.stack([np.sin(phi), np.zeros_like(phi), np.cos(phi)], axis=-1)
    tan = np.stack([np.cos(phi), np.zeros_like(phi), -np.sin(phi)], axis=-1)
    pos = r * nrm + (0.5 - v)[..., None] * h * np.array([0, 1, 0])
    side = _mesh(pos, nrm, tan, -1.0, np.stack([u, v], -1), _grid_indices(n, 1, flip=True))
    if not caps:
        return side
    discs = []
    for sign in (1.0, -1.0):
        phi_c = 2.0 * np.pi * np.arange(n) / n
        ring = np.stack([np.sin(phi_c), np.zeros(n), np.cos(phi_c)], axis=-1)
        disc = np.concatenate([np.zeros((1, 3)), ring])  # centre then rim, unit radius
        cpos = r * disc + [0.0, sign * 0.5 * h, 0.0]
        cuv = np.stack([0.5 + 0.5 * disc[:, 0], 0.5 - sign * 0.5 * disc[:, 2]], axis=-1)
        k = np.arange(1, n + 1)
        nxt = k % n + 1
        # Rim order 1..n goes counter-clockwise about +y, so the fan is CCW from above for the top cap.
        fan = np.stack([np.zeros(n, int), k, nxt] if sign > 0 else [np.zeros(n, int), nxt, k], axis=1)
        ones = np.ones((n + 1, 1))
        discs.append(_mesh(cpos, ones * [0, sign, 0], ones * [1, 0, 0], 1.0, cuv, fan))
    return merged([side, *discs])


def torus(major: float = 1.0, minor: float = 0.25, segments: tuple[int, int] = DEFAULT_SEGMENTS) -> MeshData:
    """A ring torus around the y axis, its centre circle in the xz plane.

    Parameters
    ----------
    major : float
        Radius of the centre circle, > 0.
    minor : float
        Radius of the tube, 0 < minor < major (otherwise the surface self-intersects).
    segments : (n_u, n_v)
        Cells around the y axis (>= 3) and around the tube (>= 3).

    Notes
    -----
    ``p(u, v) = ((R + r cosθ) sinφ, r sinθ, (R + r cosθ) cosφ)`` with ``φ = 2πu`` as on :func:`sphere` and
    ``θ = 2πv`` (v = 0 on the outer equator, going up first). Tangent ``(cosφ, 0, -sinφ)``;
    ``cross(n, t)`` is the ∂p/∂v direction, so ``w = +1``.
    """
    big = _positive("torus", "major", major)
    small = _positive("torus", "minor", minor)
    if small >= big:
        raise SceneError(f"must be < major ({big:g}) for a torus, got {small:g}", field="minor")
    nu, nv = _pair("torus", "segments", segments, (3, 3))
    u, v = _uv_grid(nu, nv)
    phi, theta = 2.0 * np.pi * u, 2.0 * np.pi * v
    nrm = np.stack([np.cos(theta) * np.sin(phi), np.sin(theta), np.cos(theta) * np.cos(phi)], axis=-1)
    ring = big * np.stack([np.sin(phi), np.zeros_like(phi), np.cos(phi)], axis=-1)
    tan = np.stack([np.cos(phi), np.zeros_like(phi), -np.sin(phi)], axis=-1)
    return _mesh(ring + small * nrm, nrm, tan, 1.0, np.stack([u, v], -1), _grid_indices(nu, nv, False))


def _patch_mesh(surface, nu: int, nv: int, field: str) -> MeshData:
    """A parametric patch over [0, 1]² sampled on the grid: uv = (u, v) exactly, normal unit(f_u × f_v),
    tangent unit(f_u), w = +1 (then w · cross(n, t) has a positive f_v component)."""
    u, v = _uv_grid(nu, nv)
    pos, fu, fv = surface.evaluate(u, v, 1)
    nrm = np.cross(fu, fv)
    area = np.linalg.norm(nrm, axis=-1)
    scale = np.linalg.norm(fu, axis=-1) * np.linalg.norm(fv, axis=-1)
    bad = ~(area > 1e-9 * scale) | ~np.isfinite(area)
    if np.any(bad):
        j, i = np.argwhere(bad)[0]
        raise SceneError(
            f"the surface is degenerate at (u, v) = ({u[j, i]:.3g}, {v[j, i]:.3g}): f_u × f_v = 0, no normal there",
            field=field,
        )
    return _mesh(pos, nrm, fu, 1.0, np.stack([u, v], -1), _grid_indices(nu, nv, False))


# --------------------------------------------------------------------------------------------- Bézier patch
def bezier_degeneracy(control: np.ndarray) -> str | None:
    """Why a 4 × 4 × 3 control net does not give a regular patch (None if it does).

    Checked on a 17² grid of (u, v), corners included: f_u × f_v must not vanish anywhere, so the mesh's
    exact normals and the reflection solver's tangent frame exist (coincident or collinear points fail)."""
    control = np.asarray(control, dtype=np.float64)
    if control.shape != (4, 4, 3):
        return f"must be 4 × 4 points [x, y, z], got an array of shape {control.shape}"
    if not np.all(np.isfinite(control)):
        return "control points must be finite numbers"
    size = float(np.ptp(control.reshape(-1, 3), axis=0).max())
    if not size > 0:
        return "all control points coincide; the patch is a single point"
    u, v = np.meshgrid(np.linspace(0, 1, 17), np.linspace(0, 1, 17), indexing="xy")
    fu, fv = BezierPatch(control).derivatives(u, v)
    bad = np.linalg.norm(np.cross(fu, fv), axis=-1) <= 1e-9 * size * size
    if np.any(bad):
        j, i = np.argwhere(bad)[0]
        return (
            f"the patch is degenerate at (u, v) = ({u[j, i]:.3g}, {v[j, i]:.3g}): f_u × f_v = 0 there "
            "(coincident or collinear control points), so it has no normal"
        )
    return None


def bezier_surface(control_points) -> BezierPatch:
    """The exact patch of a ``bezier`` mesh (shared by the mesh and the reflection code)."""
    control = np.asarray(control_points, dtype=np.float64)
    problem = bezier_degeneracy(control)
    if problem:
        raise SceneError(problem, field="control_points")
    return BezierPatch(control)


def bezier(control_points, segments: tuple[int, int] = (32, 32)) -> MeshData:
    """A bicubic Bézier patch sampled on a ``(n_u + 1) × (n_v + 1)`` grid of (u, v) ∈ [0, 1]².

    Parameters
    ----------
    control_points : 4 × 4 × 3
        ``control_points[i][j]`` weighs the Bernstein polynomials ``B_i(u) B_j(v)``: the outer list runs
        along u, the inner along v (:class:`reflets.scene.surfaces.BezierPatch`).
    segments : (n_u, n_v)
        Grid cells (>= 1 each).

    Notes
    -----
    The front side is the one ``f_u × f_v`` points to: seen from it, u runs to the right and v up (the net
    ``P00 → P30 → P33`` turns counter-clockwise). uv is exactly the patch parameter (the reference starts
    its Newton refinement there); normal ``unit(f_u × f_v)``, tangent ``unit(f_u)``, ``w = +1``.
    """
    nu, nv = _pair("bezier", "segments", segments, (1, 1))
    return _patch_mesh(bezier_surface(control_points), nu, nv, "control_points")


# --------------------------------------------------------------------------------------------- height field
def heights_problem(heights: np.ndarray) -> str | None:
    """Why an array is not a usable height grid (None if it is)."""
    if heights.ndim != 2:
        return f"heights must be a 2D array (rows along z, columns along x), got {heights.ndim} dimensions"
    if heights.shape[0] < 2 or heights.shape[1] < 2:
        return f"heights need at least 2 × 2 samples, got {heights.shape[0]} × {heights.shape[1]}"
    if not np.all(np.isfinite(heights)):
        return "heights must be finite (found NaN or inf)"
    if np.abs(heights).max() > MAX_MAGNITUDE:
        return f"heights up to {np.abs(heights).max():.3g}, over {MAX_MAGNITUDE:.0e}"
    return None


def load_heights(path: str | Path) -> np.ndarray:
    """A height grid from a NumPy ``.npy`` file, float64; SceneError naming ``file`` otherwise.

    .npy rather than an image: heights are data, not colours — an image would be quantised (8 or 16 bits) and,
    for PNG, sRGB-decoded by the image readers, so the scene author could not write exact heights."""
    path = Path(path)
    if path.suffix.lower() != ".npy":
        raise SceneError(f"height fields are read from NumPy .npy files, got {path.name!r}", file=path, field="file")
    if not path.is_file():
        raise SceneError("height-field file not found", file=path, field="file")
    try:
        grid = np.load(path, allow_pickle=False)
    except ARRAY_READ_ERRORS as exc:
        raise SceneError(f"cannot read as a .npy array ({exc})", file=path, field="file") from None
    if not (np.issubdtype(grid.dtype, np.integer) or np.issubdtype(grid.dtype, np.floating)):
        raise SceneError(f"heights must be real numbers, the file holds {grid.dtype}", file=path, field="file")
    grid = grid.astype(np.float64)
    problem = heights_problem(grid)
    if problem:
        raise SceneError(problem, file=path, field="file")
    return grid


def heightfield_surface(
    heights=None, file=None, size: tuple[float, float] | float = (1.0, 1.0), height_scale: float = 1.0
) -> HeightField:
    """The exact surface of a ``heightfield`` mesh: ``y = height_scale · h(x, z)``, Catmull–Rom bicubic.

    Row 0 of the grid is at z = −d/2, so the rows are reversed into HeightField's v (which runs along −z
    like the plane's, making ``f_u × f_v`` point to +y)."""
    w, d = _sizes("heightfield", "size", size, 2)
    if (heights is None) == (file is None):
        raise SceneError("give exactly one of heights (inline 2D array) or file (a .npy file)", field="heights")
    if heights is not None:
        grid = np.asarray(heights, dtype=np.float64)
        problem = heights_problem(grid)
        if problem:
            raise SceneError(problem, field="heights")
    else:
        grid = load_heights(file)
    scale = float(height_scale)
    if not math.isfinite(scale):
        raise SceneError(f"must be a finite number, got {height_scale!r}", field="height_scale")
    return HeightField(scale * grid[::-1], (-0.5 * w, 0.5 * w), (0.5 * d, -0.5 * d), up="y")


def heightfield(
    heights=None,
    file=None,
    size: tuple[float, float] | float = (1.0, 1.0),
    height_scale: float = 1.0,
    segments: tuple[int, int] | None = None,
) -> MeshData:
    """A height field ``y = height_scale · h(x, z)`` over the rectangle ``size = (w, d)`` centred at the origin.

    Parameters
    ----------
    heights : 2D array (n_z, n_x), or None
        Samples; ``heights[r][c]`` is at ``x = −w/2 + c w/(n_x − 1)``, ``z = −d/2 + r d/(n_z − 1)`` (row 0 at the
        far edge seen from a camera looking down −z, like an image laid on a :func:`plane`).
    file : path of a .npy file, or None
        The same grid from a file (exactly one of heights and file).
    segments : (n_x, n_z) or None
        Grid cells; default one vertex per sample (n_x − 1, n_z − 1). Between samples the surface is the
        Catmull–Rom bicubic interpolant (:class:`reflets.scene.surfaces.HeightField`), so a finer mesh
        follows the same surface.

    Notes
    -----
    uv as on :func:`plane`: u along +x, v along −z (uv (0, 0) at (−w/2, ·, +d/2)); the normal
    ``unit(f_u × f_v)`` has a positive y component; tangent ``unit(f_u)``, ``w = +1``.
    """
    surface = heightfield_surface(heights, file, size, height_scale)
    n_z, n_x = surface.heights.shape
    nu, nv = (n_x - 1, n_z - 1) if segments is None else _pair("heightfield", "segments", segments, (1, 1))
    return _patch_mesh(surface, nu, nv, "heights" if file is None else "file")


SHAPES: dict[str, Callable[..., MeshData]] = {
    "plane": plane,
    "sphere": sphere,
    "cube": cube,
    "cylinder": cylinder,
    "torus": torus,
    "bezier": bezier,
    "heightfield": heightfield,
}
"""Shape name (as written in scene files) → builder."""
