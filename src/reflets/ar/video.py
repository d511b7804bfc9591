"""Frames in and out of ``reflets ar run``: a video file or a camera through OpenCV's VideoCapture, or a list of
images; out to a video (VideoWriter) or a folder of PNG frames. Frames are RGB uint8 (OpenCV's BGR converted at
the edges), and nothing the user has is overwritten: an existing output is an error."""

from __future__ import annotations

from collections.abc import Iterator
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from ..errors import ArgumentError
from .board import _aruco

VIDEO_SUFFIXES = {".mp4": "mp4v", ".avi": "MJPG", ".mkv": "MJPG"}
IMAGE_SUFFIXES = {".png", ".jpg", ".jpeg", ".bmp", ".tif", ".tiff"}
#: the frame rate written into output videos
FPS = 30.0


#: the largest camera number accepted (OpenCV's V4L backend has /dev/video0 … 63)
MAX_CAMERA_INDEX = 63


@dataclass
class FrameSource:
    images: list[Path] | None = None
    capture: object = None  # cv2.VideoCapture
    name: str = ""

    @classmethod
    def open(cls, inputs: list[str], webcam: int | None) -> FrameSource:
        """Frames from ``inputs`` (a video file or images) or camera number ``webcam``."""
        cv2 = _aruco()
        if webcam is not None:
            if inputs:
                raise ArgumentError("give either input files or --webcam, not both", field="--webcam")
            if isinstance(webcam, bool) or not isinstance(webcam, int) or not 0 <= webcam <= MAX_CAMERA_INDEX:
                # refused before OpenCV sees it: VideoCapture(-1) ended in a segmentation fault (issue 32)
                raise ArgumentError(f"a camera index is from 0 to {MAX_CAMERA_INDEX}, got {webcam!r}",
                                    field="--webcam")  # fmt: skip
            capture = cv2.VideoCapture(int(webcam))
            if not capture.isOpened():
                raise ArgumentError(f"camera {webcam} cannot be opened", field="--webcam")
            return cls(capture=capture, name=f"camera {webcam}")
        if not inputs:
            raise ArgumentError("no input: give a video file, images, or --webcam N", field="input")
        paths = [Path(p) for p in inputs]
        for p in paths:
            if not p.is_file():
                raise ArgumentError("no such file", file=p)
        if len(paths) == 1 and paths[0].suffix.lower() not in IMAGE_SUFFIXES:
            capture = cv2.VideoCapture(str(paths[0]))
            if not capture.isOpened():
                raise ArgumentError("OpenCV cannot read this video", file=paths[0])
            return cls(capture=capture, name=str(paths[0]))
        return cls(images=paths, name=f"{len(paths)} images")

    def frames(self, limit: int | None = None) -> Iterator[np.ndarray]:
        from PIL import Image

        cv2 = _aruco()
        count = 0
        while limit is None or count < limit:
            if self.images is not None:
                if count >= len(self.images):
                    return
                try:
                    frame = np.asarray(Image.open(self.images[count]).convert("RGB"))
                except (OSError, ValueError) as exc:
                    raise ArgumentError(f"cannot read the image ({exc})", file=self.images[count]) from None
            else:
                ok, bgr = self.capture.read()
                if not ok:
                    self.capture.release()
                    return
                frame = cv2.cvtColor(bgr, cv2.COLOR_BGR2RGB)
            count += 1
            yield frame


class FrameSink:
    """A video file or a folder of numbered PNGs, created on the first frame."""

    def __init__(self, path: Path):
        self.path, self.writer, self.count = path, None, 0

    @classmethod
    def open(cls, output: str) -> FrameSink:
        path = Path(output)
        if path.exists():
            raise ArgumentError("exists already; choose another name (nothing was written)", file=path)
        suffix = path.suffix.lower()
        if suffix and suffix not in VIDEO_SUFFIXES:
            raise ArgumentError(f"a video ends in {', '.join(VIDEO_SUFFIXES)}; a folder of frames has no suffix",
                                file=path)  # fmt: skip
        if not path.parent.is_dir():
            raise ArgumentError("the folder does not exist", file=path.parent)
        return cls(path)

    def write(self, frame: np.ndarray) -> None:
        cv2 = _aruco()
        if self.path.suffix:
            if self.writer is None:
                fourcc = cv2.VideoWriter_fourcc(*VIDEO_SUFFIXES[self.path.suffix.lower()])
                self.writer = cv2.VideoWriter(str(self.path), fourcc, FPS, frame.shape[1::-1])
                if not self.writer.isOpened():
                    raise ArgumentError("OpenCV cannot write this video format here", file=self.path)
            self.writer.write(cv2.cvtColor(frame, cv2.COLOR_RGB2BGR))
        else:
            from ..imageio import write_png8

            self.path.mkdir(exist_ok=True)
            write_png8(self.path / f"frame_{self.count:05d}.png", frame)
        self.count += 1

    def close(self) -> None:
        if self.writer is not None:
            self.writer.release()

    def describe(self) -> str:
        kind = "video" if self.path.suffix else "folder"
        return f"{self.path} ({kind}, {self.count} frames)"
