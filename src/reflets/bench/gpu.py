"""`reflets bench gpu`: real-time frames at 1280 × 720 and 1920 × 1080 — meant for a machine with a GPU, and run on
llvmpipe for its ratios.

Scenes: the showcase (every technique on), the DamagedHelmet (its glTF materials and textures, the studio map and
a point light, as `reflets bench assets` lights it), a GGX sphere on a floor under 1 and 16 point lights and under
1 and 4 quad lights (ltc), 100 sphere instances — each through one persistent ``Renderer``:

- **orbit**: the camera moves every frame (``set_camera`` then ``render_texture``): the frame when only the camera
  changes (the shadow maps, the translucent light views and the prefiltered map are kept; the cascades and the
  Fermat solve follow the camera);
- **still**: nothing changes (``render_texture`` alone): a progressive method adds new samples on the passes that
  change, the others kept from the first frame of the view;
- **orbit + read-back**: ``render()`` (the frame and one float32 read-back).

Frame time: the wall clock of each frame from its start to the GPU's finish (``Renderer.finish()``, outside
the renderer: a frame itself never waits), median and p95. ``cpu_ms`` is the
frame's passes submitted, ``image_ms`` its image formed (a progressive frame added to the sum; on llvmpipe that
read waits for the frame's fragments), ``gpu_ms`` per pass from timer queries (a real GPU's; none on llvmpipe).

The AR loop (``ar.composite.Compositor``, differential mode, the sky as a still light probe, 12 poses orbiting the
board) runs at the same sizes when the ``ar`` extra is installed: its wall clock per frame (it returns an array:
there is no frame without read-back).
"""

from __future__ import annotations

import json
import statistics
import subprocess
import sys
import time
import warnings

import numpy as np

from .. import jsonio
from ..diagnostics import RefletsWarning
from ..gpu.context import is_software

SIZES = ((1280, 720), (1920, 1080))
#: seconds a scene's subprocess may take (llvmpipe's 1080p showcase: about 40)
SCENE_TIMEOUT_S = 600
#: the showcase where a frame's submission shows (the issue's bound on llvmpipe: cpu_ms ≤ 5 ms)
SMALL = (64, 48)
#: frames per mode: a GPU's figures need many; llvmpipe's 1080p showcase frame takes seconds
FRAMES = {"gpu": 60, "software": 3, "quick": 2}


def _cases() -> list[tuple[str, object]]:
    """(label, a function size → scene) per scene of the benchmark."""
    from ..scene import load_dict
    from .assets import ASSET_FILES, _timing_scene
    from .renderer import _scaling_scene, showcase_scene

    return [
        ("showcase", lambda size: showcase_scene(size)),
        ("DamagedHelmet", lambda size: _timing_scene(ASSET_FILES["DamagedHelmet"], size)),
        ("1 point light", lambda size: load_dict(_scaling_scene(size, points=1))),
        ("16 point lights", lambda size: load_dict(_scaling_scene(size, points=16))),
        ("1 quad light", lambda size: load_dict(_scaling_scene(size, points=0, quads=1))),
        ("4 quad lights", lambda size: load_dict(_scaling_scene(size, points=0, quads=4))),
        ("100 instances", lambda size: load_dict(_scaling_scene(size, instances=100))),
    ]


def _orbit(camera, frames: int) -> list[tuple[float, float, float]]:
    eye, target = np.asarray(camera.position, float), np.asarray(camera.look_at, float)
    offset = eye - target
    radius, start = float(np.hypot(offset[0], offset[2])), float(np.arctan2(offset[0], offset[2]))
    return [(float(target[0] + radius * np.sin(a)), float(eye[1]), float(target[2] + radius * np.cos(a)))
            for a in start + np.linspace(-0.3, 0.3, frames)]  # fmt: skip


def _loop(renderer, frames: int, mode: str, positions) -> dict:
    """Each frame from its start to the GPU's finish (nothing of the next frame overlaps it); the GPU's timer
    queries of exactly these frames (``measuring``: read at the end)."""
    times, cpu, image = [], [], []
    with renderer._technique.timer.measuring() as timer:
        for k in range(frames):
            start = time.perf_counter()
            if mode != "still":
                renderer.set_camera(position=positions[k])
            if mode == "orbit + read-back":
                renderer.render()
            else:
                renderer.render_texture()
            renderer.finish()
            times.append(1e3 * (time.perf_counter() - start))
            cpu.append(renderer.stats["cpu_ms"])
            image.append(renderer.stats["image_ms"])
    passes: dict[str, list[float]] = {}
    for frame in timer.pass_history:
        for name, ms in frame.items():
            passes.setdefault(name, []).append(ms)
    return {
        "mode": mode,
        "frames": frames,
        "frame_ms_median": statistics.median(times),
        "frame_ms_p95": float(np.percentile(times, 95)),
        "cpu_ms_median": statistics.median(cpu),
        "image_ms_median": statistics.median(image),
        "gpu_ms_median": statistics.median(timer.gpu_ms) if timer.gpu_ms else None,
        "gpu_ms_passes": {name: statistics.median(ms) for name, ms in passes.items()},
    }


def _renderer_rows(frames: int, sizes, progress) -> list[dict]:
    """Each scene and size in a process of its own (a viewer's or a script's session: what one scene leaves in
    the driver — llvmpipe places its waits differently after other scenes — does not reach the next row)."""
    rows = []
    for label, _ in _cases():
        for size in sizes:
            progress(f"{label} {size[0]}×{size[1]}")
            job = json.dumps({"scene": label, "size": list(size), "frames": frames})
            done = subprocess.run([sys.executable, "-m", "reflets.bench.gpu", job], capture_output=True, text=True,
                                  timeout=SCENE_TIMEOUT_S)  # fmt: skip
            if done.returncode != 0:
                last = (done.stderr.strip().splitlines() or ["no message"])[-1]
                raise RuntimeError(f"bench gpu, {label} {size[0]}×{size[1]}: {last}")
            rows += json.loads(done.stdout.strip().splitlines()[-1])
    return rows


def _scene_rows(label: str, size: tuple[int, int], frames: int) -> list[dict]:
    """One scene's rows (the subprocess's work): prepare, then each mode's frames."""
    import reflets

    make = dict(_cases())[label]
    scene = make(size)
    started = time.perf_counter()
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", RefletsWarning)
        renderer = reflets.Renderer(scene, size=size)
    rows = []
    with renderer:
        renderer.render()  # compiles the programs, draws what does not depend on the camera
        prepare_ms = 1e3 * (time.perf_counter() - started)
        positions = _orbit(scene.camera, frames)
        for mode in ("orbit", "still", "orbit + read-back"):
            rows.append({"scene": label, "size": list(size), "prepare_ms": prepare_ms,
                         **_loop(renderer, frames, mode, positions)})  # fmt: skip
        if label == "showcase":
            rows[-1]["pass_costs"] = _pass_costs(renderer, positions[0])
    return rows


def _pass_costs(renderer, position) -> dict[str, list]:
    """Where a showcase frame's time goes, pass by pass: a ``finish()`` after each (the only clock llvmpipe has),
    in the first frame of a view (every pass whole) and in the next one (the changing parts alone)."""
    technique = renderer._technique
    technique.measure_passes = True
    costs = {}
    try:
        renderer.set_camera(position=position)
        for frame in ("new view", "same view"):
            renderer.render_texture()
            renderer.finish()
            costs[frame] = [[f"{k} {method}", meshes, ms]
                            for k, (method, meshes, ms) in enumerate(technique.pass_costs())]  # fmt: skip
    finally:
        technique.measure_passes = False
    return costs


def _small_showcase(frames: int) -> dict:
    """The showcase at 64 × 48, where the pixels cost little and a frame's submission shows: ``cpu_ms`` of
    frames from one view (the changing passes alone) and after a camera move, and ``image_ms`` (median)."""
    import reflets

    from .renderer import showcase_scene

    scene = showcase_scene(SMALL)
    positions = _orbit(scene.camera, frames)
    with reflets.Renderer(scene, size=SMALL) as renderer:
        renderer.render_texture()
        still = _loop(renderer, frames, "still", positions)
        orbit = _loop(renderer, frames, "orbit", positions)
        fermat = next(t for method, t in renderer._technique.passes if method == "fermat")
        reflected = [data for data, _ in fermat._reflected_meshes + fermat._reflected_emitters]
    return {"size": list(SMALL), "still": still, "orbit": orbit,
            "reflected_triangles": sum(data.n_triangles for data in reflected)}  # fmt: skip


def _ar_rows(frames: int, sizes, progress) -> tuple[list[dict], str | None]:
    try:
        from ..ar import capture
        from ..ar.camera import Intrinsics
        from ..ar.composite import Compositor
        from ..ar.showcase import OBJECTS, device_poses
        from ..ar.world import SKY
        from ..imageio import read_image
        from ..scene import load_dict
    except ImportError as exc:  # the 'ar' extra
        return [], f"the AR loop needs the 'ar' extra ({exc.name} is missing)"
    rows = []
    cube = capture.CubeMap.from_equirect(read_image(SKY), 128)
    poses = list(device_poses(max(frames, 2)))
    for size in sizes:
        progress(f"AR loop {size[0]}×{size[1]}")
        intrinsics = Intrinsics.from_fov(size, 50)
        photo = np.full((size[1], size[0], 3), 128, np.uint8)
        compositor = Compositor(load_dict(OBJECTS), "differential", samples=4000, directions=200)
        try:
            compositor(photo, intrinsics, *poses[0], cube)  # its first frame prepares
            times = []
            for R, t in poses[:frames]:
                start = time.perf_counter()
                compositor(photo, intrinsics, R, t, cube)
                times.append(1e3 * (time.perf_counter() - start))
        finally:
            compositor.release()
        rows.append({"scene": "AR loop (differential, still probe)", "size": list(size), "mode": "orbit + read-back",
                     "frames": len(times), "frame_ms_median": statistics.median(times),
                     "frame_ms_p95": float(np.percentile(times, 95))})  # fmt: skip
    return rows, None


def _fmt(value, digits: int = 1) -> str:
    return "–" if value is None or value != value else f"{value:.{digits}f}"  # None or NaN: not measured


def bench_gpu(quick: bool, out_dir) -> tuple[dict, str]:
    from ..gpu import get_context, gl_info

    software = is_software(get_context())
    frames = FRAMES["quick" if quick else "software" if software else "gpu"]
    sizes = SIZES[:1] if quick else SIZES
    started = time.perf_counter()

    def progress(what: str) -> None:
        print(f"[{time.perf_counter() - started:5.0f} s] {what}", flush=True)

    rows = _renderer_rows(frames, sizes, progress)
    progress(f"showcase {SMALL[0]}×{SMALL[1]}")
    small = _small_showcase(max(frames, 15))
    ar_rows, ar_missing = _ar_rows(frames, sizes, progress)
    device = gl_info()
    md = [
        "# Real-time frames (`reflets bench gpu`)",
        "",
        f"Device: {device['renderer']} ({device['vendor']}, OpenGL {device['version']}). "
        f"{frames} frames per mode; frame time from a frame's start to the GPU's finish (median, p95); "
        "`cpu_ms` the passes submitted, `image_ms` the image formed (llvmpipe waits there for the frame's "
        "fragments), `gpu_ms` the passes' timer queries (none on llvmpipe). "
        + ("On llvmpipe the frame times are this CPU's, not a GPU's: read the ratios between rows. " if software
           else "")  # fmt: skip
        + "Modes: orbit (the camera moves every frame), still (nothing changes), orbit + read-back (`render()`).",
        "",
        "| scene | size | mode | frame median (ms) | frame p95 (ms) | cpu_ms | image_ms | gpu_ms |",
        "|---|---|---|---|---|---|---|---|",
    ]
    for r in rows + ar_rows:
        md.append(f"| {r['scene']} | {r['size'][0]}×{r['size'][1]} | {r['mode']} | {_fmt(r['frame_ms_median'])} | "
                  f"{_fmt(r['frame_ms_p95'])} | {_fmt(r.get('cpu_ms_median'), 2)} | "
                  f"{_fmt(r.get('image_ms_median'), 2)} | {_fmt(r.get('gpu_ms_median'), 2)} |")  # fmt: skip
    md += ["", f"Showcase at {SMALL[0]}×{SMALL[1]} (median of {small['still']['frames']} frames): `cpu_ms` "
           f"{small['still']['cpu_ms_median']:.2f} from an unchanged view, {small['orbit']['cpu_ms_median']:.1f} "
           f"after a camera move (the Fermat solve and draw of {small['reflected_triangles']:,} reflected "
           f"triangles); `image_ms` {small['still']['image_ms_median']:.2f}."]  # fmt: skip
    if ar_missing:
        md += ["", f"AR loop not run: {ar_missing}."]
    for r in rows:
        if "pass_costs" in r:
            costs = r["pass_costs"]
            md += ["", f"Showcase {r['size'][0]}×{r['size'][1]}, each pass's ms (a `finish()` after each; the frame "
                   "sum and the image not included):", "", "| pass | meshes | first frame of a view | next frame |",
                   "|---|---|---|---|"]  # fmt: skip
            for (name, meshes, first), (_, _, next_) in zip(costs["new view"], costs["same view"], strict=True):
                md.append(f"| {name} | {meshes} | {_fmt(first)} | {_fmt(next_)} |")
    with_passes = [r for r in rows if r["gpu_ms_passes"]]
    if with_passes:
        md += ["", "GPU time per pass (median ms, timer queries):", ""]
        for r in with_passes:
            parts = ", ".join(f"{name} {ms:.2f}" for name, ms in r["gpu_ms_passes"].items())
            md.append(f"- {r['scene']} {r['size'][0]}×{r['size'][1]} {r['mode']}: {parts}")
    md.append("")
    results = {"device": device, "software": software, "frames": frames, "rows": rows, "small": small, "ar": ar_rows,
               "ar_missing": ar_missing, "wall_s": time.perf_counter() - started}  # fmt: skip
    return results, "\n".join(md)


def main(argv: list[str]) -> int:
    """The benchmark's subprocess: one scene's rows as one JSON line; a job it cannot read: one line, exit 2."""
    scenes = [label for label, _ in _cases()]
    try:
        if len(argv) != 1:
            raise ValueError('usage: python -m reflets.bench.gpu \'{"scene": …, "size": [w, h], "frames": n}\'')
        job = json.loads(argv[0])
        if not isinstance(job, dict) or job.get("scene") not in scenes:
            raise ValueError(f"a job is an object whose 'scene' is one of: {', '.join(scenes)}")
        size, frames = job.get("size"), job.get("frames")
        sizes_ok = isinstance(size, list) and len(size) == 2
        if not (sizes_ok and all(isinstance(v, int) and 16 <= v <= 4096 for v in size)):
            raise ValueError("'size' is [width, height], 16…4096 each")
        if not (isinstance(frames, int) and 1 <= frames <= 1000):
            raise ValueError("'frames' is an integer in 1…1000")
    except (ValueError, RecursionError) as exc:
        print(f"reflets.bench.gpu: {exc}", file=sys.stderr)
        return 2
    rows = _scene_rows(job["scene"], tuple(size), frames)
    print(jsonio.dumps(rows))  # strict JSON: a pass not drawn (NaN) is null
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
