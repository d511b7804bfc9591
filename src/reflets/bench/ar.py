"""`reflets bench ar`: augmented reality (004) on generated data — real photographs are not available offline.

1. **Tracking**: views of the board (``ar.synthetic.render_view``: the exact projective warp of its image) at
   640 × 480, 50° vertical field of view, four azimuths at 50° elevation, against distance, Gaussian blur and
   noise: camera position error (mm) and rotation error (degrees) of ``ar.tracking`` (OpenCV's ArUco detector,
   SQPnP + Levenberg–Marquardt), and the share of views where the board was found.
2. **Composite vs ground truth**: the synthetic world (``ar.world``: the printed board on a grey floor under the
   sky map, path traced by Mitsuba 3) photographed at 640 × 480 without the objects — a Lambert bunny and a
   rough metal sphere (GGX α = 0.1: the document's Phong lobe of the equivalent exponent) —, the objects
   composited in, compared with the same world rendered with the objects really in it (8-bit sRGB both):
   relative MSE and FLIP (LDR) over the object's pixels and over the shadow (pixels, off the object, where the
   ground truth, smoothed over the path tracer's noise, is over 3 % darker than the photograph). Modes: the
   document's (face-constant diffuse with W_F exact or its fit, mip-map specular, sphere shadows) and
   differential rendering over reflets' prefiltered IBL; lighting: the environment captured from 12 LDR frames
   of the device's front camera (auto-exposure gains 0.7–1.3, estimated; parallax radius 3 m; poses tracked by
   the back camera), the same with a bracketed short exposure per pose (1/1024, its ratio known: the sun
   unclipped), and the true HDR sky as a light probe (what the lighting model does when capture is perfect).
3. **Live loop**: the median time per stage over 12 frames at 640 × 480 (detect, pose, capture, environment
   conversion, prefilter + prepare, shading, shadows, composite), wall clock on this machine (llvmpipe on a
   CPU-only machine: the ratios between stages, not absolute times, transfer to a GPU).
"""

from __future__ import annotations

import statistics
import time
from pathlib import Path

import numpy as np

from ..ar import capture
from ..ar.board import Board
from ..ar.camera import Intrinsics, camera_fields
from ..ar.composite import Compositor
from ..ar.session import Session, grey
from ..ar.showcase import OBJECTS, RADIUS, device_poses, regions, rig_capture, view_pose
from ..ar.synthetic import look_at_pose, render_view
from ..ar.tracking import detect, pose_error, solve_pose
from ..ar.world import SKY, World
from ..imageio import read_image, write_png8
from ..metrics import flip_per_pixel, relmse
from ..scene import load_dict

MODES = [("document, W_F fit", "document", "fit"), ("document, W_F exact", "document", "exact"),
         ("differential", "differential", "exact")]  # fmt: skip
def _tracking(quick: bool) -> list[dict]:
    board = Board.grid()
    intrinsics = Intrinsics.from_fov((640, 480), 50, principal=(326.0, 236.0))
    distances = (0.5, 1.0) if quick else (0.4, 0.6, 0.9, 1.3)
    degradations = [(0.0, 0.0), (1.5, 6.0)] if quick else [(0.0, 0.0), (1.0, 0.0), (2.0, 0.0), (0.0, 4.0),
                                                            (0.0, 8.0), (1.0, 4.0), (2.0, 8.0)]  # fmt: skip
    rows = []
    for distance in distances:
        for blur, noise in degradations:
            errors, found = [], 0
            for k, azimuth in enumerate(np.radians([20, 110, 200, 290])):
                eye = distance * np.array([np.cos(np.radians(50)) * np.sin(azimuth), np.sin(np.radians(50)),
                                           np.cos(np.radians(50)) * np.cos(azimuth)])  # fmt: skip
                R, t = look_at_pose(eye, (0.01, 0, -0.01))
                image = render_view(board, intrinsics, R, t, blur=blur, noise=noise, seed=k)
                pose = solve_pose(*detect(image, board), intrinsics)
                if pose is not None:
                    found += 1
                    errors.append(pose_error(pose.R, pose.t, R, t))
            position = [1e3 * e[0] for e in errors]
            angle = [e[1] for e in errors]
            rows.append({"distance_m": distance, "blur_px": blur, "noise": noise, "found": found / 4,
                         "position_mm_median": statistics.median(position) if errors else None,
                         "position_mm_max": max(position) if errors else None,
                         "rotation_deg_median": statistics.median(angle) if errors else None,
                         "rotation_deg_max": max(angle) if errors else None})  # fmt: skip
    return rows


def _captures(world: World, board: Board, quick: bool, out_dir: Path):
    back = Intrinsics.from_fov((160, 120) if quick else (640, 480), 50)
    front = Intrinsics.from_fov((96, 72) if quick else (320, 240), 90)
    face = 32 if quick else 128
    single = rig_capture(world, board, back, front, face)
    bracketed = rig_capture(world, board, back, front, face, bracket=True)
    write_png8(out_dir / "ar_capture_frame.png", single.front_frame)
    write_png8(out_dir / "ar_captured_environment.png", capture.quantise(capture.to_equirect(bracketed.cube, 256)))
    info = {"frames": len(single.back_frames), "captured": single.captured, "face": face,
            "device_pose_mm_max": single.pose_mm_max}  # fmt: skip
    return {"captured": single.cube, "captured, bracketed": bracketed.cube}, info, single.back_frames


def _composites(world: World, board: Board, cubes: dict, quick: bool, out_dir: Path) -> tuple[list[dict], dict]:
    objects = load_dict(OBJECTS)
    intrinsics = Intrinsics.from_fov((160, 120) if quick else (640, 480), 50)
    R, t = view_pose()
    camera = camera_fields(intrinsics, R, t)
    spp = 16 if quick else 64
    photo = capture.quantise(world.render(camera, spp=spp, seed=1))
    truth = capture.quantise(world.render(camera, objects, spp=spp, seed=2))
    pose = solve_pose(*detect(grey(photo), board), intrinsics)
    lightings = {**cubes, "light probe": capture.CubeMap.from_equirect(read_image(SKY), cubes["captured"].size)}
    truth_linear, photo_linear = capture.decode_response(truth / 255.0), capture.decode_response(photo / 255.0)
    images = {"photograph": photo, "ground truth": truth}
    rows, masks = [], None
    for label, mode, weights in MODES:
        compositor = Compositor(objects, mode, weights=weights, samples=4000 if quick else 20000,
                                directions=200 if quick else 1000)  # fmt: skip
        for lighting, environment in lightings.items():
            out = compositor(photo, intrinsics, pose.R, pose.t, environment)
            masks = masks or regions(truth_linear, photo_linear, out.coverage)
            flip = flip_per_pixel(capture.decode_response(out.image / 255.0), truth_linear, "LDR")
            row = {"mode": label, "lighting": lighting}
            for region, mask in masks.items():
                row[f"{region}_relmse"] = relmse(out.linear[mask][None], truth_linear[mask][None])
                row[f"{region}_flip"] = float(flip[mask].mean())
            rows.append(row)
            if lighting == "captured, bracketed" and weights == "exact":  # the images kept beside the results
                images[f"{label} ({lighting})"] = out.image
    for name, image in images.items():
        stem = "".join(c if c.isalnum() else "_" for c in name).strip("_")
        write_png8(out_dir / f"ar_{stem}.png", image)
    info = {"pixels": {k: int(v.sum()) for k, v in masks.items()},
            "pose_mm": 1e3 * pose_error(pose.R, pose.t, R, t)[0]}  # fmt: skip
    return rows, info


def _live_loop(frames: list[np.ndarray], quick: bool) -> list[dict]:
    objects = load_dict(OBJECTS)
    intrinsics = Intrinsics.from_fov(frames[0].shape[1::-1], 50)
    rows = []
    for label, mode, weights in (MODES[1], MODES[2]):
        session = Session(objects, Board.grid(), intrinsics, mode=mode, radius=RADIUS, weights=weights,
                          samples=4000 if quick else 20000, directions=200 if quick else 1000)  # fmt: skip
        rows.append(_stage_row(label, session.compositor.timings, [session.process(f).timings for f in frames]))
    return rows


def _stage_row(mode: str, precompute: dict, timings: list[dict]) -> dict:
    """The median of each stage over frames (a stage some frames lack: over those that have it)."""
    stages = sorted({k for t in timings for k in t})
    return {"mode": mode, "precompute_ms": precompute,
            **{k: statistics.median([t[k] for t in timings if k in t]) for k in stages}}  # fmt: skip


def _stage_table(rows: list[dict], stages: list[str]) -> list[str]:
    """Markdown: a row of median ms per stage per mode, then each mode's precomputation."""
    lines = ["| mode | " + " | ".join(s[:-3] for s in stages) + " |", "|---" * (len(stages) + 1) + "|"]
    lines += [f"| {r['mode']} | " + " | ".join(_fmt(r.get(s), 3) for s in stages) + " |" for r in rows]
    return lines + ["", "Precomputation per object (ms): " + "; ".join(
        f"{r['mode']}: " + (", ".join(f"{k[:-3]} {v:.0f}" for k, v in r["precompute_ms"].items()) or "none")
        for r in rows)]  # fmt: skip


def _plot(tracking: list[dict], out_dir: Path) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, axes = plt.subplots(1, 2, figsize=(10, 3.6))
    for blur, noise in sorted({(r["blur_px"], r["noise"]) for r in tracking}):
        rows = [r for r in tracking if r["blur_px"] == blur and r["noise"] == noise and r["found"] > 0]
        label = f"blur {blur:g} px, noise σ {noise:g}"
        axes[0].plot([r["distance_m"] for r in rows], [r["position_mm_median"] for r in rows], "o-", label=label)
        axes[1].plot([r["distance_m"] for r in rows], [r["rotation_deg_median"] for r in rows], "o-", label=label)
    axes[0].axhline(5, color="grey", ls=":", label="acceptance 5 mm")
    axes[1].axhline(0.5, color="grey", ls=":", label="acceptance 0.5°")
    axes[0].set(xlabel="distance to the board (m)", ylabel="position error, median (mm)", yscale="log")
    axes[1].set(xlabel="distance to the board (m)", ylabel="rotation error, median (°)", yscale="log")
    axes[0].legend(fontsize=6)
    fig.tight_layout()
    fig.savefig(out_dir / "ar.png", dpi=110)
    plt.close(fig)


def _fmt(value, digits=2) -> str:
    return "–" if value is None else f"{value:.{digits}g}" if abs(value) < 1 else f"{value:.{digits}f}"


def bench_ar(quick: bool, out_dir) -> tuple[dict, str]:
    out_dir = Path(out_dir)
    t0 = time.perf_counter()
    tracking = _tracking(quick)
    board = Board.grid()
    world = World(board, SKY)
    cubes, capture_info, frames = _captures(world, board, quick, out_dir)
    composites, composite_info = _composites(world, board, cubes, quick, out_dir)
    live = _live_loop(frames, quick)
    _plot(tracking, out_dir)
    results = {"tracking": tracking, "capture": capture_info, "composite": composites,
               "composite_info": composite_info, "live_loop": live,
               "seconds": time.perf_counter() - t0}  # fmt: skip

    md = ["# Augmented reality (004): tracking, capture, compositing", "",
          "Generated data (no real photographs offline): board views warped exactly, the world path traced by "
          "Mitsuba 3. Generated by `reflets bench ar`.", "", "![pose error](ar.png)", "",
          "## Tracking (640 × 480, 50° fov, 4 azimuths at 50° elevation)", "",
          "| distance m | blur px | noise σ | found | position mm (median / max) | rotation ° (median / max) |",
          "|---|---|---|---|---|---|"]  # fmt: skip
    for r in tracking:
        md.append(f"| {r['distance_m']} | {r['blur_px']:g} | {r['noise']:g} | {r['found']:.0%} | "
                  f"{_fmt(r['position_mm_median'])} / {_fmt(r['position_mm_max'])} | "
                  f"{_fmt(r['rotation_deg_median'])} / {_fmt(r['rotation_deg_max'])} |")  # fmt: skip
    md += ["", "## Composite vs ground truth", "",
           f"Capture: {capture_info['captured']} of {capture_info['frames']} front-camera frames, cube faces "
           f"{capture_info['face']}²; the composited view's tracked pose is {composite_info['pose_mm']:.1f} mm off; "
           f"{composite_info['pixels']['object']} object pixels, {composite_info['pixels']['shadow']} shadow pixels. "
           "Images: `ar_*.png` beside this file.", "",
           "| mode | lighting | object relMSE | object FLIP | shadow relMSE | shadow FLIP |",
           "|---|---|---|---|---|---|"]  # fmt: skip
    for r in composites:
        md.append(f"| {r['mode']} | {r['lighting']} | {r['object_relmse']:.2e} | {r['object_flip']:.3f} | "
                  f"{r['shadow_relmse']:.2e} | {r['shadow_flip']:.3f} |")  # fmt: skip
    stages = ["detect_ms", "pose_ms", "capture_ms", "rays_ms", "environment_ms", "prepare_ms", "shadow_texture_ms",
              "shadow_ms", "shading_ms", "composite_ms", "frame_ms"]  # fmt: skip
    md += ["", f"## Live loop: median ms per stage over {len(frames)} frames at {frames[0].shape[1]} × "
           f"{frames[0].shape[0]} (the document: 20–60 fps on a 2014 phone)", "", *_stage_table(live, stages)]
    return results, "\n".join(md) + "\n"


def bench_ar_loop(quick: bool, out_dir) -> tuple[dict, str]:
    """`reflets bench ar-loop`: the compositing stages of the live loop alone (the GPU's share: rays, the
    renders and their prefiltering, the document's shading and shadow texture, the composite), at 640 × 480 over
    12 known poses orbiting the board, the light probe's sky as the environment, a uniform grey photograph —
    neither OpenCV nor Mitsuba needed, so that it runs on a GPU machine as it is. Tracking and capture (CPU
    work) are timed by `reflets bench ar`."""
    objects = load_dict(OBJECTS)
    size = (160, 120) if quick else (640, 480)
    intrinsics = Intrinsics.from_fov(size, 50)
    photo = np.full((size[1], size[0], 3), 128, np.uint8)
    cube = capture.CubeMap.from_equirect(read_image(SKY), 32 if quick else 128)
    poses = list(device_poses(4 if quick else 12))
    rows = []
    for label, mode, weights in (MODES[1], MODES[2]):
        compositor = Compositor(objects, mode, weights=weights, samples=4000 if quick else 20000,
                                directions=200 if quick else 1000)  # fmt: skip
        for still in (False, True):
            timings = []
            for R, t in poses:
                # a new map each frame, as under capture; or the same one (a probe, a capture that has stopped)
                environment = cube if still else capture.CubeMap(cube.faces, cube.weights)
                start = time.perf_counter()
                out = compositor(photo, intrinsics, R, t, environment)
                timings.append({**out.timings, "frame_ms": 1e3 * (time.perf_counter() - start)})
            rows.append(_stage_row(label + (", still map" if still else ""), compositor.timings, timings))
        compositor.release()
    stages = ["rays_ms", "environment_ms", "prepare_ms", "shadow_texture_ms", "shadow_ms", "shading_ms",
              "composite_ms", "frame_ms"]  # fmt: skip
    md = ["# Augmented reality: the compositing stages of the live loop", "",
          f"Median ms per stage over {len(poses)} poses at {size[0]} × {size[1]}: the environment changing every "
          "frame, as under capture, or still (the same map: a light probe, a capture that has stopped; its first "
          "frame included). Generated by `reflets bench ar-loop`.", "", *_stage_table(rows, stages)]
    return {"size": list(size), "poses": len(poses), "rows": rows}, "\n".join(md) + "\n"
