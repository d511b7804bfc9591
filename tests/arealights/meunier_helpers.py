"""The area-light document's test scene and the error measures of the brute / adaptive / biased tests.

Scene (Meunier 2007, Figs 2.14–2.18): camera (0, 3, 4) looking at the origin, fov 45°, a 4×4 plane at y = 0,
a unit square one-sided light at height 1 facing down (−y), radiance 5.
"""

from __future__ import annotations

import numpy as np

import reflets
from reflets.validation import polygon_irradiance

SIZE = (100, 75)
#: c1, c2, c4 of the document's light: normalize((c2 − c1) × (c4 − c1)) = (0, −1, 0), towards the plane
CORNERS = [[-0.5, 1.0, -0.5], [0.5, 1.0, -0.5], [-0.5, 1.0, 0.5]]


def document_scene(material: dict, light: dict | None = None, size=SIZE) -> reflets.Scene:
    """The document's plane + light scene with ``material`` on the plane (``light`` replaces the quad)."""
    quad = {"type": "quad", "corners": CORNERS, "radiance": [5, 5, 5]}
    return reflets.load_dict(
        {
            "camera": {"position": [0, 3, 4], "look_at": [0, 0, 0], "fov_y": 45, "size": list(size)},
            "materials": {"floor": material},
            "mesh": [{"shape": "plane", "size": [4, 4], "material": "floor"}],
            "light": [light or quad],
        }
    )


def phong(exponent: float, kd: float = 0.0) -> dict:
    """The document's Phong material (un-normalised form, its eq 1.5), ρ_s = 1."""
    return {"type": "phong", "kd": [kd] * 3, "ks": [1, 1, 1], "exponent": exponent}


def light_normal(light) -> np.ndarray:
    """normalize((c2 − c1) × (c4 − c1)) of a quad light (first three polygon vertices otherwise)."""
    p = light.polygon()
    n = np.cross(p[1] - p[0], p[-1] - p[0])
    return n / np.linalg.norm(n)


def plane_pixels(scene: reflets.Scene, size=SIZE) -> tuple[np.ndarray, np.ndarray]:
    """World positions (H, W, 3) of the plane as the GPU samples them, and the mask of pixels that see the
    plane without the camera ray crossing an emitter first."""
    positions = reflets.render(scene, method="position", size=size).astype(np.float64)
    on_plane = (np.abs(positions[..., 1]) < 1e-4) & np.any(positions != 0.0, axis=-1)
    eye = np.asarray(scene.camera.position, dtype=np.float64)
    behind_emitter = np.zeros(on_plane.shape, dtype=bool)
    for light in scene.light:
        p = light.polygon()
        n = np.cross(p[1] - p[0], p[2] - p[0])
        n /= np.linalg.norm(n)
        d = positions - eye
        denom = d @ n
        t = ((p[0] - eye) @ n) / np.where(np.abs(denom) > 1e-12, denom, np.nan)
        hit = eye + t[..., None] * d
        inside = (t > 0) & (t < 1)
        for k in range(len(p)):
            a, b = p[k], p[(k + 1) % len(p)]
            inside &= (np.cross(b - a, hit - a) @ n) * np.sign(np.cross(p[1] - p[0], p[2] - p[0]) @ n) >= 0
        behind_emitter |= inside
    return positions, on_plane & ~behind_emitter


def relative_mse(image: np.ndarray, exact: np.ndarray, mask: np.ndarray) -> float:
    """mean((a − b)²) / mean(b²) over the masked pixels (all channels)."""
    a, b = image[mask].astype(np.float64), exact[mask].astype(np.float64)
    return float(np.mean((a - b) ** 2) / np.mean(b**2))


def exact_lambert(scene: reflets.Scene, positions: np.ndarray, mask: np.ndarray, albedo: float) -> np.ndarray:
    """Exact radiance of a Lambert plane (normal +y) under the scene's polygon lights (Lambert's formula)."""
    out = np.zeros(positions.shape)
    pts = positions[mask]
    normals = np.broadcast_to([0.0, 1.0, 0.0], pts.shape)
    for light in scene.light:
        e = polygon_irradiance(pts, normals, light.polygon())
        out[mask] += albedo / np.pi * np.outer(e, light.radiance)
    return out
