"""Tracking: ArUco markers detected (``cv2.aruco.ArucoDetector``, sub-pixel corner refinement), matched to the
board's 3D corners, the pose solved by PnP (``cv2.solvePnP``, SQPnP then Levenberg–Marquardt refinement); a
pose is kept ``KEEP_FRAMES`` frames after the board is lost (as the document's code)."""

from __future__ import annotations

import time
from dataclasses import dataclass

import numpy as np

from .board import Board, _aruco, opencv_errors
from .camera import Intrinsics

#: frames a pose is kept after the board is lost
KEEP_FRAMES = 10


@dataclass
class Pose:
    R: np.ndarray  # world → camera rotation (OpenCV axes)
    t: np.ndarray
    markers: int  # how many markers it was solved from (0: kept from an earlier frame)


def detect(image: np.ndarray, board: Board, name: str | None = None) -> tuple[np.ndarray, np.ndarray]:
    """The board's markers in a grey image: their 3D corners (N × 4, 3) and image corners (N × 4, 2); ``name``
    labels the image in errors."""
    cv2 = _aruco()
    parameters = cv2.aruco.DetectorParameters()
    parameters.cornerRefinementMethod = cv2.aruco.CORNER_REFINE_SUBPIX
    with opencv_errors("detect markers", **({"file": name} if name is not None else {"field": "image"})):
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
    """The pose from the markers' corners; None: too few, or a view PnP cannot solve — SQPnP asserts (cv2.error)
    when the corners' undistorted rays are too close together to tell a pose, a frame without a pose, not a
    failure of the whole input (the board and the intrinsics were checked where they were read)."""
    cv2 = _aruco()
    if len(world) < 4:
        return None
    try:
        ok, rvec, tvec = cv2.solvePnP(world, pixels, intrinsics.K, intrinsics.dist, flags=cv2.SOLVEPNP_SQPNP)
        if not ok:
            return None
        rvec, tvec = cv2.solvePnPRefineLM(world, pixels, intrinsics.K, intrinsics.dist, rvec, tvec)
        R = cv2.Rodrigues(rvec)[0]
    except cv2.error:
        return None
    if not (np.all(np.isfinite(R)) and np.all(np.isfinite(tvec))):
        return None
    return Pose(R, tvec.ravel(), len(world) // 4)


class Tracker:
    """Poses frame after frame: solved from the markers seen, or the last one kept for KEEP_FRAMES frames after
    the board is lost (then None until it is found again)."""

    def __init__(self, board: Board, intrinsics: Intrinsics):
        self.board, self.intrinsics = board, intrinsics
        self._last: Pose | None = None
        self._lost = 0

    def update(self, image: np.ndarray, timings: dict[str, float] | None = None,
               name: str | None = None) -> Pose | None:  # fmt: skip
        """The pose of a grey image; ``timings`` receives detect_ms and pose_ms; ``name`` labels errors."""
        t0 = time.perf_counter()
        markers = detect(image, self.board, name)
        t1 = time.perf_counter()
        pose = solve_pose(*markers, self.intrinsics)
        if timings is not None:
            timings["detect_ms"], timings["pose_ms"] = 1e3 * (t1 - t0), 1e3 * (time.perf_counter() - t1)
        if pose is not None:
            self._last, self._lost = pose, 0
        elif self._last is not None and self._lost < KEEP_FRAMES:
            self._lost += 1
            pose = Pose(self._last.R, self._last.t, 0)
        else:
            self._last = None
        return pose


def track(images, board: Board, intrinsics: Intrinsics, names=None) -> list[Pose | None]:
    """A pose per image (None before the board is first seen, or after it is lost for over KEEP_FRAMES);
    ``names`` label the images in errors."""
    tracker = Tracker(board, intrinsics)
    if names is None:
        return [tracker.update(image) for image in images]
    return [tracker.update(image, name=str(name)) for image, name in zip(images, names, strict=True)]


def pose_error(R: np.ndarray, t: np.ndarray, R_true: np.ndarray, t_true: np.ndarray) -> tuple[float, float]:
    """(camera position error in world units, rotation error in degrees)."""
    position = -R.T @ t
    position_true = -R_true.T @ t_true
    angle = np.degrees(np.arccos(np.clip((np.trace(R @ R_true.T) - 1) / 2, -1.0, 1.0)))
    return float(np.linalg.norm(position - position_true)), float(angle)
