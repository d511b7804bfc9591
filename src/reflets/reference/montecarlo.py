"""NumPy Monte Carlo reference: float64 direct lighting with multiple importance sampling.

Independent of every GLSL file: it uses the NumPy BRDFs, Embree ray casting and float64 shading. Per pixel
and sample it estimates

    L = Le(camera ray) + Σ_delta f L cos / r² · V + Σ_area [light sample ⊕ BRDF sample] + [env sample ⊕ BRDF]

where ⊕ is a multiple-importance combination (Veach & Guibas 1995, power or balance heuristic) of one
light-sampled and one BRDF-sampled estimate; the BRDF sample is shared by every area light and the
environment. Delta lights have no variance. Samples are Latin-hypercube stratified per pixel, the random
streams seeded by (seed, chunk), so the same seed gives the same image. The per-pixel standard error is
the sample standard deviation / √spp.

``visibility=False`` drops shadow tests (the area-light document's unoccluded setting): light samples are
never blocked, BRDF samples test only the emitters, the environment is always seen. A light with
``shadows = false`` is traced that way alone.
``pixel="center"`` traces every sample through the pixel centre — exactly what the GPU renderer samples —
while ``pixel="box"`` jitters it over the pixel (what Mitsuba's box filter integrates).

``adaptive_error=e`` refines the pixels a fixed sample count leaves noisy (a point light's sub-pixel highlight in
a near-mirror texel): each round, the pixels whose relative standard error (luminance, relative to the pixel or
to the image's mean luminance when brighter) exceeds ``e`` are rendered again with 4× the samples, up to
``adaptive_spp``, from new random streams — and take that round's estimate alone. The selection depends only on
earlier, independent samples, so every estimate stays unbiased.
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass
from typing import Literal

import numpy as np

from ..errors import ArgumentError
from ..resources import check, fitting_size
from ..scene.camera import camera_rays
from ..scene.environment import load_environment
from ..scene.lightmask import LUMINANCE, load_masks
from ..scene.model import DirectionalLight, PointLight, Scene
from .geometry import EMITTERS, MESHES, SceneGeometry
from .lights import EnvironmentSampler, PolygonSampler
from .mirrors import MirrorBounce
from .parallel import places, within_memory
from .transmission import MAX_CROSSINGS, NUMBERS_PER_CROSSING, Transmission

RAYS_PER_CHUNK = 1 << 17
#: bytes per pixel the image holds (float64 mean and standard error, float32 image and stderr) and the working
#: set of a chunk of RAYS_PER_CHUNK rays (measured 78–106 MB on the plane, GGX sphere, environment and mirror
#: scenes at 16 spp; 1024² at 1 spp: 116 B per pixel in all)
REFERENCE_BYTES_PER_PIXEL = 72
REFERENCE_CHUNK_BYTES = 128_000_000


@dataclass
class ReferenceResult:
    """A reference image, its per-pixel standard error, and what it cost."""

    image: np.ndarray  # float32 (H, W, 3)
    stderr: np.ndarray  # float32 (H, W, 3)
    spp: int
    seconds: float
    engine: str = "numpy"
    pixel_spp: np.ndarray | None = None  # (H, W) samples behind each pixel when adaptive rounds refined some

    @property
    def samples_per_second(self) -> float:
        h, w, _ = self.image.shape
        samples = h * w * self.spp if self.pixel_spp is None else float(self.pixel_spp.sum())
        return samples / max(self.seconds, 1e-9)


#: the most samples adaptive rounds give a pixel: a round holds one pixel's samples at once (~1 KB a sample)
MAX_ADAPTIVE_SPP = 1 << 18


def _check_adaptive(error, max_spp, spp: int) -> None:
    if isinstance(error, bool) or not isinstance(error, int | float) or not (math.isfinite(error) and error > 0):
        raise ArgumentError(f"must be a positive number, got {error!r}", field="adaptive_error")
    if isinstance(max_spp, bool) or not isinstance(max_spp, int) or not spp <= max_spp <= MAX_ADAPTIVE_SPP:
        raise ArgumentError(f"must be an integer from spp ({spp}) to {MAX_ADAPTIVE_SPP:,}, got {max_spp!r}",
                            field="adaptive_spp")  # fmt: skip


def _mis(p_this: np.ndarray, p_other: np.ndarray, heuristic: str) -> np.ndarray:
    """The strategy's MIS weight, from the ratio of the densities (their squares overflow for a near-delta lobe's
    huge pdf): 1 / (1 + r²) (power) or 1 / (1 + r) (balance), r = p_other / p_this; 0 where p_this is 0."""
    ok = p_this > 0
    with np.errstate(divide="ignore", invalid="ignore", over="ignore"):
        r = np.where(np.isinf(p_this) & np.isinf(p_other), 1.0, p_other / np.where(ok, p_this, 1.0))  # ∞/∞: even
        return np.where(ok, 1.0 / (1.0 + (r * r if heuristic == "power" else r)), 0.0)


def _latin_hypercube(rng: np.random.Generator, pixels: int, spp: int, dims: int) -> np.ndarray:
    """(pixels, spp, dims) numbers in [0, 1), each dimension stratified over a pixel's spp samples."""
    strata = np.argsort(rng.random((pixels, spp, dims)), axis=1)
    return (strata + rng.random((pixels, spp, dims))) / spp


class MonteCarloReference:
    """Reusable state for one scene: ray-casting geometry, light samplers, materials."""

    def __init__(self, scene: Scene, visibility: bool = True, heuristic: Literal["power", "balance"] = "power"):
        if heuristic not in ("power", "balance"):
            raise ArgumentError(f"unknown MIS heuristic '{heuristic}'; allowed: power, balance", field="heuristic")
        self.scene = scene
        self.visibility = visibility
        self.heuristic = heuristic
        self.geometry = SceneGeometry(scene)
        self.materials = [scene.materials[name] for name in self.geometry.material_names]
        masks = load_masks(scene)
        self.area = [PolygonSampler(light, masks.get(i)) for i, light in self.geometry.lights]
        self.delta = [light for light in scene.light if isinstance(light, PointLight | DirectionalLight)]
        image = load_environment(scene)
        self.env = EnvironmentSampler(image, scene.environment) if image is not None else None
        color = scene.background_color()
        self.background = None if color is None else np.asarray(color, dtype=np.float64)
        self.transmission = Transmission(self.materials)
        # the light samples, the BRDF sample, the environment's, a transmissive crossing's, the pixel jitter (last)
        self.crossing_column = 2 * len(self.area) + 2 + (2 if self.env else 0)
        crossings = MAX_CROSSINGS * NUMBERS_PER_CROSSING if self.transmission else 0
        self.dims = self.crossing_column + crossings + 2
        self.mirrors = MirrorBounce(scene, self.geometry.face_mesh)

    # ------------------------------------------------------------------------------------------ driver
    def render(
        self,
        spp: int,
        seed: int = 0,
        size: tuple[int, int] | None = None,
        pixel: Literal["center", "box"] = "center",
        progress: bool = True,
        adaptive_error: float | None = None,
        adaptive_spp: int = 16384,
        workers: int | None = 1,
        cluster=None,
    ) -> ReferenceResult:
        """``workers`` processes of this machine, or the workers of the Dask cluster at ``cluster``, share the
        tiles (reflets.reference.parallel): each tile draws from its own stream, so the image is the same."""
        if spp < 1:
            raise ArgumentError(f"must be ≥ 1, got {spp}", field="spp")
        if pixel not in ("center", "box"):
            raise ArgumentError(f"unknown pixel mode '{pixel}'; allowed: center, box", field="pixel")
        if adaptive_error is not None:
            _check_adaptive(adaptive_error, adaptive_spp, spp)
        width, height = size or self.scene.camera.size
        n_pixels = width * height
        place = places(None if cluster is not None else workers, cluster)  # workers: this machine's (not a cluster's)
        if workers is None:  # every core by default: as many as the memory holds (a count given is checked)
            place = within_memory(place, REFERENCE_CHUNK_BYTES, n_pixels * REFERENCE_BYTES_PER_PIXEL)
        chunks = place.processes * REFERENCE_CHUNK_BYTES  # each process of this machine holds a chunk of rays
        image_bytes = n_pixels * REFERENCE_BYTES_PER_PIXEL
        if place.processes > 1:  # a count of processes given: the one to lower when it is what does not fit
            check("workers", chunks + image_bytes, value=place.processes,
                  what=f"{place.processes:,} processes × a chunk of rays ({REFERENCE_CHUNK_BYTES // 10**6} MB) + "
                  "the image",
                  fits=lambda budget: max(budget - image_bytes, 0) // REFERENCE_CHUNK_BYTES or None)  # fmt: skip
        try:
            check(
                "size",
                chunks + n_pixels * REFERENCE_BYTES_PER_PIXEL,
                value=f"{width}x{height}",
                what=f"the reference: {n_pixels:,} pixels × {REFERENCE_BYTES_PER_PIXEL} B + a chunk of rays"
                + (f" in each of {place.processes} processes" if place.processes > 1 else ""),
                fits=lambda budget: fitting_size(width, height, REFERENCE_BYTES_PER_PIXEL, max(budget - chunks, 0)),
            )
            mean = np.zeros((n_pixels, 3))
            err = np.zeros((n_pixels, 3))
            start = time.perf_counter()
            frame = (width, height, pixel)
            with place.start(MonteCarloReference, (self.scene, self.visibility, self.heuristic), local=self) as tiles:
                self._estimate(tiles, np.arange(n_pixels), spp, (seed,), mean, err, frame, progress, place.label)
                counts = np.full(n_pixels, spp)
                if adaptive_error is not None:
                    self._refine(tiles, mean, err, counts, adaptive_error, adaptive_spp, seed, frame)
        finally:
            place.close()
        seconds = time.perf_counter() - start
        return ReferenceResult(
            image=mean.reshape(height, width, 3).astype(np.float32),
            stderr=err.reshape(height, width, 3).astype(np.float32),
            spp=spp,
            seconds=seconds,
            pixel_spp=counts.reshape(height, width) if adaptive_error is not None else None,
        )

    def _estimate(self, tiles, pixels, spp, stream, mean, err, frame, progress=False, label="") -> None:
        """Mean and standard error of ``spp`` samples at each of ``pixels`` (flat indices), in tiles whose random
        streams are seeded by ``stream`` + (tile index,), drawn wherever ``tiles`` (a session of
        reflets.reference.parallel) runs them."""
        chunk = max(1, RAYS_PER_CHUNK // spp)
        tasks = [(pixels[first : first + chunk], spp, (*stream, index), frame)
                 for index, first in enumerate(range(0, len(pixels), chunk))]  # fmt: skip
        bar = _progress(progress, len(tasks), label)
        try:
            for index, (tile_mean, tile_err) in tiles.run(tasks, [1] * len(tasks), bar.advance):
                ids = tasks[index][0]
                mean[ids], err[ids] = tile_mean, tile_err
        finally:
            bar.close()

    def task(self, task, advance) -> tuple[np.ndarray, np.ndarray]:
        """One tile (reflets.reference.parallel): (pixel indices, spp, its stream, (width, height, pixel)) → the
        pixels' mean and standard error."""
        ids, spp, stream, (width, height, pixel) = task
        values = self._pixels(ids, width, height, spp, np.random.default_rng(stream), pixel)  # (P, spp, 3)
        mean = values.mean(axis=1)
        err = np.zeros_like(mean)
        if spp > 1:
            std = values.std(axis=1, ddof=1)
            std[std <= 1e-9 * np.abs(mean)] = 0.0  # rounding noise of a deterministic value
            err = std / np.sqrt(spp)
        advance(1)
        return mean, err

    def _refine(self, tiles, mean, err, counts, target, max_spp, seed, frame) -> None:
        """Adaptive rounds (module docstring): noisy pixels re-rendered alone with 4× the samples."""
        weights = LUMINANCE
        for round_ in range(1, 64):
            luminance = mean @ weights
            scale = np.maximum(np.abs(luminance), max(float(np.mean(np.abs(luminance))), 1e-12))
            noisy = np.flatnonzero((err @ weights > target * scale) & (counts < max_spp))
            if noisy.size == 0:
                return
            spp = int(min(counts[noisy].max() * 4, max_spp))
            self._estimate(tiles, noisy, spp, (seed, round_, 1), mean, err, frame)
            counts[noisy] = spp

    # --------------------------------------------------------------------------------------- per chunk
    def _pixels(self, ids, width, height, spp, rng, pixel) -> np.ndarray:
        u = _latin_hypercube(rng, len(ids), spp, self.dims).reshape(-1, self.dims)
        rows = np.repeat(ids // width, spp)
        cols = np.repeat(ids % width, spp)
        jitter = u[:, -2:] if pixel == "box" else np.full((len(u), 2), 0.5)
        origin, dirs = camera_rays(self.scene.camera, cols + jitter[:, 0], rows + jitter[:, 1], width, height)
        out = self.trace(origin, dirs, u, mirrors=True)
        return out.reshape(len(ids), spp, 3)

    def trace(self, origin: np.ndarray, dirs: np.ndarray, u: np.ndarray, mirrors: bool = False, depth: int = 0,
              medium: np.ndarray | None = None) -> np.ndarray:  # fmt: skip
        """Radiance arriving along rays (origin + t·dirs) from the first surface they hit; ``mirrors``: add one
        specular bounce on reflector meshes (reference/mirrors.py); ``depth``: transmissive surfaces crossed so far,
        ``medium`` (N, 4): the absorption σ of the volume each ray travels in and 1, or 0 outside
        (reference/transmission.py)."""
        out = np.zeros((len(u), 3))
        hits = self.geometry.intersect(np.broadcast_to(origin, dirs.shape), dirs, salt=u[:, -1])
        miss = hits.kind < 0
        out[miss] = self._escaped(dirs[miss])
        on_emitter = np.nonzero(hits.kind == EMITTERS)[0]
        if len(on_emitter):
            points = np.broadcast_to(origin, dirs.shape)[on_emitter] + hits.t[on_emitter, None] * dirs[on_emitter]
            out[on_emitter] = self._emitter_radiance(hits.prim[on_emitter], dirs[on_emitter], points)
        on_mesh = np.nonzero(hits.kind == MESHES)[0]
        if len(on_mesh):
            out[on_mesh] = self._shade(on_mesh, hits, dirs, u, depth, medium)
            if mirrors and self.mirrors:
                out[on_mesh] += self.mirrors.radiance(self, on_mesh, hits, origin, dirs, u)
        if medium is not None:  # Beer–Lambert over the way to the hit (a miss: the whole way out)
            distance = np.where(miss, np.inf, hits.t)[:, None]
            sigma = medium[:, :3]
            out *= np.exp(-sigma * np.where(sigma > 0, distance, 0.0))
        return out

    def _escaped(self, dirs: np.ndarray) -> np.ndarray:
        if self.env is not None and self.background is None:
            return self.env.radiance(dirs)
        return np.broadcast_to(self.background if self.background is not None else 0.0, dirs.shape)

    def _emitter_radiance(self, prim: np.ndarray, dirs: np.ndarray, points: np.ndarray) -> np.ndarray:
        out = np.zeros(dirs.shape)
        owner = self.geometry.emitter_owner[prim]
        for j, sampler in enumerate(self.area):
            sel = owner == j
            _, front = sampler.emitted(dirs[sel])
            out[sel] = np.where(front[:, None], sampler.radiance_at(points[sel]), 0.0)
        return out

    # ------------------------------------------------------------------------------------------- shading
    def _shade(self, idx: np.ndarray, hits, dirs: np.ndarray, u: np.ndarray, depth: int = 0,
               medium: np.ndarray | None = None) -> np.ndarray:  # fmt: skip
        geo = self.geometry
        surf = geo.surface(hits.prim[idx], hits.u[idx], hits.v[idx], dirs[idx])
        result = np.zeros((len(idx), 3))
        bound = self._bind(surf, geo.uv_sets(hits.prim[idx], hits.u[idx], hits.v[idx]), result)
        x, frame = surf.position, surf.frame
        to_local = np.swapaxes(frame, -1, -2)
        wo_world = -dirs[idx]
        wo = np.einsum("nij,nj->ni", to_local, wo_world)
        origin = x + geo.epsilon * surf.geometric_normal
        if self.transmission:  # before u is narrowed to these hits: the continued paths take theirs
            column = self.crossing_column + NUMBERS_PER_CROSSING * depth
            result += self.transmission.radiance(self, idx, surf, bound, wo, u, depth, medium, column)
        u = u[idx]

        def brdf(wi_world: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
            """f(wo, wi) · cosθi for world directions (per-material evaluation)."""
            wi = np.einsum("nij,nj->ni", to_local, wi_world)
            f = np.zeros(wi.shape)
            for s, material in bound.values():
                f[s] = material.eval(wo[s], wi[s])
            return f * np.maximum(wi[:, 2:3], 0.0), wi

        # Delta lights: exact, one shadow ray each.
        for light in self.delta:
            if isinstance(light, PointLight):
                d = np.asarray(light.position) - x
                dist = np.linalg.norm(d, axis=-1)
                wi = d / dist[:, None]
                radiance = np.asarray(light.intensity) * (light.falloff(-wi) / (dist * dist))[:, None]
            else:
                wi = np.broadcast_to(-np.asarray(light.direction) / np.linalg.norm(light.direction), x.shape)
                dist = np.full(len(x), 2.0 * geo.radius + np.linalg.norm(x - geo.centre, axis=-1))
                radiance = np.broadcast_to(np.asarray(light.irradiance, dtype=np.float64), x.shape)
            fcos, _ = brdf(wi)
            visible = self._unoccluded(origin, wi, dist, light, salt=u[:, -1])
            result += np.where(visible[:, None], fcos * radiance, 0.0)

        # One BRDF sample shared by the area lights and the environment.
        col = 2 * len(self.area)
        wi_b, pdf_b = self._sample_brdf(bound, wo, u[:, col], u[:, col + 1])
        wi_b_world = np.einsum("nij,nj->ni", frame, wi_b)
        fcos_b, _ = brdf(wi_b_world)
        valid_b = (pdf_b > 0) & np.any(fcos_b > 0, axis=1)
        hit_b = geo.intersect(origin, wi_b_world, emitters_only=not self.visibility)
        # lights with shadows = false see the BRDF sample as if nothing but emitters were there
        unshadowed = [not getattr(sampler.light, "shadows", True) for sampler in self.area]
        env_unshadowed = self.env is not None and not self.scene.environment.shadows
        free = self.visibility and (any(unshadowed) or env_unshadowed)
        hit_free = geo.intersect(origin, wi_b_world, emitters_only=True) if free else hit_b

        for j, sampler in enumerate(self.area):
            # Light sampling.
            y = sampler.sample(u[:, 2 * j], u[:, 2 * j + 1])
            d = y - x
            dist = np.linalg.norm(d, axis=-1)
            wi = d / np.maximum(dist, 1e-300)[:, None]
            cos_l, front = sampler.emitted(wi)
            p_light = np.where(front, dist * dist / (sampler.area * np.maximum(cos_l, 1e-300)), 0.0)
            fcos, wi_local = brdf(wi)
            p_brdf = self._pdf_brdf(bound, wo, wi_local)
            ok = front & self._unoccluded(origin, wi, dist * (1.0 - 1e-4) - geo.epsilon, sampler.light)  # stop short
            weight = _mis(p_light, p_brdf, self.heuristic)
            contrib = fcos * sampler.radiance_at(y) * (weight / np.where(ok, p_light, 1.0))[:, None]
            result += np.where(ok[:, None], contrib, 0.0)
            # BRDF sampling: rays that reach this light first.
            hit = hit_free if unshadowed[j] else hit_b
            on = valid_b & (hit.kind == EMITTERS)
            on[on] = geo.emitter_owner[hit.prim[on]] == j
            if np.any(on):
                cos_l_b, front_b = sampler.emitted(wi_b_world[on])
                dist_b = hit.t[on]
                p_light_b = dist_b * dist_b / (sampler.area * np.maximum(cos_l_b, 1e-300))
                w_b = _mis(pdf_b[on], p_light_b, self.heuristic)
                y_b = origin[on] + dist_b[:, None] * wi_b_world[on]
                add = fcos_b[on] * sampler.radiance_at(y_b) * (w_b / pdf_b[on])[:, None]
                result[on] += np.where(front_b[:, None], add, 0.0)

        if self.env is not None:
            col = 2 * len(self.area) + 2
            wi, p_env = self.env.sample(u[:, col], u[:, col + 1])
            fcos, wi_local = brdf(wi)
            p_brdf = self._pdf_brdf(bound, wo, wi_local)
            far = np.full(len(x), 4.0 * geo.radius + np.linalg.norm(x - geo.centre, axis=-1))
            ok = (p_env > 0) & self._unoccluded(origin, wi, far, self.scene.environment)
            weight = _mis(p_env, p_brdf, self.heuristic)
            contrib = fcos * self.env.radiance(wi) * (weight / np.where(ok, p_env, 1.0))[:, None]
            result += np.where(ok[:, None], contrib, 0.0)
            # Unoccluded mode casts BRDF rays at the emitters only: anything else reaches the environment.
            if self.visibility and not env_unshadowed:
                escaped = valid_b & (hit_b.kind < 0)
            else:
                escaped = valid_b & ((hit_free if self.visibility else hit_b).kind != EMITTERS)
            if np.any(escaped):
                w_b = _mis(pdf_b[escaped], self.env.pdf(wi_b_world[escaped]), self.heuristic)
                add = fcos_b[escaped] * self.env.radiance(wi_b_world[escaped]) * (w_b / pdf_b[escaped])[:, None]
                result[escaped] += add
        return result

    def _unoccluded(self, origin: np.ndarray, wi: np.ndarray, dist: np.ndarray, light=None, salt=None) -> np.ndarray:
        """Not blocked; ``salt``: a number per ray (a sample's last stream dimension: the pixel jitter, unused
        through pixel centres) where nothing else tells a pixel's samples apart — a delta light's shadow rays."""
        if not self.visibility or not getattr(light, "shadows", True):
            return np.ones(len(origin), dtype=bool)
        return ~self.geometry.occluded(origin, wi, dist, salt=salt)

    def _bind(self, surf, uv: np.ndarray, emitted: np.ndarray) -> dict[int, tuple[np.ndarray, object]]:
        """Material index → (its hits, what evaluates the BRDF there: ``Material.at`` each hit's uv), with the
        material's normal map applied to ``surf.frame`` and its emission added to ``emitted`` — the GPU's order:
        textures first, then the unchanged BRDF."""
        bound = {}
        for m_index in np.unique(surf.material):
            s = surf.material == m_index
            material = self.materials[m_index]
            geometric = surf.frame[s]
            surf.frame[s] = material.shading_frame(geometric, uv[s])
            emitted[s] += material.emitted(uv[s])
            bound[m_index] = (s, material.at(uv[s], (geometric, surf.frame[s])))
        return bound

    @staticmethod
    def _sample_brdf(bound, wo, u1, u2):
        wi = np.zeros(wo.shape)
        pdf = np.zeros(len(wo))
        for s, material in bound.values():
            wi[s], pdf[s] = material.sample(wo[s], u1[s], u2[s])
        return wi, pdf

    @staticmethod
    def _pdf_brdf(bound, wo, wi):
        pdf = np.zeros(len(wo))
        for s, material in bound.values():
            pdf[s] = material.pdf(wo[s], wi[s])
        return pdf


class _NoProgress:
    def advance(self, tiles: int = 1) -> None:
        pass

    def close(self) -> None:
        pass


class _RichProgress:
    def __init__(self, total: int, label: str = ""):
        from rich.progress import BarColumn, Progress, TextColumn, TimeRemainingColumn

        self.progress = Progress(
            TextColumn("reference" + label),
            BarColumn(),
            TextColumn("{task.completed}/{task.total}"),
            TimeRemainingColumn(),
            transient=True,
        )
        self.task = self.progress.add_task("reference", total=total)
        self.progress.start()

    def advance(self, tiles: int = 1) -> None:
        self.progress.advance(self.task, tiles)

    def close(self) -> None:
        self.progress.stop()


def _progress(enabled: bool, total: int, label: str = ""):
    return _RichProgress(total, label) if enabled and total > 1 else _NoProgress()
