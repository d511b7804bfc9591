"""`reflets bench shadows`: each shadow design's error against the reference that traces shadow rays, and its
cost against the same frame without shadows.

Scenes: a sphere and the Stanford bunny on a floor, under a quad light, a point light or a directional light
(plus a dim fill light without shadows, so that shadowed pixels are not black), and the sphere on a 400 × 400
floor under the directional light. Designs: shadow maps with PCF for the delta lights; for the quad light the
ratio estimator over n × n sample views (n = 2, 4 — the default —, 6) and PCSS from one view at the emitter's
centre; on the large floor one map of the whole scene against the camera's cascades (and the frame time with
the camera moving, the cascades refitted every frame). Errors (relative MSE): over the floor's visible pixels, over
the shadow (pixels where the reference loses over 5 % of the light's contribution) and over the penumbra alone
(where the reference sees between 5 % and 95 % of the light); relative MSE is ``reflets.metrics.relmse``
(per pixel, (test − ref)² / (ref² + 0.01), averaged). Frame time: median of repeated frames of a
persistent ``Renderer`` (``ltc``), the same frame with the light's shadows off in the same run.
"""

from __future__ import annotations

import statistics
import time
import warnings

import numpy as np

from ..demo import scene_path
from ..diagnostics import RefletsWarning
from ..metrics import masked_relmse

LIGHTS = {
    "quad": {"type": "quad", "corners": [[0.2, 1.5, -0.4], [1.0, 1.5, -0.4], [0.2, 1.5, 0.4]], "radiance": [6, 6, 6]},
    "point": {"type": "point", "position": [1.0, 2.5, 0.5], "intensity": [8, 8, 8]},
    "directional": {"type": "directional", "direction": [-0.4, -1, -0.3], "irradiance": [2, 2, 2]},
}
FILL = {"type": "directional", "direction": [0.2, -1, 0.4], "irradiance": [0.3, 0.3, 0.3], "shadows": False}
#: (label, technique parameters) per design; the delta lights have one design (the maps with PCF)
AREA_DESIGNS = [
    ("ratio 2×2", {"soft_shadows": "ratio", "shadow_samples": 2}),
    ("ratio 4×4 (default)", {"soft_shadows": "ratio", "shadow_samples": 4}),
    ("ratio 6×6", {"soft_shadows": "ratio", "shadow_samples": 6}),
    ("PCSS", {"soft_shadows": "pcss"}),
]
DELTA_DESIGNS = [("shadow map + PCF", {})]
#: the directional light over a large floor: one map of the whole scene, or the camera's cascades
CASCADE_DESIGNS = [("one map", {"shadow_cascades": 1}), ("cascades (default)", {})]
LARGE_FLOOR = 400.0
#: the camera positions a moving-camera frame alternates between (the cascades are refitted every frame)
MOVES = ({"position": [0.3, 2.5, 4.0]}, {"position": [-0.3, 2.4, 4.1]})


def scene_dict(obj: str, light: dict, size, shadows: bool = True, lights=None, floor: float = 6.0) -> dict:
    meshes = {
        "sphere": {"shape": "sphere", "radius": 0.5, "material": "ball", "transform": {"translate": [0, 0.5, 0]}},
        "bunny": {
            "file": str((scene_path("60_showcase.toml").parent / ".." / "meshes" / "bunny.ply").resolve()),
            "material": "ball",
            "transform": {"scale": 1.1},
        },
    }
    return {
        "camera": {"position": [0, 2.5, 4], "look_at": [0, 0.3, 0], "fov_y": 40, "size": list(size)},
        "materials": {
            "floor": {"type": "lambert", "albedo": [0.7, 0.7, 0.7]},
            "ball": {"type": "microfacet", "alpha": 0.3, "diffuse": [0.4, 0.3, 0.2]},
        },
        "mesh": [{"shape": "plane", "size": [floor, floor], "material": "floor"}, meshes[obj]],
        "light": lights if lights is not None else [{**light, "shadows": shadows}, FILL],
    }


def _frame_ms(scene, frames: int, moving: bool = False, **params) -> tuple[float, float, np.ndarray, float]:
    """(prepare ms, median frame ms, image, median ms of a frame after a camera move — NaN unless ``moving``) of
    a persistent Renderer."""
    import reflets

    t = time.perf_counter()
    renderer = reflets.Renderer(scene, method="ltc", **params)
    prepare = 1e3 * (time.perf_counter() - t)
    image = renderer.render()  # compiles the programs
    times, moved = [], []
    for _ in range(frames):
        t = time.perf_counter()
        image = renderer.render()
        times.append(1e3 * (time.perf_counter() - t))
    camera = scene.camera.model_dump()
    for k in range(frames if moving else 0):
        t = time.perf_counter()
        renderer.set_camera(**MOVES[k % 2])
        renderer.render()
        moved.append(1e3 * (time.perf_counter() - t))
    if moving:
        renderer.set_camera(position=camera["position"])
    renderer.release()
    return prepare, statistics.median(times), image, statistics.median(moved) if moved else float("nan")


def _case(obj: str, light_name: str, size, spp: int, frames: int, floor_size: float = 6.0) -> list[dict]:
    import reflets

    light = LIGHTS[light_name]
    large = floor_size > 6.0
    scene = reflets.load_dict(scene_dict(obj, light, size, floor=floor_size))
    reference = reflets.reference(scene, spp=spp, progress=False).image
    _, off_ms, unshadowed, off_moving = _frame_ms(
        reflets.load_dict(scene_dict(obj, light, size, shadows=False, floor=floor_size)), frames, moving=large
    )
    fill = reflets.render(
        reflets.load_dict(scene_dict(obj, light, size, lights=[FILL], floor=floor_size)), method="ltc"
    )
    floor = reflets.render(
        reflets.load_dict({**scene_dict(obj, light, size, floor=floor_size), "mesh": [scene.mesh[0]]}), method="ltc"
    )
    on_floor = np.any(floor != 0, axis=-1) & (np.abs(floor - unshadowed).sum(-1) < 1e-6)
    contribution = np.maximum((unshadowed - fill).sum(-1), 1e-6)
    seen = (reference - fill).sum(-1) / contribution  # the fraction of the light the reference sees
    shadow = on_floor & (seen < 0.95)
    penumbra = shadow & (seen > 0.05)
    umbra = on_floor & (seen < 0.5)  # the hard shadow of a delta light (over half its light lost)
    rows = []
    designs = CASCADE_DESIGNS if large else AREA_DESIGNS if light_name == "quad" else DELTA_DESIGNS
    for label, params in [("no shadows", {}), *designs]:
        if label == "no shadows":
            prepare, ms, image, moving_ms = float("nan"), off_ms, unshadowed, off_moving
        else:
            prepare, ms, image, moving_ms = _frame_ms(scene, frames, moving=large, **params)
        rows.append(
            {
                "object": obj if not large else f"{obj}, {floor_size:.0f} × {floor_size:.0f} floor",
                "light": light_name,
                "design": label,
                "prepare_ms": prepare,
                "frame_ms": ms,
                "frame_ms_without_shadows": off_ms,
                "moving_camera_frame_ms": moving_ms,
                "floor_relmse": masked_relmse(image, reference, on_floor),
                "shadow_relmse": masked_relmse(image, reference, shadow) if shadow.any() else None,
                "penumbra_relmse": masked_relmse(image, reference, penumbra) if penumbra.sum() > 20 else None,
                "umbra_mean_ratio": float(image[umbra].mean() / reference[umbra].mean()) if umbra.any() else None,
                "shadow_pixels": int(shadow.sum()),
                "penumbra_pixels": int(penumbra.sum()),
            }
        )
    return rows


def _plot(rows: list[dict], path) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, axes = plt.subplots(1, 2, figsize=(10, 4))
    for ax, obj in zip(axes, ("sphere", "bunny"), strict=True):
        for row in (r for r in rows if r["object"] == obj and r["light"] == "quad"):
            ax.scatter(row["frame_ms"], row["shadow_relmse"], label=row["design"])
            ax.annotate(row["design"], (row["frame_ms"], row["shadow_relmse"]), fontsize=8)
        ax.set_xlabel("frame time (ms, median)")
        ax.set_ylabel("relative MSE over the shadow")
        ax.set_yscale("log")
        ax.set_title(f"{obj} on a floor, quad light")
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)


def _ms(value) -> str:
    return "–" if value != value else f"{value:.0f}"


def _fmt(value) -> str:
    return "–" if value is None or value != value else f"{value:.2e}"


def bench_shadows(quick: bool, out_dir) -> tuple[dict, str]:
    size, spp, frames = ((80, 60), 16, 2) if quick else ((320, 240), 256, 9)
    rows = []
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", RefletsWarning)
        for obj in ("sphere", "bunny"):
            for light in LIGHTS:
                rows += _case(obj, light, size, spp, frames)
        rows += _case("sphere", "directional", size, spp, frames, floor_size=LARGE_FLOOR)
    _plot(rows, out_dir / "shadows.png")
    lines = [
        "# Shadows: error against the reference with visibility, and cost",
        "",
        f"{size[0]}×{size[1]}, method `ltc`; the NumPy reference at {spp} spp traces shadow rays (its noise is part "
        "of each error); frame times are medians of "
        f"{frames} frames of a persistent `Renderer`, with the light's shadows off measured in the same run. "
        "Generated by `reflets bench shadows`.",
        "",
        "![error vs time](shadows.png)",
        "",
        "Shadow: the floor's pixels where the reference loses over 5 % of the light; penumbra: where it sees 5 to 95 % "
        "of it; umbra mean: the mean of the pixels where it loses over half, GPU / reference.",
        "",
        f"Last rows: the sphere on a {LARGE_FLOOR:.0f} × {LARGE_FLOOR:.0f} floor under the directional light, one map "
        "of the whole scene against the camera's cascades; with the camera moving between two nearby positions "
        "every frame (cascades refitted and drawn again): "
        + "; ".join(
            f"{r['design']} {r['moving_camera_frame_ms']:.1f} ms"
            for r in rows
            if r["moving_camera_frame_ms"] == r["moving_camera_frame_ms"]
        )
        + ".",
        "",
        "| object | light | design | frame ms | without shadows | prepare ms | floor relMSE | shadow relMSE | "
        "penumbra relMSE | umbra mean |",
        "|---|---|---|---|---|---|---|---|---|---|",
    ]
    for r in rows:
        lines.append(
            f"| {r['object']} | {r['light']} | {r['design']} | {r['frame_ms']:.1f} | "
            f"{r['frame_ms_without_shadows']:.1f} | {_ms(r['prepare_ms'])} | "
            f"{_fmt(r['floor_relmse'])} | {_fmt(r['shadow_relmse'])} | {_fmt(r['penumbra_relmse'])} | "
            f"{'–' if r['umbra_mean_ratio'] is None else format(r['umbra_mean_ratio'], '.3f')} |"
        )
    return {"size": list(size), "reference_spp": spp, "frames": frames, "rows": rows}, "\n".join(lines) + "\n"
