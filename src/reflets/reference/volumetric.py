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

:func:`render_volumetric` path traces the same medium inside a scene's closed meshes, lit by one point or
directional light: straight shadow rays through an index-matched boundary (η = 1), or, through a smooth
refracting one, Fresnel and Snell at every crossing and a manifold connection to the light (a point light
cannot be reached through a refracting boundary by tracing or by a shadow ray: its refracted path to an interior
point is found by Newton's method, and its flux density there from the beam's cross-section).
"""

from __future__ import annotations

import numbers
from dataclasses import dataclass
from pathlib import Path

import numpy as np
from rich.progress import BarColumn, Progress, TextColumn, TimeRemainingColumn

from ..brdf.base import orthonormal_basis
from ..errors import ArgumentError
from ..scene.lightmask import LUMINANCE
from ..translucency.medium import Medium
from ..translucency.optics import (
    fresnel_reflectance,
    fresnel_transmittance,
    henyey_greenstein,
    refracted_cos,
    sample_henyey_greenstein,
)
from .checkpoint import PartialSums, reference_key
from .parallel import ordered, places, within_memory
from .results import VolumetricImage


@dataclass
class SlabResult:
    """Exitant flux per unit transmitted flux, split by scattering order."""

    single: float
    multiple: float
    single_stderr: float
    multiple_stderr: float
    photons: int
    #: multiple scattering's exitance per photon in radial bins about the entry point (``radial_edges``)
    radial: np.ndarray | None = None

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
    radial_edges: np.ndarray | None = None,
) -> SlabResult:
    """Diffuse reflectance of a semi-infinite slab of a one-channel ``medium`` (scalar coefficients, mm⁻¹) lit by
    a collimated beam at ``cos_incidence``; see the module docstring. ``radial_edges``: also the multiple
    scattering's radial distribution of exit points (a diffusion profile's shape)."""
    if np.ndim(medium.sigma_a) != 0:
        raise ValueError("slab_reflectance takes a one-channel medium: use medium.channel(c)")
    sigma_t = float(medium.sigma_t)
    albedo = float(medium.albedo)
    rng = np.random.default_rng(seed)
    sums = np.zeros(2)  # single, multiple: Σ w
    sums2 = np.zeros(2)  # Σ w² (per photon: a photon leaves once)
    radial = None if radial_edges is None else np.zeros(len(radial_edges) - 1)
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
                    if radial_edges is not None:
                        many = leave[~single]
                        radial += np.histogram(np.hypot(pos[many, 0], pos[many, 1]), radial_edges, weights=w[many])[0]
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
        radial=None if radial is None else radial / photons,
    )


# ---------------------------------------------------------------------------------------------- meshes


def _check_volumetric_scene(scene):
    from ..errors import ArgumentError
    from ..scene.model import DirectionalLight, EnvironmentLight, PointLight, PolygonLight, QuadLight
    from ..translucency.material import Translucent

    materials = {mesh.material for mesh in scene.mesh}
    if len(materials) != 1 or not isinstance(scene.materials[next(iter(materials))], Translucent):
        raise ArgumentError(
            "the volumetric reference renders scenes whose meshes all share one translucent material",
            field="mesh.material",
        )
    material = scene.materials[next(iter(materials))]
    kinds = PointLight | DirectionalLight | QuadLight | PolygonLight | EnvironmentLight
    lights = [light for light in scene.light if isinstance(light, kinds)]
    if len(scene.light) != 1 or not lights:
        raise ArgumentError(
            "the volumetric reference needs exactly one point, directional, quad, polygon or environment light",
            field="light",
        )
    if getattr(lights[0], "mask", None) is not None:
        raise ArgumentError("the volumetric reference takes quad lights without a mask", field="light[0].mask")
    if scene.camera.orthographic:
        raise ArgumentError("the volumetric reference traces from a pinhole: the camera must be perspective",
                            field="camera.projection")  # fmt: skip
    if getattr(lights[0], "spot", None) is not None:
        raise ArgumentError("the volumetric reference takes isotropic point lights: drop the spot cone",
                            field="light[0].spot")  # fmt: skip
    return material, lights[0]


class _NextEvent:
    """The scene's one light as the walks connect to it from a scattering vertex: a point light (position and
    intensity per channel, times the emitter's cos θ_y once the light ray's leaving direction is known) or a
    directional light (travel direction, irradiance per channel). A quad or polygon light is a uniform point y of
    the emitter (reference.lights.PolygonSampler) of intensity L A cos θ_y; the environment an importance-sampled
    direction ω (EnvironmentSampler) of irradiance L(ω) / p(ω)."""

    def __init__(self, scene, light):
        from ..scene.environment import load_environment
        from ..scene.model import DirectionalLight, EnvironmentLight, PolygonLight, QuadLight
        from .lights import EnvironmentSampler, PolygonSampler

        self.light = light
        self.polygon = PolygonSampler(light) if isinstance(light, QuadLight | PolygonLight) else None
        self.sky = EnvironmentSampler(load_environment(scene), light) if isinstance(light, EnvironmentLight) else None
        #: a point (position) to connect to, else a direction (the light's travel)
        self.point = not isinstance(light, DirectionalLight | EnvironmentLight)

    def draw(self, rng, n: int) -> tuple[np.ndarray, np.ndarray]:
        """(positions, or travel directions, (n, 3); intensity, or irradiance, per channel (n, 3)) for n vertices."""
        light = self.light
        if self.polygon is not None:
            y = self.polygon.sample(rng.random(n), rng.random(n))
            return y, self.polygon.radiance_at(y) * self.polygon.area
        if self.sky is not None:
            towards, pdf = self.sky.sample(rng.random(n), rng.random(n))
            ok = pdf > 0.0
            irradiance = np.where(ok[:, None], self.sky.radiance(towards) / np.where(ok, pdf, 1.0)[:, None], 0.0)
            return -towards, irradiance
        if self.point:
            return _rows(light.position, n), _rows(light.intensity, n)
        return _rows(np.asarray(light.direction, np.float64) / np.linalg.norm(light.direction), n), _rows(
            light.irradiance, n
        )

    def cosine(self, leaving: np.ndarray) -> np.ndarray | float:
        """The emitter's cos θ_y for light rays leaving it along ``leaving`` (0 behind a one-sided emitter)."""
        if self.polygon is None:
            return 1.0
        cos, front = self.polygon.emitted(-leaving)
        return np.where(front, cos, 0.0)


def _rows(vector, n: int) -> np.ndarray:
    return np.broadcast_to(np.asarray(vector, np.float64), (n, 3))


def _light_stream(rng):
    """A stream for the light's random points and directions, independent of the walks' (spawned from the same
    seed: the walks draw the same numbers whatever the light)."""
    return np.random.default_rng(rng.bit_generator.seed_seq.spawn(1)[0])


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


#: bytes the walks hold per image pixel, index-matched and refracting (measured on a sphere covering 71 % of the
#: image, 128×96 to 1024×768: 416–437 and 4,174–4,426 B per image pixel, i.e. 620 and 6,300 per covered pixel),
#: counted over every pixel (an object may cover the whole image), and a process's fixed working set
VOLUMETRIC_BYTES_PER_PIXEL = {False: 640, True: 6400}
VOLUMETRIC_FIXED_BYTES = 64_000_000


def volumetric_bytes(scene, size=None, workers: int = 1, refract: bool | None = None) -> int:
    """Peak bytes of :func:`render_volumetric`: per process that walks (and the parent's own job beside
    ``workers > 1`` processes), width · height · VOLUMETRIC_BYTES_PER_PIXEL (refracting or not) +
    VOLUMETRIC_FIXED_BYTES."""
    width, height = size or scene.camera.size
    per_pixel, fixed = _memory_terms(scene, workers, refract)
    return fixed + width * height * per_pixel


def _memory_terms(scene, workers: int, refract) -> tuple[int, int]:
    """(bytes per image pixel, fixed bytes) of :func:`volumetric_bytes`, over every process."""
    material, _ = _check_volumetric_scene(scene)
    refracting = abs(material.eta - 1.0) > 1e-9 if refract is None else bool(refract)
    processes = workers + 1 if workers > 1 else 1
    return processes * VOLUMETRIC_BYTES_PER_PIXEL[refracting], processes * VOLUMETRIC_FIXED_BYTES


def render_volumetric(
    scene,
    spp: int = 16,
    *,
    seed: int = 0,
    size=None,
    progress: bool = True,
    refract: bool | None = None,
    orders: int | None = None,
    workers: int | None = 1,
    cluster=None,
    checkpoint: str | Path | None = None,
    keep_checkpoint: bool = False,
    target_error: float | None = None,
) -> VolumetricImage:
    """Volumetric path tracing of a homogeneous translucent medium inside the scene's closed meshes, lit by one
    point, directional, quad, polygon or environment light (an emitter's points sampled uniformly over its area,
    each a point light of intensity L A cos θ_y; the sky importance-sampled, each direction a directional light of
    irradiance L / p): the ground truth of the ``translucent`` technique (all orders of scattering).

    Index-matched boundary (``eta = 1``): camera rays enter straight, every scattering vertex connects to
    the light with a shadow ray whose transmittance counts the medium crossed on the way (re-entries included,
    e.g. through a bunny's ear), free flights that reach the boundary leave. Henyey–Greenstein phase, absorption
    weighting, Russian roulette; each colour channel is its own walk. One pixel-centre ray per sample (as the
    GPU's pixel centres); the image carries its Monte Carlo standard error.

    A refracting boundary (``eta ≠ 1``, or ``refract=True``) goes through :func:`_walk_refracting`: Fresnel
    and Snell at every crossing, and the light reached through the boundary by a manifold connection
    (:func:`_refracted_connection`). There the camera ray's own reflection is left out (the image is the light
    that leaves the medium towards the camera: the technique's ``single`` + ``multiple`` terms). ``orders``
    caps the scattering events per path (1: single scattering only).

    The samples are drawn in blocks (:func:`sample_blocks`: fixed by ``spp`` and the pixels, never by the
    workers), each from its own child of ``seed``'s SeedSequence, and their sums added in block order:
    ``workers > 1`` shares the blocks between that many processes (a reference at the document's 1024×768 takes
    an hour of one core), ``cluster`` between the workers of a Dask cluster (reflets.reference.cluster), and both
    give the same image and standard error, bit for bit, as one process.

    ``checkpoint``: an ``.npz`` file the partial sums are written to as the blocks complete — every
    ``checkpoint.SAVE_EVERY_S`` seconds, and at once on Ctrl-C or an error (a kill loses the blocks since the last
    write, and those running) (:mod:`reflets.reference.checkpoint`); when it exists, the run goes on from it and
    ends in the uninterrupted run's image. It holds the finished sums at the end: removed here unless
    ``keep_checkpoint`` (the CLI removes it once the images are written).
    ``target_error``: stop after the first block at which the mean relative standard error of the object's pixels
    (luminance) is at most this (``result.spp``: the samples taken) — the same block for any number of workers."""
    if size is not None:
        scene = scene.model_copy(update={"camera": scene.camera.model_copy(update={"size": tuple(size)})})
    if target_error is not None and (isinstance(target_error, bool) or not isinstance(target_error, numbers.Real)
                                     or not 0 < target_error < 1):  # fmt: skip
        raise ArgumentError(f"must be a number in (0, 1), got {target_error!r}", field="target_error")
    place = places(None if cluster is not None else workers, cluster)  # workers: this machine's (not a cluster's)
    try:
        if workers is None:  # every core by default: as many as the memory holds (a count given is checked)
            one = volumetric_bytes(scene, None, 1, refract)
            place = within_memory(place, one, one)
        _check_memory(scene, place.processes, refract)
        job = _VolumetricJob(scene, refract, orders)
        blocks, tiles = task_plan(spp, len(job.pix))
        partial = None
        if checkpoint is not None:
            key = reference_key(scene, engine="volumetric", sampling=SAMPLING_VERSION, spp=spp, seed=seed,
                                refract=refract, orders=orders, blocks=blocks, tiles=tiles)  # fmt: skip
            partial = PartialSums(checkpoint, key)
        # an albedo map: the light leaving the medium towards the camera × its texel where it leaves (the camera hit)
        tint = job.material.tint(job.geometry.uv_sets(job.hits.prim[job.pix], job.hits.u[job.pix],
                                                      job.hits.v[job.pix]))  # fmt: skip
        runner = _BlockRunner(job, blocks, tiles, seed, tint, partial, target_error)
        runner.run(place, (scene, refract, orders), progress)
    finally:
        place.close()
    if partial is not None and not keep_checkpoint:
        partial.remove()
    mean, var = mean_and_variance(runner.total, runner.total2, runner.samples, tint)
    spp = runner.samples
    h, w = job.shape
    image = np.zeros((h * w, 3), np.float32)
    err = np.zeros((h * w, 3), np.float32)
    image[job.pix] = mean
    err[job.pix] = np.sqrt(var)
    return VolumetricImage(image.reshape(h, w, 3), err.reshape(h, w, 3), job.mask.reshape(h, w), spp)


def _check_memory(scene, workers: int, refract) -> None:
    from ..resources import check, fitting_size

    width, height = scene.camera.size
    per_pixel, fixed = _memory_terms(scene, workers, refract)
    check(
        "size",
        volumetric_bytes(scene, None, workers, refract),
        value=f"{width}x{height}",
        what=f"the volumetric reference: {width * height:,} pixels × {per_pixel:,} B"
        + (f" over {workers} processes and this one" if workers > 1 else ""),
        fits=lambda budget: fitting_size(width, height, per_pixel, max(budget - fixed, 0)),
    )


class _VolumetricJob:
    """One scene's camera rays, geometry and light, ready to draw samples (rebuilt in each worker process)."""

    def __init__(self, scene, refract, orders):
        from ..scene.camera import pixel_rays
        from .geometry import MESHES, SceneGeometry

        material, light = _check_volumetric_scene(scene)
        self.source = _NextEvent(scene, light)
        self.geometry = SceneGeometry(scene.model_copy(update={"light": []}))  # the medium's boundary only
        self.medium = material.medium()
        self.scale = material.mm_per_unit  # σ per mm → per scene unit
        self.orders = orders
        origin, dirs = pixel_rays(scene.camera)
        self.shape = dirs.shape[:2]
        self.dirs = dirs.reshape(-1, 3)
        self.hits = self.geometry.intersect(np.broadcast_to(origin, self.dirs.shape), self.dirs)
        self.mask = self.hits.kind == MESHES
        self.pix = np.nonzero(self.mask)[0]
        self.entry = origin + self.dirs[self.pix] * self.hits.t[self.pix, None]
        self.material = material
        self.refracting = abs(material.eta - 1.0) > 1e-9 if refract is None else refract
        self.label = "volumetric reference" + (" (refracting boundary)" if self.refracting else "")

    def task(self, task, advance) -> tuple[np.ndarray, np.ndarray]:
        """A block of samples over a tile of the object's pixels (reflets.reference.parallel): (spp, its
        SeedSequence, (first, stop) object pixels) → its sums."""
        spp, seed, tile = task
        return self.sums(spp, np.random.default_rng(seed), advance, slice(*tile))

    def sums(self, spp: int, rng, advance, tile: slice = slice(None)) -> tuple[np.ndarray, np.ndarray]:
        """Per-pixel Σ and Σ² over ``spp`` samples (P, 3) of the object's pixels ``tile``; ``advance(k)`` after
        every k samples done."""
        pix = self.pix[tile]
        if self.refracting:
            return _render_refracting(
                self.geometry, self.medium, self.scale, self.source, self.dirs[pix], self.hits, pix,
                spp, rng, self.orders, advance,
            )  # fmt: skip
        return self._sums_index_matched(spp, rng, advance, tile)

    def _sums_index_matched(self, spp, rng, advance, tile: slice):
        geometry, medium, source, orders = self.geometry, self.medium, self.source, self.orders
        pix, entry = self.pix[tile], self.entry[tile]
        dirs = self.dirs
        total = np.zeros((len(pix), 3))
        total2 = np.zeros((len(pix), 3))
        light_rng = _light_stream(rng)
        for _ in range(spp):
            for c in range(3):
                sigma_t = float(medium.sigma_t[c]) * self.scale
                albedo = float(medium.albedo[c])
                n = len(pix)
                pos = entry + dirs[pix] * geometry.epsilon
                d = dirs[pix].copy()
                wgt = np.ones(n)
                acc = np.zeros(n)
                events = np.zeros(n, dtype=np.int64)
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
                    where, power = source.draw(light_rng, stay.size)
                    if source.point:
                        v = where - pos[stay]
                        dist = np.linalg.norm(v, axis=1)
                        wl = v / dist[:, None]
                        incident = power[:, c] / (dist * dist) * source.cosine(-wl)
                    else:
                        wl, dist, incident = -where, np.full(stay.size, np.inf), power[:, c]
                    inside = _inside_length(geometry, pos[stay], np.ascontiguousarray(wl), dist)
                    phase = henyey_greenstein(np.sum(d[stay] * wl, axis=1), medium.g)
                    acc[stay] += wgt[stay] * phase * incident * np.exp(-sigma_t * inside)
                    events[stay] += 1
                    if orders is not None:
                        wgt[stay[events[stay] >= orders]] = 0.0
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
            advance(1)
        return total, total2


def mean_and_variance(total, total2, n: int, tint) -> tuple[np.ndarray, np.ndarray]:
    """Per-pixel mean of ``n`` samples from their Σ and Σ², and the variance of that mean, both tinted by the
    albedo map where the light leaves."""
    mean = total / n
    var = np.maximum(total2 / n - mean**2, 0.0) / max(n - 1, 1)
    return mean * tint, var * tint**2


#: how the samples are drawn (blocks, tiles, their seeds): a checkpoint of another version is not resumed (bump on a
#: change)
SAMPLING_VERSION = 3
#: the object's pixels a task walks at most: a block of samples is split into tiles of pixels, so that a large image
#: makes many tasks (a cluster's workers share them) of bounded memory
VOLUMETRIC_TILE_PIXELS = 16_384


def pixel_tiles(pixels: int) -> list[tuple[int, int]]:
    """The tiles (first, stop) of the object's ``pixels``: VOLUMETRIC_TILE_PIXELS each, the last one shorter."""
    return [(a, min(a + VOLUMETRIC_TILE_PIXELS, pixels)) for a in range(0, pixels, VOLUMETRIC_TILE_PIXELS)] or [(0, 0)]


def task_plan(spp: int, pixels: int) -> tuple[list[int], list[tuple[int, int]]]:
    """A reference's tasks: its blocks of samples (sized from a tile's pixels) and its tiles of the object's
    ``pixels`` — every block walks every tile."""
    return sample_blocks(spp, min(pixels, VOLUMETRIC_TILE_PIXELS)), pixel_tiles(pixels)


def task_seed(seed: int, block: int, tile: int, tiles: int) -> np.random.SeedSequence:
    """The random stream of a block's tile: the block's child of ``seed``'s SeedSequence, and that child's child
    per tile when there are several (one tile: the block's stream itself, as before tiles)."""
    return np.random.SeedSequence(seed, spawn_key=(block,) if tiles == 1 else (block, tile))


def sample_blocks(spp: int, pixels: int) -> list[int]:
    """How ``spp`` samples are split into tasks: at most what one batch holds (``_samples_per_batch``), and at
    least eight tasks when there are eight samples or more — from ``spp`` and the pixels alone, so that the image
    does not depend on how many processes share them."""
    block = max(1, min(_samples_per_batch(pixels), spp // 8))
    return [min(block, spp - start) for start in range(0, spp, block)]


class _BlockRunner:
    """Runs a reference's blocks of samples — wherever reflets.reference.parallel places them — and adds their sums in
    block order, whatever order they finish in (so that the floating-point sums equal one process's, bit for bit);
    goes on from a checkpoint and writes it as it goes (at once on an interruption or an error, and at the end: the
    caller removes it once the images are safe), stops at a target error, and shows the samples done, the time left
    and the current error."""

    def __init__(self, job, blocks: list[int], tiles: list[tuple[int, int]], seed: int, tint,
                 partial: PartialSums | None, target: float | None):  # fmt: skip
        self.job, self.blocks, self.tiles, self.seed, self.tint = job, blocks, tiles, seed, tint
        self.partial, self.target = partial, target
        self.next_block, self.total, self.total2 = partial.load() if partial is not None else (0, 0.0, 0.0)
        if self.next_block > len(blocks):
            raise ArgumentError("holds more blocks than this reference has", file=partial.path, field="--resume")

    @property
    def samples(self) -> int:
        return sum(self.blocks[: self.next_block])

    def error(self) -> float:
        """The mean relative standard error of the object pixels' luminance after the blocks added so far (the
        channels are independent walks: their variances add with the squared weights)."""
        n = self.samples
        if n < 2 or np.ndim(self.total) == 0:
            return float("inf")
        mean, var = mean_and_variance(self.total, self.total2, n, self.tint)
        lum, err = mean @ LUMINANCE, np.sqrt(var @ LUMINANCE**2)
        seen = lum > 0
        return float(np.mean(err[seen] / lum[seen])) if seen.any() else 0.0

    def _add(self, t, t2) -> bool:
        """Add the next block's sums; True when the run is done (every block, or the target error reached)."""
        self.total, self.total2 = self.total + t, self.total2 + t2
        self.next_block += 1
        done = self.next_block == len(self.blocks) or (self.target is not None and self.error() <= self.target)
        self._save(force=done)
        return done

    def _save(self, force: bool) -> None:
        if self.partial is not None and self.next_block > 0:
            self.partial.save(self.next_block, self.total, self.total2, force=force)

    def run(self, place, build_args: tuple, progress: bool) -> None:
        """Add the blocks still to do, drawn where ``place`` says (reflets.reference.parallel.places)."""
        first = self.next_block
        todo = self.blocks[first:]
        if not todo or (self.target is not None and self.error() <= self.target):
            return  # the checkpoint of a finished run
        columns = (TextColumn("{task.description}"), BarColumn(), TextColumn("{task.completed:.0f}/{task.total} spp"),
                   TimeRemainingColumn(), TextColumn("{task.fields[error]}"))  # fmt: skip
        # the time left from the whole run's pace (blocks of a large image take minutes: rich's default 30 s window
        # would hold one)
        with Progress(*columns, disable=not progress, transient=True, speed_estimate_period=24 * 3600) as bar:
            task = bar.add_task(self.job.label + place.label, total=sum(self.blocks), completed=self.samples,
                                error="")  # fmt: skip
            n = len(self.tiles)  # each block's tiles, in order: the progress counts samples of the whole image
            tasks = [(spp, task_seed(self.seed, first + i, t, n), tile)
                     for i, spp in enumerate(todo) for t, tile in enumerate(self.tiles)]  # fmt: skip
            try:
                with place.start(_VolumetricJob, build_args, local=self.job) as session:
                    sizes = [spp for spp, _, _ in tasks]  # a tile's samples: 1 / n of the image's
                    results = session.run(tasks, sizes, lambda k: bar.advance(task, k / n))
                    pixels = len(self.job.pix)
                    for index, (t, t2) in ordered(results):
                        if index % n == 0:
                            block_t, block_t2 = np.zeros((pixels, 3)), np.zeros((pixels, 3))
                        a, b = self.tiles[index % n]
                        block_t[a:b], block_t2[a:b] = t, t2
                        if index % n < n - 1:
                            continue
                        done = self._add(block_t, block_t2)  # a whole block: added as before tiles
                        bar.update(task, error=f"σ/μ {self.error():.3g}")
                        if done:
                            break
            except BaseException:  # a kill, Ctrl-C or an error: what was added is kept
                self._save(force=True)
                raise


# ------------------------------------------------------------------------------ refracting boundary (η ≠ 1)


def _refract(d: np.ndarray, n: np.ndarray, ratio) -> tuple[np.ndarray, np.ndarray]:
    """Snell: unit directions d through normals n facing against them, ratio = n_from / n_to; (directions, ok),
    ok False under total internal reflection."""
    cos_i = -np.sum(d * n, axis=-1)
    sin2_t = np.asarray(ratio) ** 2 * np.maximum(0.0, 1.0 - cos_i * cos_i)
    cos_t = np.sqrt(np.maximum(0.0, 1.0 - sin2_t))
    t = np.asarray(ratio)[..., None] * d + (np.asarray(ratio) * cos_i - cos_t)[..., None] * n
    return t / np.linalg.norm(t, axis=-1, keepdims=True), sin2_t < 1.0


def _planar_start(geometry, u, eta: float, omega, origin, point: bool) -> None:
    """Newton's starting ray (in place): the exact refracted connection through the tangent plane where the
    straight line from the light to u meets the boundary (Snell in the plane of incidence, a monotonic 1-D
    equation solved by bisection); it leaves a couple of iterations on the mesh instead of a dozen."""
    from .geometry import MESHES

    hits = geometry.intersect(origin, omega)
    hit = np.nonzero(hits.kind == MESHES)[0]
    if hit.size == 0:
        return
    surf = _hit_points(geometry, hits.prim[hit], hits.u[hit], hits.v[hit], omega[hit])
    y, nrm, uu = surf.position, surf.normal, u[hit]
    depth = np.sum((y - uu) * nrm, axis=1)  # u below the tangent plane
    if point:
        source = origin[hit]
        height = np.sum((source - y) * nrm, axis=1)
        foot_l = source - height[:, None] * nrm
        foot_u = uu + depth[:, None] * nrm
        along = foot_u - foot_l
        reach = np.linalg.norm(along, axis=1)
        along /= np.maximum(reach, 1e-300)[:, None]
        lo, hi = np.zeros(hit.size), reach.copy()
        for _ in range(40):  # x: distance from the light's foot to the entry point
            x = 0.5 * (lo + hi)
            f = x / np.hypot(x, height) - eta * (reach - x) / np.maximum(np.hypot(reach - x, depth), 1e-300)
            lo, hi = np.where(f < 0, x, lo), np.where(f < 0, hi, x)
        entry = foot_l + along * (0.5 * (lo + hi))[:, None]
        start = entry - source
        start /= np.linalg.norm(start, axis=1, keepdims=True)
        ok = (depth > 0) & (height > 0) & np.all(np.isfinite(start), axis=1)
        omega[hit[ok]] = start[ok]
    else:
        t, refracted = _refract(omega[hit], nrm, 1.0 / eta)
        cos_t = -np.sum(t * nrm, axis=1)
        entry = uu - t * (depth / np.maximum(cos_t, 1e-12))[:, None]
        ok = (depth > 0) & refracted & (cos_t > 1e-6)
        origin[hit[ok]] = entry[ok] - omega[hit[ok]] * 4.0 * geometry.radius


def _refracted_connection(geometry, u, eta: float, *, light_pos=None, travel=None, iterations: int = 16):
    """The light reaching interior points u through the smooth boundary (a manifold next-event estimation:
    Hanika et al. 2015, one refracting vertex). The light ray is parameterised by two numbers — its direction
    around the current one (point light) or its origin across the beam (directional light) — traced to the
    boundary point y, refracted there (interpolated normal) and followed to the plane through u orthogonal to
    it; Newton on the miss distance, with the Jacobian J of that map by finite differences of the same traces.
    At the solution the beam's cross-section at u is |det J| per unit of the parameters, so the flux density
    normal to the refracted beam at u is power × F_T(y) / |det J| (I/d² without refraction). Returns (travel
    direction t at u, F_T/|det J|, distance |u − y| inside, valid, the light ray's direction where it leaves the
    light); not valid: no convergence, grazing or
    missing traces, or the boundary between y and u (light entering elsewhere, e.g. through a thin part and out
    again, is not followed)."""
    from ..brdf.base import orthonormal_basis
    from .geometry import MESHES

    n = len(u)
    radius = geometry.radius
    point = light_pos is not None
    if point:
        omega = u - light_pos
        dist = np.linalg.norm(omega, axis=1)
        omega /= dist[:, None]
        origin = np.broadcast_to(np.asarray(light_pos, np.float64), (n, 3)).copy()
        eps = 1e-3 * radius / dist
    else:
        omega = np.broadcast_to(np.asarray(travel, np.float64), (n, 3)).copy()
        origin = u - omega * 4.0 * radius  # outside the bounding sphere
        eps = np.full(n, 1e-3 * radius)
    _planar_start(geometry, u, eta, omega, origin, point)
    param = omega if point else origin  # what Newton moves (updated in place)
    prev, move = param.copy(), np.zeros((n, 3))
    best = np.full(n, np.inf)  # miss distance at prev
    has_prev = np.zeros(n, dtype=bool)
    halvings = np.zeros(n, dtype=np.int64)
    t_out = np.zeros((n, 3))
    start_dir = np.zeros((n, 3))
    factor = np.zeros(n)
    inside = np.zeros(n)
    valid = np.zeros(n, dtype=bool)
    active = np.arange(n)
    tol = 1e-5 * radius  # float32 traces: hit points are off their rays by ~1e-7 of the distance
    for _ in range(iterations):
        if active.size == 0:
            break
        m = active.size
        e1, e2 = orthonormal_basis(omega[active])
        h = eps[active, None]
        if point:
            o = np.tile(origin[active], (3, 1))
            dk = np.concatenate([omega[active], omega[active] + h * e1, omega[active] + h * e2])
            dk /= np.linalg.norm(dk, axis=1, keepdims=True)
        else:
            o = np.concatenate([origin[active], origin[active] + h * e1, origin[active] + h * e2])
            dk = np.tile(omega[active], (3, 1))
        hits = geometry.intersect(o, dk)
        ok = (hits.kind == MESHES).reshape(3, m).all(axis=0)
        prim = np.where(hits.kind == MESHES, hits.prim, 0)
        surf = _hit_points(geometry, prim, hits.u, hits.v, dk)  # normals facing the light
        nrm = surf.normal
        tk, refracted = _refract(dk, nrm, 1.0 / eta)
        ok &= refracted.reshape(3, m).all(axis=0)
        y = surf.position.reshape(3, m, 3)
        tk = tk.reshape(3, m, 3)
        t0 = tk[0]
        uu = u[active]
        s = np.sum((uu - y) * t0, axis=-1) / np.maximum(np.sum(tk * t0, axis=-1), 1e-12)
        ok &= s[0] > 0.0
        p = y + s[..., None] * tk
        b1, b2 = orthonormal_basis(t0)
        miss = p[0] - uu
        r = np.stack([np.sum(miss * b1, axis=1), np.sum(miss * b2, axis=1)], axis=1)
        dp1, dp2 = (p[1] - p[0]) / h, (p[2] - p[0]) / h
        j = np.stack(
            [
                np.stack([np.sum(dp1 * b1, axis=1), np.sum(dp2 * b1, axis=1)], axis=1),
                np.stack([np.sum(dp1 * b2, axis=1), np.sum(dp2 * b2, axis=1)], axis=1),
            ],
            axis=1,
        )
        det = j[:, 0, 0] * j[:, 1, 1] - j[:, 0, 1] * j[:, 1, 0]
        ok &= np.abs(det) > 1e-12 * radius * radius
        rn = np.linalg.norm(r, axis=1)
        # backtracking: a step that misses the object or does not reduce the miss distance is halved
        worse = ~ok | (rn >= best[active])
        retry = worse & has_prev[active] & (halvings[active] < 6)
        if np.any(retry):
            a = active[retry]
            move[a] *= 0.5
            halvings[a] += 1
            param[a] = prev[a] + move[a]
        done = ~worse & (rn < tol)
        if np.any(done):
            a = active[done]
            cos_y = -np.sum(dk[:m][done] * nrm[:m][done], axis=1)
            t_out[a] = t0[done]
            start_dir[a] = dk[:m][done]
            factor[a] = fresnel_transmittance(cos_y, eta) / np.abs(det[done])
            inside[a] = np.linalg.norm(uu[done] - y[0][done], axis=1)
            valid[a] = True
        step_on = ~worse & ~done
        if np.any(step_on):
            a = active[step_on]
            delta = -np.linalg.solve(j[step_on], r[step_on][..., None])[..., 0]
            limit = 0.1 if point else 0.1 * radius
            norm = np.linalg.norm(delta, axis=1, keepdims=True)
            delta *= np.minimum(1.0, limit / np.maximum(norm, 1e-300))
            prev[a] = param[a]
            best[a] = rn[step_on]
            has_prev[a] = True
            halvings[a] = 0
            move[a] = delta[:, :1] * e1[step_on] + delta[:, 1:] * e2[step_on]
            param[a] = prev[a] + move[a]
        if point:
            param[active] /= np.linalg.norm(param[active], axis=1, keepdims=True)
        active = active[retry | step_on]
    # the refracted segment y → u must stay inside (no boundary before u)
    idx = np.nonzero(valid)[0]
    if idx.size:
        eps_ray = geometry.epsilon
        start = u[idx] - t_out[idx] * inside[idx, None]
        hits = geometry.intersect(start + t_out[idx] * eps_ray, t_out[idx])
        blocked = (hits.kind >= 0) & (hits.t + eps_ray < inside[idx] - 10 * eps_ray)
        valid[idx[blocked]] = False
    return t_out, factor, inside, valid, start_dir


@dataclass
class _HitPoints:
    position: np.ndarray
    normal: np.ndarray  # interpolated, facing against the ray
    geometric_normal: np.ndarray  # facing against the ray


def _hit_points(geometry, prim, u, v, d) -> _HitPoints:
    """Position and normals at mesh hits (float64 from the barycentrics): the part of SceneGeometry.surface the
    walk needs, without the tangent frame (this runs a dozen times per scattering event)."""
    face = geometry.faces[prim]
    w = np.stack([1.0 - u - v, u, v], axis=-1)[..., None]
    p = geometry.vertices[face]
    n = np.sum(w * geometry.normals[face], axis=-2)
    n /= np.linalg.norm(n, axis=-1, keepdims=True)
    e1, e2 = p[:, 1] - p[:, 0], p[:, 2] - p[:, 0]
    ng = np.stack(
        [
            e1[:, 1] * e2[:, 2] - e1[:, 2] * e2[:, 1],
            e1[:, 2] * e2[:, 0] - e1[:, 0] * e2[:, 2],
            e1[:, 0] * e2[:, 1] - e1[:, 1] * e2[:, 0],
        ],
        axis=-1,
    )
    ng /= np.maximum(np.linalg.norm(ng, axis=-1, keepdims=True), 1e-300)
    flip = np.where(np.sum(ng * d, axis=-1) > 0, -1.0, 1.0)[:, None]
    return _HitPoints(np.sum(w * p, axis=-2), n * flip, ng * flip)


def _samples_per_batch(pixels: int) -> int:
    """Samples of every pixel and channel walked as one array (about 300,000 paths: long enough for the tail of
    the walks to run vectorised, small enough for memory)."""
    return max(1, 300_000 // max(3 * pixels, 1))


def _render_refracting(geometry, medium, scale, source, dirs, hits, pix, spp, rng, orders, advance):
    """All samples and channels of the refracting walk as one batch (chunked): per-path coefficients, so that
    the long tail of the walks runs on large arrays. Returns per-pixel Σ and Σ² of the samples (P, 3)."""
    n = len(pix)
    total = np.zeros((n, 3))
    total2 = np.zeros((n, 3))
    per_chunk = _samples_per_batch(n)
    done = 0
    while done < spp:
        k = min(per_chunk, spp - done)
        channel = np.tile(np.repeat(np.arange(3), n), k)
        pixel = np.tile(np.arange(n), 3 * k)
        acc = _walk_refracting(geometry, medium, channel, scale, source, dirs[pixel], hits, pix[pixel], rng, orders)
        acc = acc.reshape(k, 3, n)
        total += acc.sum(axis=0).T
        total2 += (acc * acc).sum(axis=0).T
        done += k
        advance(k)
    return total, total2


def _walk_refracting(geometry, medium, channel, scale: float, source, dirs, hits, rays, rng, orders=None):
    """One path per camera ray (channel per path) through a smooth dielectric boundary (render_volumetric)."""
    from .geometry import MESHES

    eta = float(medium.eta)
    sigma_t = np.asarray(medium.sigma_t, np.float64)[channel] * scale
    albedo = np.asarray(medium.albedo, np.float64)[channel]
    eps = geometry.epsilon
    light_rng = _light_stream(rng)
    n = len(rays)
    surf = _hit_points(geometry, hits.prim[rays], hits.u[rays], hits.v[rays], dirs)  # normals facing the camera
    d, ok = _refract(dirs, surf.normal, 1.0 / eta)
    ok &= np.sum(d * surf.geometric_normal, axis=1) < 0.0
    # radiance leaving a medium of index η is divided by η²; the camera ray's reflection is not followed
    w = np.where(ok, fresnel_transmittance(-np.sum(dirs * surf.normal, axis=1), eta) / eta**2, 0.0)
    pos = surf.position.copy()
    inside = np.ones(n, dtype=bool)
    events = np.zeros(n, dtype=np.int64)
    acc = np.zeros(n)
    idx = np.nonzero(w > 0.0)[0]
    for _ in range(100_000):
        if idx.size == 0:
            break
        bound = geometry.intersect(pos[idx] + d[idx] * eps, d[idx])
        has = bound.kind == MESHES
        t_bound = np.where(has, bound.t + eps, np.inf)
        ins = inside[idx]
        t_free = np.where(ins, -np.log1p(-rng.random(idx.size)) / sigma_t[idx], np.inf)
        scatter = ins & (t_free < t_bound)
        sc = idx[scatter]
        if sc.size:
            pos[sc] += d[sc] * t_free[scatter, None]
            w[sc] *= albedo[sc]
            events[sc] += 1
            where, power = source.draw(light_rng, sc.size)  # (emitters are not in the traced geometry)
            connect = {"light_pos": where} if source.point else {"travel": where}
            t_light, factor, length, valid, leaving = _refracted_connection(geometry, pos[sc], eta, **connect)
            power = power[np.arange(sc.size), channel[sc]] * source.cosine(leaving)
            phase = henyey_greenstein(-np.sum(d[sc] * t_light, axis=1), medium.g)
            contribution = w[sc] * phase * power * factor * np.exp(-sigma_t[sc] * length)
            acc[sc] += np.where(valid, contribution, 0.0)
            cos_t = sample_henyey_greenstein(medium.g, rng.random(sc.size))
            d[sc] = _scatter(d[sc], cos_t, 2.0 * np.pi * rng.random(sc.size))
            if orders is not None:
                w[sc[events[sc] >= orders]] = 0.0
            low = sc[w[sc] < 1e-3]
            if low.size:
                survive = rng.random(low.size) < 0.1
                w[low[survive]] *= 10.0
                w[low[~survive]] = 0.0
        # boundary: Fresnel reflection or refraction, from either side
        at = ~scatter & has
        b = idx[at]
        if b.size:
            sb = _hit_points(geometry, bound.prim[at], bound.u[at], bound.v[at], d[b])  # normals facing against d
            nb = sb.normal
            pos[b] = sb.position
            from_inside = inside[b]
            cos_i = -np.sum(d[b] * nb, axis=1)
            reflect = rng.random(b.size) < fresnel_reflectance(cos_i, np.where(from_inside, 1.0 / eta, eta))
            t, _ = _refract(d[b], nb, np.where(from_inside, eta, 1.0 / eta))
            new = np.where(reflect[:, None], d[b] + 2.0 * cos_i[:, None] * nb, t)
            side = np.sum(new * sb.geometric_normal, axis=1)
            w[b[np.where(reflect, side <= 0.0, side >= 0.0)]] = 0.0  # shading normal against the geometry
            d[b] = new
            inside[b[~reflect]] = ~from_inside[~reflect]
        w[idx[~has & ~scatter]] = 0.0  # escaped (next-event estimation only: a light hit is not counted)
        idx = idx[w[idx] > 0.0]
    return acc
