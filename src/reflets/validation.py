"""Closed-form radiance images for scenes simple enough to solve exactly.

Used by the tests (the GPU renderer must match to 0.5 %) and by the demo (which prints the error), so
the claim "matches the analytic solution" is re-checked on every machine that runs either.
"""

from __future__ import annotations

import numpy as np

from .scene.camera import pixel_rays
from .scene.model import DirectionalLight, PlaneMesh, PointLight, Scene, SphereMesh


class NotAnalytic(ValueError):
    """The scene is not one of the configurations with a closed form."""


def analytic_image(scene: Scene, size: tuple[int, int] | None = None):
    """Exact radiance (H, W, 3) and a mask of pixels where it applies (away from silhouettes and edges).

    Configurations: one Lambert plane (any translation) under point lights, or one Lambert sphere (any
    translation, uniform scale) under directional lights; background black.
    """
    if len(scene.mesh) != 1 or scene.environment is not None:
        raise NotAnalytic("needs exactly one mesh and no environment")
    mesh = scene.mesh[0]
    material = scene.materials[mesh.material]
    if material.type != "lambert" or mesh.transform.rotate != (0.0, 0.0, 0.0):
        raise NotAnalytic("needs an unrotated Lambert mesh")
    if scene.camera.orthographic:
        raise NotAnalytic("needs a perspective camera")
    rho = np.asarray(material.albedo)
    origin, dirs = pixel_rays(scene.camera, size)
    t_centre = np.asarray(mesh.transform.translate, dtype=np.float64)
    scale = np.broadcast_to(np.asarray(mesh.transform.scale, dtype=np.float64), (3,))
    if isinstance(mesh, PlaneMesh) and all(isinstance(light, PointLight) for light in scene.light):
        # Ray / plane y = t_y; inside the (scaled) rectangle, one pixel footprint away from its border.
        t = (t_centre[1] - origin[1]) / np.where(dirs[..., 1] == 0, np.nan, dirs[..., 1])
        hit = origin + t[..., None] * dirs
        half = 0.5 * np.array([mesh.size[0] * scale[0], mesh.size[1] * scale[2]])
        footprint = 2.0 * t * np.tan(np.radians(scene.camera.fov_y) / 2) / (size or scene.camera.size)[1]
        inside = (np.abs(hit[..., 0] - t_centre[0]) < half[0] - 2 * footprint) & (
            np.abs(hit[..., 2] - t_centre[2]) < half[1] - 2 * footprint
        )
        mask = (t > 0) & inside
        normal = np.array([0.0, 1.0 if origin[1] > t_centre[1] else -1.0, 0.0])
        radiance = np.zeros(dirs.shape)
        for light in scene.light:
            d = np.asarray(light.position) - hit
            r2 = np.sum(d * d, axis=-1)
            cos = np.maximum(np.sum(d * normal, axis=-1) / np.sqrt(r2), 0.0)
            cone = light.falloff((-d / np.sqrt(r2)[..., None]).reshape(-1, 3)).reshape(r2.shape)
            radiance += rho / np.pi * np.asarray(light.intensity) * (cone * cos / r2)[..., None]
    elif isinstance(mesh, SphereMesh) and all(isinstance(light, DirectionalLight) for light in scene.light):
        if not np.allclose(scale, scale[0]):
            raise NotAnalytic("needs a uniformly scaled sphere")
        radius = mesh.radius * scale[0]
        oc = origin - t_centre
        b = dirs @ oc
        disc = b * b - (oc @ oc - radius * radius)
        t = -b - np.sqrt(np.maximum(disc, 0.0))
        hit = origin + t[..., None] * dirs
        normal = (hit - t_centre) / radius
        # Keep pixels whose ray is well inside the silhouette (grazing hits are sensitive to tessellation).
        mask = (disc > 0) & (t > 0) & (-(dirs * normal).sum(-1) > 0.2)
        radiance = np.zeros(dirs.shape)
        lit = np.zeros(mask.shape, dtype=bool)
        for light in scene.light:
            wi = -np.asarray(light.direction, dtype=np.float64)
            wi /= np.linalg.norm(wi)
            cos = np.maximum(normal @ wi, 0.0)
            radiance += rho / np.pi * np.asarray(light.irradiance) * cos[..., None]
            lit |= cos > 0.1
        # ... and away from the terminator, where a relative error is ill-conditioned (n·l > 0.1).
        mask &= lit
    else:
        raise NotAnalytic("supported: Lambert plane + point lights, Lambert sphere + directional lights")
    radiance[~mask] = 0.0
    return radiance.astype(np.float32), mask


def max_relative_error(image: np.ndarray, exact: np.ndarray, mask: np.ndarray, floor: float = 1e-3) -> float:
    """Largest |image − exact| / exact over masked pixels whose exact value exceeds ``floor`` × max."""
    keep = mask[..., None] & (exact > floor * exact.max())
    return float(np.max(np.abs(image - exact)[keep] / exact[keep])) if np.any(keep) else 0.0


def polygon_irradiance(
    points: np.ndarray, normals: np.ndarray, polygon: np.ndarray, tolerance: float = 0.0
) -> np.ndarray:
    """Irradiance at ``points`` (normals ``normals``) from a polygon of unit radiance, exact (Lambert 1760):
    E = ½ |Σ_i Θ_i (Γ_i · n)|, u_i = normalize(p_i − x), Θ_i = acos(u_i · u_{i+1}), Γ_i = normalize(u_i × u_{i+1}).

    Every vertex must be above each point's horizon, within ``tolerance`` (a polygon already clipped to it has
    vertices on it, to rounding); no clipping here: configurations that need it raise.
    """
    u = polygon[None, :, :] - points[:, None, :]
    u /= np.linalg.norm(u, axis=-1, keepdims=True)
    if np.any(np.einsum("nvk,nk->nv", u, normals) < -tolerance):
        raise NotAnalytic("a polygon vertex is below the horizon of a shaded point (clipping not implemented)")
    v = np.roll(u, -1, axis=1)
    theta = np.arccos(np.clip(np.sum(u * v, axis=-1), -1.0, 1.0))
    gamma = np.cross(u, v)
    gamma /= np.maximum(np.linalg.norm(gamma, axis=-1, keepdims=True), 1e-300)
    return 0.5 * np.abs(np.sum(theta * np.einsum("nvk,nk->nv", gamma, normals), axis=1))
