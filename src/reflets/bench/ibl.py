"""`reflets bench ibl`: prefiltered image-based lighting against the reference, and its cost.

A sphere under the sky map (``12_ref_sphere_env.toml``'s environment, nothing else) for GGX gold at α = 0.05 …
0.6 and one material of every analytic model of the BRDF library: relative MSE over the sphere against the
NumPy reference (``reflets.metrics.relmse``), for the prefiltered split sum (the default) and the 32 × 16
grid of distant lights it replaces (and the occlusion looked up in every direction at every pixel, against the
default checkerboard); the GPU prefiltering time; and the frame time with the environment (``env_ms``) against
the same frame lit by one point light instead (``point_ms``), medians of persistent ``Renderer``s' frames,
interleaved, in one run.
"""

from __future__ import annotations

import statistics
import time

import numpy as np

from ..demo import scene_path
from ..metrics import relmse

GOLD = {"type": "microfacet", "fresnel": "conductor", "eta": [0.2, 0.9, 1.1], "k": [3.9, 2.4, 2.2]}
MATERIALS = {
    **{f"GGX gold α={a:g}": {**GOLD, "alpha": a} for a in (0.05, 0.1, 0.15, 0.3, 0.6)},
    "Lambert": {"type": "lambert", "albedo": [0.7, 0.6, 0.5]},
    "plastic (GGX α=0.2 + diffuse)": {
        "type": "microfacet",
        "alpha": 0.2,
        "fresnel": "dielectric",
        "eta": 1.5,
        "diffuse": [0.5, 0.1, 0.1],
    },
    "Phong e=50 (normalised)": {
        "type": "phong",
        "kd": [0.3, 0.3, 0.3],
        "ks": [0.5, 0.5, 0.5],
        "exponent": 50,
        "normalized": True,
    },
    "Blinn-Phong e=100 (normalised)": {
        "type": "blinn_phong",
        "kd": [0.3, 0.3, 0.3],
        "ks": [0.5, 0.5, 0.5],
        "exponent": 100,
        "normalized": True,
    },
    "Ward α=0.15": {"type": "ward", "kd": [0.3, 0.3, 0.3], "ks": [0.3, 0.3, 0.3], "alpha": 0.15},
    "Ashikhmin-Shirley n=100": {
        "type": "ashikhmin_shirley",
        "rd": [0.3, 0.3, 0.3],
        "rs": [0.3, 0.3, 0.3],
        "nu": 100,
        "nv": 100,
    },
}
POINT = {"type": "point", "position": [2.0, 3.0, 2.0], "intensity": [10, 10, 10]}


def _scene(material: dict, size, light=None):
    import reflets

    base = reflets.load_scene(scene_path("12_ref_sphere_env.toml"))
    data = base.model_dump(exclude={"base_dir"}, exclude_none=True)
    data["camera"]["size"] = list(size)
    data["materials"] = {name: material for name in data["materials"]}
    if light is not None:
        data["light"] = [light]
        data["background"] = [0.0, 0.0, 0.0]
    return reflets.load_dict(data, base_dir=base.base_dir)


def _frames(scenes: dict, frames: int) -> dict[str, tuple[float, np.ndarray]]:
    """Median frame time (ms) and image of each ``name: (scene, params)``, one persistent ``Renderer`` each,
    their frames interleaved (the machine's drift hits every configuration alike)."""
    import reflets

    renderers = {name: reflets.Renderer(scene, method="forward", **params) for name, (scene, params) in scenes.items()}
    try:
        images = {name: renderer.render() for name, renderer in renderers.items()}
        times: dict[str, list[float]] = {name: [] for name in renderers}
        for _ in range(frames):
            for name, renderer in renderers.items():
                t = time.perf_counter()
                images[name] = renderer.render()
                times[name].append(1e3 * (time.perf_counter() - t))
    finally:
        for renderer in renderers.values():
            renderer.release()
    return {name: (statistics.median(times[name]), images[name]) for name in renderers}


def bench_ibl(quick: bool, out_dir) -> tuple[dict, str]:
    import reflets

    from ..gpu import get_context
    from ..scene.environment import load_environment
    from ..techniques.ibl import PrefilteredEnvironment

    size, spp, frames = ((80, 60), 16, 3) if quick else ((320, 240), 256, 9)
    rows = []
    for name, material in MATERIALS.items():
        scene = _scene(material, size)
        reference = reflets.reference(scene, spp=spp, progress=False).image
        sphere = np.any(reflets.render(scene, method="position") != 0, axis=-1)
        timed = _frames(
            {
                "env": (scene, {}),
                "every": (scene, {"environment_occlusion": "every-pixel"}),
                "grid": (scene, {"environment": "grid"}),
                "point": (_scene(material, size, POINT), {}),
            },
            frames,
        )
        (env_ms, image), (every_ms, every), (grid_ms, grid) = timed["env"], timed["every"], timed["grid"]
        point_ms = timed["point"][0]
        rows.append(
            {
                "material": name,
                "relmse": relmse(image[sphere][None], reference[sphere][None]),
                "relmse_every_pixel": relmse(every[sphere][None], reference[sphere][None]),
                "relmse_grid": relmse(grid[sphere][None], reference[sphere][None]),
                "env_ms": env_ms,
                "every_pixel_ms": every_ms,
                "grid_ms": grid_ms,
                "point_ms": point_ms,
            }
        )
    scene = _scene(MATERIALS["Lambert"], size)
    image = load_environment(scene)
    ctx = get_context()
    times = []
    for _ in range(3):
        source = ctx.texture((image.shape[1], image.shape[0]), 3, image.tobytes(), dtype="f4")
        ctx.finish()
        t = time.perf_counter()
        maps = PrefilteredEnvironment(source, image, scene.environment)
        ctx.finish()
        times.append(1e3 * (time.perf_counter() - t))
        maps.release()
        source.release()
    prefilter_ms = statistics.median(times)
    lines = [
        "# Prefiltered image-based lighting",
        "",
        f"A sphere under the sky map alone, {size[0]}×{size[1]}, method `forward`; relative MSE over the sphere "
        f"against the NumPy reference at {spp} spp (its noise is part of each error); frame times are medians of "
        f"{frames} frames of a persistent `Renderer` per configuration, their frames interleaved. Generated by "
        "`reflets bench ibl`.",
        "",
        f"Prefiltering the {image.shape[1]}×{image.shape[0]} map on the GPU (7 GGX levels from 256×128, 256 "
        f"samples per texel) and its irradiance map: {prefilter_ms:.0f} ms (median of 3).",
        "",
        "| material | relMSE prefiltered | every-pixel occlusion | grid 32×16 | env_ms | every-pixel ms | grid ms "
        "| point_ms | env_ms / point_ms |",
        "|---|---|---|---|---|---|---|---|---|",
        *[
            f"| {r['material']} | {r['relmse']:.2e} | {r['relmse_every_pixel']:.2e} | {r['relmse_grid']:.2e} | "
            f"{r['env_ms']:.1f} | {r['every_pixel_ms']:.1f} | {r['grid_ms']:.1f} | {r['point_ms']:.1f} | "
            f"{r['env_ms'] / r['point_ms']:.2f} |"
            for r in rows
        ],
        "",
    ]
    return {"size": list(size), "reference_spp": spp, "prefilter_ms": prefilter_ms, "rows": rows}, "\n".join(lines)
