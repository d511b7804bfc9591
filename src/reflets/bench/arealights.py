"""`reflets bench arealights`: the area-light document's experiment, extended.

A 4×4 plane and one unit square light at height 1 (camera (0, 3, 4), fov 45°), Phong ρ_d = 0, ρ_s = 1 with
e ∈ {150, 200, 500} (the document's un-normalised form), GGX α ∈ {0.1, 0.3, 0.6} and Lambert; every method at
several settings. Then the other BRDFs that have a shipped ``ltc`` table (Beckmann, normalised Phong and
Blinn-Phong, Ward) at α = 0.1 and 0.3 (Phong lobes: the equivalent e = 2/α² − 2): the ``ltc`` bases and
brute 8². For each: median frame time over ≥ 10 frames at 800×600 (draw only, read-back excluded; GPU timer
queries on a real GPU, finish() + wall clock on llvmpipe), light samples evaluated per pixel (mean over the
plane), relative MSE and FLIP against the unoccluded NumPy reference, and the largest error as a
fraction of the peak against a converged ``brute`` 64² grid (the Monte Carlo reference's own noise reaches
4 % of the peak, too much for a maximum). Errors are measured at 200×150 (same camera) so the reference stays
affordable; times at 800×600. Writes arealights.{json,md,png}.
"""

from __future__ import annotations

import statistics
from pathlib import Path

import numpy as np

from ..errors import RefletsError

#: the same plane lit by one point light at the light's centre: the cost floor of a shading pass
POINT_LIGHT = {"type": "point", "position": [0, 1, 0], "intensity": [5, 5, 5]}
LIGHT = {"type": "quad", "corners": [[-0.5, 1, -0.5], [0.5, 1, -0.5], [-0.5, 1, 0.5]], "radiance": [5, 5, 5]}

MATERIALS = {
    "phong e=150": {"type": "phong", "kd": [0, 0, 0], "ks": [1, 1, 1], "exponent": 150},
    "phong e=200": {"type": "phong", "kd": [0, 0, 0], "ks": [1, 1, 1], "exponent": 200},
    "phong e=500": {"type": "phong", "kd": [0, 0, 0], "ks": [1, 1, 1], "exponent": 500},
    "ggx a=0.1": {"type": "microfacet", "distribution": "ggx", "alpha": 0.1},
    "ggx a=0.3": {"type": "microfacet", "distribution": "ggx", "alpha": 0.3},
    "ggx a=0.6": {"type": "microfacet", "distribution": "ggx", "alpha": 0.6},
    "lambert": {"type": "lambert", "albedo": [0.8, 0.8, 0.8]},
}
_LOBE = {"kd": [0, 0, 0], "ks": [1, 1, 1]}
#: the families of the other shipped ltc tables, measured with TABLE_SETTINGS only
TABLE_MATERIALS = {
    f"{name} a={alpha}": material
    for alpha in (0.1, 0.3)
    for name, material in (
        ("beckmann", {"type": "microfacet", "distribution": "beckmann", "alpha": alpha}),
        ("phong normalized", {"type": "phong", "normalized": True, "exponent": 2 / alpha**2 - 2, **_LOBE}),
        ("blinn-phong normalized", {"type": "blinn_phong", "normalized": True, "exponent": 2 / alpha**2 - 2, **_LOBE}),
        ("ward", {"type": "ward", "variant": "duer", "alpha": alpha, **_LOBE}),
    )
}
TABLE_SETTINGS = ("ltc", "ltc base=cosine", "brute 8²")

#: (curve label, method, parameters, spp)
SETTINGS = (
    [(f"brute {n}²", "brute", {"grid": n}, 1) for n in (4, 8, 16, 20, 32)]
    + [("adaptive", "adaptive", {"dither": False}, 1), ("adaptive+dither", "adaptive", {"dither": True}, 1)]
    + [(f"biased t={t} {n}²", "biased", {"threshold": t, "grid": n}, 1) for t in (0.99, 0.9) for n in (4, 8)]
    + [(f"mc mis {s}spp", "mc", {"strategy": "mis", "samples": 16}, s) for s in (16, 64, 256)]
    + [("mc two-region 64spp", "mc", {"strategy": "two_region", "samples": 16}, 64)]
    + [("analytic", "analytic", {}, 1), ("ltc", "ltc", {}, 1), ("ltc base=cosine", "ltc", {"base": "cosine"}, 1)]
)
#: the converged grid the largest error is measured against (64² vs 128²: ≤ 7·10⁻⁴ of the peak on these scenes)
EXACT_GRID = 64


def scene_dict(material: dict, size=(800, 600)) -> dict:
    return {
        "camera": {"position": [0, 3, 4], "look_at": [0, 0, 0], "fov_y": 45, "size": list(size)},
        "materials": {"m": material},
        "mesh": [{"shape": "plane", "size": [4, 4], "material": "m"}],
        "light": [LIGHT],
    }


def curve_of(label: str) -> str:
    """The method family a setting belongs to (one plot curve each)."""
    for prefix in ("brute", "adaptive", "biased t=0.99", "biased t=0.9", "mc mis", "mc two-region"):
        if label.startswith(prefix):
            return prefix
    return label


def _time_image(technique, size, spp: int, repeats: int) -> float:
    """Median time of a whole image (all of a progressive method's frames), draw only."""
    times = []
    for _ in range(repeats):
        with technique.timer.measuring() as timer:
            technique.render(size=size, spp=spp)
        times.append(sum(timer.frame_times()))
    return statistics.median(times)


def bench_arealights(
    quick: bool, out_dir: Path, materials: list[str] | None = None, settings: list[str] | None = None
) -> tuple[dict, str]:
    """The whole suite; ``materials`` and ``settings`` (labels of MATERIALS and SETTINGS) run a part of it, e.g.
    the ltc rows alone (tools/bench_arealights_part.py), without the ltc cost comparison."""
    import reflets

    from ..gpu import get_context
    from ..metrics import flip, relmse
    from ..techniques import get_technique

    ctx = get_context()
    time_size, error_size = ((200, 150), (100, 75)) if quick else ((800, 600), (200, 150))
    frames, ref_spp = (3, 64) if quick else (10, 256)
    part = materials is not None or settings is not None
    everything = {**MATERIALS, **TABLE_MATERIALS}
    if materials is None:
        materials = dict(
            list(MATERIALS.items())[:: (3 if quick else 1)] + list(TABLE_MATERIALS.items())[:: (4 if quick else 1)]
        )
    else:
        materials = {name: everything[name] for name in materials}
    rows = []
    point_ms = None
    for mat_name, material in materials.items():
        scene = reflets.load_dict(scene_dict(material, time_size))
        small = reflets.load_dict(scene_dict(material, error_size))
        ref = reflets.reference(small, spp=ref_spp, visibility=False, progress=False)
        emitter_free = _plane_mask(small)
        exact = reflets.render(small, method="brute", grid=EXACT_GRID)[emitter_free]
        peak = float(exact.max())
        if point_ms is None:  # the same plane with one point light: the cost floor of a shading pass
            point_scene = reflets.load_dict(
                {
                    **scene_dict(material, time_size),
                    "light": [POINT_LIGHT],
                }
            )
            forward = get_technique("forward")(ctx)
            forward.prepare(point_scene)
            point_ms = _time_image(forward, time_size, 1, frames)
            forward.release()
        chosen = [
            s
            for s in SETTINGS
            if (settings is None or s[0] in settings) and (mat_name in MATERIALS or s[0] in TABLE_SETTINGS)
        ]
        for label, method, params, spp in chosen:
            try:
                technique = get_technique(method)(ctx, **params)
            except RefletsError as exc:
                rows.append({"material": mat_name, "setting": label, "error": str(exc)})
                continue
            technique.prepare(scene)
            ms = _time_image(technique, time_size, spp, frames)
            technique.release()
            image = reflets.render(small, method=method, spp=spp, **params)
            counter = get_technique(method)(ctx, **{**params, "output": "samples"})
            counter.prepare(small)
            per_frame = params.get("samples", spp) if method == "mc" else spp
            samples = counter.render(size=error_size, spp=per_frame)[..., 0]  # one frame's count
            counter.release()
            spp_factor = spp // per_frame if method == "mc" else 1
            rows.append(
                {
                    "material": mat_name,
                    "setting": label,
                    "curve": curve_of(label),
                    "method": method,
                    "params": params,
                    "spp": spp,
                    "frame_ms": ms,
                    "ratio_to_point_light": ms / point_ms,
                    "samples_per_pixel": float(samples[emitter_free].mean() * spp_factor),
                    "relmse": relmse(image[emitter_free][None], ref.image[emitter_free][None]),
                    "flip": flip(
                        np.where(emitter_free[..., None], image, 0), np.where(emitter_free[..., None], ref.image, 0)
                    ),
                    "max_error": float(np.abs(image[emitter_free] - exact).max() / peak),
                }
            )
    plot(rows, out_dir / "arealights.png")
    markdown = _markdown(rows, time_size, error_size, frames, ref_spp, point_ms)
    if part:
        return {"part": {"materials": list(materials), "settings": settings}, "rows": rows}, markdown
    cost = ltc_cost(ctx, time_size, rounds=3 if quick else 8)
    return {
        "time_size": list(time_size),
        "error_size": list(error_size),
        "frames": frames,
        "reference_spp": ref_spp,
        "point_light_ms": point_ms,
        "rows": rows,
        "ltc_cost": cost,
    }, markdown + _cost_markdown(cost, time_size)


#: the LTC cost comparison: (label, method, parameters, light); GGX α = 0.3 as in the three.js reference
COST_CASES = [
    ("forward, no light", "forward", {}, None),
    ("forward, one point light", "forward", {}, "point"),
    ("ltc", "ltc", {}, "quad"),
    ("ltc, sphere horizon", "ltc", {"horizon": "sphere"}, "quad"),
    ("ltc without horizon clipping", "ltc", {"profile": "no_clip"}, "quad"),
    ("ltc without table fetches", "ltc", {"profile": "no_fetch"}, "quad"),
    ("ltc setup only (no polygon integral)", "ltc", {"profile": "no_edges"}, "quad"),
]


def ltc_cost(ctx, size, rounds: int, frames: int = 5) -> dict:
    """Frame times of ``ltc``, its stages and the point-light pass, measured in interleaved rounds (a shared
    machine's load drifts; interleaving gives every case the same drift). On llvmpipe the distribution is
    bimodal: a frame runs on two threads when the host gives the second core and on one when it does not, so
    the median moves with the host's load while the 10th percentile (two threads) and the ratios stay put."""
    import reflets

    from ..techniques import get_technique

    lights = {
        None: [],
        "point": [POINT_LIGHT],
        "quad": [LIGHT],
    }
    techniques = {}
    for label, method, params, light in COST_CASES:
        scene = reflets.load_dict({**scene_dict(MATERIALS["ggx a=0.3"], size), "light": lights[light]})
        technique = get_technique(method)(ctx, **params)
        technique.prepare(scene)
        technique.render(size=size)  # compile and warm up
        techniques[label] = technique
    times = {label: [] for label in techniques}
    for _ in range(rounds):
        for label, technique in techniques.items():
            times[label].extend(_frame_times(technique, size, frames))
    for technique in techniques.values():
        technique.release()
    medians = {label: statistics.median(t) for label, t in times.items()}
    p10 = {label: float(np.percentile(t, 10)) for label, t in times.items()}
    point = "forward, one point light"
    return {
        "size": list(size),
        "rounds": rounds,
        "frames_per_round": frames,
        "median_ms": medians,
        "p10_ms": p10,
        "ltc_over_point_light": medians["ltc"] / medians[point],
        "ltc_over_point_light_p10": p10["ltc"] / p10[point],
    }


def _frame_times(technique, size, frames: int) -> list[float]:
    """Each frame's time (GPU timer on a real GPU, finish() + wall clock on llvmpipe), draw only."""
    with technique.timer.measuring() as timer:
        for _ in range(frames):
            technique.render(size=size)
    return timer.frame_times()


def _cost_markdown(cost: dict, size) -> str:
    m, p10 = cost["median_ms"], cost["p10_ms"]
    lines = [
        "## Where the time of `ltc` goes",
        "",
        f"GGX α = 0.3, {size[0]}×{size[1]}, {cost['rounds']} interleaved rounds of {cost['frames_per_round']} "
        f"frames. `ltc` / one point light = **{cost['ltc_over_point_light']:.2f}×** (medians), "
        f"**{cost['ltc_over_point_light_p10']:.2f}×** (10th percentiles). On llvmpipe a frame's time is bimodal "
        "(two threads when the host gives the second core, one when it does not): the median follows the "
        "host's load, the 10th percentile is the two-thread time. The stage variants are timing aids only "
        "(their images are wrong); a stage's cost is the full frame minus the variant without it.",
        "",
        "| case | median ms / frame | 10th percentile | cost of the dropped stage (p10, ms) |",
        "|---|---|---|---|",
    ]
    for label, ms in m.items():
        dropped = f"{p10['ltc'] - p10[label]:.2f}" if label.startswith("ltc without") or "only" in label else ""
        lines.append(f"| {label} | {ms:.2f} | {p10[label]:.2f} | {dropped} |")
    return "\n".join(lines + [""])


def bench_ltc_cost(quick: bool, out_dir: Path) -> tuple[dict, str]:
    """Only the ltc cost comparison of ``arealights`` (a minute, not an hour)."""
    from ..gpu import get_context

    size = (200, 150) if quick else (800, 600)
    cost = ltc_cost(get_context(), size, rounds=3 if quick else 12)
    accuracy = horizon_accuracy((100, 75) if quick else (200, 150), 64 if quick else 256)
    return {**cost, "horizon_accuracy": accuracy}, _cost_markdown(cost, size) + _accuracy_markdown(accuracy)


def horizon_accuracy(size, spp: int) -> list[dict]:
    """Relative MSE of ``ltc`` with exact and sphere horizon clipping against the unoccluded reference, for the
    materials whose transformed polygons cross the horizon most (narrow lobes at grazing views)."""
    import reflets

    from ..metrics import relmse

    rows = []
    for name in ("ggx a=0.1", "ggx a=0.3", "phong e=150"):
        scene = reflets.load_dict(scene_dict(MATERIALS[name], size))
        ref = reflets.reference(scene, spp=spp, visibility=False, progress=False)
        mask = _plane_mask(scene)
        row = {"material": name, "reference_spp": spp}
        for horizon in ("exact", "sphere"):  # both with the clamped-cosine tables, the only ones sphere takes
            image = reflets.render(scene, method="ltc", horizon=horizon, base="cosine")
            row[horizon] = relmse(image[mask][None], ref.image[mask][None])
        rows.append(row)
    return rows


def _accuracy_markdown(rows: list[dict]) -> str:
    lines = [
        "",
        "## Horizon clipping: exact vs sphere",
        "",
        f"Relative MSE of `ltc` against the unoccluded reference ({rows[0]['reference_spp']} spp), benchmark "
        "scene at 200×150.",
        "",
        "| material | exact | sphere |",
        "|---|---|---|",
    ]
    lines += [f"| {r['material']} | {r['exact']:.2e} | {r['sphere']:.2e} |" for r in rows]
    return "\n".join(lines + [""])


def _plane_mask(scene) -> np.ndarray:
    """Pixels whose camera ray hits the plane first (not the light's emitter, not the background)."""
    from ..reference.geometry import MESHES, SceneGeometry
    from ..scene.camera import pixel_rays

    origin, dirs = pixel_rays(scene.camera)
    hits = SceneGeometry(scene).intersect(np.broadcast_to(origin, dirs.shape).reshape(-1, 3), dirs.reshape(-1, 3))
    return (hits.kind == MESHES).reshape(dirs.shape[:2])


def _markdown(rows, time_size, error_size, frames, ref_spp, point_ms) -> str:
    lines = [
        "# Area lights: error vs time",
        "",
        f"Frame time: median of {frames} frames at {time_size[0]}×{time_size[1]} (draw only). Error: relative MSE "
        f"(eps 0.01) and FLIP over the plane at {error_size[0]}×{error_size[1]} against the unoccluded NumPy "
        f"reference ({ref_spp} spp); max error: the largest |error| over the plane as a fraction of the peak, "
        f"against brute {EXACT_GRID}² (converged). One point light on the same plane: {point_ms:.2f} ms per frame.",
        "",
        "| material | setting | ms / frame | × point light | samples / px | relMSE | FLIP | max error |",
        "|---|---|---|---|---|---|---|---|",
    ]
    for r in rows:
        if "error" in r:
            lines.append(f"| {r['material']} | {r['setting']} | — | — | — | — | {r['error']} | — |")
            continue
        lines.append(
            f"| {r['material']} | {r['setting']} | {r['frame_ms']:.1f} | {r['ratio_to_point_light']:.1f} | "
            f"{r['samples_per_pixel']:.1f} | {r['relmse']:.2e} | {r['flip']:.3f} | {r['max_error']:.2%} |"
        )
    lines += ["", "![error vs time](arealights.png)", ""]
    return "\n".join(lines)


def plot(rows: list[dict], path: Path) -> None:
    """Log-log error-vs-time plot, one panel per material, one curve per method family."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    rows = [r for r in rows if "error" not in r]
    materials = list(dict.fromkeys(r["material"] for r in rows))
    cols = min(4, len(materials))
    fig, axes = plt.subplots(
        (len(materials) + cols - 1) // cols,
        cols,
        figsize=(4.2 * cols, 3.6 * ((len(materials) + cols - 1) // cols)),
        squeeze=False,
    )
    for ax, mat in zip(axes.ravel(), materials, strict=False):
        for curve in dict.fromkeys(r["curve"] for r in rows):
            pts = sorted(
                (r["frame_ms"], max(r["relmse"], 1e-9)) for r in rows if r["material"] == mat and r["curve"] == curve
            )
            if pts:
                ax.plot(*zip(*pts, strict=True), marker="o", label=curve)
        ax.set_xscale("log")
        ax.set_yscale("log")
        ax.set_title(mat)
        ax.set_xlabel("ms per frame")
        ax.set_ylabel("relative MSE")
        ax.grid(True, which="both", alpha=0.3)
    for ax in axes.ravel()[len(materials) :]:
        ax.axis("off")
    axes.ravel()[0].legend(fontsize=7)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)
