"""`reflets demo`: render the built-in scenes with every technique that applies, into an HTML gallery.

Each entry writes ``NAME.exr`` (linear HDR) and ``NAME.png`` (sRGB), times the technique (``prepare`` once,
then the median of a few frames: GPU timer queries on a real GPU, ``finish()`` + wall clock on llvmpipe),
and, where the scene has a closed-form solution, prints the largest relative error against it.
"""

from __future__ import annotations

import html
import platform
import statistics
import time
from dataclasses import asdict, dataclass
from importlib import resources
from pathlib import Path

from . import jsonio
from .errors import OutputError
from .gpu import get_context, gl_info
from .imageio import write_image
from .scene import load_scene
from .techniques import get_technique
from .validation import NotAnalytic, analytic_image, max_relative_error

FRAMES = 3

REFERENCE_SPP = 32


@dataclass(frozen=True)
class Method:
    """A technique as shown in the demo: its name, parameters and samples per pixel."""

    name: str
    params: tuple[tuple[str, object], ...] = ()
    spp: int = 1

    @property
    def label(self) -> str:
        extra = ",".join([f"{k}={v}" for k, v in self.params] + ([f"spp={self.spp}"] if self.spp > 1 else []))
        return self.name + (f"[{extra}]" if extra else "")


@dataclass(frozen=True)
class DemoEntry:
    """A built-in scene (file in reflets/data/scenes), the methods shown for it, and whether the gallery also
    shows the NumPy Monte Carlo reference next to them (with error metrics; shadows traced, as the GPU maps
    them)."""

    scene: str
    methods: tuple[Method, ...] = (Method("forward"),)
    reference: bool = False
    reference_spp: int = REFERENCE_SPP  # 1 where every light is a delta light (the reference is then exact)
    #: "box" beside a supersampled method (its pixels are box means: textures, edges); refined to this relative
    #: standard error where the reference's pixels stay noisy (near-mirror texels; see reflets.reference)
    pixel: str = "center"
    adaptive_error: float | None = None


AREA_METHODS = (
    Method("brute", (("grid", 8),)),
    Method("adaptive"),
    Method("biased"),
    Method("mc", (("strategy", "mis"),), spp=64),
    Method("analytic"),
    Method("ltc"),
)


#: later techniques add their scenes here
DEMO: list[DemoEntry] = [
    DemoEntry("60_showcase.toml", (Method("auto", spp=32),), reference=True),
    DemoEntry("01_plane_point.toml"),
    DemoEntry("02_sphere_directional.toml"),
    DemoEntry("03_shapes.toml"),
    DemoEntry("04_bunny_arealight.toml"),
    DemoEntry("05_environment.toml"),
    DemoEntry("06_materials.toml"),
    DemoEntry("10_ref_plane_quad.toml", reference=True),
    DemoEntry("11_ref_ggx_sphere_quad.toml", reference=True),
    DemoEntry("12_ref_sphere_env.toml", reference=True),
    DemoEntry("20_arealight_phong.toml", AREA_METHODS, reference=True),
    DemoEntry("21_arealight_ggx.toml", AREA_METHODS, reference=True),
    DemoEntry(
        "30_translucent_slab.toml",
        (Method("translucent"), Method("translucent", (("ms_quadrature", "bilinear"),)), Method("forward")),
    ),
    DemoEntry("31_translucent_bunny.toml", (Method("translucent"), Method("forward"))),
    DemoEntry("32_translucent_dragon.toml", (Method("translucent"),)),
    DemoEntry("33_translucent_spheres.toml", (Method("translucent"),)),
    DemoEntry(
        "40_reflect_teapot_sphere.toml",
        (Method("fermat"), Method("fermat", (("subdivide", 1),)), Method("fermat", (("solver", "document"),))),
        reference=True,
        reference_spp=1,
    ),
    DemoEntry("42_reflect_bezier.toml", (Method("fermat"),), reference=True, reference_spp=1),
    DemoEntry("41_reflect_room.toml", (Method("fermat"), Method("forward")), reference=True, reference_spp=8),
    DemoEntry("50_brushed_plate.toml", (Method("scratches", spp=128), Method("forward"))),
    DemoEntry("51_scratched_plate.toml", (Method("scratches", spp=64), Method("forward"))),
    DemoEntry("52_scratched_teapot.toml", (Method("scratches", spp=64), Method("forward"))),
    DemoEntry("53_spun_plate.toml", reference=True, reference_spp=1),  # a point light: the reference is exact
    DemoEntry("54_spun_plate_bent.toml", reference=True, reference_spp=1),
    # real assets as authored (Khronos glTF samples shipped in data/assets), beside their reference; under quad
    # lights a textured material takes forward's midpoint rule, each sample's lobe widened by its patch
    DemoEntry("70_helmet_area.toml", (Method("auto", spp=16),), reference=True, pixel="box", adaptive_error=0.05),
    DemoEntry("71_helmet_environment.toml", (Method("auto", spp=16),), reference=True, pixel="box",
              adaptive_error=0.05),  # fmt: skip
    DemoEntry("72_bottle_environment.toml", (Method("auto", spp=16),), reference=True, pixel="box",
              adaptive_error=0.05),  # fmt: skip
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
    reference: dict | None = None  # metrics vs the NumPy reference, its image and timing
    description: str = ""  # the scene file's description (what to look at, what the reference can render)
    view: str = ""  # the command that opens this scene and method in the interactive viewer


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
    jobs = [(entry, method) for entry in DEMO for method in entry.methods]
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
        references = {}
        for entry, method in jobs:
            progress.update(task, description=f"{entry.scene} · {method.label}")
            result = _render_entry(ctx, entry.scene, method, size, out_dir)
            if entry.reference:
                if entry.scene not in references:
                    progress.update(task, description=f"{entry.scene} · NumPy reference, {entry.reference_spp} spp")
                    references[entry.scene] = _reference_image(entry, size, out_dir)
                result.reference = _compare_with_reference(result, references[entry.scene], out_dir)
            results.append(result)
            progress.advance(task)
        progress.update(task, description="augmented reality: capture, composite, ground truth (Mitsuba 3)")
        augmented = _ar_entry(out_dir)
    info = gl_info()
    _write_gallery(out_dir, results, info, augmented)
    jsonio.write(
        out_dir / "results.json",
        {"opengl": info, "results": [asdict(r) for r in results], "augmented_reality": augmented},
        indent=2,
    )
    _print_summary(results, info, out_dir)
    return results


def _render_entry(ctx, name: str, method: Method, size, out_dir: Path) -> DemoResult:
    scene = load_scene(scene_path(name))
    technique = get_technique(method.name)(ctx, **dict(method.params))
    start = time.perf_counter()
    technique.prepare(scene)
    prepare_ms = (time.perf_counter() - start) * 1e3
    image_ms = []
    for _ in range(FRAMES):  # a whole image: all frames of a progressive method, draw only
        with technique.timer.measuring() as timer:
            image = technique.render(size=size, spp=method.spp)
        image_ms.append((sum(timer.gpu_ms), sum(timer.wall_ms)))
    gpu_used = bool(technique.timer.gpu_ms)
    technique.release()
    stem = f"{Path(name).stem}.{method.name}"
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
        description=scene.description or "",
        method=method.label,
        size=f"{w}x{h}",
        prepare_ms=prepare_ms,
        frame_ms=statistics.median(t[0] if gpu_used else t[1] for t in image_ms),
        timer="GPU query" if gpu_used else "wall clock (finish)",
        analytic_max_rel_error=error,
        exr=f"{stem}.exr",
        png=f"{stem}.png",
        view=" ".join(
            [f"reflets view {scene_path(name)} --method {method.name}"] + [f"--param {k}={v}" for k, v in method.params]
        ),
    )


def _reference_image(entry: DemoEntry, size, out_dir: Path):
    """The NumPy Monte Carlo reference of a demo scene (rendered once, shared by its methods)."""
    from .reference import reference

    scene = load_scene(scene_path(entry.scene))
    ref = reference(scene, spp=entry.reference_spp, size=size, progress=False, pixel=entry.pixel,
                    adaptive_error=entry.adaptive_error)  # fmt: skip
    stem = f"{Path(entry.scene).stem}.reference"
    write_image(out_dir / f"{stem}.exr", ref.image)
    write_image(out_dir / f"{stem}.stderr.exr", ref.stderr)
    write_image(out_dir / f"{stem}.png", ref.image)
    return ref, f"{stem}.png"


def _compare_with_reference(result: DemoResult, reference, out_dir: Path) -> dict:
    from .imageio import read_image, write_png8
    from .metrics import compare, difference_image, zscores

    ref, ref_png = reference
    image = read_image(out_dir / result.exr)
    stem = Path(result.exr).stem
    write_png8(out_dir / f"{stem}.diff.png", difference_image(image, ref.image))
    return {
        **compare(image, ref.image),
        **zscores(image, ref.image, ref.stderr),
        "spp": ref.spp,
        "seconds": ref.seconds,
        "png": ref_png,
        "diff": f"{stem}.diff.png",
    }


def _print_summary(results: list[DemoResult], info: dict, out_dir: Path) -> None:
    from rich.console import Console
    from rich.markup import escape  # method labels such as brute[grid=8] are not markup
    from rich.table import Table

    table = Table(title=f"reflets demo — {info['renderer']}")
    for col in (
        "scene",
        "method",
        "size",
        "prepare ms",
        "frame ms (median)",
        "max rel. error vs exact",
        "relMSE vs reference",
        "within 3σ of reference",
    ):
        table.add_column(
            col,
            justify="left" if col in ("scene", "method", "size") else "right",
            overflow="fold",
            min_width=24 if col == "method" else None,
        )
    for r in results:
        err = "—" if r.analytic_max_rel_error is None else f"{r.analytic_max_rel_error:.2e}"
        ref = r.reference or {}
        rel = f"{ref['relmse']:.2e}" if ref else "—"
        within = f"{100 * ref['within_3_stderr']:.1f} %" if ref and _has_z(ref) else "—"
        table.add_row(r.name, escape(r.method), r.size, f"{r.prepare_ms:.0f}", f"{r.frame_ms:.1f}", err, rel, within)
    console = Console(width=max(190, Console().width))
    console.print(table)
    console.print(f"gallery: {out_dir / 'index.html'}")


def _has_z(ref: dict) -> bool:
    """False for a reference without Monte Carlo noise (delta lights only): its z-scores are NaN."""
    return ref["within_3_stderr"] == ref["within_3_stderr"]


def _ar_entry(out_dir: Path) -> dict | str:
    """The augmented-reality entry (``ar.showcase.gallery``), or why it is missing (the ``ar`` extra and
    Mitsuba 3, which renders the photographs and the ground truth)."""
    try:
        import cv2  # noqa: F401
        import mitsuba  # noqa: F401
    except ImportError as exc:
        return f"augmented reality not shown: {exc.name} is missing (pip install 'reflets[ar,reference]')"
    from .ar.showcase import gallery

    return gallery(out_dir)


def _ar_card(entry: dict | str) -> str:
    if isinstance(entry, str):
        return f"<figure><figcaption>{html.escape(entry)}</figcaption></figure>"
    images = "".join(
        f'<figure class="sub"><img src="{html.escape(name)}" alt="{html.escape(label)}"><figcaption><small>'
        f"{html.escape(label)}</small></figcaption></figure>"
        for label, name in entry["images"].items()
    )
    errors = "; ".join(
        f"{mode}: relMSE {e['object_relmse']:.2e} over the objects, {e['shadow_relmse']:.2e} over their shadow"
        for mode, e in entry["errors"].items()
    )
    return (
        '<figure style="grid-column: 1 / -1"><figcaption><b>Augmented reality (004)</b><br><small>Generated data '
        "(no real photographs offline): the marker board on a floor under the sky map, path traced by Mitsuba 3. "
        f"Environment captured by a device's front camera over {entry['frames']} poses ({entry['captured']} tracked,"
        " each with a bracketed short exposure); the photograph's pose tracked "
        f"{entry['pose_mm']:.1f} mm off; the objects composited by differential rendering (reflets' IBL) and by the "
        f"document's lighting, beside the ground truth (the objects really in the world). {errors}. "
        "Measurements: <code>reflets bench ar</code>.</small></figcaption>"
        f'<div class="ar">{images}</div></figure>'
    )


def _write_gallery(out_dir: Path, results: list[DemoResult], info: dict, augmented: dict | str = "") -> None:
    cards = []
    for r in results:
        err = (
            ""
            if r.analytic_max_rel_error is None
            else f"<br>max relative error vs closed form: {r.analytic_max_rel_error:.2e}"
        )
        ref = r.reference
        if ref:
            z_text = (
                f", mean |z| {ref['mean_abs_z']:.2f}, {100 * ref['within_3_stderr']:.1f} % within 3σ"
                if _has_z(ref)
                else " (a noise-free reference: no z-scores)"
            )
            err += (
                f"<br>vs NumPy reference ({ref['spp']} spp, {ref['seconds']:.1f} s): relMSE {ref['relmse']:.2e}, "
                f"FLIP {ref['flip']:.3f}"
                f"{z_text}"
                f'<div class="pair"><img src="{html.escape(ref["png"])}" alt="reference">'
                f'<img src="{html.escape(ref["diff"])}" alt="difference"></div>'
                "<small>reference (left) and relative difference (right, magma)</small>"
            )
        cards.append(
            f'<figure><a href="{html.escape(r.exr)}"><img src="{html.escape(r.png)}" alt="{html.escape(r.title)}">'
            f"</a><figcaption><b>{html.escape(r.title)}</b>"
            + (f"<br><small>{html.escape(r.description)}</small>" if r.description else "")
            + f"<br>method <code>{html.escape(r.method)}</code>, "
            f"{r.size}<br>prepare {r.prepare_ms:.0f} ms, frame {r.frame_ms:.1f} ms ({html.escape(r.timer)}, median "
            f"of {FRAMES}){err}"
            + (f"<br><small>interactive: <code>{html.escape(r.view)}</code></small>" if r.view else "")
            + "</figcaption></figure>"
        )
    page = f"""<!doctype html>
<html lang="en"><head><meta charset="utf-8"><title>reflets demo</title>
<style>
body {{ font-family: system-ui, sans-serif; margin: 2em; background: #111; color: #ddd; }}
main {{ display: grid; grid-template-columns: repeat(auto-fill, minmax(420px, 1fr)); gap: 1.5em; }}
figure {{ margin: 0; background: #1c1c1c; padding: 0.8em; border-radius: 6px; }}
img {{ width: 100%; image-rendering: pixelated; }} .pair {{ display: flex; gap: 0.4em; margin-top: 0.4em; }}
.pair img {{ width: 50%; }} code {{ color: #9cf; }} a {{ color: #9cf; }}
.ar {{ display: grid; grid-template-columns: repeat(3, 1fr); gap: 0.5em; }} .sub {{ padding: 0; }}
</style></head><body>
<h1>reflets demo</h1>
<p>OpenGL: {html.escape(info["renderer"])} — {html.escape(info["version"])}; Python {platform.python_version()};
{time.strftime("%Y-%m-%d %H:%M")}. Click an image for its linear EXR. Frame times on a software rasteriser
(llvmpipe) are CPU times, not GPU times.</p>
<main>
{chr(10).join(cards)}
{_ar_card(augmented) if augmented else ""}
</main></body></html>
"""
    (out_dir / "index.html").write_text(page, encoding="utf-8")
