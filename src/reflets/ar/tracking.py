"""Tracking: ArUco markers detected (``cv2.aruco.ArucoDetector``, sub-pixel corner refinement), matched to the
board's 3D corners, the pose solved by PnP (``cv2.solvePnP``, SQPnP then Levenberg–Marquardt refinement); a
pose is kept ``KEEP_FRAMES`` frames after the board is lost (as the document's code)."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .board import Board, _aruco
from .camera import Intrinsics

#: frames a pose is kept after the board is lost
KEEP_FRAMES = 10


@dataclass
class Pose:
    R: np.ndarray  # world → camera rotation (OpenCV axes)
    t: np.ndarray
    markers: int  # how many markers it was solved from (0: kept from an earlier frame)


def detect(image: np.ndarray, board: Board) -> tuple[np.ndarray, np.ndarray]:
    """The board's markers in a grey image: their 3D corners (N × 4, 3) and image corners (N × 4, 2)."""
    cv2 = _aruco()
    parameters = cv2.aruco.DetectorParameters()
    parameters.cornerRefinementMethod = cv2.aruco.CORNER_REFINE_SUBPIX
    detector = cv2.aruco.ArucoDetector(board.cv_dictionary(), parameters)
    corners, ids, _ = detector.detectMarkers(image)
    world, pixels = [], []
    for c, marker in zip(corners, [] if ids is None else ids.ravel(), strict=False):
        if int(marker) in board.markers:
            world.append(board.markers[int(marker)])
            pixels.append(np.asarray(c, np.float64).reshape(4, 2))
    if not world:
        return np.zeros((0, 3)), np.zeros((0, 2))
    return np.concatenate(world), np.concatenate(pixels)


def solve_pose(world: np.ndarray, pixels: np.ndarray, intrinsics: Intrinsics) -> Pose | None:
    cv2 = _aruco()
    if len(world) < 4:
        return None
    ok, rvec, tvec = cv2.solvePnP(world, pixels, intrinsics.K, intrinsics.dist, flags=cv2.SOLVEPNP_SQPNP)
    if not ok:
        return None
    rvec, tvec = cv2.solvePnPRefineLM(world, pixels, intrinsics.K, intrinsics.dist, rvec, tvec)
    return Pose(cv2.Rodrigues(rvec)[0], tvec.ravel(), len(world) // 4)


def track(images, board: Board, intrinsics: Intrinsics) -> list[Pose | None]:
    """A pose per image (None before the board is first seen, or after it is lost for over KEEP_FRAMES)."""
    poses, last, lost = [], None, 0
    for image in images:
        pose = solve_pose(*detect(image, board), intrinsics)
        if pose is not None:
            last, lost = pose, 0
        elif last is not None and lost < KEEP_FRAMES:
            lost += 1
            pose = Pose(last.R, last.t, 0)
        else:
            last = None
        poses.append(pose)
    return poses


def pose_error(R: np.ndarray, t: np.ndarray, R_true: np.ndarray, t_true: np.ndarray) -> tuple[float, float]:
    """(camera position error in world units, rotation error in degrees)."""
    position = -R.T @ t
    position_true = -R_true.T @ t_true
    angle = np.degrees(np.arccos(np.clip((np.trace(R @ R_true.T) - 1) / 2, -1.0, 1.0)))
    return float(np.linalg.norm(position - position_true)), float(angle)
