"""The equirectangular (latitude–longitude) map convention shared by the renderer, the references and the
scratches reference: Mitsuba 3's layout (u = atan2(x, −z)/2π, v = acos(y)/π in the map's own frame), and the
rotation of a map about +y. Pure NumPy, below every package that reads environment maps."""

from __future__ import annotations

import numpy as np


def rotation_y(degrees: float) -> np.ndarray:
    """3×3 rotation about +y (right-handed)."""
    a = np.radians(degrees)
    c, s = np.cos(a), np.sin(a)
    return np.array([[c, 0.0, s], [0.0, 1.0, 0.0], [-s, 0.0, c]])


def equirect_direction(u: np.ndarray, v: np.ndarray) -> np.ndarray:
    """Inverse of the Mitsuba-3 mapping u = atan2(x, −z)/2π, v = acos(y)/π (environment's own frame)."""
    phi, theta = np.broadcast_arrays(2.0 * np.pi * np.asarray(u, dtype=np.float64), np.pi * np.asarray(v))
    return np.stack([np.sin(theta) * np.sin(phi), np.cos(theta), -np.sin(theta) * np.cos(phi)], axis=-1)


def row_solid_angles(height: int, width: int) -> np.ndarray:
    """Solid angle of one pixel of each row of a height × width map: Δφ (cos θ_top − cos θ_bottom)."""
    theta = np.linspace(0.0, np.pi, height + 1)
    return (2.0 * np.pi / width) * (np.cos(theta[:-1]) - np.cos(theta[1:]))


def equirect_uv(d: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(u, v) of directions in the environment's frame (Mitsuba 3 layout; same as ``equirect_uv`` in GLSL)."""
    u = np.arctan2(d[..., 0], -d[..., 2]) / (2.0 * np.pi)
    return u - np.floor(u), np.arccos(np.clip(d[..., 1], -1.0, 1.0)) / np.pi
