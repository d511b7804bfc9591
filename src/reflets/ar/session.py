"""The live loop of 004 (its Fig 4.7), one frame at a time: detect the board's markers, solve the pose (kept a
few frames when the board is lost), reproject the frame into the environment cube map, then shade and
composite the virtual objects — each stage timed. ``reflets ar composite`` runs it on one photograph after
capture frames, ``reflets ar run`` on a video, a camera or a list of images."""

from __future__ import annotations

import time
from dataclasses import dataclass, field

import numpy as np

from ..scene import Scene
from . import capture
from .board import Board
from .camera import Intrinsics
from .composite import Composite, Compositor
from .tracking import Pose, Tracker

#: the cube map's face size when nothing else is asked (the document's is 512; the diffuse and the specular of
#: glossy lobes read coarse mips, and the prefiltered IBL downsamples anyway)
CUBE_SIZE = 128


def grey(frame: np.ndarray) -> np.ndarray:
    """The luminance of an RGB uint8 frame, what marker detection reads."""
    return np.round(np.asarray(frame, np.float64) @ capture.LUMINANCE).astype(np.uint8)


@dataclass
class FrameResult:
    pose: Pose | None
    composite: Composite | None  # None: no pose yet (the frame is shown as it is)
    gain: float | None  # the frame's exposure relative to the map (None: not captured)
    timings: dict[str, float] = field(default_factory=dict)


class Session:
    """One tracked camera lighting and compositing ``objects`` into its frames."""

    def __init__(self, objects: Scene, board: Board, intrinsics: Intrinsics, *, mode: str = "differential",
                 radius: float | None = None, cube: capture.CubeMap | None = None, capture_frames: bool = True,
                 response="srgb", **compositor):  # fmt: skip
        self.board, self.intrinsics, self.radius, self.response = board, intrinsics, radius, response
        self.cube = cube if cube is not None else capture.CubeMap.empty(CUBE_SIZE)
        self.lighting = capture.filled(self.cube)  # what the compositor reads: the unseen texels filled
        self.capture_frames = capture_frames and cube is None
        self.compositor = Compositor(objects, mode, response=response, **compositor)
        self.tracker = Tracker(board, intrinsics)

    def track(self, frame: np.ndarray, timings: dict[str, float] | None = None) -> Pose | None:
        return self.tracker.update(grey(frame), timings)

    def add_capture(self, frame: np.ndarray, pose: Pose) -> float:
        """Reproject a frame seen with ``pose`` into the map; its gain relative to the map."""
        gain = capture.capture(self.cube, frame, self.intrinsics, pose.R, pose.t, radius=self.radius,
                               response=self.response)  # fmt: skip
        self.lighting = capture.filled(self.cube)
        return gain

    def process(self, frame: np.ndarray, composite: bool = True, pose: Pose | None = None) -> FrameResult:
        """Track (unless ``pose`` is given), capture, composite."""
        timings: dict[str, float] = {}
        t0 = time.perf_counter()
        pose = pose if pose is not None else self.track(frame, timings)
        gain = None
        if pose is not None and self.capture_frames and pose.markers > 0:
            t1 = time.perf_counter()
            gain = self.add_capture(frame, pose)
            timings["capture_ms"] = 1e3 * (time.perf_counter() - t1)
        result = None
        if pose is not None and composite:
            result = self.compositor(frame, self.intrinsics, pose.R, pose.t, self.lighting, exposure=gain or 1.0)
            timings.update(result.timings)
        timings["frame_ms"] = 1e3 * (time.perf_counter() - t0)
        return FrameResult(pose, result, gain, timings)
