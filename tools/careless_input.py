"""Careless and hostile command lines against the newer commands (issue 32): `ar track / calibrate / composite /
run / board`, `highlights`, `edit-highlights`, `view --script`, every command's outputs, and mesh files (a
Draco-compressed glTF, broken OBJ / GLB). Each case is one `reflets` process (``python -m reflets.cli``, stdin
closed, 60 s at most; 30 s for the few that run for ever when mishandled) in a fresh temporary folder holding
only the files it needs, and is checked against issue 32's rule:

- **refused** (bad input): exit status 2, exactly one line on stderr, starting with ``reflets: error:`` and naming
  the file, field or argument the case says (one of the substrings in ``must_mention``), no traceback, and no
  file in the work folder created, changed or removed;
- **accepted** (valid but odd input): exit status 0, the expected output exists, the inputs are unchanged, and
  stderr holds nothing but ``reflets: warning:`` lines;
- **either**: a few cases where refusing and accepting are both sound (2,000 strokes, an empty stroke list, a
  stroke away from the mesh, a wait of 0 frames): judged by the rule of whichever the command did.

Anything else — a traceback, exit 1, a signal (a segmentation fault), a timeout, exit 0 after nonsense, more than
one line on stderr, a file changed — is **mishandled**: printed with the case's name, command, exit status and
the first lines of its stderr; the exit status is then 1.

The inputs are built here, without reflets (whose tree may be half-edited while this runs): boards and camera
files as JSON, views of a 3 × 3 ArUco board with known poses drawn by a homography of its top view (OpenCV),
tiny TOML scenes, strokes, targets, event scripts, a 1-bit 30000² PNG of 110 kB (a decompression bomb), the
Khronos Draco Box (tests/data/gltf, or $REFLETS_ASSETS/gltf). `view` cases that open a window run under
``xvfb-run -a`` (skipped without it); those refused before the window opens run with no display at all, so a
check made only after the window opened shows up as mishandled.

    .venv/bin/python tools/careless_input.py                 # every case, two at a time
    .venv/bin/python tools/careless_input.py --only ar-track --jobs 4 --json /tmp/careless.json
    .venv/bin/python tools/careless_input.py --list          # the cases, not run
"""

from __future__ import annotations

import argparse
import functools
import hashlib
import importlib.util
import io
import itertools
import json
import os
import shlex
import shutil
import signal
import struct
import subprocess
import sys
import tempfile
import threading
import time
import zlib
from collections import Counter
from collections.abc import Callable
from concurrent.futures import ThreadPoolExecutor, as_completed
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

REFLETS = [sys.executable, "-m", "reflets.cli"]
ASSETS = Path(os.environ.get("REFLETS_ASSETS", Path(__file__).resolve().parents[1] / "tests" / "data"))
DRACO_BOX = ASSETS / "gltf" / "Box" / "Box.gltf"  # KHR_draco_mesh_compression, required
SMALL_GLB = ASSETS / "gltf" / "TextureCoordinateTest" / "TextureCoordinateTest.glb"
HAVE_DRACO = importlib.util.find_spec("DracoPy") is not None  # in this interpreter: the venv's
TIMEOUT = 60.0
HANG = 30.0  # cases that run for ever when mishandled (a refusal takes a second)
STDERR_LINES = 6  # of a mishandled case, shown


class Folder:
    """A file-spec value: make a directory (with the listed files in it)."""

    def __init__(self, *names: str):
        self.names = names


#: a file spec's value: text, bytes, a function giving either (built on first use), a Folder, or None (absent)
Content = str | bytes | Callable[[], str | bytes] | Folder | None


@dataclass(frozen=True)
class Case:
    name: str  # "surface/what": the surface is the command (or "outputs", "meshes")
    argv: tuple[str, ...]  # after `reflets`, paths relative to the work folder
    files: dict[str, Content]  # the work folder's content before the run
    expected: str  # "refused" | "accepted" | "either"
    must_mention: tuple[str, ...] = ()  # refused: the error line names one of these
    output: str = ""  # accepted: this file or folder must exist afterwards
    display: bool = False  # opens a window: runs under xvfb-run
    timeout: float = TIMEOUT
    check: Callable[[Path], str | None] | None = field(default=None, compare=False)  # accepted: a problem or None

    @property
    def surface(self) -> str:
        return self.name.split("/", 1)[0]


def refused(name, argv, files, *mention, **kw) -> Case:
    return Case(name, tuple(argv), files, "refused", tuple(mention), **kw)


def accepted(name, argv, files, output, **kw) -> Case:
    return Case(name, tuple(argv), files, "accepted", output=output, **kw)


# --------------------------------------------------------------------------------------------- inputs, cheaply
NAN, INF = float("nan"), float("inf")
W, H = 320, 240  # the camera images
FOCAL = 0.5 * H / np.tan(np.radians(55) / 2)
K_GOOD = [[FOCAL, 0.0, W / 2], [0.0, FOCAL, H / 2], [0.0, 0.0, 1.0]]
EYES = [(0.2, 0.3, 0.4), (-0.25, 0.35, 0.3), (0.0, 0.45, 0.3), (0.3, 0.4, -0.1), (-0.3, 0.4, -0.15)]


def jtext(obj) -> str:
    """JSON as careless tools write it: NaN and Infinity as Python's json module spells them."""
    return json.dumps(obj)


def grid_markers(columns: int = 3, rows: int = 3, size: float = 0.05, gap: float = 0.0125) -> dict[str, list]:
    """reflets.ar.board.Board.grid's corners, ids row by row (OpenCV corner order), on y = 0."""
    pitch = size + gap
    x0, z0 = -0.5 * (columns * pitch - gap), -0.5 * (rows * pitch - gap)
    markers = {}
    for r, c in itertools.product(range(rows), range(columns)):
        x, z = x0 + c * pitch, z0 + r * pitch
        markers[str(r * columns + c)] = [[x, 0, z], [x + size, 0, z], [x + size, 0, z + size], [x, 0, z + size]]
    return markers


def camera(**change) -> dict:
    return {"K": [row[:] for row in K_GOOD], "dist": [0.0] * 5, "size": [W, H], **change}


def camera_k(i: int, j: int, value, **change) -> dict:
    data = camera(**change)
    data["K"][i][j] = value
    return data


def board(**change) -> dict:
    return {"dictionary": "DICT_6X6_250", "markers": grid_markers(), **change}


def without(data: dict, key: str) -> dict:
    return {k: v for k, v in data.items() if k != key}


@functools.cache
def _top_view(dictionary: str = "DICT_6X6_250", ppu: float = 2000.0, margin: float = 0.02):
    import cv2

    aruco = cv2.aruco.getPredefinedDictionary(getattr(cv2.aruco, dictionary))
    markers = {int(k): np.asarray(v, float) for k, v in grid_markers().items()}
    corners = np.concatenate(list(markers.values()))
    lo, hi = corners[:, [0, 2]].min(0) - margin, corners[:, [0, 2]].max(0) + margin
    width, height = np.ceil((hi - lo) * ppu).astype(int)
    image = np.full((height, width), 255, np.uint8)
    to_pixel = np.array([[ppu, 0, -lo[0] * ppu], [0, ppu, -lo[1] * ppu], [0, 0, 1]])
    for marker, c in markers.items():
        side = int(round(np.linalg.norm(c[1] - c[0]) * ppu))
        col, row = (to_pixel @ [c[0, 0], c[0, 2], 1])[:2].round().astype(int)
        image[row : row + side, col : col + side] = cv2.aruco.generateImageMarker(aruco, marker, side)
    return image, to_pixel


def board_view(k: int, size: tuple[int, int] = (W, H)) -> np.ndarray:
    """A grey view (H, W) of the 3 × 3 board from EYES[k] through K_GOOD (scaled to ``size``): the board's plane
    y = 0 is a homography of its top view (OpenCV pose: x right, y down, z forward)."""
    import cv2

    top, to_pixel = _top_view()
    eye = np.asarray(EYES[k], float)
    f = -eye / np.linalg.norm(eye)  # looking at the origin
    s = np.cross(f, [0.0, 1.0, 0.0])
    s /= np.linalg.norm(s)
    R = np.stack([s, -np.cross(s, f), f])
    t = -R @ eye
    K = np.diag([size[0] / W, size[1] / H, 1.0]) @ np.asarray(K_GOOD)
    homography = K @ np.stack([R[:, 0], R[:, 2], t], axis=1) @ np.linalg.inv(to_pixel)
    return cv2.warpPerspective(top, homography, size, flags=cv2.INTER_AREA, borderValue=128)


def png(array: np.ndarray, mode: str = "RGB") -> bytes:
    from PIL import Image

    buffer = io.BytesIO()
    image = Image.fromarray(array)
    (image if mode == "L" else image.convert(mode)).save(buffer, format="PNG")
    return buffer.getvalue()


@functools.cache
def view_png(k: int, size: tuple[int, int] = (W, H), mode: str = "RGB") -> bytes:
    return png(board_view(k, size), mode)


@functools.cache
def view_jpeg(k: int) -> bytes:
    from PIL import Image

    buffer = io.BytesIO()
    Image.fromarray(board_view(k)).convert("RGB").save(buffer, format="JPEG", quality=95)
    return buffer.getvalue()


@functools.cache
def view_png16(k: int) -> bytes:
    from PIL import Image

    buffer = io.BytesIO()
    Image.fromarray(board_view(k).astype(np.uint16) * 257).save(buffer, format="PNG")  # mode I;16
    return buffer.getvalue()


def _chunk(kind: bytes, data: bytes) -> bytes:
    return struct.pack(">I", len(data)) + kind + data + struct.pack(">I", zlib.crc32(kind + data) & 0xFFFFFFFF)


@functools.cache
def bomb_png(side: int = 30000) -> bytes:
    """A valid 1-bit grey PNG of side × side black pixels: 110 kB on disk, 900 M pixels decoded."""
    row = b"\x00" * (1 + (side + 7) // 8)  # filter byte, then the packed bits
    packer = zlib.compressobj(9)
    body = b"".join(packer.compress(row) for _ in range(side)) + packer.flush()
    header = struct.pack(">IIBBBBB", side, side, 1, 0, 0, 0, 0)
    return b"\x89PNG\r\n\x1a\n" + _chunk(b"IHDR", header) + _chunk(b"IDAT", body) + _chunk(b"IEND", b"")


def truncated(content: Callable[[], bytes], fraction: float = 0.5) -> Callable[[], bytes]:
    return lambda: (data := content())[: int(len(data) * fraction)]


def asset(path: Path) -> Callable[[], bytes]:
    return lambda: path.read_bytes()


def glb_cut_in_geometry(path: Path) -> bytes:
    """A GLB cut 300 bytes into its binary chunk: the header still says the whole length, the first meshes'
    indices and positions are cut (a cut in a texture alone is harmless once a scene replaces the materials)."""
    data = path.read_bytes()
    json_length = struct.unpack("<I", data[12:16])[0]
    return data[: 20 + json_length + 8 + 300]


def npz(**arrays) -> Callable[[], bytes]:
    def build() -> bytes:
        buffer = io.BytesIO()
        np.savez(buffer, **arrays)
        return buffer.getvalue()

    return build


def npy(array) -> Callable[[], bytes]:
    def build() -> bytes:
        buffer = io.BytesIO()
        np.save(buffer, array)
        return buffer.getvalue()

    return build


#: tests/test_outputs.py's scene: 8 × 6 pixels, a plane under a point light
SCENE = """
[camera]
position = [0, 2, 4]
look_at = [0, 0, 0]
fov_y = 40
size = [8, 6]

[materials.m]
type = "lambert"
albedo = [0.5, 0.5, 0.5]

[[mesh]]
shape = "plane"
size = [2, 2]
material = "m"

[[light]]
type = "point"
position = [0, 2, 0]
intensity = [5, 5, 5]
"""

#: the editing commands' scene: an anisotropic sphere (non-degenerate ℓ) and a plane of 9 × 9 = 81 vertices
EDIT_SCENE = """
[camera]
position = [0, 1, 4]
look_at = [0, 0, 0]
fov_y = 40
size = [32, 24]

[materials.m]
type = "ward"
alpha = [0.1, 0.3]

[[mesh]]
shape = "sphere"
segments = [24, 12]
material = "m"

[[mesh]]
shape = "plane"
size = [2, 2]
segments = [8, 8]
material = "m"
transform = { translate = [0, -1.2, 0] }

[[light]]
type = "point"
position = [2, 3, 2]
intensity = [1, 1, 1]

[[light]]
type = "quad"
corners = [[-1, 3, 1], [1, 3, 1], [-1, 3, -1]]
radiance = [1, 1, 1]
"""
PLANE_VERTICES = 81

#: the AR tests' virtual object: a clay sphere standing on the board
AR_OBJECTS = """
[camera]
position = [0, 1, 1]
look_at = [0, 0, 0]

[materials.clay]
type = "lambert"
albedo = [0.7, 0.5, 0.35]

[[mesh]]
shape = "sphere"
radius = 0.05
segments = [32, 16]
transform = { translate = [0, 0.05, 0] }
material = "clay"
"""


def box_scene(material: bool) -> str:
    """A scene whose mesh is the Draco Box (copied beside it)."""
    head = '[camera]\nposition = [2, 1.5, 3]\nlook_at = [0, 0, 0]\nfov_y = 40\nsize = [16, 12]\n\n'
    mat = '[materials.m]\ntype = "lambert"\nalbedo = [0.6, 0.6, 0.6]\n\n' if material else ""
    mesh = '[[mesh]]\nfile = "Box.gltf"\n' + ('material = "m"\n' if material else "") + "\n"
    light = '[[light]]\ntype = "point"\nposition = [2, 3, 2]\nintensity = [5, 5, 5]\n'
    return head + mat + mesh + light


def mesh_scene(file: str) -> str:
    """SCENE with its plane replaced by a mesh file; a glTF keeps its own materials (replacing them warns)."""
    scene = SCENE.replace('shape = "plane"\nsize = [2, 2]', f'file = "{file}"')
    return scene.replace('material = "m"\n', "") if file.endswith((".glb", ".gltf")) else scene


STROKE = {"tool": "bend", "centre": [0.2, 0.35, 0.9], "radius": 0.4, "stroke": [0.0, 0.3, 0.0]}


def stroke(**change) -> dict:
    return {**STROKE, **change}


def targets(count: int = PLANE_VERTICES, free: int = 20, **change) -> Callable[[], bytes]:
    """Targets for mesh[1] (the plane): ℓ* along x on the first ``free`` vertices."""
    ell = np.zeros((count, 3))
    ell[:free, 0] = 1.0
    mask = np.zeros(count, bool)
    mask[:free] = True
    return npz(**{"ell": ell, "mask": mask, **change})


# --------------------------------------------------------------------------------------------- the cases
def ar_files(**change: Content) -> dict[str, Content]:
    files: dict[str, Content] = {
        "camera.json": jtext(camera()),
        "board.json": jtext(board()),
        "objects.toml": AR_OBJECTS,
        **{f"v{k}.png": functools.partial(view_png, k) for k in range(4)},
    }
    files.update(change)
    return files


AR = ("--intrinsics", "camera.json", "--board", "board.json")
TRACK = ("ar", "track", "v0.png", "v1.png", *AR, "-o", "poses.json")
CALIBRATE = ("ar", "calibrate", "v0.png", "v1.png", "v2.png", "v3.png", "--board", "board.json", "-o", "cam.json")
COMPOSITE = ("ar", "composite", "objects.toml", "--background", "v0.png", "--capture", "v1.png", *AR, "-o", "out.png")
RUN = ("ar", "run", "objects.toml", "v0.png", "v1.png", *AR, "-o", "frames")
AR_COMMANDS = {  # surface → (argv, output)
    "ar-track": (TRACK, "poses.json"),
    "ar-calibrate": (CALIBRATE, "cam.json"),
    "ar-composite": (COMPOSITE, "out.png"),
    "ar-run": (RUN, "frames"),
}

K_ROWS = camera(K=[K_GOOD[0], K_GOOD[0], K_GOOD[2]])
CAMERA_FILES: dict[str, Content] = {  # camera.json, careless
    "fx-nan": jtext(camera_k(0, 0, NAN)),
    "fx-zero": jtext(camera_k(0, 0, 0.0)),
    "focal-zero": jtext(camera(K=[[0, 0, W / 2], [0, 0, H / 2], [0, 0, 1]])),
    "fx-negative": jtext(camera_k(0, 0, -FOCAL)),
    "fy-negative": jtext(camera_k(1, 1, -FOCAL)),
    "focal-1e300": jtext(camera(K=[[1e300, 0, W / 2], [0, 1e300, H / 2], [0, 0, 1]])),
    "fx-infinity": jtext(camera_k(0, 0, INF)),
    "K-singular": jtext(K_ROWS),
    "K-not-upper-triangular": jtext(camera_k(1, 0, 40.0)),
    "K-bottom-row": jtext(camera_k(2, 0, 0.01)),
    "K22-is-2": jtext(camera_k(2, 2, 2.0)),
    "K22-is-0": jtext(camera_k(2, 2, 0.0)),
    "K-2x3": jtext(camera(K=K_GOOD[:2])),
    "K-strings": jtext(camera(K=[[str(v) for v in row] for row in K_GOOD])),
    "K-null": jtext(camera(K=None)),
    "K-booleans": jtext(camera(K=[[True, False, True], [False, True, True], [False, False, True]])),
    "size-zero": jtext(camera(size=[0, 0])),
    "size-negative": jtext(camera(size=[-W, H])),
    "size-fractional": jtext(camera(size=[W + 0.5, H])),
    "size-strings": jtext(camera(size=[str(W), str(H)])),
    "size-three-items": jtext(camera(size=[W, H, 3])),
    "size-1e9": jtext(camera(size=[10**9, 10**9])),
    "dist-length-6": jtext(camera(dist=[0.0] * 6)),
    "dist-length-8-rational": jtext(camera(dist=[0.0] * 5 + [0.1, 0.0, 0.0])),
    "fov-179-degrees": jtext(camera(K=[[1.0, 0, W / 2], [0, 1.0, H / 2], [0, 0, 1]])),
    "principal-point-far-outside": jtext(camera_k(0, 2, 10.0 * W)),
    "dist-nan": jtext(camera(dist=[NAN, 0, 0, 0, 0])),
    "dist-1e300": jtext(camera(dist=[1e300, 0, 0, 0, 0])),
    "dist-string": jtext(camera(dist="none")),
    "missing-K": jtext(without(camera(), "K")),
    "missing-size": jtext(without(camera(), "size")),
    "extra-key": jtext(camera(fov_y=55)),
    "list-not-object": jtext([K_GOOD, [0] * 5, [W, H]]),
    "empty-file": "",
    "directory": Folder(),
    "absent": None,
    "duplicate-key": f'{{"K": {json.dumps(K_GOOD)}, "K": {json.dumps(K_ROWS["K"])}, "dist": [0, 0, 0, 0, 0], '
    f'"size": [{W}, {H}]}}',
    "not-utf8": b"\xff\xfe\x00\x81 not json",
    "truncated-json": jtext(camera())[:40],
}

_ids = grid_markers()
BOARD_FILES: dict[str, Content] = {  # board.json, careless
    "markers-empty-list": jtext(board(markers=[])),
    "markers-empty-object": jtext(board(markers={})),
    "markers-null": jtext(board(markers=None)),
    "markers-list-of-corners": jtext(board(markers=list(_ids.values()))),
    "duplicate-ids-0-and-01": jtext(board(markers={**_ids, "01": _ids["1"]} | {"0": _ids["0"]})),
    "duplicate-json-key": jtext(board())[:-2] + ', "0": ' + json.dumps(_ids["1"]) + "}}",
    "coincident-corners": jtext(board(markers={**_ids, "4": [[0, 0, 0]] * 4})),
    "corners-1e300": jtext(board(markers={**_ids, "4": [[1e300, 0, 1e300]] + _ids["4"][1:]})),
    "corners-nan": jtext(board(markers={**_ids, "4": [[NAN, 0, 0]] + _ids["4"][1:]})),
    "three-corners": jtext(board(markers={**_ids, "4": _ids["4"][:3]})),
    "two-coordinates": jtext(board(markers={**_ids, "4": [c[::2] for c in _ids["4"]]})),
    "corner-strings": jtext(board(markers={**_ids, "4": [[str(v) for v in c] for c in _ids["4"]]})),
    "dictionary-ArucoDetector": jtext(board(dictionary="ArucoDetector")),
    "dictionary-getPredefinedDictionary": jtext(board(dictionary="getPredefinedDictionary")),
    "dictionary-unknown": jtext(board(dictionary="DICT_FOO")),
    "dictionary-number": jtext(board(dictionary=10)),
    "dictionary-null": jtext(board(dictionary=None)),
    "id-beyond-dictionary": jtext(board(dictionary="DICT_4X4_50", markers={"60": _ids["4"]})),
    "negative-id": jtext(board(markers={**_ids, "-1": _ids["4"]})),
    "id-not-a-number": jtext(board(markers={**_ids, "a": _ids["4"]})),
    "id-fractional": jtext(board(markers={**_ids, "1.5": _ids["4"]})),
    "missing-dictionary": jtext(without(board(), "dictionary")),
    "missing-markers": jtext(without(board(), "markers")),
    "extra-key": jtext(board(units="m")),
    "list-not-object": jtext(["DICT_6X6_250", _ids]),
    "empty-file": "",
    "directory": Folder(),
    "absent": None,
    "not-utf8": b"\xff\xd8\xff\xe0 a jpeg?",
}

IMAGE_FILES: dict[str, Content] = {  # one camera image, careless
    "image-absent": None,
    "image-directory": Folder(),
    "image-text-named-png": "this is not an image\n",
    "image-truncated-png": truncated(functools.partial(view_png, 1)),
    "image-empty-file": b"",
    "image-decompression-bomb": bomb_png,
}

ODD_CAMERAS = {  # accepted by ar track
    "ok-principal-point-off-centre": camera(K=[[FOCAL, 0, 0.3 * W], [0, FOCAL, 0.62 * H], [0, 0, 1]]),
    "ok-integer-K": camera(K=[[int(FOCAL), 0, W // 2], [0, int(FOCAL), H // 2], [0, 0, 1]]),
    "ok-small-distortion": camera(dist=[0.01, -0.002, 0.0, 0.0, 0.0]),
    "ok-no-dist-key": without(camera(), "dist"),
    "ok-dist-length-4": camera(dist=[0.01, 0.0, 0.0, 0.0]),  # OpenCV's k1 k2 p1 p2
    "ok-dist-length-8-zeros": camera(dist=[0.01, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0]),
}
ODD_BOARDS = {  # accepted by ar track
    "ok-single-marker-board": board(markers={"4": _ids["4"]}),
    "ok-board-of-unseen-marker": board(markers={"200": _ids["4"]}),
    "ok-other-dictionary": board(dictionary="DICT_4X4_50"),
}


#: `ar run` reads camera.json and board.json as `ar composite` does: a sample of the variants, to save time
RUN_SAMPLE = {"fx-nan", "focal-zero", "K-singular", "K22-is-2", "size-zero", "dist-length-6", "missing-K", "directory",
              "duplicate-key", "empty-file", "markers-empty-object", "duplicate-ids-0-and-01", "coincident-corners",
              "dictionary-ArucoDetector", "id-beyond-dictionary", "absent"}  # fmt: skip


def ar_cases() -> list[Case]:
    cases = []
    for surface, (argv, output) in AR_COMMANDS.items():
        cameras, boards = CAMERA_FILES, BOARD_FILES
        if surface == "ar-run":
            cameras = {k: v for k, v in CAMERA_FILES.items() if k in RUN_SAMPLE}
            boards = {k: v for k, v in BOARD_FILES.items() if k in RUN_SAMPLE}
        cases.append(accepted(f"{surface}/ok-baseline", argv, ar_files(), output))
        if surface != "ar-calibrate":  # calibrate takes no intrinsics
            for what, content in cameras.items():
                cases.append(refused(f"{surface}/camera-{what}", argv, ar_files(**{"camera.json": content}),
                                     "camera.json"))  # fmt: skip
            cases.append(refused(f"{surface}/camera-size-mismatch", argv,
                                 ar_files(**{"camera.json": jtext(camera(size=[640, 480]))}),
                                 "camera.json", "v0.png", "v1.png", "640x480"))  # fmt: skip
        for what, content in boards.items():
            cases.append(refused(f"{surface}/board-{what}", argv, ar_files(**{"board.json": content}), "board.json"))
        for what, content in IMAGE_FILES.items():
            cases.append(refused(f"{surface}/{what}", argv, ar_files(**{"v1.png": content}), "v1.png"))
    for what, content in IMAGE_FILES.items():
        cases.append(refused(f"ar-composite/background-{what}", COMPOSITE, ar_files(**{"v0.png": content}), "v0.png"))

    for what, data in ODD_CAMERAS.items():
        cases.append(accepted(f"ar-track/{what}", TRACK, ar_files(**{"camera.json": jtext(data)}), "poses.json"))
    for what, data in ODD_BOARDS.items():
        cases.append(accepted(f"ar-track/{what}", TRACK, ar_files(**{"board.json": jtext(data)}), "poses.json"))
    odd_images = {"ok-grey-png": functools.partial(view_png, 1, (W, H), "L"), "ok-jpeg-named-png": lambda: view_jpeg(1),
                  "ok-16-bit-png": lambda: view_png16(1), "ok-rgba-png": functools.partial(view_png, 1, (W, H), "RGBA"),
                  "ok-no-board-in-view": lambda: png(np.full((H, W), 128, np.uint8))}  # fmt: skip
    for what, content in odd_images.items():
        cases.append(accepted(f"ar-track/{what}", TRACK, ar_files(**{"v1.png": content}), "poses.json"))
    cases += [
        accepted("ar-composite/ok-principal-point-off-centre", COMPOSITE,
                 ar_files(**{"camera.json": jtext(ODD_CAMERAS["ok-principal-point-off-centre"])}), "out.png"),
        accepted("ar-calibrate/ok-five-views", (*CALIBRATE[:6], "v4.png", *CALIBRATE[6:]),
                 ar_files(**{"v4.png": functools.partial(view_png, 4)}), "cam.json"),
        refused("ar-calibrate/images-of-two-sizes", CALIBRATE,
                ar_files(**{"v3.png": functools.partial(view_png, 3, (W // 2, H // 2))}), "v3.png"),
        refused("ar-calibrate/two-views-only", CALIBRATE[:4] + CALIBRATE[6:], ar_files(), "views", "images"),
        refused("ar-calibrate/non-planar-board", CALIBRATE,
                ar_files(**{"board.json": jtext(board(markers={**_ids, "4": [[x, 0.02, z] for x, _, z in _ids["4"]]}))
                            }), "board.json", "--board", "planar"),
        refused("ar-composite/no-board-in-background", COMPOSITE,
                ar_files(**{"v0.png": lambda: png(np.full((H, W), 128, np.uint8))}), "v0.png"),
        refused("ar-composite/objects-empty-toml", COMPOSITE, ar_files(**{"objects.toml": ""}), "objects.toml"),
        refused("ar-composite/objects-absent", COMPOSITE, ar_files(**{"objects.toml": None}), "objects.toml"),
        refused("ar-composite/capture-and-environment", (*COMPOSITE, "--environment", "v2.png"), ar_files(),
                "--environment", "--capture"),
        refused("ar-composite/environment-absent", COMPOSITE[:5] + COMPOSITE[7:] + ("--environment", "sky.hdr"),
                ar_files(), "sky.hdr"),
        refused("ar-composite/environment-text", COMPOSITE[:5] + COMPOSITE[7:] + ("--environment", "sky.hdr"),
                ar_files(**{"sky.hdr": "not an image"}), "sky.hdr"),
        refused("ar-composite/method-unknown", (*COMPOSITE, "--method", "nosuch"), ar_files(), "nosuch", "--method"),
    ]
    for option, values in (("--supersample", ("0", "9", "-1")), ("--radius", ("0", "nan", "-1", "inf"))):
        for value in values:
            for surface, argv in (("ar-composite", COMPOSITE), ("ar-run", RUN)):
                cases.append(refused(f"{surface}/{option[2:]}-{value}", (*argv, option, value), ar_files(), option))
    run_o = RUN[:-1]  # ... -o, the output next
    no_inputs = (RUN[:3], RUN[5:])
    cases += [
        refused("ar-run/webcam--1", (*no_inputs[0], *no_inputs[1], "--webcam", "-1"), ar_files(), "--webcam"),
        refused("ar-run/webcam-99999", (*no_inputs[0], *no_inputs[1], "--webcam", "99999"), ar_files(), "--webcam"),
        refused("ar-run/webcam-0-no-camera-here", (*no_inputs[0], *no_inputs[1], "--webcam", "0"), ar_files(),
                "--webcam", "camera 0"),
        refused("ar-run/webcam-and-files", (*RUN, "--webcam", "0"), ar_files(), "--webcam"),
        refused("ar-run/no-input", (*no_inputs[0], *no_inputs[1]), ar_files(), "input"),
        refused("ar-run/frames-0", (*RUN, "--frames", "0"), ar_files(), "--frames"),
        refused("ar-run/frames--3", (*RUN, "--frames", "-3"), ar_files(), "--frames"),
        refused("ar-run/video-garbage", (*no_inputs[0], "clip.mp4", *no_inputs[1]),
                ar_files(**{"clip.mp4": b"\x00\x00\x00\x18ftypmp42 garbage"}), "clip.mp4"),
        refused("ar-run/video-empty", (*no_inputs[0], "clip.avi", *no_inputs[1]), ar_files(**{"clip.avi": b""}),
                "clip.avi"),
        accepted("ar-run/ok-frames-1", (*RUN, "--frames", "1"), ar_files(), "frames"),
        accepted("ar-run/ok-avi", (*run_o, "out.avi"), ar_files(), "out.avi"),
    ]
    return cases


def ar_board_cases() -> list[Case]:
    base = ("ar", "board", "-o", "board.json", "--columns", "2", "--rows", "2")
    cases = [accepted("ar-board/ok-baseline", (*base, "--image", "board.png"), {}, "board.json"),
             accepted("ar-board/ok-single-marker", ("ar", "board", "-o", "board.json", "--columns", "1", "--rows", "1"),
                      {}, "board.json"),
             accepted("ar-board/ok-every-id-of-DICT_4X4_50", ("ar", "board", "-o", "board.json", "--columns", "10",
                      "--rows", "5", "--dictionary", "DICT_4X4_50"), {}, "board.json")]  # fmt: skip
    bad = [("--columns", "0"), ("--columns", "-2"), ("--rows", "-1"), ("--rows", "0"), ("--size", "0"),
           ("--size", "nan"), ("--size", "inf"), ("--size", "-1"), ("--size", "1e300"), ("--gap", "-1"),
           ("--gap", "nan"), ("--gap", "inf"), ("--gap", "-0.05"), ("--dictionary", "DICT_FOO"),
           ("--dictionary", "ArucoDetector"), ("--dictionary", "getPredefinedDictionary"),
           ("--dictionary", "")]  # fmt: skip
    for option, value in bad:
        mention = ("dictionary", value) if option == "--dictionary" else (option,)
        cases.append(refused(f"ar-board/{option[2:]}-{value or 'empty'}", (*base, option, value), {}, *mention))
        if option in ("--size", "--gap"):
            cases.append(refused(f"ar-board/{option[2:]}-{value}-with-image",
                                 (*base, option, value, "--image", "board.png"), {}, option))  # fmt: skip
    cases += [
        refused("ar-board/1000x1000", ("ar", "board", "-o", "board.json", "--columns", "1000", "--rows", "1000"), {},
                "--columns", "--rows", "--dictionary", "markers", timeout=HANG),
        refused("ar-board/1000x1000-with-image", ("ar", "board", "-o", "board.json", "--columns", "1000", "--rows",
                "1000", "--image", "board.png"), {}, "--columns", "--rows", "--dictionary", "markers", timeout=HANG),
        refused("ar-board/more-markers-than-DICT_4X4_50", (*base[:4], "--columns", "10", "--rows", "6",
                "--dictionary", "DICT_4X4_50"), {}, "--columns", "--rows", "--dictionary", "DICT_4X4_50"),
    ]  # fmt: skip
    return cases


def output_cases() -> list[Case]:
    """Every command's outputs: an existing file, an input, a missing folder, a directory, a wrong extension."""
    scene = {"scene.toml": SCENE}
    edit = {"scene.toml": EDIT_SCENE, "strokes.json": jtext([STROKE]), "targets.npz": targets()}
    old = b"the user's own file"
    commands = {  # name → (argv before the output, output option, good output, files, inputs that are files)
        "render": (("render", "scene.toml", "--method", "normal"), "-o", "out.exr", scene, ["scene.toml"]),
        "export-gltf": (("export-gltf", "scene.toml"), "-o", "out.glb", scene, ["scene.toml"]),
        "reference": (("reference", "scene.toml", "--spp", "1", "--size", "4x3", "-q", "--workers", "1"), "-o",
                      "out.exr", scene, ["scene.toml"]),
        "highlights": (("highlights", "scene.toml", "--mesh", "0"), "-o", "out.npz", edit, ["scene.toml"]),
        "edit-highlights": (("edit-highlights", "scene.toml", "--mesh", "0", "--strokes", "strokes.json"), "-o",
                            "out.npz", edit, ["scene.toml", "strokes.json"]),
        "edit-highlights-targets": (("edit-highlights", "scene.toml", "--mesh", "1", "--targets", "targets.npz",
                                     "--iterations", "2"), "-o", "out.npz", edit, ["targets.npz", "scene.toml"]),
        "ar-board": (("ar", "board", "--columns", "2", "--rows", "2"), "-o", "out.json", {}, []),
        "ar-board-image": (("ar", "board", "-o", "b.json", "--columns", "2", "--rows", "2"), "--image", "out.png", {},
                           []),
        "ar-track": (TRACK[:-2], "-o", "out.json", ar_files(), ["camera.json", "board.json", "v0.png"]),
        "ar-calibrate": (CALIBRATE[:-2], "-o", "out.json", ar_files(), ["board.json", "v0.png"]),
        "ar-composite": (COMPOSITE[:-2], "-o", "out.png", ar_files(),
                         ["v0.png", "v1.png", "camera.json", "board.json", "objects.toml"]),
        "compare": (("compare", "a.png", "b.png"), "--diff", "out.png",
                    {"a.png": functools.partial(view_png, 0), "b.png": functools.partial(view_png, 1)},
                    ["a.png", "b.png"]),
        "view-screenshot": (("view", "scene.toml", "--frames", "1"), "--screenshot", "out.png", scene, ["scene.toml"]),
        "view-save-scene": (("view", "scene.toml", "--frames", "1"), "--save-scene", "out.toml", scene,
                            ["scene.toml"]),
        "view-stats": (("view", "scene.toml", "--frames", "1"), "--stats", "out.json", scene, ["scene.toml"]),
    }  # fmt: skip
    cases = []
    for name, (argv, option, out, files, inputs) in commands.items():
        ext = Path(out).suffix
        view = name.startswith("view")
        cases.append(refused(f"outputs/{name}-existing", (*argv, option, out), {**files, out: old}, out, display=view))
        cases.append(accepted(f"outputs/{name}-existing-overwrite", (*argv, option, out, "--overwrite"),
                              {**files, out: old}, out, display=view,
                              check=lambda work, out=out: "the old file is still there"
                              if (work / out).read_bytes() == old else None))  # fmt: skip
        for source in inputs:
            cases.append(refused(f"outputs/{name}-is-input-{source}", (*argv, option, source, "--overwrite"), files,
                                 source, display=view))  # fmt: skip
        cases.append(refused(f"outputs/{name}-missing-folder", (*argv, option, f"missing/dir/x{ext}"), files,
                             "missing", display=view))  # fmt: skip
        if name != "reference":  # reference: an existing folder takes a batch (STEM.exr per scene)
            folder = f"folder{ext}"
            cases.append(refused(f"outputs/{name}-is-a-directory", (*argv, option, folder),
                                 {**files, folder: Folder("keep.txt")}, folder, display=view))  # fmt: skip
        cases.append(refused(f"outputs/{name}-wrong-extension", (*argv, option, "out.txt"), files, "out.txt",
                             display=view))  # fmt: skip
    cases += [
        refused("outputs/ar-board-image-not-png", ("ar", "board", "-o", "new.json", "--image", "bad.txt"), {},
                "bad.txt", "--image"),
        refused("outputs/ar-board-image-is-the-json", ("ar", "board", "-o", "b.png", "--image", "b.png",
                                                       "--overwrite"), {}, "b.png"),
        refused("outputs/ar-run-existing-mp4", (*RUN[:-1], "out.mp4"), ar_files(**{"out.mp4": old}), "out.mp4"),
        refused("outputs/ar-run-existing-folder", (*RUN[:-1], "frames"), ar_files(**{"frames": Folder("mine.txt")}),
                "frames"),
        accepted("outputs/ar-run-existing-folder-overwrite", (*RUN[:-1], "frames", "--overwrite"),
                 ar_files(**{"frames": Folder("frame_00000.png")}), "frames",
                 check=lambda work: "frames/frame_00000.png not replaced"
                 if (work / "frames" / "frame_00000.png").read_bytes().startswith(b"the user") else None),
        accepted("outputs/reference-into-existing-folder", ("reference", "scene.toml", "--spp", "1", "--size", "4x3",
                 "-q", "--workers", "1", "-o", "refs"), {**scene, "refs": Folder()}, "refs/scene.exr"),
        refused("outputs/ar-run-missing-folder", (*RUN[:-1], "missing/out.mp4"), ar_files(), "missing"),
        refused("outputs/ar-run-is-input-image", (*RUN[:-1], "v0.png", "--overwrite"), ar_files(), "v0.png"),
        refused("outputs/ar-run-wrong-extension", (*RUN[:-1], "out.txt"), ar_files(), "out.txt"),
        refused("outputs/ar-run-is-input-video", ("ar", "run", "objects.toml", "clip.avi", *AR, "-o", "clip.avi",
                                                  "--overwrite"),
                ar_files(**{"clip.avi": b"RIFF"}), "clip.avi"),
        refused("outputs/reference-stderr-existing", ("reference", "scene.toml", "--spp", "1", "--size", "4x3", "-q",
                                                      "--workers", "1", "-o", "out.exr"),
                {**scene, "out.stderr.exr": old}, "out.stderr.exr"),
        refused("outputs/view-save-scene-is-scene", ("view", "scene.toml", "--frames", "1", "--save-scene",
                                                     "scene.toml", "--overwrite"), scene, "scene.toml"),
        refused("outputs/view-stats-is-script", ("view", "scene.toml", "--frames", "1", "--script", "s.json",
                                                      "--stats", "s.json", "--overwrite"),
                {**scene, "s.json": "[]"}, "s.json"),
        refused("outputs/render-is-mesh-file", ("render", "mesh.toml", "-o", "m.obj", "--overwrite"),
                {"mesh.toml": mesh_scene("m.obj"), "m.obj": "v 0 0 0\nv 1 0 0\nv 0 0 1\nf 1 2 3\n"}, "m.obj", "out"),
        refused("outputs/render-is-environment-map", ("render", "env.toml", "-o", "env.npy", "--overwrite"),
                {"env.toml": SCENE + '\n[[light]]\ntype = "environment"\nfile = "env.npy"\n',
                 "env.npy": npy(np.full((8, 16, 3), 0.5, np.float32))}, "env.npy"),
    ]  # fmt: skip
    return cases


def edit_cases() -> list[Case]:
    files = {"scene.toml": EDIT_SCENE, "strokes.json": jtext([STROKE])}
    argv = ("edit-highlights", "scene.toml", "--mesh", "0", "--strokes", "strokes.json", "-o", "u.npz")
    targ = ("edit-highlights", "scene.toml", "--mesh", "1", "--targets", "targets.npz", "--iterations", "3",
            "-o", "u.npz")  # fmt: skip
    tfiles = {"scene.toml": EDIT_SCENE, "targets.npz": targets()}
    v = PLANE_VERTICES
    cases = [
        accepted("edit-highlights/ok-strokes", argv, files, "u.npz"),
        accepted("edit-highlights/ok-targets", targ, tfiles, "u.npz"),
        accepted("edit-highlights/ok-iterations-1", (*argv, "--iterations", "1"), files, "u.npz"),
        accepted("edit-highlights/ok-tiny-radius", argv, {**files, "strokes.json": jtext([stroke(radius=1e-4)])},
                 "u.npz"),
        accepted("edit-highlights/ok-expand-then-bend", argv,
                 {**files, "strokes.json": jtext([stroke(tool="expand"), STROKE])}, "u.npz"),
        accepted("edit-highlights/ok-light-0", (*argv, "--light", "0"), files, "u.npz"),
        Case("edit-highlights/2000-strokes", argv, {**files, "strokes.json": jtext([STROKE] * 2000)}, "either",
             ("strokes.json", "strokes"), output="u.npz", timeout=HANG),
        Case("edit-highlights/empty-stroke-list", argv, {**files, "strokes.json": "[]"}, "either",
             ("strokes.json", "strokes"), output="u.npz"),
        Case("edit-highlights/stroke-far-from-the-mesh", argv,
             {**files, "strokes.json": jtext([stroke(centre=[100.0, 100.0, 100.0])])}, "either",
             ("strokes.json", "strokes[0]"), output="u.npz"),
    ]
    bad_strokes = {  # what → (strokes, a substring the error must hold)
        "tool-list": ([stroke(tool=["bend"])], "tool"),
        "tool-unknown": ([stroke(tool="smudge")], "tool"),
        "tool-null": ([stroke(tool=None)], "tool"),
        "radius-string": ([stroke(radius="0.4")], "radius"),
        "radius-null": ([stroke(radius=None)], "radius"),
        "radius-zero": ([stroke(radius=0)], "radius"),
        "radius-negative": ([stroke(radius=-0.4)], "radius"),
        "radius-nan": ([stroke(radius=NAN)], "strokes.json"),  # a NaN literal: not JSON at all
        "radius-infinity": ([stroke(radius=INF)], "strokes.json"),
        "radius-true": ([stroke(radius=True)], "radius"),
        "radius-list": ([stroke(radius=[0.4])], "radius"),
        "centre-2-items": ([stroke(centre=[0.2, 0.35])], "centre"),
        "centre-strings": ([stroke(centre=["0.2", "0.35", "0.9"])], "centre"),
        "centre-nan": ([stroke(centre=[NAN, 0.35, 0.9])], "strokes.json"),
        "centre-1e300": ([stroke(centre=[1e300, 0.35, 0.9])], "centre"),
        "stroke-zero-vector": ([stroke(stroke=[0.0, 0.0, 0.0])], "stroke"),
        "stroke-4-items": ([stroke(stroke=[0.0, 0.3, 0.0, 1.0])], "stroke"),
        "stroke-null": ([stroke(stroke=None)], "stroke"),
        "missing-key": ([without(STROKE, "radius")], "radius"),
        "extra-key": ([stroke(pressure=0.5)], "pressure"),
        "second-stroke-bad": ([STROKE, stroke(radius=-1)], "strokes[1]"),
        "not-a-list": (STROKE, "strokes.json"),
        "list-of-numbers": ([1, 2, 3], "strokes[0]"),
    }
    for what, (content, mention) in bad_strokes.items():
        cases.append(refused(f"edit-highlights/{what}", argv, {**files, "strokes.json": jtext(content)}, mention))
    raw_strokes = {"empty-file": "", "directory": Folder(), "absent": None,
                   "nested-100000": "[" * 100000 + "]" * 100000,
                   "duplicate-key": '[{"tool": "bend", "tool": "expand", "centre": [0, 0, 1], "radius": 0.4, '
                                    '"stroke": [0, 0.3, 0]}]'}  # fmt: skip
    for what, content in raw_strokes.items():
        cases.append(refused(f"edit-highlights/strokes-{what}", argv, {**files, "strokes.json": content},
                             "strokes.json"))  # fmt: skip
    options = {
        "iterations--5": ("--iterations", "-5"),
        "iterations-0": ("--iterations", "0"),
        "mesh-99": ("--mesh", "99"),
        "mesh--1": ("--mesh", "-1"),
        "light-99": ("--light", "99"),
        "light--1": ("--light", "-1"),
        "light-quad": ("--light", "1"),
    }
    for what, (option, value) in options.items():
        new = list(argv)
        if option in new:
            new[new.index(option) + 1] = value
        else:
            new += [option, value]
        cases.append(refused(f"edit-highlights/{what}", new, files, option))
    cases += [
        refused("edit-highlights/iterations-1e9", (*argv, "--iterations", "1000000000"), files, "--iterations",
                timeout=HANG),
        refused("edit-highlights/targets-and-strokes", (*argv, "--targets", "targets.npz"), {**files, **tfiles},
                "--targets", "--strokes"),
        refused("edit-highlights/neither-targets-nor-strokes", argv[:4] + argv[6:], files, "--targets", "--strokes"),
    ]
    bad_targets: dict[str, Content] = {
        "npy": npy(np.zeros((v, 3))),
        "nan": targets(ell=np.full((v, 3), NAN)),
        "infinity": targets(ell=np.full((v, 3), INF)),
        "1e300": targets(ell=np.full((v, 3), 1e300)),
        "complex": targets(ell=np.ones((v, 3), complex)),
        "strings": targets(ell=np.full((v, 3), "x")),
        "wrong-shape": targets(ell=np.zeros((v, 2))),
        "transposed": targets(ell=np.zeros((3, v))),
        "wrong-vertex-count": targets(count=v - 1),
        "mask-wrong-length": targets(mask=np.ones(v + 5, bool)),
        "mask-2d": targets(mask=np.ones((v, 1), bool)),
        "object-arrays": npz(ell=np.array([None] * v, dtype=object), mask=np.array([True] * v, dtype=object)),
        "empty-mask": targets(free=0),
        "missing-mask": npz(ell=np.zeros((v, 3))),
        "zero-d": npz(ell=np.float64(1.0), mask=np.bool_(True)),
        "text-file": "ell,mask\n",
        "empty-file": b"",
        "directory": Folder(),
        "absent": None,
        "truncated": truncated(targets()),
    }
    for what, content in bad_targets.items():
        cases.append(refused(f"edit-highlights/targets-{what}", ("edit-highlights", "scene.toml", "--mesh", "1",
                             "--targets", f"targets.np{'y' if what == 'npy' else 'z'}", "-o", "u.npz"),
                             {"scene.toml": EDIT_SCENE, f"targets.np{'y' if what == 'npy' else 'z'}": content},
                             "targets.np", "--targets", "mask"))  # fmt: skip

    hl = ("highlights", "scene.toml", "--mesh", "0", "-o", "h.npz")
    scene = {"scene.toml": EDIT_SCENE}
    cases += [
        accepted("highlights/ok-baseline", hl, scene, "h.npz"),
        accepted("highlights/ok-plane", ("highlights", "scene.toml", "--mesh", "1", "-o", "h.npz"), scene, "h.npz"),
        refused("highlights/mesh-99", ("highlights", "scene.toml", "--mesh", "99", "-o", "h.npz"), scene, "--mesh"),
        refused("highlights/mesh--1", ("highlights", "scene.toml", "--mesh", "-1", "-o", "h.npz"), scene, "--mesh"),
        refused("highlights/light-99", (*hl, "--light", "99"), scene, "--light"),
        refused("highlights/light-quad", (*hl, "--light", "1"), scene, "--light"),
        refused("highlights/no-point-light", hl, {"scene.toml": EDIT_SCENE.split("[[light]]")[0] + "[[light]]"
                + EDIT_SCENE.split("[[light]]")[2]}, "light"),
        refused("highlights/scene-absent", hl, {}, "scene.toml"),
        refused("highlights/scene-directory", hl, {"scene.toml": Folder()}, "scene.toml"),
        refused("highlights/scene-not-toml", hl, {"scene.toml": "[camera\nposition = "}, "scene.toml"),
    ]  # fmt: skip
    return cases


def view_cases() -> list[Case]:
    files = {"scene.toml": SCENE}
    argv = ("view", "scene.toml", "--script", "script.json", "--frames", "2", "--screenshot", "shot.png")

    def script(events) -> dict[str, Content]:
        return {**files, "script.json": events if isinstance(events, str | bytes | Folder) else jtext(events)}

    orbit = {"type": "orbit", "dx": 5}
    cases = [
        accepted("view/ok-baseline", argv,
                 script([orbit, {"type": "wait", "frames": 2}, {"type": "zoom", "factor": 1.1}]), "shot.png",
                 display=True),
        accepted("view/ok-empty-script", argv, script([]), "shot.png", display=True),
        accepted("view/ok-no-script", ("view", "scene.toml", "--frames", "1", "--screenshot", "shot.png"), files,
                 "shot.png", display=True),
        Case("view/wait-0-frames", argv, script([{"type": "wait", "frames": 0}, orbit]), "either", ("frames",),
             output="shot.png", display=True),
        refused("view/frames-0", (*argv[:-4], "--frames", "0", *argv[-2:]), script([orbit]), "--frames"),
        refused("view/frames--1", (*argv[:-4], "--frames", "-1", *argv[-2:]), script([orbit]), "--frames"),
        refused("view/frames-1e9", (*argv[:-4], "--frames", "1000000000", *argv[-2:]), script([orbit]), "--frames",
                display=True, timeout=HANG),
        refused("view/screenshot-without-frames", ("view", "scene.toml", "--screenshot", "shot.png"), files,
                "--screenshot", "--frames", display=True, timeout=HANG),
        refused("view/scene-absent", argv, script([orbit]) | {"scene.toml": None}, "scene.toml"),
        refused("view/size-0x0", (*argv, "--size", "0x0"), script([orbit]), "--size"),
        refused("view/method-unknown", (*argv, "--method", "nosuch"), script([orbit]), "nosuch", "--method",
                display=True),
    ]  # fmt: skip
    before_window = {  # refused reading the script: no display needed
        "not-a-list": ({"type": "orbit"}, "script.json"),
        "event-not-an-object": ([1, 2], "script.json"),
        "event-without-type": ([{"dx": 5}], "type"),
        "nested-100000": ("[" * 100000 + "]" * 100000, "script.json"),
        "directory": (Folder(), "script.json"),
        "duplicate-keys": ('[{"type": "orbit", "type": "zoom", "factor": 2}]', "script.json"),
        "empty-file": ("", "script.json"),
        "not-utf8": (b"\xff\xfe[\x00]", "script.json"),
        "nan-literal": ('[{"type": "zoom", "factor": NaN}]', "script.json"),
        "absent": (None, "script.json"),
    }
    for what, (content, mention) in before_window.items():
        cases.append(refused(f"view/script-{what}", argv, script(content) if content is not None
                             else files, mention, "--script"))  # fmt: skip
    in_window = {  # events the controller refuses (checked up front or when replayed: a display either way)
        "wait-frames-many": ([{"type": "wait", "frames": "many"}], "frames"),
        "wait-frames-negative": ([{"type": "wait", "frames": -5}, orbit], "frames"),
        "wait-frames-1e9": ([{"type": "wait", "frames": 10**9}], "frames"),
        "wait-frames-float": ([{"type": "wait", "frames": 2.5}], "frames"),
        "wait-frames-null": ([{"type": "wait", "frames": None}], "frames"),
        "zoom-0": ([{"type": "zoom", "factor": 0}], "factor"),
        "zoom-negative": ([{"type": "zoom", "factor": -2}], "factor"),
        "zoom-1e308": ([{"type": "zoom", "factor": 1e308}], "factor"),
        "zoom-string": ([{"type": "zoom", "factor": "big"}], "factor"),
        "zoom-missing-factor": ([{"type": "zoom"}], "factor"),
        "orbit-1e308": ([{"type": "orbit", "dx": 1e308}], "dx"),
        "unknown-type": ([{"type": "explode"}], "explode"),
        "type-not-a-string": ([{"type": ["orbit"]}], "type"),
        "extra-field": ([{"type": "orbit", "dx": 5, "speed": 3}], "speed"),
        "pointer-missing-xy": ([{"type": "pointer", "action": "down"}], "pointer"),
        "pointer-bad-action": ([{"type": "pointer", "action": "explode", "x": 1, "y": 1}], "action"),
        "select-mesh-99": ([{"type": "select", "mesh": 99}], "mesh"),
        "material-unknown": ([{"type": "material", "name": "nosuch", "fields": {"albedo": [1, 0, 0]}}], "nosuch"),
        "material-bad-field": ([{"type": "material", "name": "m", "fields": {"albedo": "red"}}], "albedo"),
        "exposure-nan-string": ([{"type": "exposure", "stops": "NaN"}], "stops"),
        "reference-spp-0": ([{"type": "reference", "spp": 0}], "spp"),
        "event-method-unknown": ([{"type": "method", "name": "nosuch"}], "nosuch"),
        "tonemap-unknown": ([{"type": "tonemap", "mode": "filmic"}], "filmic"),
        "show-unknown": ([{"type": "show", "mode": "everything"}], "everything"),
        "100001-events": ([orbit] * 100001, "script.json"),
    }
    for what, (content, mention) in in_window.items():
        hang = what in ("wait-frames-1e9", "100001-events", "reference-spp-0")
        cases.append(refused(f"view/{what}", argv, script(content), mention, "script.json", display=True,
                             timeout=HANG if hang else TIMEOUT))  # fmt: skip
    return cases


def box_check(work: Path) -> str | None:
    """`render Box.gltf --method position`: every covered pixel on the unit cube's surface (max |coordinate| =
    0.5), a fair part of the image covered."""
    image = np.load(work / "box.npy")
    covered = np.any(image != 0, axis=2)
    if covered.mean() < 0.05:
        return f"the box covers {covered.mean():.1%} of the image"
    off = np.abs(np.abs(image[covered]).max(axis=1) - 0.5).max()
    return f"a pixel {off:.3f} off the unit cube's surface: wrong geometry" if off > 2e-3 else None


def box_highlights_check(work: Path) -> str | None:
    with np.load(work / "h.npz") as data:
        p = data["positions"]
    if p.shape != (24, 3) or not np.allclose(np.abs(p), 0.5, atol=1e-5):
        return f"positions {p.shape}, not the 24 corners-by-face of the unit cube"
    return None


def mesh_cases() -> list[Case]:
    box = {"Box.gltf": asset(DRACO_BOX), "Box.bin": asset(DRACO_BOX.with_suffix(".bin"))}
    render = ("render", "scene.toml", "--method", "normal", "-o", "out.exr")
    draco = "meshes/draco"
    cases = [
        accepted(f"{draco}-box-scene-with-material", render, {**box, "scene.toml": box_scene(True)}, "out.exr"),
        accepted(f"{draco}-box-scene-without-material", render, {**box, "scene.toml": box_scene(False)}, "out.exr"),
        accepted(f"{draco}-box-render-file", ("render", "Box.gltf", "--method", "position", "--size", "32x24", "-o",
                 "box.npy"), box, "box.npy", check=box_check) if HAVE_DRACO else
        refused(f"{draco}-box-render-file-without-DracoPy", ("render", "Box.gltf", "-o", "box.npy"), box, "Draco"),
        accepted(f"{draco}-box-highlights", ("highlights", "scene.toml", "--mesh", "0", "-o", "h.npz"),
                 {**box, "scene.toml": box_scene(True)}, "h.npz", check=box_highlights_check),
        accepted(f"{draco}-box-export-gltf", ("export-gltf", "scene.toml", "-o", "out.glb"),
                 {**box, "scene.toml": box_scene(True)}, "out.glb"),
        refused(f"{draco}-box-without-bin", render, {"Box.gltf": asset(DRACO_BOX), "scene.toml": box_scene(True)},
                "Box.bin", "Box.gltf"),
        refused(f"{draco}-box-truncated-bin", render, {"Box.gltf": asset(DRACO_BOX), "scene.toml": box_scene(False),
                "Box.bin": truncated(asset(DRACO_BOX.with_suffix(".bin")))}, "Box.bin", "Box.gltf"),
        refused(f"{draco}-box-garbage-bin", render, {"Box.gltf": asset(DRACO_BOX), "scene.toml": box_scene(False),
                "Box.bin": b"\x00" * 120}, "Box.bin", "Box.gltf"),
    ]  # fmt: skip
    if not DRACO_BOX.is_file():
        cases = []  # no asset: these cases cannot be built
    broken: dict[str, Content] = {
        "empty.obj": "",
        "garbage.obj": bytes(range(256)) * 16,
        "no-faces.obj": "v 0 0 0\nv 1 0 0\nv 0 1 0\n",
        "bad-index.obj": "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 9\n",
        "nan.obj": "v nan 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n",
        "huge.obj": "v 1e300 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n",
        "empty.glb": b"",
        "garbage.glb": b"glTF" + bytes(range(256)),
        "empty.gltf": "",
        "not-json.gltf": "{ this is not json",
        "empty.ply": "",
        "garbage.stl": b"\x00" * 84 + b"\xff" * 10,
    }
    if SMALL_GLB.is_file():
        broken["truncated.glb"] = functools.partial(glb_cut_in_geometry, SMALL_GLB)
    for name, content in broken.items():
        cases.append(refused(f"meshes/render-{name}", ("render", name, "-o", "out.exr"), {name: content}, name))
        cases.append(refused(f"meshes/scene-{name}", render, {name: content, "scene.toml": mesh_scene(name)}, name))
    cases.append(refused("meshes/scene-mesh-absent", render, {"scene.toml": mesh_scene("nope.obj")}, "nope.obj"))
    cases.append(refused("meshes/scene-mesh-directory", render,
                         {"scene.toml": mesh_scene("dir.obj"), "dir.obj": Folder()}, "dir.obj"))  # fmt: skip
    return cases


def all_cases() -> list[Case]:
    cases = ar_cases() + ar_board_cases() + output_cases() + edit_cases() + view_cases() + mesh_cases()
    names = Counter(c.name for c in cases)
    assert not [n for n, k in names.items() if k > 1], [n for n, k in names.items() if k > 1]
    return cases


# --------------------------------------------------------------------------------------------- running one case
@dataclass
class Result:
    case: Case
    verdict: str  # "ok" | "mishandled" | "skipped"
    reason: str = ""
    status: int | None = None  # exit status; None: timed out; < 0: killed by that signal
    seconds: float = 0.0
    stderr: str = ""
    command: str = ""

    def as_dict(self) -> dict:
        return {"name": self.case.name, "surface": self.case.surface, "expected": self.case.expected,
                "verdict": self.verdict, "reason": self.reason, "status": self.status,
                "seconds": round(self.seconds, 2), "command": self.command,
                "stderr": self.stderr.splitlines()[:STDERR_LINES]}  # fmt: skip


def materialise(files: dict[str, Content], work: Path) -> None:
    for name, content in files.items():
        path = work / name
        path.parent.mkdir(parents=True, exist_ok=True)
        if content is None:
            continue
        if isinstance(content, Folder):
            path.mkdir()
            for inner in content.names:
                (path / inner).write_text("the user's own file\n")
            continue
        if callable(content):
            content = content()
        path.write_bytes(content.encode() if isinstance(content, str) else content)


def snapshot(work: Path) -> dict[str, str]:
    """Every path under the work folder → a digest of its content ("dir" for a folder)."""
    state = {}
    for path in sorted(work.rglob("*")):
        rel = path.relative_to(work).as_posix()
        state[rel] = "dir" if path.is_dir() else hashlib.sha1(path.read_bytes()).hexdigest()
    return state


def changes(before: dict[str, str], after: dict[str, str], ignore: str = "") -> dict[str, list[str]]:
    """Paths created, changed and removed between two snapshots (``ignore``: an output, and what is under it)."""

    def kept(p: str) -> bool:
        return not ignore or (p != ignore and not p.startswith(ignore + "/"))

    return {
        "created": [p for p in after if p not in before and kept(p)],
        "changed": [p for p in before if p in after and before[p] != after[p] and kept(p)],
        "removed": [p for p in before if p not in after and kept(p)],
    }


def describe(diff: dict[str, list[str]]) -> str:
    return "; ".join(f"{what} {', '.join(names[:3])}{' …' if len(names) > 3 else ''}"
                     for what, names in diff.items() if names)  # fmt: skip


def _crash(status: int | None, stderr: str, case: Case) -> str:
    """What went wrong in any case: a timeout, a signal, a traceback ('' when none of them)."""
    if status is None:
        return f"timed out after {case.timeout:.0f} s"
    if status < 0 or (case.display and status > 128):  # xvfb-run's shell reports a signal as 128 + n
        number = -status if status < 0 else status - 128
        try:
            return f"killed by {signal.Signals(number).name}"
        except ValueError:
            return f"killed by signal {number}"
    if "Traceback (most recent call last)" in stderr:
        last = [line for line in stderr.splitlines() if line.strip()][-1].strip()
        return f"traceback: {last[:160]}"
    return ""


def judge(case: Case, status: int | None, stderr: str, before: dict, after: dict, work: Path) -> str:
    """'' when the case was handled as issue 32 says, else why not (one line)."""
    if crash := _crash(status, stderr, case):
        return crash
    lines = [line for line in stderr.splitlines() if line.strip()]
    expected = case.expected if case.expected != "either" else ("accepted" if status == 0 else "refused")
    if expected == "refused":
        if status == 0:
            return "exit 0 after nonsense (expected a refusal, exit 2)"
        if status != 2:
            return f"exit {status} (expected 2): {lines[0][:160] if lines else 'no message'}"
        if len(lines) != 1:
            return f"{len(lines)} lines on stderr (expected one): {' | '.join(line[:70] for line in lines[:3])}"
        if not lines[0].startswith("reflets: error:"):
            return f"the line does not start with 'reflets: error:': {lines[0][:160]}"
        if case.must_mention and not any(word in lines[0] for word in case.must_mention):
            return f"the error names none of {list(case.must_mention)}: {lines[0][:160]}"
        if any((diff := changes(before, after)).values()):
            return f"refused, yet the work folder changed: {describe(diff)}"
        return ""
    if status != 0:
        return f"exit {status} (expected acceptance, 0): {lines[0][:160] if lines else 'no message'}"
    if noise := [line for line in lines if not line.startswith("reflets: warning:")]:
        return f"stderr besides warnings: {noise[0][:160]}"
    if not (work / case.output).exists():
        return f"exit 0 but no {case.output}"
    diff = changes(before, after, ignore=case.output)  # other new files are the command's (a board's image)
    diff["created"] = [p for p in diff["created"] if p.endswith(".tmp")]  # but not a temporary file left behind
    if any(diff.values()):
        return f"accepted, but the inputs changed: {describe(diff)}"
    if case.check is not None:
        try:
            return case.check(work) or ""
        except Exception as exc:  # the output is unreadable: that is the finding
            return f"the output does not check: {type(exc).__name__}: {exc}"
    return ""


_slot = threading.local()
_slots = itertools.count()


def run_case(case: Case, xvfb: str | None, keep: Path | None) -> Result:
    command = "reflets " + shlex.join(case.argv)
    if case.display and xvfb is None:
        return Result(case, "skipped", "needs a display: xvfb-run not found", command=command)
    if not hasattr(_slot, "n"):
        _slot.n = next(_slots)
    work = Path(tempfile.mkdtemp(prefix="careless-"))
    try:
        try:
            materialise(case.files, work)
        except (ImportError, OSError) as exc:
            return Result(case, "skipped", f"cannot build the inputs ({exc})", command=command)
        before = snapshot(work)
        argv = [*REFLETS, *case.argv]
        env = {**os.environ, "PYTHONDONTWRITEBYTECODE": "1"}
        if case.display:  # one X server number range per worker: parallel xvfb-run -a can race for a number
            argv = [xvfb, "-a", "-n", str(150 + 20 * _slot.n), "-s", "-screen 0 1024x768x24", *argv]
        else:
            env.pop("DISPLAY", None)
            env.pop("WAYLAND_DISPLAY", None)
        started = time.perf_counter()
        process = subprocess.Popen(argv, cwd=work, stdin=subprocess.DEVNULL, stdout=subprocess.PIPE,
                                   stderr=subprocess.PIPE, env=env, start_new_session=True)  # fmt: skip
        try:
            _, err = process.communicate(timeout=case.timeout)
            status = process.returncode
        except subprocess.TimeoutExpired:
            os.killpg(process.pid, signal.SIGKILL)  # its own session: the command and anything it started
            _, err = process.communicate()
            status = None
        seconds = time.perf_counter() - started
        stderr = err.decode("utf-8", "replace")
        reason = judge(case, status, stderr, before, snapshot(work), work)
        if reason and keep is not None:
            shutil.copytree(work, keep / case.name.replace("/", "__"), dirs_exist_ok=True, symlinks=True)
        return Result(case, "mishandled" if reason else "ok", reason, status, seconds, stderr, command)
    finally:
        shutil.rmtree(work, ignore_errors=True)


# --------------------------------------------------------------------------------------------- the report
def report(results: list[Result], seconds: float, jobs: int) -> None:
    surfaces = sorted({r.case.surface for r in results})
    print(f"\n{'surface':<18}{'cases':>6}{'ok':>6}{'mishandled':>12}{'skipped':>9}")
    for surface in surfaces:
        rows = [r for r in results if r.case.surface == surface]
        count = Counter(r.verdict for r in rows)
        print(f"{surface:<18}{len(rows):>6}{count['ok']:>6}{count['mishandled']:>12}{count['skipped']:>9}")
    count = Counter(r.verdict for r in results)
    print(f"{'all':<18}{len(results):>6}{count['ok']:>6}{count['mishandled']:>12}{count['skipped']:>9}")
    bad = [r for r in results if r.verdict == "mishandled"]
    for r in bad:
        status = "timeout" if r.status is None else r.status
        print(f"\nMISHANDLED {r.case.name} (expected {r.case.expected}; exit {status}, {r.seconds:.1f} s)")
        print(f"  $ {r.command}")
        print(f"  {r.reason}")
        for line in r.stderr.splitlines()[:STDERR_LINES]:
            print(f"  | {line[:200]}")
    skipped = [r for r in results if r.verdict == "skipped"]
    if skipped:
        print(f"\nskipped: {len(skipped)} ({skipped[0].reason})")
    print(f"\n{len(bad)} of {len(results)} cases mishandled; {seconds:.0f} s with {jobs} jobs")


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--only", metavar="SUBSTRING", help="run the cases whose name contains this")
    parser.add_argument("--jobs", type=int, default=2, help="cases run at once (default 2)")
    parser.add_argument("--json", metavar="PATH", help="write the results as JSON")
    parser.add_argument("--list", action="store_true", help="list the cases and exit")
    parser.add_argument("--keep", metavar="DIR", help="copy the work folder of each mishandled case into DIR")
    args = parser.parse_args(argv)
    if args.jobs < 1:
        parser.error("--jobs must be at least 1")
    cases = [c for c in all_cases() if not args.only or args.only in c.name]
    if args.list:
        for c in cases:
            print(f"{c.expected:<9}{c.name}    reflets {shlex.join(c.argv)}")
        print(f"{len(cases)} cases")
        return 0
    if not cases:
        print(f"no case matches {args.only!r}", file=sys.stderr)
        return 2
    keep = Path(args.keep) if args.keep else None
    if keep is not None:
        keep.mkdir(parents=True, exist_ok=True)
    xvfb = shutil.which("xvfb-run")
    print(f"{len(cases)} cases, {args.jobs} at a time; reflets: {shlex.join(REFLETS)}; "
          f"display: {'xvfb-run' if xvfb else 'none (view cases that open a window are skipped)'}")  # fmt: skip
    started = time.perf_counter()
    results = []
    with ThreadPoolExecutor(args.jobs) as pool:
        futures = [pool.submit(run_case, case, xvfb, keep) for case in cases]
        for k, future in enumerate(as_completed(futures), 1):
            r = future.result()
            results.append(r)
            tag = {"ok": "ok", "mishandled": "MISHANDLED", "skipped": "skipped"}[r.verdict]
            print(f"[{k:3d}/{len(cases)}] {tag:<10} {r.case.name} ({r.seconds:.1f} s)", flush=True)
    seconds = time.perf_counter() - started
    order = {c.name: k for k, c in enumerate(cases)}
    results.sort(key=lambda r: order[r.case.name])
    report(results, seconds, args.jobs)
    if args.json:
        Path(args.json).write_text(json.dumps({"seconds": round(seconds, 1), "jobs": args.jobs,
                                               "results": [r.as_dict() for r in results]}, indent=1))  # fmt: skip
    return 1 if any(r.verdict == "mishandled" for r in results) else 0


if __name__ == "__main__":
    sys.exit(main())
