"""Issue 32: every bad input of the ar commands (camera.json, board.json, the `ar board` options, the images) ends
in one line on stderr naming the file or option, exit status 2, nothing written — and odd but valid input reads
right. Then a seeded fuzz of camera.json and board.json."""

from __future__ import annotations

import copy
import json
import struct
import zlib

import numpy as np
import pytest

pytest.importorskip("cv2")
hypothesis = pytest.importorskip("hypothesis")
from hypothesis import HealthCheck, given, settings  # noqa: E402
from hypothesis import strategies as st  # noqa: E402
from PIL import Image  # noqa: E402

from reflets.ar.board import DICTIONARIES, Board  # noqa: E402
from reflets.ar.camera import Intrinsics  # noqa: E402
from reflets.ar.images import MAX_FRAME_PIXELS, read_frame  # noqa: E402
from reflets.cli import main  # noqa: E402
from reflets.errors import ArgumentError  # noqa: E402

SIZE = (32, 24)
BOARD = {"dictionary": "DICT_6X6_250", "markers": {str(k): v.tolist() for k, v in Board.grid(2, 2).markers.items()}}
CAMERA = {"K": Intrinsics.from_fov(SIZE, 55).K.tolist(), "dist": [0.0] * 5, "size": list(SIZE)}


def _png(path, width: int, height: int) -> None:
    """A 1-bit black PNG of any size, written row by row: a decompression bomb is a few kilobytes on disk."""

    def chunk(kind: bytes, data: bytes) -> bytes:
        return struct.pack(">I", len(data)) + kind + data + struct.pack(">I", zlib.crc32(kind + data))

    z, row = zlib.compressobj(9), bytes(1 + (width + 7) // 8)
    data = b"".join(z.compress(row) for _ in range(height)) + z.flush()
    header = struct.pack(">IIBBBBB", width, height, 1, 0, 0, 0, 0)
    path.write_bytes(b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", header) + chunk(b"IDAT", data) + chunk(b"IEND", b""))


@pytest.fixture(scope="module")
def folder(tmp_path_factory):
    folder = tmp_path_factory.mktemp("inputs")
    (folder / "board.json").write_text(json.dumps(BOARD))
    (folder / "camera.json").write_text(json.dumps(CAMERA))
    Image.fromarray(np.full(SIZE[::-1], 128, np.uint8)).save(folder / "frame.png")
    Image.fromarray(np.zeros((10, 12), np.uint8)).save(folder / "small.png")
    Image.fromarray(np.random.default_rng(0).integers(0, 256, SIZE[::-1], np.uint8)).save(folder / "noise.png")
    noise = (folder / "noise.png").read_bytes()
    (folder / "truncated.png").write_bytes(noise[: len(noise) // 2])  # the header whole, half its pixels
    (folder / "text.png").write_text("not an image")
    (folder / "empty.png").write_bytes(b"")
    (folder / "folder.png").mkdir()
    (folder / "folder.json").mkdir()
    _png(folder / "bomb.png", 20000, 20000)  # 400 million pixels, Pillow's DecompressionBombError: 49 kB
    _png(folder / "large.png", 8000, 8000)  # 64 million: under Pillow's limit, over MAX_FRAME_PIXELS
    return folder


def _mutated(base: dict, change) -> dict:
    data = copy.deepcopy(base)
    change(data)
    return data


def _set(path, value):
    """A change setting data[path[0]][path[1]]... to value."""

    def change(data):
        for key in path[:-1]:
            data = data[key]
        data[path[-1]] = value

    return change


def _refused(argv, capsys, *expected, output=None):
    assert main(argv) == 2, argv
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and err.startswith("reflets: error: ") and "Traceback" not in err, err
    for text in expected:
        assert text in err, (text, err)
    assert output is None or not output.exists()
    return err


def _track(folder, tmp_path, board=None, camera=None, images=("frame.png",)):
    board, camera = board or folder / "board.json", camera or folder / "camera.json"
    return ["ar", "track", *(str(folder / i) for i in images), "--board", str(board), "--intrinsics", str(camera),
            "-o", str(tmp_path / "poses.json")]  # fmt: skip


CAMERAS = {
    "NaN focal": (_set(("K", 0, 0), float("nan")), "NaN is not JSON"),  # json.dumps writes the NaN token
    "zero focal": (_set(("K", 0, 0), 0), "K: fx is 0"),
    "negative focal": (_set(("K", 1, 1), -300.0), "K: fy is -300"),
    "huge focal": (_set(("K", 0, 0), 1e300), "K[0][0]"),
    "singular K": (_set(("K", 2), [0, 0, 0]), "K: the bottom row is [0.0, 0.0, 0.0]"),
    "size 0x0": (_set(("size",), [0, 0]), "size[0]"),
    "size not integers": (_set(("size",), [32.5, 24]), "size[0]"),
    "principal point far off": (_set(("K", 0, 2), 1e6), "K: the principal point's cx"),
    "9 coefficients": (_set(("dist",), [0.0] * 9), "dist: 9 coefficients"),
    "a string for a number": (_set(("K", 0, 0), "300"), "K[0][0]"),
    "unknown key": (_set(("skew",), 0), "skew"),
}


@pytest.mark.parametrize("case", CAMERAS)
def test_a_bad_camera_json_is_one_line(folder, tmp_path, capsys, case):
    change, expected = CAMERAS[case]
    camera = tmp_path / "camera.json"
    camera.write_text(json.dumps(_mutated(CAMERA, change)))
    _refused(_track(folder, tmp_path, camera=camera), capsys, f"{camera}: --intrinsics: ", expected,
             output=tmp_path / "poses.json")  # fmt: skip


BOARDS = {
    "markers a list": (_set(("markers",), []), "markers: input should be a valid dictionary"),
    "no markers": (_set(("markers",), {}), "markers: no markers"),
    "0 and 01": (lambda d: d["markers"].update({"01": d["markers"]["1"]}), "'01' is not a marker id"),
    "+1": (lambda d: d["markers"].update({"+1": d["markers"].pop("1")}), "'+1' is not a marker id"),
    " 1": (lambda d: d["markers"].update({" 1": d["markers"].pop("1")}), "' 1' is not a marker id"),
    "-1": (lambda d: d["markers"].update({"-1": d["markers"].pop("1")}), "'-1' is not a marker id"),
    "id out of range": (
        lambda d: d["markers"].update({"250": d["markers"].pop("1")}),
        "id 250 is out of range; DICT_6X6_250 has ids 0 to 249",
    ),
    "coincident corners": (_set(("markers", "0", 1), BOARD["markers"]["0"][0]), "marker 0: corners 0 and 1"),
    "huge corner": (_set(("markers", "0", 0, 0), 1e300), "markers.0[0][0]"),
    "three corners": (lambda d: d["markers"]["0"].pop(), "markers.0"),
    "off the plane": (_set(("markers", "2", 3, 1), 0.01), "marker 2: corner 3 has y = 0.01"),
    "mirrored": (lambda d: d["markers"]["3"].reverse(), "marker 3 faces down"),
    "not convex": (_set(("markers", "0", 2), BOARD["markers"]["0"][0]), "marker 0: its corners are not a convex"),
    "overlapping": (_set(("markers", "1"), BOARD["markers"]["0"]), "markers 0 and 1 overlap"),
    "aruco_Dictionary": (_set(("dictionary",), "aruco_Dictionary"), "'aruco_Dictionary' is not an ArUco dictionary"),
    "ArucoDetector": (_set(("dictionary",), "ArucoDetector"), "'ArucoDetector' is not an ArUco dictionary"),
    "DICT_FOO": (_set(("dictionary",), "DICT_FOO"), "dictionary: 'DICT_FOO' is not"),
}


@pytest.mark.parametrize("case", BOARDS)
def test_a_bad_board_json_is_one_line(folder, tmp_path, capsys, case):
    change, expected = BOARDS[case]
    board = tmp_path / "board.json"
    board.write_text(json.dumps(_mutated(BOARD, change)))
    _refused(_track(folder, tmp_path, board=board), capsys, f"{board}: --board: ", expected,
             output=tmp_path / "poses.json")  # fmt: skip


def test_a_duplicate_key_or_a_directory_as_json_is_one_line(folder, tmp_path, capsys):
    board = tmp_path / "board.json"
    board.write_text('{"dictionary": "DICT_6X6_250", "dictionary": "DICT_4X4_50", "markers": {}}')
    _refused(_track(folder, tmp_path, board=board), capsys, "--board", "'dictionary' is given twice")
    _refused(_track(folder, tmp_path, board=folder / "folder.json"), capsys, "folder.json: --board: is a directory")
    _refused(_track(folder, tmp_path, camera=folder / "folder.json"), capsys, "folder.json: --intrinsics: is a dir")
    assert not (tmp_path / "poses.json").exists()


IMAGES = {
    "bomb.png": "is 400,000,000 pixels (a decompression bomb?); a frame is at most 16384 pixels a side",
    "large.png": f"is 8000x8000 pixels; a frame is at most 16384 pixels a side and {MAX_FRAME_PIXELS:,} in all",
    "truncated.png": "cannot decode the image (image file is truncated)",
    "text.png": "is not an image Pillow can read",
    "empty.png": "is empty",
    "folder.png": "is a directory",
    "missing.png": "file not found",
    "small.png": "is 12x10, the intrinsics are for 32x24",
}


@pytest.mark.parametrize("name", IMAGES)
def test_a_bad_image_is_one_line_naming_it(folder, tmp_path, capsys, name):
    """The frame first in the list, then after a good one: every header is checked before anything is decoded."""
    for images in ((name,), ("frame.png", name)):
        _refused(_track(folder, tmp_path, images=images), capsys, f"{folder / name}: {IMAGES[name]}",
                 output=tmp_path / "poses.json")  # fmt: skip


def test_calibrate_and_composite_refuse_bad_images_in_one_line(folder, tmp_path, capsys):
    out = tmp_path / "camera.json"
    common = ["--board", str(folder / "board.json"), "-o", str(out)]
    _refused(["ar", "calibrate", str(folder / "frame.png"), str(folder / "small.png"), *common], capsys,
             "small.png: is 12x10, not 32x24 as the others", output=out)  # fmt: skip
    _refused(["ar", "calibrate", str(folder / "frame.png"), *common], capsys, "only 0 of 1 images", output=out)
    _refused(["ar", "composite", "objects.toml", "--background", str(folder / "bomb.png"), "--intrinsics",
              str(folder / "camera.json"), *common[:2], "-o", str(tmp_path / "out.png")], capsys,
             "bomb.png: is 400,000,000 pixels", output=tmp_path / "out.png")  # fmt: skip


def test_frame_sources_refuse_in_one_line(folder, tmp_path, capfd):
    """``ar run``'s inputs: an image list is checked whole at open (a bad or odd-sized image late in it is found
    before anything is written); a file that is no video says so — with none of FFmpeg's log on stderr."""
    from reflets.ar.video import FrameSource

    cases = {
        ("frame.png", "small.png"): "small.png: is 12x10, not 32x24 as",
        ("frame.png", "bomb.png"): "bomb.png",
        ("folder.png",): "folder.png: is a directory",
        ("text.mp4",): "text.mp4: OpenCV cannot read this video",
    }
    (folder / "text.mp4").write_text("not a video")
    for names, expected in cases.items():
        with pytest.raises(ArgumentError, match=expected):
            FrameSource.open([str(folder / n) for n in names], None)
    assert capfd.readouterr().err == ""
    (frame,) = FrameSource.open([str(folder / "frame.png")], None).frames()
    assert frame.shape == (*SIZE[::-1], 3) and frame.dtype == np.uint8


def test_ar_board_options_are_one_line_and_nothing_is_written(tmp_path, capsys):
    out, image = tmp_path / "board.json", tmp_path / "board.png"
    cases = [
        (["--columns", "0"], "--columns: must be a whole number of markers"),
        (["--rows", "-2"], "--rows: must be a whole number of markers"),
        (["--columns", "20", "--rows", "20"], "20 x 20 = 400 markers; DICT_6X6_250 has 250"),
        (["--columns", "8", "--dictionary", "DICT_APRILTAG_16h5", "--rows", "4"], "32 markers; DICT_APRILTAG_16h5 has"),
        (["--size", "nan"], "--size: must be a number from 1e-06"),
        (["--size", "0"], "--size: must be a number"),
        (["--size", "1e300"], "--size: must be a number"),
        (["--gap", "-1"], "--gap: must be a number from 0"),
        (["--gap", "inf"], "--gap: must be a number from 0"),
        (["--dictionary", "ArucoDetector"], "--dictionary: 'ArucoDetector' is not an ArUco dictionary"),
        (["--size", "50", "--image", str(image)], "--image: the board's image would be 1000360x800311 pixels"),
        (["--size", "0.0001", "--image", str(image)], "--image: marker 0 would be 0 pixels wide"),
    ]
    for options, expected in cases:
        _refused(["ar", "board", "-o", str(out), *options], capsys, expected, output=out)
        assert not image.exists()


def test_odd_but_valid_inputs_read_right(folder, tmp_path):
    """Dictionaries as OpenCV has them; 4, 8 or 14 distortion coefficients (those beyond k3 zero) as k1 k2 p1 p2
    k3; a 16-bit grey frame scaled to 8 bits (not clipped), a palette with transparency; corners PnP cannot
    solve (all on one pixel): no pose; a rotated marker, a corner off the plane by rounding."""
    import cv2

    for name, count in DICTIONARIES.items():
        if hasattr(cv2.aruco, name):
            assert cv2.aruco.getPredefinedDictionary(getattr(cv2.aruco, name)).bytesList.shape[0] == count, name
    for dist in ([0.1, -0.02, 0.001, 0.002], [0.1, -0.02, 0.001, 0.002, 0.003, 0, 0, 0], [0.1] + [0.0] * 13):
        path = tmp_path / "camera.json"
        path.write_text(json.dumps({**CAMERA, "dist": dist}))
        assert Intrinsics.load(path).dist.tolist() == [*dist[:5], 0.0][:5]
    codes = (np.arange(SIZE[0] * SIZE[1]).reshape(SIZE[::-1]) * 80).astype(np.uint16)
    Image.fromarray(codes).save(tmp_path / "grey16.png")
    assert np.abs(read_frame(tmp_path / "grey16.png").astype(float) - codes / 257).max() <= 0.5
    palette = Image.fromarray((np.arange(SIZE[0] * SIZE[1]).reshape(SIZE[::-1]) % 4).astype(np.uint8), "P")
    palette.putpalette([0, 0, 0, 255, 0, 0, 0, 255, 0, 0, 0, 255])
    palette.save(tmp_path / "palette.png", transparency=0)
    assert read_frame(tmp_path / "palette.png", "RGB")[0, :4].tolist() == [[0, 0, 0], [255, 0, 0], [0, 255, 0],
                                                                          [0, 0, 255]]  # fmt: skip
    from reflets.ar.tracking import solve_pose

    corners = np.concatenate(list(Board.grid(2, 2).markers.values()))
    camera = Intrinsics.from_fov(SIZE, 55)
    assert solve_pose(corners, np.full((16, 2), 5.0), camera) is None  # SQPnP's assertion: a frame without a pose
    diamond = {
        "dictionary": "DICT_4X4_50",
        "markers": {
            "7": [[0, 0, -1], [1, 0, 0], [0, 0, 1], [-1, 0, 0]],
            "0": [[2, 1e-12, 2], [3, 0, 2], [3, 0, 3], [2, 0, 3]],
        },
    }
    (tmp_path / "board.json").write_text(json.dumps(diamond))
    board = Board.load(tmp_path / "board.json")
    assert sorted(board.markers) == [0, 7] and board.markers[0][0, 1] == 0.0  # on the plane within rounding


# ------------------------------------------------------------------------------------------------------ fuzzing


def fuzz(examples: int):
    """Seeded (the same cases every run), no deadline, no example database written."""
    return settings(derandomize=True, deadline=None, suppress_health_check=list(HealthCheck), database=None,
                    max_examples=examples)  # fmt: skip


NUMBERS = st.one_of(st.floats(allow_nan=True, allow_infinity=True), st.integers(-(2**70), 2**70),
                    st.sampled_from([0.0, -1.0, 1e-300, 1e300, -1e12, 1e13, 0.5, 16384, 16385]))  # fmt: skip
VALUES = st.one_of(NUMBERS, st.none(), st.booleans(), st.text(max_size=8), st.lists(NUMBERS, max_size=4),
                   st.sampled_from(["01", "DICT_4X4_50", "ArucoDetector", {}, [], [[0, 0, 0]] * 4]))  # fmt: skip


def _places(data, prefix=()):
    yield prefix
    if isinstance(data, dict):
        for key, value in data.items():
            yield from _places(value, (*prefix, key))
    elif isinstance(data, list):
        for index, value in enumerate(data):
            yield from _places(value, (*prefix, index))


@st.composite
def mutated(draw, base):
    """``base`` with 1–3 changes: a value replaced (NaN, inf, huge, a string, a list, null...), a key removed, or a
    key added next to one."""
    data = copy.deepcopy(base)
    for _ in range(draw(st.integers(1, 3))):
        places = [p for p in _places(data) if p]
        if not places:
            break
        place = draw(st.sampled_from(places))
        parent = data
        for key in place[:-1]:
            parent = parent[key]
        action = draw(st.sampled_from(["replace", "replace", "delete", "add"]))
        if action == "replace":
            parent[place[-1]] = copy.deepcopy(draw(VALUES))  # a fresh copy: later changes must not reach VALUES
        elif action == "delete":
            del parent[place[-1]]
        elif isinstance(parent, dict):
            parent[draw(st.sampled_from(["0" + str(place[-1]), "extra", "249", "1"]))] = copy.deepcopy(draw(VALUES))
    return data


def _loads_or_one_line(tmp_path_factory, data, loader):
    path = tmp_path_factory.getbasetemp() / "fuzzed.json"
    path.write_text(json.dumps(data))  # NaN and Infinity written as JSON's extension: refused as not JSON
    try:
        return loader(path)
    except ArgumentError as exc:
        assert str(exc) and "\n" not in str(exc), repr(str(exc))
        return None


@fuzz(60)
@given(mutated(CAMERA))
def test_mutated_camera_json_loads_sanely_or_fails_in_one_line(tmp_path_factory, data):
    camera = _loads_or_one_line(tmp_path_factory, data, Intrinsics.load)
    if camera is not None:
        K, (w, h) = camera.K, camera.size
        assert np.all(np.isfinite(K)) and K[0, 0] > 0 and K[1, 1] > 0 and abs(np.linalg.det(K)) > 0
        assert K[1, 0] == K[2, 0] == K[2, 1] == 0 and K[2, 2] == 1 and camera.dist.shape == (5,)
        assert np.all(np.isfinite(camera.dist)) and 1 <= w * h <= MAX_FRAME_PIXELS
        assert all(isinstance(v, int) for v in camera.size)


@fuzz(60)
@given(mutated(BOARD))
def test_mutated_board_json_loads_sanely_or_fails_in_one_line(tmp_path_factory, data):
    board = _loads_or_one_line(tmp_path_factory, data, Board.load)
    if board is not None:
        assert board.dictionary in DICTIONARIES and 1 <= len(board.markers) <= DICTIONARIES[board.dictionary]
        for marker, corners in board.markers.items():
            assert isinstance(marker, int) and 0 <= marker < DICTIONARIES[board.dictionary]
            assert corners.shape == (4, 3) and np.all(np.isfinite(corners)) and np.all(corners[:, 1] == 0)
        board.cv_dictionary()
