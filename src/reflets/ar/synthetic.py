"""Views of a marker board with known poses — the test data of the tracking (real photographs are not available
offline: these are generated, and say so). A planar board seen by a pinhole camera is exactly a projective
warp of its top view: each pixel's ray meets the plane y = 0, the board image is sampled there (bilinear),
paper elsewhere a mid grey; then optional Gaussian blur (σ in pixels), brightness gain and noise. A lens with
distortion bends each pixel's ray: its position is undistorted (the inverse of OpenCV's model) first."""

from __future__ import annotations

import numpy as np

from ..scene.transform import look_at
from .board import Board, _aruco
from .camera import CV_TO_GL, Intrinsics


def look_at_pose(eye, target=(0.0, 0.0, 0.0), up=(0.0, 1.0, 0.0)) -> tuple[np.ndarray, np.ndarray]:
    """The OpenCV pose (R, t: x_cam = R x_world + t) of a camera at ``eye`` looking at ``target``: the OpenGL
    view of ``scene.transform.look_at`` with the axes flipped."""
    R = CV_TO_GL @ look_at(eye, target, up)[:3, :3]
    return R, -R @ np.asarray(eye, np.float64)


def render_view(
    board: Board,
    intrinsics: Intrinsics,
    R: np.ndarray,
    t: np.ndarray,
    blur: float = 0.0,
    noise: float = 0.0,
    gain: float = 1.0,
    seed: int = 0,
) -> np.ndarray:
    """A grey uint8 image (H, W) of the board seen with pose (R, t) through ``intrinsics``, its lens distortion
    included."""
    cv2 = _aruco()
    top, to_pixel = board.image()
    w, h = intrinsics.size
    u, v = np.meshgrid(np.arange(w, dtype=np.float64), np.arange(h, dtype=np.float64))
    if np.any(intrinsics.dist != 0):
        rays_cam = _undistorted_rays(u.ravel(), v.ravel(), intrinsics)
    else:  # the pinhole path, kept exactly as before distortion was modelled
        rays_cam = np.linalg.solve(intrinsics.K, np.stack([u.ravel(), v.ravel(), np.ones(u.size)]))
    rays = R.T @ rays_cam  # world directions
    centre = -R.T @ t
    with np.errstate(divide="ignore", invalid="ignore"):
        s = -centre[1] / rays[1]
    hit = centre[:, None] + s * rays
    valid = (s > 0) & np.isfinite(s)
    col = to_pixel[0, 0] * hit[0] + to_pixel[0, 2]
    row = to_pixel[1, 1] * hit[2] + to_pixel[1, 2]
    map_x = np.where(valid, col, -1).reshape(h, w).astype(np.float32)
    map_y = np.where(valid, row, -1).reshape(h, w).astype(np.float32)
    image = cv2.remap(top, map_x, map_y, cv2.INTER_LINEAR,
                      borderMode=cv2.BORDER_CONSTANT, borderValue=128).astype(np.float64)  # fmt: skip
    if blur > 0:
        image = cv2.GaussianBlur(image, (0, 0), blur)
    image = image * gain
    if noise > 0:
        image = image + np.random.default_rng(seed).normal(0.0, noise, image.shape)
    return np.clip(np.round(image), 0, 255).astype(np.uint8)


def _undistorted_rays(u: np.ndarray, v: np.ndarray, intrinsics: Intrinsics) -> np.ndarray:
    """Camera-frame rays (3, N) of the pixels (u, v) seen through a lens with distortion: the ideal pinhole
    positions they come from, by ``cv2.undistortPoints``, in normalized coordinates (z = 1). Its iteration runs
    to convergence: OpenCV's default (5 iterations) leaves an error that grows with the distortion, and these
    views are test data."""
    cv2 = _aruco()
    criteria = (cv2.TERM_CRITERIA_COUNT | cv2.TERM_CRITERIA_EPS, 100, 1e-10)
    pixels = np.stack([u, v], axis=1).reshape(-1, 1, 2)
    if hasattr(cv2, "undistortPointsIter"):  # OpenCV 4 takes the criteria here
        normalized = cv2.undistortPointsIter(pixels, intrinsics.K, intrinsics.dist, None, None, criteria)
    else:  # OpenCV 5, in undistortPoints
        normalized = cv2.undistortPoints(pixels, intrinsics.K, intrinsics.dist, None, None, None, criteria)
    normalized = normalized.reshape(-1, 2)
    return np.stack([normalized[:, 0], normalized[:, 1], np.ones(len(normalized))])
