"""A marker board: ArUco markers at known 3D corners in the board's frame, which is the world (y up, the board in
the plane y = 0, units of the user's choice — metres below). JSON:
``{"dictionary": "DICT_6X6_250", "markers": {"ID": [[x, y, z] × 4]}}``, corners in OpenCV's order (the marker's
top-left, top-right, bottom-right, bottom-left as its image is drawn, seen from above: +x right, +z down).

A board file is checked where it is read, as everything downstream assumes: a dictionary OpenCV predefines, ids of
it, each marker a convex quadrilateral on y = 0 facing up (calibration needs the plane, the capture and the
composited objects take y as up), the markers apart from each other."""

from __future__ import annotations

import functools
import math
import os
import re
from contextlib import contextmanager
from dataclasses import dataclass
from pathlib import Path

import numpy as np
from pydantic import Field, ValidationInfo, field_validator

from ..arguments import read_model
from ..errors import ArgumentError
from ..quantities import MAX_MAGNITUDE
from ..quantities import JsonNumber as Number
from . import InputFile, write_json

#: OpenCV's predefined ArUco dictionaries and their number of markers (ids 0 … n − 1): only these names are
#: looked up in cv2.aruco (any other attribute of it is not a dictionary)
DICTIONARIES = {
    **{f"DICT_{bits}X{bits}_{n}": n for bits in (4, 5, 6, 7) for n in (50, 100, 250, 1000)},
    "DICT_ARUCO_ORIGINAL": 1024,
    "DICT_APRILTAG_16h5": 30,
    "DICT_APRILTAG_25h9": 35,
    "DICT_APRILTAG_36h10": 2320,
    "DICT_APRILTAG_36h11": 587,
    "DICT_ARUCO_MIP_36h12": 250,
}
#: DICTIONARIES as the errors list them
_DICTIONARY_NAMES = "DICT_{4X4,5X5,6X6,7X7}_{50,100,250,1000}, " + ", ".join(list(DICTIONARIES)[16:])
#: the shortest side a marker may have, in board units (a micrometre in metres): PnP's sums of squared
#: coordinates would come near float underflow, and no camera resolves it
MIN_MARKER_SIDE = 1e-6
#: the narrowest and widest inside angle of a marker's quadrilateral (a square's are 90°)
MIN_CORNER_DEGREES = 1.0
#: a corner's y within this fraction of the board's extent is on the plane y = 0 (the rounding of a rotated
#: board, a hand-measured one's error: 0.3 mm on a 30 cm board), and is set to 0; markers touching within it do
#: not overlap
PLANE_TOLERANCE = 1e-3
#: pixels per board unit of the board's image (4000 per metre: about 100 dpi)
PIXELS_PER_UNIT = 4000.0
#: pairs of markers tested for overlap at once (bounds the temporary arrays: ~0.5 kB a pair)
_PAIRS_AT_ONCE = 1 << 16


@functools.cache
def _aruco():
    """cv2, with OpenCV's own log lines silenced, and FFmpeg's under its video capture: every failure reaches the
    user as one line of reflets' (:func:`opencv_errors`)."""
    os.environ.setdefault("OPENCV_FFMPEG_LOGLEVEL", "-8")  # AV_LOG_QUIET, read when the first capture opens
    try:
        import cv2
    except ImportError:
        raise ArgumentError("augmented reality needs the 'ar' extra: pip install 'reflets[ar]'") from None
    cv2.utils.logging.setLogLevel(cv2.utils.logging.LOG_LEVEL_SILENT)
    return cv2


@contextmanager
def opencv_errors(doing: str, **where):
    """OpenCV's failure (cv2.error: an assertion deep in its C++, several lines) as one ArgumentError naming the
    input — ``where``: its file= or field= — and saying what could not be done."""
    cv2 = _aruco()
    try:
        yield
    except cv2.error as exc:
        lines = [line.strip() for line in str(exc).splitlines() if line.strip()]
        reason = getattr(exc, "err", None) or (lines[-1] if lines else "cv2.error")
        raise ArgumentError(f"OpenCV could not {doing} ({' '.join(str(reason).split())})", **where) from None


def dictionary_size(name: object) -> int:
    """How many markers the predefined dictionary ``name`` has; ValueError if it is not one of DICTIONARIES."""
    if name not in DICTIONARIES:
        raise ValueError(f"{name!r} is not an ArUco dictionary; one of {_DICTIONARY_NAMES}")
    return DICTIONARIES[name]


_CANONICAL_ID = re.compile(r"0|[1-9][0-9]{0,9}")


def _marker_ids(keys, dictionary: str | None) -> list[int]:
    """The ids a board file's keys give: whole numbers written canonically (``"01"`` and ``"1"`` are not two
    names of one marker, ``"+1"``, ``" 1"``, ``"-1"`` none), within the dictionary's size."""
    ids = []
    for key in keys:
        if not _CANONICAL_ID.fullmatch(key):
            raise ValueError(f"{key!r} is not a marker id; ids are whole numbers written 0, 1, 2... (no sign, space "
                             "or leading zero)")  # fmt: skip
        ids.append(int(key))
    if dictionary in DICTIONARIES and max(ids) >= DICTIONARIES[dictionary]:
        raise ValueError(f"id {max(ids)} is out of range; {dictionary} has ids 0 to {DICTIONARIES[dictionary] - 1}")
    return ids


def _check_marker(marker: int, corners: np.ndarray) -> None:
    """A marker is a convex quadrilateral facing +y, in OpenCV's corner order: sides of MIN_MARKER_SIDE at least,
    each inside angle within MIN_CORNER_DEGREES of 0° and 180° (as sines of the turns, all positive)."""
    xz = corners[:, [0, 2]]
    edges = np.roll(xz, -1, axis=0) - xz
    lengths = np.hypot(edges[:, 0], edges[:, 1])  # hypot: no underflow of tiny squares
    short = int(np.argmin(lengths))
    if lengths[short] < MIN_MARKER_SIDE:
        raise ValueError(f"marker {marker}: corners {short} and {(short + 1) % 4} are {lengths[short]:.3g} apart; "
                         f"a marker's sides are at least {MIN_MARKER_SIDE:g}")  # fmt: skip
    unit = edges / lengths[:, None]
    following = np.roll(unit, -1, axis=0)
    turns = unit[:, 0] * following[:, 1] - unit[:, 1] * following[:, 0]  # the sine of each corner's turn
    if np.all(turns < 0):
        raise ValueError(f"marker {marker} faces down (its corners turn the other way seen from +y); list them "
                         "top-left, top-right, bottom-right, bottom-left seen from above")  # fmt: skip
    if not np.all(turns >= math.sin(math.radians(MIN_CORNER_DEGREES))):
        raise ValueError(f"marker {marker}: its corners are not a convex quadrilateral with angles between "
                         f"{MIN_CORNER_DEGREES:g}° and {180 - MIN_CORNER_DEGREES:g}° (in order top-left, top-right, "
                         "bottom-right, bottom-left)")  # fmt: skip


def _overlapping(quads: np.ndarray, tolerance: float) -> tuple[int, int] | None:
    """The first pair (i, j) of convex quadrilaterals (N, 4, 2) whose insides overlap by more than ``tolerance``,
    or None: their bounding boxes first, then the separating axes (the edges' normals) of the pairs left."""
    lo, hi = quads.min(axis=1), quads.max(axis=1)
    boxes = np.all((lo[:, None] < hi[None] - tolerance) & (lo[None] < hi[:, None] - tolerance), axis=2)
    first, second = np.nonzero(np.triu(boxes, 1))
    edges = np.roll(quads, -1, axis=1) - quads
    normals = np.stack([-edges[..., 1], edges[..., 0]], axis=-1)
    normals /= np.linalg.norm(normals, axis=-1, keepdims=True)
    for start in range(0, len(first), _PAIRS_AT_ONCE):
        i, j = first[start : start + _PAIRS_AT_ONCE], second[start : start + _PAIRS_AT_ONCE]
        axes = np.concatenate([normals[i], normals[j]], axis=1)  # (P, 8, 2)
        a, b = np.einsum("pad,pcd->pac", axes, quads[i]), np.einsum("pad,pcd->pac", axes, quads[j])
        apart = (a.max(axis=2) <= b.min(axis=2) + tolerance) | (b.max(axis=2) <= a.min(axis=2) + tolerance)
        overlap = np.nonzero(~apart.any(axis=1))[0]
        if len(overlap):
            return int(i[overlap[0]]), int(j[overlap[0]])
    return None


Corner = tuple[Number, Number, Number]


class _BoardFile(InputFile):
    """board.json as Board.save writes it."""

    dictionary: str
    markers: dict[str, tuple[Corner, Corner, Corner, Corner]] = Field(max_length=max(DICTIONARIES.values()))

    @field_validator("dictionary")
    @classmethod
    def _predefined(cls, name: str) -> str:
        dictionary_size(name)
        return name

    @field_validator("markers")
    @classmethod
    def _geometry(cls, markers: dict, info: ValidationInfo) -> dict[int, np.ndarray]:
        """{id: (4, 3) corners}, each marker checked, all on y = 0 (set to 0 exactly), none overlapping."""
        if not markers:
            raise ValueError("no markers; a board has one at least")
        ids = _marker_ids(markers, info.data.get("dictionary"))
        corners = np.array(list(markers.values()), np.float64)  # (N, 4, 3)
        extent = max(float(np.ptp(corners[..., [0, 2]].reshape(-1, 2), axis=0).max()), MIN_MARKER_SIDE)
        off = np.argwhere(np.abs(corners[..., 1]) > PLANE_TOLERANCE * extent)
        if len(off):
            n, k = off[0]
            raise ValueError(f"marker {ids[n]}: corner {k} has y = {corners[n, k, 1]:g}; the board is the plane y = 0 "
                             "(reflets' world: y up), every corner on it")  # fmt: skip
        corners[..., 1] = 0.0
        for marker, quad in zip(ids, corners, strict=True):
            _check_marker(marker, quad)
        pair = _overlapping(corners[..., [0, 2]], PLANE_TOLERANCE * extent)
        if pair is not None:
            raise ValueError(f"markers {ids[pair[0]]} and {ids[pair[1]]} overlap; each marker has its own place")
        return dict(zip(ids, corners, strict=True))


def _check_grid(columns, rows, size, gap, dictionary) -> None:
    """The options of ``reflets ar board`` (Board.grid's arguments), each refused by its option's name."""
    try:
        count = dictionary_size(dictionary)
    except ValueError as exc:
        raise ArgumentError(str(exc), field="--dictionary") from None
    for option, value in (("--columns", columns), ("--rows", rows)):
        if isinstance(value, bool) or not isinstance(value, int | np.integer) or value < 1:
            raise ArgumentError(f"must be a whole number of markers, 1 or more; got {value!r}", field=option)
    if columns * rows > count:
        raise ArgumentError(f"{columns} x {rows} = {columns * rows} markers; {dictionary} has {count} (fewer, or a "
                            "larger dictionary)", field="--columns x --rows")  # fmt: skip
    for option, value, low in (("--size", size, MIN_MARKER_SIDE), ("--gap", gap, 0.0)):
        number = isinstance(value, int | float | np.number) and not isinstance(value, bool)
        if not (number and math.isfinite(value) and low <= value <= MAX_MAGNITUDE):
            raise ArgumentError(f"must be a number from {low:g} to {MAX_MAGNITUDE:g}, got {value!r}", field=option)
    if max(columns, rows) * (size + gap) > MAX_MAGNITUDE:
        raise ArgumentError(f"the board would be {max(columns, rows) * (size + gap):g} units across; at most "
                            f"{MAX_MAGNITUDE:g}", field="--size")  # fmt: skip


@dataclass
class Board:
    dictionary: str
    markers: dict[int, np.ndarray]  # id → (4, 3) corners

    @classmethod
    def grid(cls, columns: int = 5, rows: int = 4, size: float = 0.05, gap: float = 0.0125,
             dictionary: str = "DICT_6X6_250") -> Board:  # fmt: skip
        """Markers of side ``size`` in a grid on y = 0, centred on the origin, ids from 0 row by row (the first
        row at −z: the top of the board's image seen from above, +x to the right)."""
        _check_grid(columns, rows, size, gap, dictionary)
        pitch = size + gap
        x0 = -0.5 * (columns * pitch - gap)
        z0 = -0.5 * (rows * pitch - gap)
        markers = {}
        for r in range(rows):
            for c in range(columns):
                x, z = x0 + c * pitch, z0 + r * pitch
                markers[r * columns + c] = np.array(
                    [[x, 0, z], [x + size, 0, z], [x + size, 0, z + size], [x, 0, z + size]], np.float64
                )
        return cls(dictionary, markers)

    @classmethod
    def load(cls, path: str | Path) -> Board:
        """A board file, checked (:class:`_BoardFile`): any problem is one ArgumentError naming the file."""
        data = read_model(_BoardFile, path, field="--board", what="a board file (board.json)")
        return cls(data.dictionary, data.markers)

    def save(self, path: str | Path) -> Path:
        return write_json(
            path, {"dictionary": self.dictionary, "markers": {str(k): v.tolist() for k, v in self.markers.items()}}
        )

    def cv_dictionary(self):
        cv2 = _aruco()
        try:
            dictionary_size(self.dictionary)
        except ValueError as exc:
            raise ArgumentError(str(exc), field="dictionary") from None
        if not hasattr(cv2.aruco, self.dictionary):
            raise ArgumentError(f"{self.dictionary} is not in this OpenCV ({cv2.__version__}); another dictionary, "
                                "or a newer opencv-contrib-python", field="dictionary")  # fmt: skip
        return cv2.aruco.getPredefinedDictionary(getattr(cv2.aruco, self.dictionary))

    def image(self, pixels_per_unit: float = PIXELS_PER_UNIT, margin: float = 0.02) -> tuple[np.ndarray, np.ndarray]:
        """The board seen from above as a grey image (uint8, white paper, black markers with their white
        border), and the affine map from board (x, z) to its pixel (column, row): a 2 × 3 matrix. Its size is
        checked before it is allocated (a frame's limits: reflets.ar.images), and that of each marker's drawing."""
        from .images import FRAME_LIMITS, fits_a_frame

        cv2 = _aruco()
        dictionary = self.cv_dictionary()
        corners = np.concatenate(list(self.markers.values()))
        lo, hi = corners[:, [0, 2]].min(axis=0) - margin, corners[:, [0, 2]].max(axis=0) + margin
        width, height = (int(v) for v in np.ceil((hi - lo) * pixels_per_unit))
        if not fits_a_frame(width, height):
            raise ArgumentError(f"the board's image would be {width}x{height} pixels at {pixels_per_unit:g} pixels "
                                f"per board unit; {FRAME_LIMITS} (are --size and --gap in metres?)",
                                field="--image")  # fmt: skip
        smallest = dictionary.markerSize + 2  # OpenCV draws a marker's bits and its black border, one pixel each
        for marker, c in self.markers.items():
            side = np.linalg.norm(c[1] - c[0])
            if not np.allclose(c, c[0] + side * np.array([[0, 0, 0], [1, 0, 0], [1, 0, 1], [0, 0, 1.0]])):
                raise ArgumentError(f"marker {marker} is not an axis-aligned square; only a grid board is drawn",
                                    field="--image")  # fmt: skip
            if round(side * pixels_per_unit) < smallest:
                raise ArgumentError(f"marker {marker} would be {round(side * pixels_per_unit)} pixels wide at "
                                    f"{pixels_per_unit:g} pixels per board unit; at least {smallest} to be drawn "
                                    f"(--size ≥ {smallest / pixels_per_unit:g})", field="--image")  # fmt: skip
        image = np.full((height, width), 255, np.uint8)
        to_pixel = np.array(
            [[pixels_per_unit, 0, -lo[0] * pixels_per_unit], [0, pixels_per_unit, -lo[1] * pixels_per_unit]]
        )
        for marker, c in self.markers.items():
            side = int(round(np.linalg.norm(c[1] - c[0]) * pixels_per_unit))
            tile = cv2.aruco.generateImageMarker(dictionary, marker, side)
            col, row = (to_pixel @ np.array([c[0, 0], c[0, 2], 1.0])).round().astype(int)
            image[row : row + side, col : col + side] = tile
        return image, to_pixel
