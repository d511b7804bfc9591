"""`reflets bench viewer`: the interactive viewer's cost over the persistent renderer it shows.

For the showcase at 640 × 480 and 1280 × 720, ``reflets view`` runs in a real window (under ``xvfb-run`` when
there is no display) with a scripted orbit (one event per frame): median and 95th percentile of the window's
frame time (render, tone mapping of the frame's texture, panels, swap), event-to-frame latency (from the event
to its frame swapped), time from starting the command to its first frame. In this process, the same orbit through a
persistent ``Renderer`` gives the frame time the viewer is compared with (the acceptance: the viewer's median
≤ 1.5× it), and a still view accumulates until its image is within the reference's noise of its converged
value (relative MSE against 64 accumulated frames below the noise of the 64-spp NumPy reference the viewer
computes, mean σ² / (ref² + 0.01)): frames and seconds to get there.
"""

from __future__ import annotations

import json
import os
import shutil
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

from ..demo import scene_path
from ..errors import ArgumentError
from ..metrics import relmse

SCENE = "60_showcase.toml"
#: degrees of yaw per scripted orbit event
ORBIT_STEP = 2.0
#: frames of a converged image (the accumulation's limit)
CONVERGED_FRAMES = 64
#: the viewer's reference (its panel's default)
REFERENCE_SPP = 64


def _orbit_script(frames: int) -> list[dict]:
    return [{"type": "orbit", "dx": ORBIT_STEP, "dy": 0.0} for _ in range(frames)]


def _window_run(size: tuple[int, int], frames: int) -> dict:
    """``reflets view`` in a window with the orbit script: its --stats, and the seconds to its first frame."""
    with tempfile.TemporaryDirectory() as tmp:
        script, stats = Path(tmp) / "orbit.json", Path(tmp) / "stats.json"
        script.write_text(json.dumps(_orbit_script(frames)))
        command = [
            sys.executable,
            "-m",
            "reflets.cli",
            "view",
            str(scene_path(SCENE)),
            "--size",
            f"{size[0]}x{size[1]}",
        ]
        command += ["--script", str(script), "--frames", str(frames), "--stats", str(stats)]
        if not os.environ.get("DISPLAY"):
            xvfb = shutil.which("xvfb-run")
            if xvfb is None:
                raise ArgumentError("no display and no xvfb-run: install Xvfb (tools/install-system-packages)")
            command = [xvfb, "-a", "-s", f"-screen 0 {size[0] + 64}x{size[1] + 64}x24", *command]
        start = time.time()
        done = subprocess.run(command, capture_output=True, text=True, timeout=3600)
        if done.returncode != 0:
            raise ArgumentError(f"reflets view failed: {done.stderr.strip()[-400:]}", field="bench viewer")
        result = json.loads(stats.read_text())
        result["first_frame_s"] = result["first_frame_at"] - start
        return result


def _renderer_orbit(size: tuple[int, int], frames: int) -> list[float]:
    """Frame times of a persistent Renderer following the same orbit (the viewer's camera, without a window)."""
    import reflets

    from ..viewer.camera import OrbitCamera

    scene = reflets.load_scene(scene_path(SCENE))
    camera = OrbitCamera.from_camera(scene.camera.model_copy(update={"size": size}))
    times = []
    with reflets.Renderer(scene, size=size) as renderer:
        renderer.render()
        for _ in range(frames):
            camera.orbit(ORBIT_STEP, 0.0)
            t = time.perf_counter()
            renderer.set_camera(**camera.fields())
            renderer.render()
            times.append(1e3 * (time.perf_counter() - t))
    return times


def _convergence(size: tuple[int, int], reference_spp: int) -> dict:
    """Frames and seconds a still view accumulates until within the reference's noise of its own limit: the
    noise of the NumPy reference the viewer computes (``reference_spp``), mean σ² / (ref² + 0.01), estimated
    from a quarter of its samples (variance ∝ 1 / spp)."""
    import reflets

    scene = reflets.load_scene(scene_path(SCENE))
    quarter = reflets.reference(scene, spp=max(1, reference_spp // 4), size=size, progress=False)
    noise = float(np.mean(quarter.stderr**2 / (quarter.image**2 + 0.01))) / 4.0
    with reflets.Renderer(scene, size=size) as renderer:
        t0 = time.perf_counter()
        images, stamps = [], []
        for _ in range(CONVERGED_FRAMES):
            images.append(renderer.render())
            stamps.append(time.perf_counter() - t0)
        progressive = renderer.stats["frames"] > 1
    if not progressive:
        return {"progressive": False, "reference_noise_relmse": noise}
    limit = images[-1]
    errors = [relmse(image, limit) for image in images[: CONVERGED_FRAMES // 2]]
    hit = next((k for k, e in enumerate(errors) if e <= noise), None)
    return {
        "progressive": True,
        "reference_noise_relmse": noise,
        "relmse_to_limit": errors,
        "frames_to_noise": None if hit is None else hit + 1,
        "seconds_to_noise": None if hit is None else stamps[hit],
    }


def bench_viewer(quick: bool, out_dir) -> tuple[dict, str]:
    sizes = [(320, 240)] if quick else [(640, 480), (1280, 720)]
    frames = 6 if quick else 30
    rows = []
    for size in sizes:
        window = _window_run(size, frames)
        renderer = _renderer_orbit(size, frames)
        frame_ms = window["window_frame_ms"][1:]  # the first frame compiles the programs
        latency = window["event_latency_ms"][1:]
        rows.append(
            {
                "size": list(size),
                "window_median_ms": statistics.median(frame_ms),
                "window_p95_ms": float(np.percentile(frame_ms, 95)),
                "renderer_median_ms": statistics.median(renderer),
                "ratio": statistics.median(frame_ms) / statistics.median(renderer),
                "latency_median_ms": statistics.median(latency),
                "latency_p95_ms": float(np.percentile(latency, 95)),
                "first_frame_s": window["first_frame_s"],
                "renderer": window["renderer"],
                "convergence": _convergence(size, REFERENCE_SPP),
            }
        )
    lines = [
        "# Interactive viewer",
        "",
        f"The showcase (`{SCENE}`, method auto) in `reflets view`'s window with a scripted orbit ({frames} events of "
        f"{ORBIT_STEP:g}°, one per frame), against a persistent `Renderer` following the same orbit in the "
        "benchmark's own process; the window's frame is render + upload + tone mapping + panels + swap. "
        "Accumulation: a still view's relative MSE to its own limit "
        f"({CONVERGED_FRAMES} frames) against the noise of the {REFERENCE_SPP}-spp reference the viewer computes. "
        "Generated by `reflets bench viewer`.",
        "",
        "| size | window median ms | window p95 ms | renderer median ms | window / renderer | event→frame median "
        "(p95) ms | first frame s | frames (s) to the reference's noise |",
        "|---|---|---|---|---|---|---|---|",
    ]
    for r in rows:
        conv = r["convergence"]
        reached = (
            "1 (deterministic)"
            if not conv["progressive"]
            else f"{conv['frames_to_noise']} ({conv['seconds_to_noise']:.1f})"
            if conv["frames_to_noise"]
            else f"not within {CONVERGED_FRAMES // 2}"
        )
        lines.append(
            f"| {r['size'][0]}×{r['size'][1]} | {r['window_median_ms']:.1f} | {r['window_p95_ms']:.1f} | "
            f"{r['renderer_median_ms']:.1f} | {r['ratio']:.2f} | {r['latency_median_ms']:.1f} "
            f"({r['latency_p95_ms']:.1f}) | {r['first_frame_s']:.1f} | {reached} |"
        )
    return {"scene": SCENE, "frames": frames, "rows": rows}, "\n".join(lines) + "\n"
