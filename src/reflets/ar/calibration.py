"""Camera calibration from views of the marker board: the markers found in each image (``tracking.detect``)
give pairs of board and image corners, and ``cv2.calibrateCamera`` fits K and 5 distortion coefficients
(k1 k2 p1 p2 k3) to all the views at once, with the RMS reprojection error in pixels. OpenCV's initial guess of
K needs a planar target on z = 0: the board's plane y = 0 is turned onto it — a rotation of the world, which
changes the views' poses (not kept) but not K nor the distortion."""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from ..errors import ArgumentError
from .board import Board, _aruco, opencv_errors
from .camera import Intrinsics
from .tracking import detect

#: a view with fewer markers is left out: its corners barely constrain the lens
MIN_MARKERS = 4
#: fewer usable views do not determine K and the distortion
MIN_VIEWS = 3

#: board (x, y, z) → (x, z, −y): a proper rotation taking the plane y = 0 onto z = 0
_BOARD_TO_PLANE = np.array([[1.0, 0, 0], [0, 0, 1], [0, -1, 0]])


@dataclass
class Calibration:
    intrinsics: Intrinsics
    rms: float  # RMS reprojection error over the views used, in pixels
    markers: list[int]  # markers found in each image, in order (views with fewer than MIN_MARKERS left out)

    @property
    def views_used(self) -> int:
        return sum(m >= MIN_MARKERS for m in self.markers)


def calibrate(
    images: Sequence[np.ndarray],
    board: Board,
    size: tuple[int, int] | None = None,
    names: Sequence[str] | None = None,
) -> Calibration:
    """K, distortion and RMS from grey images (H, W) of ``board``, all of one ``size`` (W, H; default the
    first image's). ``names`` label the images in errors (default: their index)."""
    cv2 = _aruco()
    names = [str(n) for n in names] if names is not None else [f"image {k}" for k in range(len(images))]
    if len(images) == 0:
        raise ArgumentError("no images to calibrate from")
    corners = np.concatenate(list(board.markers.values()))
    if np.abs(corners[:, 1]).max() > 1e-9:
        raise ArgumentError("calibration needs a planar board (every corner on y = 0)", field="--board")
    size = tuple(size) if size is not None else (images[0].shape[1], images[0].shape[0])
    object_points, image_points, markers = [], [], []
    for image, name in zip(images, names, strict=True):
        if (image.shape[1], image.shape[0]) != size:
            raise ArgumentError(
                f"is {image.shape[1]}x{image.shape[0]}, not {size[0]}x{size[1]} as the others: "
                "calibration needs images of one size",
                file=name,
            )
        world, pixels = detect(image, board)
        markers.append(len(world) // 4)
        if markers[-1] >= MIN_MARKERS:
            object_points.append((world @ _BOARD_TO_PLANE.T).astype(np.float32))
            image_points.append(pixels.astype(np.float32))
    if len(object_points) < MIN_VIEWS:
        raise ArgumentError(
            f"only {len(object_points)} of {len(images)} images show {MIN_MARKERS} or more of the board's markers; "
            f"calibration needs {MIN_VIEWS} such views at least (varied, tilted)"
        )
    with opencv_errors("calibrate from these views", field="images"):
        rms, K, dist, _, _ = cv2.calibrateCamera(object_points, image_points, size, None, None)
    try:  # a fit that diverged (NaN, a negative focal length) is no camera
        intrinsics = Intrinsics.checked(K, np.asarray(dist, np.float64).ravel()[:5], size)
    except ArgumentError as exc:
        raise ArgumentError(f"the views give no usable camera ({exc.message}); take more views, varied and tilted",
                            field="images") from None  # fmt: skip
    if not np.isfinite(rms):
        raise ArgumentError(f"the fit's reprojection error is {rms}; take more views, varied and tilted",
                            field="images")  # fmt: skip
    return Calibration(intrinsics, float(rms), markers)
