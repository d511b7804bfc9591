"""`reflets bench renderer`: the persistent renderer on the showcase, and how a frame grows with lights and meshes.

- showcase (``60_showcase.toml``, method ``auto``): prepare time; a camera orbit through one ``Renderer``
  (``set_camera`` + ``render`` per frame) against the same frames through one-shot ``reflets.render()`` (every
  k-th frame: one-shot frames cost seconds on a software rasteriser), the two images compared; the cost of each
  pass of one frame (a ``ctx.finish()`` after each pass);
- each showcase object against ground truth, in the pixels where it is the nearest surface: the composed frame
  against the NumPy reference (shadow rays, as the GPU's shadow maps and environment views), and the marble alone
  under each of its lights against the volumetric reference (all orders of scattering, η = 1.5 refracted): the
  ``translucent`` technique auto uses for the point light, the far-field BRDF it uses for the quad light and
  the sky;
- scaling: a GGX sphere on a floor with 1, 4, 16 point lights, 1, 4 quad lights, and 1, 10, 100 sphere
  instances, median frame of a persistent renderer.

Frame times are the wall clock of ``render()`` (the frame and its read-back: the read waits for the GPU), medians,
all rows of one table measured in the same run; the pass costs a ``ctx.finish()`` after each pass (llvmpipe's
timer queries mean nothing). `reflets bench gpu` times frames without read-back and with timer queries.
"""

from __future__ import annotations

import statistics
import time
import warnings

import numpy as np

from ..demo import scene_path
from ..diagnostics import RefletsWarning
from ..metrics import compare
from ..scene import load_dict, load_scene


def _orbit(scene, frames: int) -> list[dict]:
    """Camera positions on a circle around the look-at point at the scene camera's distance and height."""
    cam = scene.camera
    eye, target = np.asarray(cam.position, float), np.asarray(cam.look_at, float)
    offset = eye - target
    radius, height = float(np.hypot(offset[0], offset[2])), float(offset[1])
    start = float(np.arctan2(offset[0], offset[2]))
    angles = start + np.linspace(-0.5, 0.5, frames)  # ±0.5 rad: the objects stay in view
    return [
        {
            "position": (
                float(target[0] + radius * np.sin(a)),
                float(target[1] + height),
                float(target[2] + radius * np.cos(a)),
            )
        }
        for a in angles
    ]


def _showcase(size, frames: int, one_shot_every: int) -> tuple[dict, list[str]]:
    import reflets

    scene = load_scene(scene_path("60_showcase.toml"))
    t0 = time.perf_counter()
    renderer = reflets.Renderer(scene, size=size)
    prepare_ms = 1e3 * (time.perf_counter() - t0)
    renderer.render()  # the first frame compiles the programs: not an orbit frame
    persistent, one_shot, errors = [], [], []
    for k, camera in enumerate(_orbit(scene, frames)):
        t = time.perf_counter()
        renderer.set_camera(**camera)
        image = renderer.render()
        persistent.append(1e3 * (time.perf_counter() - t))
        if k % one_shot_every == 0:
            t = time.perf_counter()
            fresh = reflets.render(renderer.scene, size=size)
            one_shot.append(1e3 * (time.perf_counter() - t))
            errors.append(compare(image, fresh)["relmse"])
    technique = renderer._technique
    technique.measure_passes = True
    renderer.set_camera(**_orbit(scene, frames)[-1])  # a new view's first frame: every pass drawn whole
    renderer.render()
    passes = [{"pass": m, "meshes": n, "ms": ms} for m, n, ms in technique.pass_costs()]
    renderer.release()
    result = {
        "size": list(size),
        "prepare_ms": prepare_ms,
        "orbit_frames": frames,
        "persistent_frame_ms_median": statistics.median(persistent),
        "one_shot_frames": len(one_shot),
        "one_shot_frame_ms_median": statistics.median(one_shot),
        "persistent_vs_one_shot_relmse_max": max(errors),
        "passes": passes,
    }
    ratio = result["one_shot_frame_ms_median"] / result["persistent_frame_ms_median"]
    lines = [
        f"## Showcase ({size[0]}×{size[1]}, method auto)",
        "",
        "| prepare | orbit frame, persistent Renderer (median of "
        f"{frames}) | same frames, one-shot `reflets.render()` (median of {len(one_shot)}) | ratio | "
        "largest relative MSE between the two |",
        "|---|---|---|---|---|",
        f"| {prepare_ms:.0f} ms | {result['persistent_frame_ms_median']:.1f} ms | "
        f"{result['one_shot_frame_ms_median']:.1f} ms | {ratio:.1f}× | {max(errors):.1e} |",
        "",
        "Cost of each pass of one frame (a `ctx.finish()` after each):",
        "",
        "| pass | meshes it shades | ms |",
        "|---|---|---|",
        *[f"| {p['pass']} | {p['meshes']} | {p['ms']:.1f} |" for p in passes],
        "",
    ]
    return result, lines


def showcase_scene(size, meshes=None, lights=None, shadows: bool = True):
    """The showcase at ``size``, optionally with only the named meshes and the lights of the given types (and
    with every light's shadows off: an object then looks the same alone as among the others)."""
    scene = load_scene(scene_path("60_showcase.toml"))
    data = scene.model_dump(exclude={"base_dir"}, exclude_none=True)
    data["camera"]["size"] = list(size)
    if meshes is not None:
        data["mesh"] = [m for m in data["mesh"] if m["name"] in meshes]
    if lights is not None:
        data["light"] = [light for light in data["light"] if light["type"] in lights]
    for light in data["light"]:
        light["shadows"] = light.get("shadows", True) and shadows
    return load_dict(data, base_dir=scene.base_dir)


def nearest_surface(part, whole) -> np.ndarray:
    """Pixels where the meshes of ``part`` (a subset of ``whole``'s) are the nearest surface of ``whole``."""
    import reflets

    mine = reflets.render(part, method="position")
    seen = reflets.render(whole, method="position")
    return np.all(np.abs(mine - seen) < 1e-5, axis=-1) & np.any(mine != 0, axis=-1)


#: what the reference evaluates on each showcase object, against what auto draws there. The scratched plate has
#: none here: its scratch lobes are singular (curves on the sphere of directions), the NumPy reference sees only
#: its base layer; its ground truth is the explicit-geometry brushed plate of `reflets bench scratches`.
REFERENCE_MODEL = {
    "floor": "same BRDF (Lambert); auto: LTC",
    "bunny": "same BRDF (GGX); auto: LTC",
    "marble": "far-field BRDF for every light; auto: subsurface for the point light (not the same model)",
    "mirror": "one specular bounce, the reflected objects by their BRDF; auto: Fermat per vertex",
}


def _objects(size, spp: int, reference_spp: int, volumetric_spp: int, out_dir) -> tuple[dict, list[str]]:

    import reflets

    from ..reference.store import stored_or_rendered
    from ..reference.volumetric import render_volumetric

    rows = []
    whole = showcase_scene(size)
    with reflets.Renderer(whole) as renderer:
        composed = renderer.render(spp=spp)
        # auto's spp is an s×s supersample of each pixel, or, with a progressive pass (scratches), frames of
        # one sample at the pixel centre: the reference samples its pixels the same way (a reflected sun's
        # edge would differ)
        supersampled = renderer._technique.frames(spp)[1] > 1
    pixel = "box" if supersampled else "center"
    reference = reflets.reference(whole, spp=reference_spp, pixel=pixel, progress=False)
    for name in [mesh.name for mesh in whole.mesh if mesh.name in REFERENCE_MODEL]:
        mask = nearest_surface(showcase_scene(size, meshes={name}), whole)
        rows.append(
            {
                "object": name,
                "pixels": int(mask.sum()),
                "relmse": compare(composed[mask][None], reference.image[mask][None])["relmse"],
                "reference": REFERENCE_MODEL[name],
                "pixel": pixel,
            }
        )
    marble_rows, references = [], {}
    for light, models in (
        ("point", (("translucent technique (what auto draws)", "auto"), ("far-field BRDF", "forward"))),
        ("quad", (("far-field BRDF by LTC (what auto draws)", "auto"),)),
        ("environment", (("far-field BRDF, prefiltered environment (what auto draws)", "auto"),)),
    ):
        marble = showcase_scene(size, meshes={"marble"}, lights={light})
        kind = "" if light == "point" else f"{light}_"
        name = f"renderer_marble_{kind}{size[0]}x{size[1]}_{volumetric_spp}spp.npz"

        def render(scene=marble):
            return render_volumetric(scene, spp=volumetric_spp, seed=0, workers=None, progress=True)

        volumetric, references[light] = stored_or_rendered(
            out_dir / "references" / name, marble, render, spp=volumetric_spp, seed=0
        )
        mask = volumetric.mask & np.any(reflets.render(marble, method="position") != 0, axis=-1)
        noise = float(np.mean(volumetric.stderr[mask] ** 2 / (volumetric.image[mask] ** 2 + 1e-2)))
        for label, method in models:
            with warnings.catch_warnings():  # forward on a translucent material warns: here it is the point
                warnings.simplefilter("ignore", RefletsWarning)
                image = reflets.render(marble, method=method)
            relmse = compare(image[mask][None], volumetric.image[mask][None])["relmse"]
            marble_rows.append({"light": light, "model": label, "relmse": relmse, "reference_noise": noise})
    result = {
        "size": list(size),
        "spp": spp,
        "reference_spp": reference_spp,
        "objects": rows,
        "marble": {"volumetric_spp": volumetric_spp, "references": references, "rows": marble_rows},
    }
    lines = [
        f"## Each showcase object against ground truth ({size[0]}×{size[1]})",
        "",
        f"The composed frame (auto, {spp} spp) against the NumPy reference ({reference_spp} spp, shadow rays — the "
        "GPU's shadow maps and environment views; its pixels sampled as auto samples them), "
        "relative MSE over the "
        "pixels where the object is the nearest surface (the scratched plate has no reference in a general scene: "
        "its lobes are singular, the reference sees only its base layer; its ground truth is the brushed plate of "
        "`reflets bench scratches`):",
        "",
        "| object | pixels | relative MSE | what the reference evaluates |",
        "|---|---|---|---|",
        *[f"| {r['object']} | {r['pixels']} | {r['relmse']:.2e} | {r['reference']} |" for r in rows],
        "",
        f"The marble alone under one light against the volumetric reference ({volumetric_spp} spp, all orders of "
        "scattering through its η = 1.5 boundary; a quad light sampled over its area, the sky by its importance "
        "sampler; "
        + ", ".join(
            f"{k} light {'stored' if r['stored'] else 'computed'} in {r['seconds']:.0f} s"
            for k, r in references.items()
        )
        + "): under a point light auto runs the translucent technique; a quad light and the sky reach a "
        "translucent object through its far-field BRDF. Relative MSE over the marble's pixels, and the "
        "reference's own noise (mean (σ / value)²) for scale:",
        "",
        "| light | model | relative MSE | reference noise |",
        "|---|---|---|---|",
        *[f"| {r['light']} | {r['model']} | {r['relmse']:.2e} | {r['reference_noise']:.1e} |" for r in marble_rows],
        "",
    ]
    return result, lines


def _scaling_scene(size, points: int = 1, quads: int = 0, instances: int = 1) -> dict:
    rng = np.random.default_rng(1)
    lights = []
    for i in range(points):
        a = 2 * np.pi * i / points
        lights.append({"type": "point", "position": [2 * np.cos(a), 2.5, 2 * np.sin(a)], "intensity": [8 / points] * 3})
    for i in range(quads):
        x = -1.5 + 3.0 * i / max(quads - 1, 1)
        lights.append(
            {
                "type": "quad",
                "corners": [[x - 0.3, 2.5, -0.3], [x + 0.3, 2.5, -0.3], [x - 0.3, 2.5, 0.3]],
                "radiance": [3] * 3,
            }
        )
    side = int(np.ceil(np.sqrt(instances)))
    meshes = [{"shape": "plane", "size": [8, 8], "material": "floor"}]
    for i in range(instances):
        x, z = (i % side) - (side - 1) / 2, (i // side) - (side - 1) / 2
        scale = 2.0 / side
        meshes.append(
            {
                "shape": "sphere",
                "radius": 0.4 * scale,
                "segments": [32, 16],
                "material": "ggx",
                "transform": {"translate": [x * scale, 0.4 * scale + 0.01 * rng.random(), z * scale]},
            }
        )
    return {
        "camera": {"position": [0, 2.5, 4.0], "look_at": [0, 0.2, 0], "fov_y": 45, "size": list(size)},
        "materials": {
            "floor": {"type": "lambert", "albedo": [0.5, 0.5, 0.5]},
            "ggx": {"type": "microfacet", "distribution": "ggx", "alpha": 0.3, "diffuse": [0.3, 0.2, 0.1]},
        },
        "mesh": meshes,
        "light": lights,
    }


def _scaling(size, frames: int) -> tuple[list[dict], list[str]]:
    import reflets

    cases = [("point lights", n, {"points": n}) for n in (1, 4, 16)]
    cases += [("quad lights (ltc)", n, {"points": 0, "quads": n}) for n in (1, 4)]
    cases += [("sphere instances", n, {"instances": n}) for n in (1, 10, 100)]
    rows = []
    for what, n, kwargs in cases:
        with reflets.Renderer(load_dict(_scaling_scene(size, **kwargs))) as renderer:
            renderer.render()
            times = []
            for _ in range(frames):
                t = time.perf_counter()
                renderer.render()
                times.append(1e3 * (time.perf_counter() - t))
        rows.append({"what": what, "count": n, "frame_ms_median": statistics.median(times), "frames": frames})
    lines = [
        f"## Frame time against lights and meshes ({size[0]}×{size[1]}, method auto, median of {frames} frames)",
        "",
        "| what | count | frame (ms) |",
        "|---|---|---|",
        *[f"| {r['what']} | {r['count']} | {r['frame_ms_median']:.1f} |" for r in rows],
        "",
    ]
    return rows, lines


def bench_renderer(quick: bool, out_dir) -> tuple[dict, str]:
    size, frames, every = ((160, 120), 6, 3) if quick else ((640, 480), 60, 10)
    showcase, lines = _showcase(size, frames, every)
    objects, object_lines = _objects(
        (80, 60) if quick else (160, 120), 16 if quick else 64, 16 if quick else 256, 2 if quick else 32, out_dir
    )
    scaling, more = _scaling((160, 120) if quick else (640, 480), 3 if quick else 9)
    text = ["# The persistent renderer", "", *lines, *object_lines, *more]
    return {"showcase": showcase, "objects": objects, "scaling": scaling}, "\n".join(text)
