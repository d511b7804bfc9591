"""Ground-truth renderers: the NumPy Monte Carlo reference and the Mitsuba 3 bridge.

>>> result = reflets.reference(scene, spp=256)            # NumPy, float64, MIS, per-pixel standard error
>>> result.image, result.stderr
>>> result = reflets.reference(scene, spp=256, engine="mitsuba")
>>> result = reflets.reference(translucent_scene, spp=32, engine="volumetric", workers=2)  # all orders of scattering
"""

from __future__ import annotations

import time
from pathlib import Path
from typing import Literal

from ..errors import ArgumentError
from ..scene import Scene
from .montecarlo import MonteCarloReference, ReferenceResult

ENGINES = ("numpy", "mitsuba", "volumetric")


def reference(
    scene: Scene | str | Path | dict,
    spp: int = 64,
    seed: int = 0,
    engine: Literal["numpy", "mitsuba", "volumetric"] = "numpy",
    visibility: bool = True,
    size: tuple[int, int] | None = None,
    pixel: Literal["center", "box"] = "center",
    heuristic: Literal["power", "balance"] = "power",
    progress: bool = True,
    workers: int | None = None,
    cluster=None,
    adaptive_error: float | None = None,
    adaptive_spp: int = 16384,
    checkpoint: str | Path | None = None,
    keep_checkpoint: bool = False,
    target_error: float | None = None,
) -> ReferenceResult:
    """Render a ground-truth image of ``scene`` (direct lighting only, like every reflets technique; the
    volumetric engine: all orders of scattering inside a translucent medium).

    Parameters
    ----------
    spp : samples per pixel; seed : random seed (same seed, same image)
    engine : "numpy" (ours) or "mitsuba" (Mitsuba 3 ``scalar_rgb`` with its ``direct`` integrator; always
        with shadows and box pixel filtering; needs the ``reference`` extra) or "volumetric" (path tracing of a
        translucent medium inside its smooth boundary, one point, directional, quad, polygon or environment light: the
        ``translucent`` technique's single + multiple scattering, reflets.reference.volumetric; pixel centres, with
        shadows)
    workers : processes of this machine sharing the work (numpy and volumetric engines: the same image for any
        number; default every core this process may use, or the place of an enclosing
        ``reflets.reference.parallel.using`` block)
    cluster : the address of a Dask scheduler (``tcp://HOST:8786``), or a connected
        reflets.reference.cluster.Cluster, whose workers share the work instead (the scene and its files travel by
        content; the same image again)
    checkpoint, keep_checkpoint, target_error : (volumetric engine) a file of the partial sums to go on from after
        a kill (kept at the end with ``keep_checkpoint``: the caller removes it once it has written the images),
        and the mean relative standard error to stop at (reflets.reference.volumetric.render_volumetric)
    visibility : shadows on (ray-cast occlusion) or off (the area-light document's unoccluded setting)
    pixel : "center" samples the pixel centre like the GPU renderer; "box" averages over the pixel
    heuristic : MIS weights, "power" (β = 2) or "balance"
    adaptive_error, adaptive_spp : (numpy engine) pixels whose relative standard error exceeds ``adaptive_error``
        re-rendered alone with 4× the samples, round after round, up to ``adaptive_spp`` (unbiased: see
        reflets.reference.montecarlo); ``result.pixel_spp`` tells how many samples each pixel got
    """
    from ..arguments import as_scene, check_size, check_spp

    scene = as_scene(scene)
    size = check_size(size)
    check_spp(spp)  # a count the user gives is bounded (as render's), before any work
    if workers is not None and (isinstance(workers, bool) or not isinstance(workers, int) or workers < 1):
        raise ArgumentError(f"workers must be at least 1 (got {workers!r})", field="workers")
    if engine != "volumetric" and (checkpoint is not None or target_error is not None):
        raise ArgumentError("checkpoints and a target error are the volumetric engine's (--engine volumetric)",
                            field="checkpoint" if checkpoint is not None else "target_error")  # fmt: skip
    if engine == "numpy":
        return MonteCarloReference(scene, visibility=visibility, heuristic=heuristic).render(
            spp, seed=seed, size=size, pixel=pixel, progress=progress, adaptive_error=adaptive_error,
            adaptive_spp=adaptive_spp, workers=workers, cluster=cluster,
        )
    if engine == "mitsuba":
        if not visibility:
            raise ArgumentError(
                "Mitsuba always computes shadows; use engine='numpy' for visibility off", field="visibility"
            )
        from .mitsuba_bridge import render_mitsuba

        start = time.perf_counter()
        image = render_mitsuba(scene, spp=spp, seed=seed, size=size, cluster=cluster)
        import numpy as np

        return ReferenceResult(
            image=image,
            stderr=np.full_like(image, np.nan),
            spp=spp,
            seconds=time.perf_counter() - start,
            engine="mitsuba",
        )
    if engine == "volumetric":
        from .volumetric import render_volumetric

        if not visibility or pixel != "center":
            raise ArgumentError(
                "the volumetric engine samples pixel centres with shadows (visibility on, pixel center)",
                field="engine",
            )
        start = time.perf_counter()
        result = render_volumetric(scene, spp=spp, seed=seed, size=size, progress=progress, workers=workers,
                                   cluster=cluster, checkpoint=checkpoint, keep_checkpoint=keep_checkpoint,
                                   target_error=target_error)  # fmt: skip
        return ReferenceResult(result.image, result.stderr, result.spp, time.perf_counter() - start,
                               engine="volumetric")  # fmt: skip
    raise ArgumentError(f"unknown engine '{engine}'; allowed: {', '.join(ENGINES)}", field="engine")


__all__ = ["reference", "ReferenceResult", "MonteCarloReference", "ENGINES"]
