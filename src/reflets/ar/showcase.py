"""The AR setting shared by `reflets bench ar` and the demo gallery: virtual objects on the synthetic world's
board (``world.py``), an environment captured by a handheld device's front camera while its back camera tracks
the board (the document's acquisition), and one photograph with its ground truth."""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np
from scipy.ndimage import binary_dilation, gaussian_filter

from ..imageio import write_png8
from ..metrics import relmse
from ..scene import load_dict
from . import capture
from .board import Board
from .camera import Intrinsics, camera_fields
from .composite import Compositor
from .session import grey
from .synthetic import look_at_pose
from .tracking import detect, pose_error, solve_pose
from .world import SKY, World

#: the device's front camera looks the other way: a half turn about the camera's y axis
FRONT = np.diag([-1.0, 1.0, -1.0])
BUNNY = Path(__file__).resolve().parents[1] / "data" / "meshes" / "bunny.ply"
#: a Lambert bunny and a rough metal sphere (GGX α = 0.1) on the board, in metres
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
#: the composited view
VIEW_EYE, VIEW_TARGET = (0.22, 0.26, 0.3), (0.01, 0.03, 0.0)
#: the front camera's auto-exposure gains over the orbit, and a bracketed short exposure's ratio to them
GAINS = np.linspace(0.7, 1.3, 12)
BRACKET = 1.0 / 1024.0
#: the capture's parallax radius (metres)
RADIUS = 3.0
#: the shadow region: where the smoothed ground truth is this much darker than the smoothed photograph
SHADOW_DROP = 0.03


def device_poses(count: int, radius: float = 0.45, height: float = 0.35):
    """Back-camera poses orbiting the board, looking at its centre."""
    for k in range(count):
        azimuth = 2 * np.pi * (k + 0.3) / count
        yield look_at_pose((radius * np.sin(azimuth), height, radius * np.cos(azimuth)), (0, 0.02, 0))


@dataclass
class RigCapture:
    cube: capture.CubeMap
    back_frames: list[np.ndarray]  # the back camera's photographs (tracked; the live loop's input)
    front_frame: np.ndarray  # the first front-camera frame, for show
    captured: int  # device poses whose back frame was tracked (their front frames captured)
    pose_mm_max: float | None  # the tracked device poses' largest position error


def rig_capture(world: World, board: Board, back: Intrinsics, front: Intrinsics, face: int,
                bracket: bool = False, spp: int = 8) -> RigCapture:  # fmt: skip
    """The environment from the front camera over 12 device poses (front-camera poses: the back camera's,
    tracked, turned by FRONT), its auto-exposure gains unknown (estimated by ``capture``); with ``bracket``,
    each pose adds a short exposure (BRACKET × the auto gain, its ratio known as a camera's exposure time is),
    which keeps the sun unclipped — the document's suggested HDR capture. The texels never seen are filled by
    elevation (``capture.filled``)."""
    cube = capture.CubeMap.empty(face)
    back_frames, front_frame, captured, errors = [], None, 0, []
    for k, (R, t) in enumerate(device_poses(len(GAINS))):
        photo = capture.quantise(world.render(camera_fields(back, R, t), spp=4, seed=100 + k))
        back_frames.append(photo)
        pose = solve_pose(*detect(grey(photo), board), back)
        if pose is None:
            continue
        errors.append(pose_error(pose.R, pose.t, R, t)[0])
        sky = world.render(camera_fields(front, FRONT @ R, FRONT @ t), spp=spp, seed=200 + k)
        frame = capture.quantise(GAINS[k] * sky)
        front_frame = frame if front_frame is None else front_frame
        gain = capture.capture(cube, frame, front, FRONT @ pose.R, FRONT @ pose.t, radius=RADIUS)
        if bracket:
            short = capture.quantise(BRACKET * GAINS[k] * sky)
            capture.capture(cube, short, front, FRONT @ pose.R, FRONT @ pose.t, radius=RADIUS,
                            exposure=BRACKET * gain)  # fmt: skip
        captured += 1
    return RigCapture(capture.filled(cube), back_frames, front_frame, captured, 1e3 * max(errors) if errors else None)


def regions(truth: np.ndarray, photo: np.ndarray, coverage: np.ndarray) -> dict[str, np.ndarray]:
    """The object (fully covered pixels) and the shadow (off the object and a 2-pixel band around it, where
    the ground truth, smoothed over the path tracer's noise, is SHADOW_DROP darker than the photograph)."""
    sigma = 2.0 * truth.shape[1] / 640
    ratio = gaussian_filter(truth.mean(axis=2), sigma) / np.maximum(gaussian_filter(photo.mean(axis=2), sigma), 1e-6)
    near_object = binary_dilation(coverage > 0, iterations=2)
    return {"object": coverage == 1.0, "shadow": (ratio < 1.0 - SHADOW_DROP) & ~near_object}


def view_pose() -> tuple[np.ndarray, np.ndarray]:
    return look_at_pose(VIEW_EYE, VIEW_TARGET)


def gallery(out_dir: Path, size: tuple[int, int] = (320, 240)) -> dict:
    """The demo gallery's AR entry: the photograph, the environment captured with bracketing, both composites
    and the ground truth (PNG files in ``out_dir``), with each composite's error over the object and the
    shadow."""
    board = Board.grid()
    world = World(board, SKY)
    back = Intrinsics.from_fov(size, 50)
    rig = rig_capture(world, board, back, Intrinsics.from_fov((size[0] // 2, size[1] // 2), 90), 64, bracket=True)
    R, t = view_pose()
    objects = load_dict(OBJECTS)
    photo = capture.quantise(world.render(camera_fields(back, R, t), spp=32, seed=1))
    truth = capture.quantise(world.render(camera_fields(back, R, t), objects, spp=32, seed=2))
    pose = solve_pose(*detect(grey(photo), board), back)
    files = {"photograph": photo, "ground truth": truth,
             "captured environment": capture.quantise(capture.to_equirect(rig.cube, 2 * size[0]))}  # fmt: skip
    truth_linear = capture.decode_response(truth / 255.0)
    errors, masks = {}, None
    for mode in ("differential", "document"):
        out = Compositor(objects, mode)(photo, back, pose.R, pose.t, rig.cube)
        files[f"composite, {mode}"] = out.image
        masks = masks or regions(truth_linear, capture.decode_response(photo / 255.0), out.coverage)
        errors[mode] = {f"{region}_relmse": relmse(out.linear[mask][None], truth_linear[mask][None])
                        for region, mask in masks.items()}  # fmt: skip
    names = {}
    for label, image in files.items():
        names[label] = f"ar_{''.join(c if c.isalnum() else '_' for c in label)}.png"
        write_png8(Path(out_dir) / names[label], image)
    return {"images": names, "errors": errors, "captured": rig.captured, "frames": len(rig.back_frames),
            "pose_mm": 1e3 * pose_error(pose.R, pose.t, R, t)[0]}  # fmt: skip
