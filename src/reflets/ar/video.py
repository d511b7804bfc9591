"""Frames in and out of ``reflets ar run``: a video file or a camera through OpenCV's VideoCapture, or a list of
images; out to a video (VideoWriter) or a folder of PNG frames. Frames are RGB uint8 (OpenCV's BGR converted at
the edges). The output follows reflets.outputs' rule: an existing one is refused unless ``--overwrite``, and it
is written under a temporary name, moved into place only when the run ends well."""

from __future__ import annotations

import os
import re
import secrets
import shutil
from collections.abc import Iterator
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from ..errors import ArgumentError
from .board import _aruco, opencv_errors
from .images import check_frame_size, check_intrinsics_size, frame_sizes, read_frame

VIDEO_SUFFIXES = {".mp4": "mp4v", ".avi": "MJPG", ".mkv": "MJPG"}
IMAGE_SUFFIXES = {".png", ".jpg", ".jpeg", ".bmp", ".tif", ".tiff"}
#: the frame rate written into output videos
FPS = 30.0
#: the names of an output folder's frames (a folder holding anything else is never replaced)
FRAME_FORMAT = "frame_{:05d}.png"
FRAME_NAME = re.compile(r"frame_\d{5,}\.png")


#: the largest camera number accepted (OpenCV's V4L backend has /dev/video0 … 63)
MAX_CAMERA_INDEX = 63


@dataclass
class FrameSource:
    images: list[Path] | None = None
    capture: object = None  # cv2.VideoCapture
    name: str = ""

    @classmethod
    def open(cls, inputs: list[str], webcam: int | None, size: tuple[int, int] | None = None) -> FrameSource:
        """Frames from ``inputs`` (a video file or images) or camera number ``webcam``; ``size``: what the frames
        must be (the intrinsics'), checked from the headers where they say it."""
        cv2 = _aruco()
        if webcam is not None:
            if inputs:
                raise ArgumentError("give either input files or --webcam, not both", field="--webcam")
            if isinstance(webcam, bool) or not isinstance(webcam, int) or not 0 <= webcam <= MAX_CAMERA_INDEX:
                # refused before OpenCV sees it: VideoCapture(-1) ended in a segmentation fault (issue 32)
                raise ArgumentError(f"a camera index is from 0 to {MAX_CAMERA_INDEX}, got {webcam!r}",
                                    field="--webcam")  # fmt: skip
            with opencv_errors("open the camera", field="--webcam"):
                capture = cv2.VideoCapture(int(webcam))
            if not capture.isOpened():
                raise ArgumentError(f"camera {webcam} cannot be opened", field="--webcam")
            return cls(capture=capture, name=f"camera {webcam}")
        if not inputs:
            raise ArgumentError("no input: give a video file, images, or --webcam N", field="input")
        paths = [Path(p) for p in inputs]
        for p in paths:
            if p.is_dir():
                raise ArgumentError("is a directory, expected a video or an image", file=p)
            if not p.is_file():
                raise ArgumentError("no such file", file=p)
        if len(paths) == 1 and paths[0].suffix.lower() not in IMAGE_SUFFIXES:
            with opencv_errors("read this video", file=paths[0]):
                capture = cv2.VideoCapture(str(paths[0]))
                if not capture.isOpened():
                    raise ArgumentError("OpenCV cannot read this video", file=paths[0])
                header = [int(capture.get(p)) for p in (cv2.CAP_PROP_FRAME_WIDTH, cv2.CAP_PROP_FRAME_HEIGHT)]
            if all(header):  # 0: not in the container's header (checked frame by frame then)
                check_frame_size(*header, file=paths[0])
                if size is not None:
                    check_intrinsics_size(*header, size, file=paths[0])
            return cls(capture=capture, name=str(paths[0]))
        # every header read (and checked) before the first frame is shown: a bad image late in the list, or one
        # of another size, is found before any output is written
        sizes = frame_sizes(paths)
        for path, (width, height) in zip(paths, sizes, strict=True):
            if size is not None:
                check_intrinsics_size(width, height, size, file=path)
            elif (width, height) != sizes[0]:
                raise ArgumentError(f"is {width}x{height}, not {sizes[0][0]}x{sizes[0][1]} as {paths[0]}: the "
                                    "frames are all one size", file=path)  # fmt: skip
        return cls(images=paths, name=f"{len(paths)} images")

    def frames(self, limit: int | None = None) -> Iterator[np.ndarray]:
        cv2 = _aruco()
        count = 0
        while limit is None or count < limit:
            if self.images is not None:
                if count >= len(self.images):
                    return
                frame = read_frame(self.images[count], "RGB")
            else:
                with opencv_errors("read a frame", field=self.name):
                    ok, bgr = self.capture.read()
                    if not ok:
                        self.capture.release()
                        return
                    check_frame_size(bgr.shape[1], bgr.shape[0], field=f"{self.name}, frame {count}")
                    frame = cv2.cvtColor(bgr, cv2.COLOR_BGR2RGB)
            count += 1
            yield frame


class FrameSink:
    """A video file or a folder of numbered PNGs, written under a temporary sibling name and moved into place when
    the run ends well (:meth:`commit`): a run that fails half-way — a bad frame, an interrupt — leaves nothing
    (:meth:`discard`), and an existing output is replaced only then, and only with ``overwrite``."""

    def __init__(self, path: Path):
        self.path, self.writer, self.count = path, None, 0
        tag = secrets.token_hex(6)
        self.writing = path.with_name(f".{path.stem}.{tag}.tmp{path.suffix}")  # the video's suffix: its container

    @classmethod
    def open(cls, output: str, overwrite: bool = False, inputs=()) -> FrameSink:
        """Checks of ``output`` (reflets.outputs' rule; a folder replaced must hold only frames of a run)."""
        from ..outputs import check_not_input

        path = Path(output)
        suffix = path.suffix.lower()
        if suffix and suffix not in VIDEO_SUFFIXES:
            raise ArgumentError(f"a video ends in {', '.join(VIDEO_SUFFIXES)}; a folder of frames has no suffix",
                                file=path)  # fmt: skip
        if not path.parent.is_dir():
            raise ArgumentError(f"the folder '{path.parent}' does not exist; create it first", file=path)
        if not os.access(path.parent, os.W_OK | os.X_OK):
            raise ArgumentError(f"the folder '{path.parent}' is not writable", file=path)
        check_not_input(path, inputs)
        if path.is_dir():  # its frames would go with it
            inside = [item for item in inputs if item is not None and path.resolve() in Path(item).resolve().parents]
            if inside:
                raise ArgumentError(f"holds one of the inputs ({inside[0]}); give the output another name", file=path)
        if path.exists() and not overwrite:
            raise ArgumentError("exists already; give --overwrite to replace it (nothing was written)", file=path)
        if path.exists() and path.is_dir() != (not suffix):
            what = ("a folder", "a video") if path.is_dir() else ("a file", "a folder of frames")
            raise ArgumentError(f"is {what[0]}; {what[1]} cannot replace it", file=path)
        if path.is_dir() and any(not FRAME_NAME.fullmatch(p.name) for p in path.iterdir()):
            raise ArgumentError("holds files that are not frames of a run: --overwrite replaces only such a folder",
                                file=path)  # fmt: skip
        return cls(path)

    def write(self, frame: np.ndarray) -> None:
        cv2 = _aruco()
        if self.path.suffix:
            with opencv_errors("write the video", file=self.path):
                if self.writer is None:
                    fourcc = cv2.VideoWriter_fourcc(*VIDEO_SUFFIXES[self.path.suffix.lower()])
                    self.writer = cv2.VideoWriter(str(self.writing), fourcc, FPS, frame.shape[1::-1])
                    if not self.writer.isOpened():
                        raise ArgumentError("OpenCV cannot write this video format here", file=self.path)
                self.writer.write(cv2.cvtColor(frame, cv2.COLOR_RGB2BGR))
        else:
            from ..imageio import write_png8

            try:
                self.writing.mkdir(exist_ok=True)
            except OSError as exc:
                raise ArgumentError(f"cannot create the frames' folder ({exc.strerror or exc})",
                                    file=self.path) from None  # fmt: skip
            write_png8(self.writing / FRAME_FORMAT.format(self.count), frame)
        self.count += 1

    def commit(self) -> None:
        """The output moved into place (an existing one replaced: a folder is moved aside, then removed)."""
        self._release()
        try:
            if self.path.is_dir():
                aside = self.path.with_name(f".{self.path.name}.{secrets.token_hex(6)}.old")
                os.replace(self.path, aside)
                os.replace(self.writing, self.path)
                shutil.rmtree(aside, ignore_errors=True)
            else:
                os.replace(self.writing, self.path)
        except OSError as exc:
            self.discard()
            raise ArgumentError(f"cannot move the output into place ({exc.strerror or exc})", file=self.path) from None

    def discard(self) -> None:
        """Nothing of a run that failed kept (the output there before, if any, untouched)."""
        self._release()
        if self.writing.is_dir():
            shutil.rmtree(self.writing, ignore_errors=True)
        else:
            self.writing.unlink(missing_ok=True)

    def _release(self) -> None:
        if self.writer is not None:
            self.writer.release()
            self.writer = None

    def describe(self) -> str:
        kind = "video" if self.path.suffix else "folder"
        return f"{self.path} ({kind}, {self.count} frames)"
