"""Volumetric Monte Carlo ground truth for translucent media (NumPy, vectorised over photons).

:func:`slab_reflectance` traces photons into a homogeneous semi-infinite medium (z < 0) behind a smooth
dielectric boundary of relative index η: exponential free flights (σ_t), Henyey–Greenstein scattering with
absorption weighting (weight × single-scattering albedo per event), Fresnel reflection at the boundary from inside
(total internal reflection included), Russian roulette for low weights. This is the physical process the dipole
models approximate, without any of their assumptions (diffusion, point source at one depth, boundary
condition): the independent reference the profiles are measured against.

Results are per unit flux *transmitted* into the medium (the entry Fresnel factor is the caller's), split into
single scattering (photons that leave after exactly one event) and multiple scattering (two or more), with the
Monte Carlo standard error of each.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from rich.progress import Progress

from ..brdf.base import orthonormal_basis
from ..translucency.medium import Medium
from ..translucency.optics import fresnel_reflectance, henyey_greenstein, refracted_cos, sample_henyey_greenstein


@dataclass
class SlabResult:
    """Exitant flux per unit transmitted flux, split by scattering order."""

    single: float
    multiple: float
    single_stderr: float
    multiple_stderr: float
    photons: int

    @property
    def total(self) -> float:
        return self.single + self.multiple


def _scatter(d: np.ndarray, cos_t: np.ndarray, phi: np.ndarray) -> np.ndarray:
    """Rotate unit directions d by polar angle acos(cos_t) and azimuth phi (a frame built around each d)."""
    sin_t = np.sqrt(np.maximum(0.0, 1.0 - cos_t * cos_t))
    t1, t2 = orthonormal_basis(d)
    return t1 * (sin_t * np.cos(phi))[:, None] + t2 * (sin_t * np.sin(phi))[:, None] + d * cos_t[:, None]


def slab_reflectance(
    medium: Medium,
    photons: int = 200_000,
    *,
    cos_incidence: float = 1.0,
    seed: int = 0,
    chunk: int = 200_000,
    roulette_weight: float = 1e-3,
    max_events: int = 100_000,
) -> SlabResult:
    """Diffuse reflectance of a semi-infinite slab of a one-channel ``medium`` (scalar coefficients, mm⁻¹) lit by
    a collimated beam at ``cos_incidence``; see the module docstring."""
    if np.ndim(medium.sigma_a) != 0:
        raise ValueError("slab_reflectance takes a one-channel medium: use medium.channel(c)")
    sigma_t = float(medium.sigma_t)
    albedo = float(medium.albedo)
    rng = np.random.default_rng(seed)
    sums = np.zeros(2)  # single, multiple: Σ w
    sums2 = np.zeros(2)  # Σ w² (per photon: a photon leaves once)
    cos_in = float(refracted_cos(cos_incidence, medium.eta))
    sin_in = np.sqrt(max(0.0, 1.0 - cos_in * cos_in))
    done = 0
    while done < photons:
        n = min(chunk, photons - done)
        done += n
        pos = np.zeros((n, 3))
        d = np.tile([sin_in, 0.0, -cos_in], (n, 1))
        w = np.ones(n)
        events = np.zeros(n, dtype=np.int64)
        idx = np.arange(n)
        for _ in range(max_events):
            if idx.size == 0:
                break
            s = -np.log1p(-rng.random(idx.size)) / sigma_t
            z_new = pos[idx, 2] + s * d[idx, 2]
            out = z_new > 0.0
            # crossing the boundary: reflect (probability F_R from inside) or leave
            if np.any(out):
                o = idx[out]
                t = -pos[o, 2] / d[o, 2]
                pos[o] += t[:, None] * d[o]
                pos[o, 2] = 0.0
                mu = d[o, 2]
                reflect = rng.random(o.size) < fresnel_reflectance(mu, medium.eta, inside=True)
                d[o[reflect], 2] *= -1.0
                leave = o[~reflect]
                if leave.size:
                    single = events[leave] == 1
                    for k, sel in ((0, single), (1, ~single)):
                        sums[k] += w[leave[sel]].sum()
                        sums2[k] += (w[leave[sel]] ** 2).sum()
                    w[leave] = 0.0
            inside = idx[~out]
            pos[inside] += s[~out, None] * d[inside]
            w[inside] *= albedo
            events[inside] += 1
            cos_t = sample_henyey_greenstein(medium.g, rng.random(inside.size))
            d[inside] = _scatter(d[inside], cos_t, 2.0 * np.pi * rng.random(inside.size))
            # Russian roulette keeps the estimator unbiased while ending long, dim paths
            low = inside[w[inside] < roulette_weight]
            if low.size:
                survive = rng.random(low.size) < 0.1
                w[low[survive]] *= 10.0
                w[low[~survive]] = 0.0
            idx = idx[w[idx] > 0.0]
    mean = sums / photons
    stderr = np.sqrt(np.maximum(sums2 / photons - mean**2, 0.0) / photons)
    return SlabResult(
        single=float(mean[0]),
        multiple=float(mean[1]),
        single_stderr=float(stderr[0]),
        multiple_stderr=float(stderr[1]),
        photons=photons,
    )


# ---------------------------------------------------------------------------------------------- meshes


@dataclass
class VolumetricImage:
    """Mean radiance per pixel and its standard error (float32 (H, W, 3)), with the object mask."""

    image: np.ndarray
    stderr: np.ndarray
    mask: np.ndarray
    spp: int


def _check_volumetric_scene(scene):
    from ..brdf.translucent import Translucent
    from ..errors import ArgumentError
    from ..scene.model import DirectionalLight, PointLight

    materials = {mesh.material for mesh in scene.mesh}
    if len(materials) != 1 or not isinstance(scene.materials[next(iter(materials))], Translucent):
        raise ArgumentError(
            "the volumetric reference renders scenes whose meshes all share one translucent material",
            field="mesh.material",
        )
    material = scene.materials[next(iter(materials))]
    if abs(material.eta - 1.0) > 1e-9:
        raise ArgumentError(
            f"the volumetric reference needs an index-matched boundary (eta = 1, got {material.eta}): through a "
            "smooth refracting boundary a point or directional light cannot be connected to paths",
            field="materials.eta",
        )
    lights = [light for light in scene.light if isinstance(light, PointLight | DirectionalLight)]
    if len(scene.light) != 1 or not lights:
        raise ArgumentError("the volumetric reference needs exactly one point or directional light", field="light")
    return material, lights[0]


def _inside_length(geometry, origins, directions, distances, max_crossings: int = 8) -> np.ndarray:
    """Length of each segment (starting inside the closed mesh) that lies inside the medium, up to ``distances``
    (np.inf: to infinity): exit, re-entry, exit… found by successive ray casts."""
    n = len(origins)
    total = np.zeros(n)
    start = np.zeros(n)  # distance along the ray already handled
    inside = np.ones(n, dtype=bool)
    active = np.arange(n)
    eps = geometry.epsilon
    for _ in range(max_crossings):
        if active.size == 0:
            break
        o = origins[active] + directions[active] * (start[active] + eps)[:, None]
        hits = geometry.intersect(o, directions[active])
        t = np.where(hits.kind >= 0, hits.t + eps, np.inf)
        end = np.minimum(start[active] + t, distances[active])
        seg = end - start[active]
        total[active] += np.where(inside[active], seg, 0.0)
        done = (hits.kind < 0) | (start[active] + t >= distances[active])
        start[active] = end
        inside[active] = ~inside[active]
        active = active[~done]
    return total


def render_volumetric(scene, spp: int = 16, *, seed: int = 0, size=None, progress: bool = True) -> VolumetricImage:
    """Volumetric path tracing of a homogeneous translucent medium inside the scene's closed meshes, lit by one
    point or directional light: the ground truth of the ``translucent`` technique (all orders of scattering).

    Index-matched boundary only (``eta = 1``): camera rays enter straight, every scattering vertex connects to
    the light with a shadow ray whose transmittance counts the medium crossed on the way (re-entries included,
    e.g. through a bunny's ear), free flights that reach the boundary leave. Henyey–Greenstein phase, absorption
    weighting, Russian roulette; each colour channel is its own walk. One pixel-centre ray per sample (as the
    GPU's pixel centres); the image carries its Monte Carlo standard error."""
    from ..reference.geometry import MESHES, SceneGeometry
    from ..scene.camera import pixel_rays
    from ..scene.model import DirectionalLight

    material, light = _check_volumetric_scene(scene)
    if size is not None:
        scene = scene.model_copy(update={"camera": scene.camera.model_copy(update={"size": tuple(size)})})
    geometry = SceneGeometry(scene)
    medium = material.medium()
    scale = material.mm_per_unit  # σ per mm → per scene unit
    origin, dirs = pixel_rays(scene.camera)
    h, w = dirs.shape[:2]
    dirs = dirs.reshape(-1, 3)
    hits = geometry.intersect(np.broadcast_to(origin, dirs.shape), dirs)
    mask = hits.kind == MESHES
    pix = np.nonzero(mask)[0]
    entry = origin + dirs[pix] * hits.t[pix, None]
    rng = np.random.default_rng(seed)
    total = np.zeros((len(pix), 3))
    total2 = np.zeros((len(pix), 3))
    directional = isinstance(light, DirectionalLight)
    if directional:
        to_light = -np.asarray(light.direction, np.float64) / np.linalg.norm(light.direction)
        power = np.asarray(light.irradiance, np.float64)
    else:
        light_pos = np.asarray(light.position, np.float64)
        power = np.asarray(light.intensity, np.float64)
    with Progress(disable=not progress, transient=True) as bar:
        task = bar.add_task("volumetric reference", total=spp * 3)
        for _ in range(spp):
            for c in range(3):
                sigma_t = float(medium.sigma_t[c]) * scale
                albedo = float(medium.albedo[c])
                n = len(pix)
                pos = entry + dirs[pix] * geometry.epsilon
                d = dirs[pix].copy()
                wgt = np.ones(n)
                acc = np.zeros(n)
                idx = np.arange(n)
                for _ in range(100_000):
                    if idx.size == 0:
                        break
                    t = -np.log1p(-rng.random(idx.size)) / sigma_t
                    bound = geometry.intersect(pos[idx], d[idx])
                    leaves = (bound.kind < 0) | (bound.t < t)
                    stay = idx[~leaves]
                    pos[stay] += d[stay] * t[~leaves, None]
                    wgt[stay] *= albedo
                    # next-event estimation towards the light
                    if directional:
                        wl = np.broadcast_to(to_light, (stay.size, 3))
                        dist = np.full(stay.size, np.inf)
                        incident = np.broadcast_to(power[c], stay.size)
                    else:
                        v = light_pos - pos[stay]
                        dist = np.linalg.norm(v, axis=1)
                        wl = v / dist[:, None]
                        incident = power[c] / (dist * dist)
                    inside = _inside_length(geometry, pos[stay], np.ascontiguousarray(wl), dist)
                    phase = henyey_greenstein(np.sum(d[stay] * wl, axis=1), medium.g)
                    acc[stay] += wgt[stay] * phase * incident * np.exp(-sigma_t * inside)
                    cos_t = sample_henyey_greenstein(medium.g, rng.random(stay.size))
                    d[stay] = _scatter(d[stay], cos_t, 2.0 * np.pi * rng.random(stay.size))
                    low = stay[wgt[stay] < 1e-3]
                    if low.size:
                        survive = rng.random(low.size) < 0.1
                        wgt[low[survive]] *= 10.0
                        wgt[low[~survive]] = 0.0
                    idx = stay[wgt[stay] > 0.0]
                total[:, c] += acc
                total2[:, c] += acc * acc
                bar.advance(task)
    mean = total / spp
    var = np.maximum(total2 / spp - mean * mean, 0.0) / max(spp - 1, 1)
    image = np.zeros((h * w, 3), np.float32)
    err = np.zeros((h * w, 3), np.float32)
    image[pix] = mean
    err[pix] = np.sqrt(var)
    return VolumetricImage(image.reshape(h, w, 3), err.reshape(h, w, 3), mask.reshape(h, w), spp)
