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
   ground truth is over 2 % darker than the photograph). Modes: the document's (face-constant diffuse with W_F
   exact or its fit, mip-map specular, sphere shadows) and differential rendering over reflets' prefiltered IBL;
   lighting: the environment captured from 12 LDR frames of the device's front camera (gains 0.7–1.3, parallax
   radius 3 m; poses tracked by the back camera), and the true HDR sky as a light probe (what the lighting
   model does when capture is perfect).
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
from ..ar.synthetic import look_at_pose, render_view
from ..ar.tracking import detect, pose_error, solve_pose
from ..ar.world import SKY, World
from ..imageio import read_image, write_png8
from ..metrics import flip_per_pixel, relmse
from ..scene import load_dict

#: the device's front camera looks the other way: a half turn about the camera's y axis
FRONT = np.diag([-1.0, 1.0, -1.0])
BUNNY = Path(__file__).resolve().parents[1] / "data" / "meshes" / "bunny.ply"
OBJECTS = {
    "camera": {"position": [0, 1, 1], "look_at": [0, 0, 0]},
    "materials": {
        "clay": {"type": "lambert", "albedo": [0.75, 0.55, 0.4]},
        "metal": {"type": "microfacet", "alpha": 0.1, "specular": [0.9, 0.9, 0.9]},
    },
    "mesh": [
        {"file": str(BUNNY), "material": "clay", "transform": {"scale": 0.08, "translate": [-0.03, 0, 0]}},
        {"shape": "sphere", "radius": 0.025, "material": "metal", "transform": {"translate": [0.055, 0.025, 0.03]}},
    ],
}
MODES = [("document, W_F fit", "document", "fit"), ("document, W_F exact", "document", "exact"),
         ("differential", "differential", "exact")]  # fmt: skip


def _encode(linear: np.ndarray) -> np.ndarray:
    return np.round(capture.encode_response(np.clip(linear, 0.0, 1.0)) * 255.0).astype(np.uint8)


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


def _device_poses(count: int, radius: float = 0.45, height: float = 0.35):
    for k in range(count):
        azimuth = 2 * np.pi * (k + 0.3) / count
        yield look_at_pose((radius * np.sin(azimuth), height, radius * np.cos(azimuth)), (0, 0.02, 0))


def _capture(world: World, board: Board, quick: bool, out_dir: Path) -> tuple[capture.CubeMap, dict, list]:
    """The environment from the front camera of 12 device poses, each pose tracked by the back camera; the back
    frames (640 × 480) are also the live loop's input."""
    back = Intrinsics.from_fov((160, 120) if quick else (640, 480), 50)
    front = Intrinsics.from_fov((96, 72) if quick else (320, 240), 90)
    cube = capture.CubeMap.empty(32 if quick else 128)
    gains = np.linspace(0.7, 1.3, 12)
    frames, captured, errors = [], 0, []
    for k, (R, t) in enumerate(_device_poses(12)):
        photo = _encode(world.render(camera_fields(back, R, t), spp=4, seed=100 + k))
        frames.append(photo)
        pose = solve_pose(*detect(grey(photo), board), back)
        if pose is None:
            continue
        errors.append(pose_error(pose.R, pose.t, R, t))
        sky = _encode(gains[k] * world.render(camera_fields(front, FRONT @ R, FRONT @ t), spp=8, seed=200 + k))
        if k == 0:
            write_png8(out_dir / "ar_capture_frame.png", sky)
        capture.capture(cube, sky, front, FRONT @ pose.R, FRONT @ pose.t, radius=3.0)
        captured += 1
    info = {"frames": 12, "captured": captured, "face": cube.size,
            "device_pose_mm_max": 1e3 * max(e[0] for e in errors) if errors else None}  # fmt: skip
    return cube, info, frames


def _composites(world: World, board: Board, cube, quick: bool, out_dir: Path) -> tuple[list[dict], dict]:
    objects = load_dict(OBJECTS)
    intrinsics = Intrinsics.from_fov((160, 120) if quick else (640, 480), 50)
    R, t = look_at_pose((0.22, 0.26, 0.3), (0.01, 0.03, 0.0))
    camera = camera_fields(intrinsics, R, t)
    spp = 16 if quick else 64
    photo = _encode(world.render(camera, spp=spp, seed=1))
    truth = _encode(world.render(camera, objects, spp=spp, seed=2))
    pose = solve_pose(*detect(grey(photo), board), intrinsics)
    probe = capture.CubeMap.from_equirect(read_image(SKY), cube.size)
    truth_linear, photo_linear = capture.decode_response(truth / 255.0), capture.decode_response(photo / 255.0)
    images = {"photograph": photo, "ground truth": truth}
    rows, masks = [], None
    for label, mode, weights in MODES:
        compositor = Compositor(objects, mode, weights=weights, samples=4000 if quick else 20000,
                                directions=200 if quick else 1000)  # fmt: skip
        for lighting, environment in (("captured", cube), ("light probe", probe)):
            out = compositor(photo, intrinsics, pose.R, pose.t, environment)
            if masks is None:
                on_object = out.coverage == 1.0
                darker = truth_linear.mean(axis=2) < 0.98 * photo_linear.mean(axis=2)
                masks = {"object": on_object, "shadow": darker & (out.coverage == 0)}
            flip = flip_per_pixel(capture.decode_response(out.image / 255.0), truth_linear, "LDR")
            row = {"mode": label, "lighting": lighting, "precompute_ms": compositor.timings}
            for region, mask in masks.items():
                row[f"{region}_relmse"] = relmse(out.linear[mask][None], truth_linear[mask][None])
                row[f"{region}_flip"] = float(flip[mask].mean())
            rows.append(row)
            images[f"{label} ({lighting})"] = out.image
    for name, image in images.items():
        write_png8(out_dir / f"ar_{name.replace(' ', '_').replace(',', '').replace('(', '').replace(')', '')}.png",
                   image)  # fmt: skip
    faces = capture.to_equirect(cube, 256)
    write_png8(out_dir / "ar_captured_environment.png", _encode(faces))
    info = {"pixels": {k: int(v.sum()) for k, v in masks.items()},
            "pose_mm": 1e3 * pose_error(pose.R, pose.t, R, t)[0]}  # fmt: skip
    return rows, info


def _live_loop(frames: list[np.ndarray], quick: bool) -> list[dict]:
    objects = load_dict(OBJECTS)
    intrinsics = Intrinsics.from_fov(frames[0].shape[1::-1], 50)
    rows = []
    for label, mode, weights in (MODES[1], MODES[2]):
        session = Session(objects, Board.grid(), intrinsics, mode=mode, radius=3.0, weights=weights,
                          samples=4000 if quick else 20000, directions=200 if quick else 1000)  # fmt: skip
        timings = [session.process(frame).timings for frame in frames]
        stages = sorted({k for t in timings for k in t})
        rows.append({"mode": label, "precompute_ms": session.compositor.timings,
                     **{k: statistics.median([t[k] for t in timings if k in t]) for k in stages}})  # fmt: skip
    return rows


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
    cube, capture_info, frames = _capture(world, board, quick, out_dir)
    composites, composite_info = _composites(world, board, cube, quick, out_dir)
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
           f"{frames[0].shape[0]} (the document: 20–60 fps on a 2014 phone)", "",
           "| mode | " + " | ".join(s[:-3] for s in stages) + " |", "|---" * (len(stages) + 1) + "|"]  # fmt: skip
    for r in live:
        md.append(f"| {r['mode']} | " + " | ".join(_fmt(r.get(s), 3) for s in stages) + " |")
    md.append("")
    md.append("Precomputation per object (ms): " + "; ".join(
        f"{r['mode']}: " + ", ".join(f"{k[:-3]} {v:.0f}" for k, v in r["precompute_ms"].items()) for r in live))
    return results, "\n".join(md) + "\n"
