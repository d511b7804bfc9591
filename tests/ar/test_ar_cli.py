"""`reflets ar composite` and `reflets ar run` on files: generated views of the synthetic world (Mitsuba 3; no
real photographs offline), the user's files never overwritten, bad input one line and exit 2."""

from __future__ import annotations

import numpy as np
import pytest

pytest.importorskip("cv2")
pytest.importorskip("mitsuba")

from PIL import Image  # noqa: E402

from reflets.ar import capture  # noqa: E402
from reflets.ar.board import Board  # noqa: E402
from reflets.ar.camera import Intrinsics, camera_fields  # noqa: E402
from reflets.ar.synthetic import look_at_pose  # noqa: E402
from reflets.ar.world import SKY, World  # noqa: E402
from reflets.cli import main  # noqa: E402

SCENE = """
[camera]
position = [0, 1, 1]
look_at = [0, 0, 0]

[materials.clay]
type = "lambert"
albedo = [0.7, 0.5, 0.35]

[[mesh]]
shape = "sphere"
radius = 0.05
transform = { translate = [0, 0.05, 0] }
material = "clay"
"""


@pytest.fixture(scope="module")
def files(tmp_path_factory):
    folder = tmp_path_factory.mktemp("ar")
    board = Board.grid()
    board.save(folder / "board.json")
    intrinsics = Intrinsics.from_fov((320, 240), 55)
    intrinsics.save(folder / "camera.json")
    (folder / "objects.toml").write_text(SCENE)
    world = World(board, SKY)
    names = []
    for k, eye in enumerate([(0.2, 0.3, 0.4), (-0.25, 0.35, 0.3), (0.0, 0.45, 0.3)]):
        R, t = look_at_pose(eye, (0, 0.02, 0))
        linear = world.render(camera_fields(intrinsics, R, t), spp=16, seed=k)
        codes = capture.quantise(linear)
        Image.fromarray(codes).save(folder / f"frame{k}.png")
        names.append(str(folder / f"frame{k}.png"))
    return folder, names


def _common(folder):
    return ["--intrinsics", str(folder / "camera.json"), "--board", str(folder / "board.json")]


@pytest.mark.slow
def test_composite_writes_the_photo_with_the_object(files, capsys):
    folder, frames = files
    out = folder / "out.png"
    rc = main(["ar", "composite", str(folder / "objects.toml"), "--background", frames[0], "--capture", *frames[1:],
               *_common(folder), "-o", str(out)])  # fmt: skip
    assert rc == 0
    text = capsys.readouterr().out
    assert "captured 2 of 2 frames" in text and "median ms per stage" in text
    composite, photo = np.asarray(Image.open(out)), np.asarray(Image.open(frames[0]))
    changed = np.any(composite != photo, axis=2)
    assert 0.01 < changed.mean() < 0.5
    rows, cols = np.nonzero(changed)
    assert abs(cols.mean() - 160) < 50 and abs(rows.mean() - 120) < 50  # around the board's centre


@pytest.mark.slow
def test_run_writes_every_frame_and_never_overwrites(files, capsys):
    folder, frames = files
    out = folder / "frames_out"
    assert main(["ar", "run", str(folder / "objects.toml"), *frames, *_common(folder), "-o", str(out)]) == 0
    assert len(list(out.glob("frame_*.png"))) == 3
    assert "3 frames, a pose in 3" in capsys.readouterr().out
    before = sorted(p.stat().st_mtime_ns for p in out.iterdir())
    assert main(["ar", "run", str(folder / "objects.toml"), *frames, *_common(folder), "-o", str(out)]) == 2
    assert sorted(p.stat().st_mtime_ns for p in out.iterdir()) == before
    assert "exists already" in capsys.readouterr().err


def test_bad_inputs_are_one_line(files, capsys, tmp_path):
    folder, frames = files
    small = tmp_path / "small.png"
    Image.fromarray(np.zeros((10, 12, 3), np.uint8)).save(small)
    cases = [
        ["ar", "composite", str(folder / "objects.toml"), "--background", str(small), *_common(folder),
         "-o", str(tmp_path / "o.png")],
        ["ar", "composite", str(folder / "objects.toml"), "--background", frames[0], *_common(folder),
         "--mode", "document", "-o", str(tmp_path / "o.txt")],
        ["ar", "run", str(folder / "objects.toml"), *_common(folder), "-o", str(tmp_path / "v.mp4")],
        ["ar", "composite", str(folder / "objects.toml"), "--background", frames[0], *_common(folder),
         "--radius", "-1", "-o", str(tmp_path / "o.png")],
        ["ar", "composite", str(folder / "objects.toml"), "--background", frames[0], "--capture", frames[1],
         "--environment", str(SKY), *_common(folder), "-o", str(tmp_path / "o.png")],
    ]  # fmt: skip
    for argv in cases:
        assert main(argv) == 2, argv
        err = capsys.readouterr().err.strip()
        assert len(err.splitlines()) == 1 and "Traceback" not in err, err


def test_a_camera_index_out_of_range_is_refused_before_opencv_sees_it():
    """``ar run --webcam -1`` ended in a segmentation fault inside cv2.VideoCapture: refused first, one line."""
    from reflets.ar.video import MAX_CAMERA_INDEX, FrameSource
    from reflets.errors import ArgumentError

    for bad in (-1, MAX_CAMERA_INDEX + 1, 10**9, True):
        with pytest.raises(ArgumentError, match=f"^--webcam: a camera index is from 0 to {MAX_CAMERA_INDEX}"):
            FrameSource.open([], bad)


def test_a_short_video_round_trips(tmp_path):
    """ar run's video path: frames written by FrameSink come back through FrameSource (OpenCV's codecs)."""
    from reflets.ar.video import FrameSink, FrameSource

    frames = [np.full((48, 64, 3), 40 * k, np.uint8) for k in range(1, 4)]
    sink = FrameSink.open(str(tmp_path / "clip.avi"))
    for frame in frames:
        sink.write(frame)
    sink.commit()
    back = list(FrameSource.open([str(tmp_path / "clip.avi")], None).frames())
    assert len(back) == 3
    for a, b in zip(back, frames, strict=True):
        assert a.shape == b.shape and np.abs(a.astype(int) - b).mean() < 3  # MJPG is lossy


@pytest.mark.slow
def test_run_on_a_synthetic_video(files, capsys):
    """The live loop on a short generated video (the three views, MJPG): a pose in every frame."""
    from reflets.ar.video import FrameSink

    folder, frames = files
    sink = FrameSink.open(str(folder / "clip.avi"))
    for name in frames:
        sink.write(np.asarray(Image.open(name).convert("RGB")))
    sink.commit()
    out = folder / "clip_out.avi"
    assert main(["ar", "run", str(folder / "objects.toml"), str(folder / "clip.avi"), *_common(folder),
                 "-o", str(out)]) == 0  # fmt: skip
    assert "3 frames, a pose in 3" in capsys.readouterr().out and out.stat().st_size > 0


def test_a_run_that_fails_half_way_leaves_nothing(files, capsys, tmp_path, monkeypatch):
    """A frame that cannot be decoded after good ones: the frames written so far are not kept (the output is
    written under a temporary name and moved into place only when the run ends well). The frames are passed
    through unchanged (the session's work is not what this checks)."""
    import types

    from reflets import cli

    passed = types.SimpleNamespace(composite=None, pose=None, timings={})
    monkeypatch.setattr(cli, "_ar_session", lambda *a: types.SimpleNamespace(process=lambda frame: passed))
    folder, frames = files
    truncated = tmp_path / "truncated.png"
    truncated.write_bytes((folder / "frame1.png").read_bytes()[:2000])
    out = tmp_path / "frames_out"
    argv = ["ar", "run", str(folder / "objects.toml"), frames[0], str(truncated), *_common(folder), "-o", str(out)]
    assert main(argv) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "truncated.png" in err, err
    assert list(tmp_path.iterdir()) == [truncated]


def test_the_frame_sink_replaces_only_with_overwrite_and_only_a_folder_of_frames(tmp_path):
    from reflets.ar.video import FrameSink
    from reflets.errors import ArgumentError

    frame = np.zeros((4, 6, 3), np.uint8)
    out = tmp_path / "frames"
    sink = FrameSink.open(str(out))
    for _ in range(3):
        sink.write(frame)
    assert not out.exists()  # nothing under the output's name until the run ends well
    sink.commit()
    assert sorted(p.name for p in out.iterdir()) == [f"frame_0000{k}.png" for k in range(3)]
    with pytest.raises(ArgumentError, match="exists already; give --overwrite"):
        FrameSink.open(str(out))
    sink = FrameSink.open(str(out), overwrite=True)
    sink.write(frame)
    sink.discard()  # a failed run: the folder there before untouched
    assert len(list(out.iterdir())) == 3
    sink = FrameSink.open(str(out), overwrite=True)
    sink.write(frame)
    sink.commit()
    assert [p.name for p in out.iterdir()] == ["frame_00000.png"]
    assert sorted(p.name for p in tmp_path.iterdir()) == ["frames"]  # no temporary left
    with pytest.raises(ArgumentError, match="holds one of the inputs"):  # its frames are this run's input
        FrameSink.open(str(out), overwrite=True, inputs=[str(out / "frame_00000.png")])
    (out / "notes.txt").write_text("mine")
    with pytest.raises(ArgumentError, match="holds files that are not frames"):
        FrameSink.open(str(out), overwrite=True)
    photo = tmp_path / "photo.mp4"
    photo.write_bytes(b"input")
    with pytest.raises(Exception, match="is one of the inputs"):
        FrameSink.open(str(photo), overwrite=True, inputs=[str(photo)])
    (tmp_path / "x.mp4").mkdir()
    with pytest.raises(ArgumentError, match="is a folder; a video cannot replace it"):
        FrameSink.open(str(tmp_path / "x.mp4"), overwrite=True)
