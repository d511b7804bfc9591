"""`reflets demo`: render the built-in scenes with every technique that applies, into an HTML gallery.

Each entry writes ``NAME.exr`` (linear HDR) and ``NAME.png`` (sRGB), times the technique (``prepare`` once,
then the median of a few frames: GPU timer queries on a real GPU, ``finish()`` + wall clock on llvmpipe),
and, where the scene has a closed-form solution, prints the largest relative error against it.
"""

from __future__ import annotations

import html
import json
import platform
import time
from dataclasses import asdict, dataclass
from importlib import resources
from pathlib import Path

from .errors import OutputError
from .gpu import get_context, gl_info
from .imageio import write_image
from .scene import load_scene
from .techniques import get_technique
from .validation import NotAnalytic, analytic_image, max_relative_error

FRAMES = 3

#: (scene file in reflets/data/scenes, methods shown for it); later techniques add their scenes here
DEMO: list[tuple[str, tuple[str, ...]]] = [
    ("01_plane_point.toml", ("forward",)),
    ("02_sphere_directional.toml", ("forward",)),
    ("03_shapes.toml", ("forward",)),
    ("04_bunny_arealight.toml", ("forward",)),
    ("05_environment.toml", ("forward",)),
]


@dataclass
class DemoResult:
    name: str
    title: str
    method: str
    size: str
    prepare_ms: float
    frame_ms: float
    timer: str
    analytic_max_rel_error: float | None
    exr: str
    png: str


def scene_path(name: str) -> Path:
    return Path(str(resources.files("reflets") / "data" / "scenes" / name))


def run_demo(out_dir: Path, size: tuple[int, int] | None = None) -> list[DemoResult]:
    """Render every demo entry into ``out_dir`` (created if missing) and write index.html + results.json."""
    from rich.console import Console
    from rich.progress import BarColumn, Progress, TextColumn, TimeElapsedColumn

    try:
        out_dir.mkdir(parents=True, exist_ok=True)
    except OSError as exc:
        raise OutputError(f"cannot create the output folder ({exc.strerror})", file=out_dir) from None
    console = Console(stderr=True)
    ctx = get_context()
    jobs = [(name, method) for name, methods in DEMO for method in methods]
    results: list[DemoResult] = []
    with Progress(
        TextColumn("{task.description}"),
        BarColumn(),
        TextColumn("{task.completed}/{task.total}"),
        TimeElapsedColumn(),
        console=console,
        transient=True,
    ) as progress:
        task = progress.add_task("demo", total=len(jobs))
        for name, method in jobs:
            progress.update(task, description=f"{name} · {method}")
            results.append(_render_entry(ctx, name, method, size, out_dir))
            progress.advance(task)
    info = gl_info()
    _write_gallery(out_dir, results, info)
    (out_dir / "results.json").write_text(
        json.dumps({"opengl": info, "results": [asdict(r) for r in results]}, indent=2)
    )
    _print_summary(results, info, out_dir)
    return results


def _render_entry(ctx, name: str, method: str, size, out_dir: Path) -> DemoResult:
    scene = load_scene(scene_path(name))
    technique = get_technique(method)(ctx)
    start = time.perf_counter()
    technique.prepare(scene)
    prepare_ms = (time.perf_counter() - start) * 1e3
    for _ in range(FRAMES):
        image = technique.render(size=size)
    timing = technique.timer.summary()
    technique.release()
    gpu = timing["gpu_ms_median"]
    stem = f"{Path(name).stem}.{method}"
    write_image(out_dir / f"{stem}.exr", image)
    write_image(out_dir / f"{stem}.png", image)
    try:
        exact, mask = analytic_image(scene, size)
        error = max_relative_error(image, exact, mask)
    except NotAnalytic:
        error = None
    h, w = image.shape[:2]
    return DemoResult(
        name=Path(name).stem,
        title=scene.title or Path(name).stem,
        method=method,
        size=f"{w}x{h}",
        prepare_ms=prepare_ms,
        frame_ms=gpu if gpu is not None else timing["wall_ms_median"],
        timer="GPU query" if gpu is not None else "wall clock (finish)",
        analytic_max_rel_error=error,
        exr=f"{stem}.exr",
        png=f"{stem}.png",
    )


def _print_summary(results: list[DemoResult], info: dict, out_dir: Path) -> None:
    from rich.console import Console
    from rich.table import Table

    table = Table(title=f"reflets demo — {info['renderer']}")
    for col in ("scene", "method", "size", "prepare ms", "frame ms (median)", "max rel. error vs exact"):
        table.add_column(col, justify="right" if "ms" in col or "error" in col else "left")
    for r in results:
        err = "—" if r.analytic_max_rel_error is None else f"{r.analytic_max_rel_error:.2e}"
        table.add_row(r.name, r.method, r.size, f"{r.prepare_ms:.0f}", f"{r.frame_ms:.1f}", err)
    console = Console(width=max(110, Console().width))
    console.print(table)
    console.print(f"gallery: {out_dir / 'index.html'}")


def _write_gallery(out_dir: Path, results: list[DemoResult], info: dict) -> None:
    cards = []
    for r in results:
        err = (
            ""
            if r.analytic_max_rel_error is None
            else f"<br>max relative error vs closed form: {r.analytic_max_rel_error:.2e}"
        )
        cards.append(
            f'<figure><a href="{html.escape(r.exr)}"><img src="{html.escape(r.png)}" alt="{html.escape(r.title)}">'
            f"</a><figcaption><b>{html.escape(r.title)}</b><br>method <code>{html.escape(r.method)}</code>, "
            f"{r.size}<br>prepare {r.prepare_ms:.0f} ms, frame {r.frame_ms:.1f} ms ({html.escape(r.timer)}, median "
            f"of {FRAMES}){err}</figcaption></figure>"
        )
    page = f"""<!doctype html>
<html lang="en"><head><meta charset="utf-8"><title>reflets demo</title>
<style>
body {{ font-family: system-ui, sans-serif; margin: 2em; background: #111; color: #ddd; }}
main {{ display: grid; grid-template-columns: repeat(auto-fill, minmax(420px, 1fr)); gap: 1.5em; }}
figure {{ margin: 0; background: #1c1c1c; padding: 0.8em; border-radius: 6px; }}
img {{ width: 100%; image-rendering: pixelated; }} code {{ color: #9cf; }} a {{ color: #9cf; }}
</style></head><body>
<h1>reflets demo</h1>
<p>OpenGL: {html.escape(info["renderer"])} — {html.escape(info["version"])}; Python {platform.python_version()};
{time.strftime("%Y-%m-%d %H:%M")}. Click an image for its linear EXR. Frame times on a software rasteriser
(llvmpipe) are CPU times, not GPU times.</p>
<main>
{chr(10).join(cards)}
</main></body></html>
"""
    (out_dir / "index.html").write_text(page, encoding="utf-8")
