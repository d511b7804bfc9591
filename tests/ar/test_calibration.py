"""Camera calibration on generated views of the board (real photographs are not available offline) through a
known lens — off-centre principal point, mild barrel distortion: K recovered within 1 % and 3 px, and a
distorted view tracked right once its distortion is known."""

from __future__ import annotations

import numpy as np
import pytest

pytest.importorskip("cv2", reason="the 'ar' extra (make test installs it)")

from reflets.ar.board import Board  # noqa: E402
from reflets.ar.calibration import calibrate  # noqa: E402
from reflets.ar.camera import Intrinsics  # noqa: E402
from reflets.ar.synthetic import look_at_pose, render_view  # noqa: E402
from reflets.ar.tracking import detect, pose_error, solve_pose  # noqa: E402
from reflets.cli import main  # noqa: E402
from reflets.errors import ArgumentError  # noqa: E402

BOARD = Board.grid()  # 5 × 4 markers of 5 cm: units are metres
LENS = Intrinsics.from_fov((640, 480), 50.0, principal=(330.0, 235.0))
LENS.dist = np.array([-0.1, 0.05, 0.0, 0.0, 0.0])


def calibration_poses(count: int = 14) -> list[tuple[np.ndarray, np.ndarray]]:
    """Eyes on a ring around the board, alternately 30° and 45° from its normal at 0.32 and 0.37 m, aimed off
    its centre so that it reaches the frame's edges, where the distortion shows."""
    poses = []
    for k in range(count):
        azimuth = 2 * np.pi * k / count
        tilt, distance = (np.radians(30), 0.32) if k % 2 == 0 else (np.radians(45), 0.37)
        eye = distance * np.array([np.sin(tilt) * np.cos(azimuth), np.cos(tilt), np.sin(tilt) * np.sin(azimuth)])
        target = (0.08 * np.cos(3 * azimuth), 0.0, 0.08 * np.sin(2 * azimuth))
        poses.append(look_at_pose(eye, target))
    return poses


@pytest.fixture(scope="module")
def views():
    """The calibration views, with mild blur and noise (rendered once: about a second)."""
    return [render_view(BOARD, LENS, R, t, blur=0.6, noise=2.0, seed=k) for k, (R, t) in enumerate(calibration_poses())]


def test_calibration_recovers_the_focal_lengths_within_1_percent_and_the_principal_point_within_3_px(views):
    result = calibrate(views, BOARD)
    K = result.intrinsics.K
    assert result.views_used == len(views) and result.intrinsics.size == (640, 480)
    np.testing.assert_allclose([K[0, 0], K[1, 1]], [LENS.K[0, 0], LENS.K[1, 1]], rtol=0.01)
    assert np.hypot(K[0, 2] - 330.0, K[1, 2] - 235.0) < 3.0, K
    assert abs(result.intrinsics.dist[0] - LENS.dist[0]) < 0.02, result.intrinsics.dist
    assert result.rms < 0.5


def test_calibration_refuses_too_few_usable_views_and_mixed_sizes(views):
    blank = np.full_like(views[0], 128)
    with pytest.raises(ArgumentError, match="only 2 of 3 images show 4 or more"):
        calibrate([views[0], blank, views[1]], BOARD)
    with pytest.raises(ArgumentError, match=r"^small\.png: is 320x240, not 640x480"):
        calibrate([views[0], views[0][::2, ::2]], BOARD, names=["big.png", "small.png"])


def test_a_distorted_view_tracks_within_5_mm_and_half_a_degree_once_its_distortion_is_known(views):
    pinhole = Intrinsics(LENS.K, np.zeros(5), LENS.size)
    for (R, t), image in list(zip(calibration_poses(), views, strict=True))[:4]:
        world, pixels = detect(image, BOARD)
        pose = solve_pose(world, pixels, LENS)
        position, degrees = pose_error(pose.R, pose.t, R, t)
        assert position < 0.005 and degrees < 0.5, (position, degrees)
        pose_ignoring_the_lens = solve_pose(world, pixels, pinhole)
        assert pose_error(pose_ignoring_the_lens.R, pose_ignoring_the_lens.t, R, t)[0] > 5 * position


def test_the_calibrate_command_writes_camera_json_and_fails_in_one_line(views, tmp_path, capsys):
    from PIL import Image

    BOARD.save(tmp_path / "board.json")
    names = []
    for k, image in enumerate(views):
        names.append(str(tmp_path / f"view{k:02d}.png"))
        Image.fromarray(image).save(names[-1])
    out = tmp_path / "camera.json"
    assert main(["ar", "calibrate", *names, "--board", str(tmp_path / "board.json"), "-o", str(out)]) == 0
    assert f"over {len(views)} of {len(views)} images" in capsys.readouterr().out
    camera = Intrinsics.load(out)
    np.testing.assert_allclose(camera.K, calibrate(views, BOARD).intrinsics.K)  # PNG is lossless
    assert camera.dist.shape == (5,) and camera.size == (640, 480)

    Image.fromarray(np.full_like(views[0], 128)).save(tmp_path / "blank.png")
    few = [names[0], str(tmp_path / "blank.png")]
    assert main(["ar", "calibrate", *few, "--board", str(tmp_path / "board.json"), "-o", str(out), "--overwrite"]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "only 1 of 2 images" in err
