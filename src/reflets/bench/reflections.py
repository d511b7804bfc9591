"""`reflets bench reflections`: per-vertex Fermat reflections — solver convergence, cost and accuracy.

1. **Convergence** (NumPy twin of the GPU solver, 10,000 seeded random eye / vertex pairs with a valid
   reflection on a sphere, an ellipsoid, a torus and a cylinder): fraction converged (law-of-reflection
   residual < 1e-5) after 1…10 iterations, for the robust solver and the document's (global chart, and the
   note's local chart); the GPU solver's rates (float32, residual < 1e-4) at 4, 5 and 8 iterations.
2. **Scenes** (the teapot by a chrome sphere, ~2,500 triangles; the room with a chrome ellipsoid, ~18,000;
   the teapot in a curved Bézier mirror, solved on its sampled texture),
   for each solver × reflected-mesh subdivision (1, 4, auto): median frame time (draw only), the
   ``forward`` frame for scale, reflected vertices per frame and per second, the fraction of reflected
   vertices whose solution converged, relative MSE and FLIP against the ray-traced reference.
3. **Curved reflected edges**: a straight floor line of the teapot scene split into 1, 4, 16, 64 segments;
   its reflection as the rasteriser draws it (straight screen segments between the GPU reflection points)
   against the exact reflection of 2,000 points of the line (bisection on the great circle, independent of
   the solvers): the maximum distance in pixels at 1024×768.

Writes reflections.{json,md} and two plots (convergence vs iterations; error vs time).
"""

from __future__ import annotations

import statistics
from importlib import resources
from pathlib import Path

import numpy as np

SCENES = {
    "teapot + sphere": "40_reflect_teapot_sphere.toml",
    "room + ellipsoid": "41_reflect_room.toml",
    "teapot + Bézier mirror": "42_reflect_bezier.toml",
}
SOLVERS = ("robust", "document")
SUBDIVISIONS = (1, 4, "auto")
EDGE_SEGMENTS = (1, 4, 16, 64)
ITERATIONS = tuple(range(1, 11))


def _scene(name: str):
    import reflets

    return reflets.load_scene(resources.files("reflets").joinpath("data", "scenes", SCENES[name]))


#: the convergence surfaces as scene reflectors (mirror material, camera unused: every pair has its own eye)
SURFACE_MESHES = {
    "sphere": {"shape": "sphere", "radius": 1.0},
    "ellipsoid": {"shape": "sphere", "radius": 1.0, "transform": {"scale": [1.0, 0.6, 1.5]}},
    "torus": {"shape": "torus", "major": 1.0, "minor": 0.35},
    "cylinder": {"shape": "cylinder", "radius": 1.0, "height": 2.0, "caps": False},
}


def surface_scene(name: str):
    import reflets

    return reflets.load_dict(
        {
            "camera": {"position": [0, 0, 5], "look_at": [0, 0, 0]},
            "materials": {"m": {"type": "mirror"}},
            "mesh": [{**SURFACE_MESHES[name], "material": "m", "reflector": True}],
        }
    )


def convergence(pairs: int) -> dict:
    """Fraction converged vs iterations for each surface and solver (NumPy), and the GPU's at 4 / 5 / 8."""
    from ..gpu import get_context
    from ..reflections import Cylinder, Ellipsoid, Sphere, Torus, random_valid_pairs, solve_document, solve_robust
    from ..reflections.technique import Fermat

    surfaces = {
        "sphere": Sphere(),
        "ellipsoid": Ellipsoid(radii=(1.0, 0.6, 1.5)),
        "torus": Torus(major=1.0, minor=0.35),
        "cylinder": Cylinder(radius=1.0, height=2.0),
    }
    solvers = {
        "robust": (solve_robust, {}),
        "document": (solve_document, {}),
        "document, local chart": (solve_document, {"local_chart": True, "singular": "least_squares"}),
    }
    out = {}
    for name, surface in surfaces.items():
        E, V = random_valid_pairs(surface, pairs if name == "sphere" else pairs // 2, 7)
        rates = {}
        for label, (fn, kw) in solvers.items():
            history = fn(surface, E, V, iterations=ITERATIONS[-1], history=True, **kw).history
            rates[label] = [float(np.mean(history[:, k] < 1e-5)) for k in ITERATIONS]
        gpu = {}
        scene = surface_scene(name)
        for solver in SOLVERS:
            gpu[solver] = {}
            for k in (4, 5, 8):
                technique = Fermat(get_context(), solver=solver, iterations=k)
                technique.prepare(scene)
                result = technique.reflection_points(V, E)
                technique.release()
                gpu[solver][k] = float(np.mean(result["residual"] < 1e-4))
        out[name] = {"pairs": len(E), "numpy": rates, "gpu": gpu}
    return out


def _frame_ms(technique, size, frames: int) -> float:
    with technique.timer.measuring() as timer:
        for _ in range(frames):
            technique.render(size=size)
    return statistics.median(timer.frame_times())


def scene_rows(size, frames: int, ref_spp: int) -> list[dict]:
    """Cost and error of every solver × subdivision on both scenes (and forward for scale)."""
    import reflets

    from ..gpu import get_context
    from ..metrics import flip, relmse
    from ..techniques import get_technique

    ctx = get_context()
    rows = []
    for name in SCENES:
        scene = _scene(name)
        ref = reflets.reference(scene, spp=ref_spp, size=size, visibility=False, progress=False).image
        forward = get_technique("forward")(ctx)
        forward.prepare(scene)
        forward.render(size=size)
        forward_ms = _frame_ms(forward, size, frames)
        forward.release()
        for solver in SOLVERS:
            for subdivide in SUBDIVISIONS:
                technique = get_technique("fermat")(ctx, solver=solver, subdivide=subdivide)
                technique.prepare(scene)
                image = technique.render(size=size)  # compile, warm up
                ms = _frame_ms(technique, size, frames)
                vertices = np.concatenate([data.positions for data, _ in technique._reflected_meshes])
                result = technique.reflection_points(vertices)
                technique.release()
                rows.append(
                    {
                        "scene": name,
                        "solver": solver,
                        "subdivide": subdivide,
                        "subdivisions": list(technique.subdivisions),
                        "reflected_vertices": int(len(vertices)),
                        "frame_ms": ms,
                        "forward_ms": forward_ms,
                        "vertices_per_second": len(vertices) / (ms * 1e-3),
                        "converged": float(np.mean(result["residual"] < 1e-4)),
                        "relmse": relmse(image, ref),
                        "flip": flip(image, ref),
                    }
                )
    return rows


def edge_deviation(size=(1024, 768), samples: int = 2000) -> list[dict]:
    """Max screen distance between the rasterised reflection of a straight floor line (GPU reflection points of
    its k + 1 vertices joined by straight segments) and its exact reflection."""
    from ..gpu import get_context
    from ..reflections import Sphere, sphere_reflection
    from ..reflections.technique import Fermat
    from ..scene.camera import project

    scene = _scene("teapot + sphere")
    sphere = scene.mesh[0]
    centre, radius = np.asarray(sphere.transform.translate, dtype=np.float64), sphere.radius
    E = np.asarray(scene.camera.position, dtype=np.float64)
    a, b = np.array([-3.0, 0.0, 1.0]), np.array([3.0, 0.0, 1.0])  # a straight line on the floor
    t = np.linspace(0.0, 1.0, samples)
    dense = a + t[:, None] * (b - a)
    exact = sphere_reflection(Sphere(centre, radius), E, dense)
    normal = (exact - centre) / radius
    seen = (np.sum(normal * (E - exact), 1) > 0) & (np.sum(normal * (dense - exact), 1) > 0)
    truth = project(scene.camera, exact[seen], size)
    technique = Fermat(get_context())
    technique.prepare(scene)
    rows = []
    for k in EDGE_SEGMENTS:
        vertices = a + (np.arange(k + 1) / k)[:, None] * (b - a)
        points = project(scene.camera, technique.reflection_points(vertices)["position"], size)
        distance = np.full(len(truth), np.inf)
        for p, q in zip(points[:-1], points[1:], strict=True):
            d = q - p
            s = np.clip(((truth - p) @ d) / max(d @ d, 1e-30), 0.0, 1.0)
            distance = np.minimum(distance, np.linalg.norm(truth - (p + s[:, None] * d), axis=1))
        rows.append({"segments": k, "max_px": float(distance.max()), "mean_px": float(distance.mean())})
    technique.release()
    return rows


def bench_reflections(quick: bool, out_dir: Path) -> tuple[dict, str]:
    size = (200, 150) if quick else (400, 300)
    results = {
        "convergence": convergence(1000 if quick else 10000),
        "scenes": scene_rows(size, 3 if quick else 10, 4 if quick else 16),
        "edges": edge_deviation(),
        "size": list(size),
    }
    plot_convergence(results["convergence"], out_dir / "reflections_convergence.png")
    plot_error_time(results["scenes"], out_dir / "reflections.png")
    return results, markdown(results)


def markdown(results: dict) -> str:
    lines = ["# Fermat reflections", "", "## Solver convergence", ""]
    lines.append(
        "Fraction of seeded random eye / vertex pairs with a valid reflection whose law-of-reflection residual "
        "is below 1e-5 (NumPy, float64) after k iterations; GPU (float32, residual < 1e-4) at 4 / 5 / 8."
    )
    lines.append("")
    lines.append("| surface | pairs | solver | k = 1 | 2 | 3 | 4 | 5 | 8 | 10 | GPU 4 / 5 / 8 |")
    lines.append("|---|---|---|---|---|---|---|---|---|---|---|")
    for name, c in results["convergence"].items():
        for label, rates in c["numpy"].items():
            gpu = c["gpu"].get(label)
            gpu_text = " / ".join(f"{gpu[k]:.4f}" for k in (4, 5, 8)) if gpu else ""
            picked = [rates[k - 1] for k in (1, 2, 3, 4, 5, 8, 10)]
            cells = " | ".join(f"{r:.4f}" for r in picked)
            lines.append(f"| {name} | {c['pairs']} | {label} | {cells} | {gpu_text} |")
    size = results["size"]
    lines += [
        "",
        f"## Scenes ({size[0]}×{size[1]})",
        "",
        "Median frame time (draw only; finish() + wall clock on llvmpipe), the forward pass of the same scene "
        "for scale, reflected vertices per frame (after subdivision) and per second, fraction of them whose "
        "solution converged, and the image error against the ray-traced reference.",
        "",
        "| scene | solver | subdivide (k per mesh) | ms / frame | forward ms | vertices | vertices / s | converged | "
        "relative MSE | FLIP |",
        "|---|---|---|---|---|---|---|---|---|---|",
    ]
    for r in results["scenes"]:
        ks = ",".join(str(k) for k in r["subdivisions"])
        lines.append(
            f"| {r['scene']} | {r['solver']} | {r['subdivide']} ({ks}) | {r['frame_ms']:.1f} | {r['forward_ms']:.1f} | "
            f"{r['reflected_vertices']} | {r['vertices_per_second']:.3g} | {r['converged']:.4f} | "
            f"{r['relmse']:.2e} | {r['flip']:.4f} |"
        )
    lines += [
        "",
        "![error vs time](reflections.png) ![convergence](reflections_convergence.png)",
        "",
        "## Curved reflected edges",
        "",
        "A straight floor line (x ∈ [−3, 3], z = 1) of the teapot scene reflected in the sphere, split into k "
        "segments: distance between the rasterised reflection (straight screen segments between the GPU "
        "reflection points) and the exact reflection of 2,000 points of the line, in pixels at 1024×768.",
        "",
        "| segments | max px | mean px |",
        "|---|---|---|",
    ]
    lines += [f"| {r['segments']} | {r['max_px']:.2f} | {r['mean_px']:.3f} |" for r in results["edges"]]
    return "\n".join(lines + [""])


def plot_convergence(conv: dict, path: Path) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, axes = plt.subplots(1, len(conv), figsize=(4.0 * len(conv), 3.4), squeeze=False)
    for ax, (name, c) in zip(axes.ravel(), conv.items(), strict=True):
        for label, rates in c["numpy"].items():
            ax.plot(ITERATIONS, [1.0 - r + 1e-5 for r in rates], marker="o", label=label)
        ax.set_yscale("log")
        ax.set_title(f"{name} ({c['pairs']} pairs)")
        ax.set_xlabel("iterations")
        ax.set_ylabel("fraction not converged (+1e-5)")
        ax.grid(True, which="both", alpha=0.3)
    axes.ravel()[0].legend(fontsize=7)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)


def plot_error_time(rows: list[dict], path: Path) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    scenes = list(dict.fromkeys(r["scene"] for r in rows))
    fig, axes = plt.subplots(1, len(scenes), figsize=(4.6 * len(scenes), 3.6), squeeze=False)
    for ax, name in zip(axes.ravel(), scenes, strict=True):
        for solver in SOLVERS:
            mine = [r for r in rows if r["scene"] == name and r["solver"] == solver]
            pts = [(r["frame_ms"], r["relmse"], str(r["subdivide"])) for r in mine]
            ax.plot([p[0] for p in pts], [p[1] for p in pts], marker="o", label=solver)
            for x, y, k in pts:
                ax.annotate(k, (x, y), fontsize=7)
        ax.set_xscale("log")
        ax.set_yscale("log")
        ax.set_title(name)
        ax.set_xlabel("ms per frame")
        ax.set_ylabel("relative MSE vs ray-traced")
        ax.grid(True, which="both", alpha=0.3)
    axes.ravel()[0].legend(fontsize=7)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)
