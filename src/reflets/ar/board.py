"""A marker board: ArUco markers at known 3D corners in the board's frame, which is the world (y up, the board in
the plane y = 0, units of the user's choice — metres below). JSON:
``{"dictionary": "DICT_6X6_250", "markers": {"ID": [[x, y, z] × 4]}}``, corners in OpenCV's order (the marker's
top-left, top-right, bottom-right, bottom-left as its image is drawn)."""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np

from ..arguments import read_json
from ..errors import ArgumentError
from . import write_json


def _aruco():
    try:
        import cv2
    except ImportError:
        raise ArgumentError("augmented reality needs the 'ar' extra: pip install 'reflets[ar]'") from None
    return cv2


@dataclass
class Board:
    dictionary: str
    markers: dict[int, np.ndarray]  # id → (4, 3) corners

    @classmethod
    def grid(cls, columns: int = 5, rows: int = 4, size: float = 0.05, gap: float = 0.0125,
             dictionary: str = "DICT_6X6_250") -> Board:  # fmt: skip
        """Markers of side ``size`` in a grid on y = 0, centred on the origin, ids from 0 row by row (the first
        row at −z: the top of the board's image seen from above, +x to the right)."""
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
        def parse(data: dict) -> Board:
            markers = {int(k): np.asarray(v, np.float64).reshape(4, 3) for k, v in data["markers"].items()}
            return cls(str(data["dictionary"]), markers)

        return read_json(path, "--board", "a board file", parse)

    def save(self, path: str | Path) -> Path:
        return write_json(
            path, {"dictionary": self.dictionary, "markers": {str(k): v.tolist() for k, v in self.markers.items()}}
        )

    def cv_dictionary(self):
        cv2 = _aruco()
        if not hasattr(cv2.aruco, self.dictionary):
            raise ArgumentError(f"unknown ArUco dictionary {self.dictionary!r}", field="board.dictionary")
        return cv2.aruco.getPredefinedDictionary(getattr(cv2.aruco, self.dictionary))

    def image(self, pixels_per_unit: float = 4000.0, margin: float = 0.02) -> tuple[np.ndarray, np.ndarray]:
        """The board seen from above as a grey image (uint8, white paper, black markers with their white
        border), and the affine map from board (x, z) to its pixel (column, row): a 2 × 3 matrix."""
        cv2 = _aruco()
        corners = np.concatenate(list(self.markers.values()))
        lo, hi = corners[:, [0, 2]].min(axis=0) - margin, corners[:, [0, 2]].max(axis=0) + margin
        width, height = np.ceil((hi - lo) * pixels_per_unit).astype(int)
        image = np.full((height, width), 255, np.uint8)
        to_pixel = np.array(
            [[pixels_per_unit, 0, -lo[0] * pixels_per_unit], [0, pixels_per_unit, -lo[1] * pixels_per_unit]]
        )
        dictionary = self.cv_dictionary()
        for marker, c in self.markers.items():
            side = int(round(np.linalg.norm(c[1] - c[0]) * pixels_per_unit))
            tile = cv2.aruco.generateImageMarker(dictionary, marker, side)
            col, row = (to_pixel @ np.array([c[0, 0], c[0, 2], 1.0])).round().astype(int)
            image[row : row + side, col : col + side] = tile
        return image, to_pixel
