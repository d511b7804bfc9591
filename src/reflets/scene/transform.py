"""4×4 matrices for object placement and the OpenGL camera, in pure NumPy (float64).

Matrices act on column vectors, ``p' = M @ [x, y, z, 1]``; upload them to GLSL transposed (or with
``transpose=True``) since NumPy is row-major and GLSL column-major.
"""

from __future__ import annotations

import math

import numpy as np

from reflets.errors import SceneError


def _vec3(field: str, value: object, *, allow_scalar: bool = False) -> np.ndarray:
    """Three finite numbers (or one, broadcast, when ``allow_scalar``) as a (3,) float64 array."""
    try:
        arr = np.atleast_1d(np.asarray(value, dtype=np.float64))
    except (TypeError, ValueError):
        arr = np.empty(0)
    ok_shape = arr.shape == (3,) or (allow_scalar and arr.shape == (1,))
    if not (ok_shape and np.all(np.isfinite(arr))):
        allowed = "a number or three numbers" if allow_scalar else "three numbers [x, y, z]"
        raise SceneError(f"must be {allowed}, all finite, got {value!r}", field=field)
    return np.broadcast_to(arr, (3,)).copy()


def _rotation(axis: int, degrees: float) -> np.ndarray:
    """Right-handed (counter-clockwise seen from the axis tip) rotation about x (0), y (1) or z (2)."""
    c, s = math.cos(math.radians(degrees)), math.sin(math.radians(degrees))
    i, j = [(1, 2), (2, 0), (0, 1)][axis]
    r = np.eye(4)
    r[i, i], r[i, j], r[j, i], r[j, j] = c, -s, s, c
    return r


def transform_matrix(translate=(0.0, 0.0, 0.0), rotate=(0.0, 0.0, 0.0), scale=1.0) -> np.ndarray:
    """Object-to-world matrix ``M = T · Rz · Ry · Rx · S``.

    Parameters
    ----------
    translate : (3,) float
        Translation applied last.
    rotate : (3,) float
        Angles in degrees about the x, y and z axes; the point is rotated about x first, then y, then z
        (fixed world axes), the usual "XYZ extrinsic" order of DCC tools' Euler angles.
    scale : float or (3,) float
        Scale along the object axes, applied first; must be non-zero (negative values mirror, which
        :meth:`MeshData.transformed` handles by flipping the winding).

    Returns
    -------
    (4, 4) float64
    """
    t = _vec3("translate", translate)
    r = _vec3("rotate", rotate)
    s = _vec3("scale", scale, allow_scalar=True)
    if np.any(s == 0.0):
        raise SceneError(f"must be non-zero on every axis (it would flatten the object), got {scale!r}", field="scale")
    m = _rotation(2, r[2]) @ _rotation(1, r[1]) @ _rotation(0, r[0]) @ np.diag([*s, 1.0])
    m[:3, 3] = t
    return m


def look_at(eye, target, up=(0.0, 1.0, 0.0)) -> np.ndarray:
    """World-to-camera (view) matrix, OpenGL convention: the camera sits at the origin looking down -z, +y up.

    Parameters
    ----------
    eye, target : (3,) float
        Camera position and the point it looks at; must differ.
    up : (3,) float
        Approximate up direction; must not be parallel to ``target - eye``.

    Returns
    -------
    (4, 4) float64
        Rows are the camera axes right, up and backwards (-forward), so ``eye`` maps to the origin and
        ``target`` to ``(0, 0, -|target - eye|)``.
    """
    eye, target, up = _vec3("eye", eye), _vec3("target", target), _vec3("up", up)
    f = target - eye
    dist = np.linalg.norm(f)
    if dist == 0.0:
        raise SceneError(f"must differ from the camera eye {eye.tolist()}", field="target")
    f /= dist
    side = np.cross(f, up)
    if np.linalg.norm(side) <= 1e-9 * np.linalg.norm(up):
        raise SceneError(f"must be non-zero and not parallel to the view direction, got {up.tolist()}", field="up")
    side /= np.linalg.norm(side)
    true_up = np.cross(side, f)
    m = np.eye(4)
    m[0, :3], m[1, :3], m[2, :3] = side, true_up, -f
    m[:3, 3] = -m[:3, :3] @ eye
    return m


def perspective(fov_y_deg: float, aspect: float, near: float, far: float) -> np.ndarray:
    """OpenGL perspective projection (as ``gluPerspective``): camera space to clip space, NDC z ∈ [-1, 1].

    Parameters
    ----------
    fov_y_deg : float
        Full vertical field of view in degrees, in (0, 180).
    aspect : float
        Width / height, > 0.
    near, far : float
        Clip distances along -z, 0 < near < far.

    Returns
    -------
    (4, 4) float64
        A camera-space point on the top frustum plane, ``y = -z tan(fov_y / 2)``, maps to NDC y = 1.
    """
    vals = {"fov_y": fov_y_deg, "aspect": aspect, "near": near, "far": far}
    for name, x in vals.items():
        if not (isinstance(x, int | float | np.number) and math.isfinite(x)):
            raise SceneError(f"must be a finite number, got {x!r}", field=name)
    if not 0.0 < fov_y_deg < 180.0:
        raise SceneError(f"must be in (0, 180) degrees, got {fov_y_deg!r}", field="fov_y")
    if aspect <= 0.0:
        raise SceneError(f"must be > 0, got {aspect!r}", field="aspect")
    if not 0.0 < near < far:
        raise SceneError(f"need 0 < near < far, got near={near!r}, far={far!r}", field="near")
    f = 1.0 / math.tan(math.radians(fov_y_deg) / 2.0)
    m = np.zeros((4, 4))
    m[0, 0], m[1, 1] = f / aspect, f
    m[2, 2], m[2, 3] = (far + near) / (near - far), 2.0 * far * near / (near - far)
    m[3, 2] = -1.0
    return m
