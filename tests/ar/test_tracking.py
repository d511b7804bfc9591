"""Marker tracking on generated views of a board with known poses (real photographs are not available
offline): the pose within the issue's 5 mm and 0.5°, the pose kept a few frames after the board is lost, and
OpenGL matrices that project as OpenCV does for any principal point."""

from __future__ import annotations

import json

import numpy as np
import pytest

pytest.importorskip("cv2", reason="the 'ar' extra (make test installs it)")

from reflets.ar.board import Board  # noqa: E402
from reflets.ar.camera import Intrinsics, gl_view  # noqa: E402
from reflets.ar.synthetic import look_at_pose, render_view  # noqa: E402
from reflets.ar.tracking import KEEP_FRAMES, detect, pose_error, solve_pose, track  # noqa: E402
from reflets.cli import main  # noqa: E402

BOARD = Board.grid()  # 5 × 4 markers of 5 cm: units are metres
CAMERA = Intrinsics.from_fov((640, 480), 50.0, principal=(330.0, 235.0))
EYES = ([0.0, 0.45, 0.25], [0.2, 0.35, 0.3], [-0.3, 0.5, -0.1], [0.1, 0.7, 0.5])


# heavier blur and noise at the farthest view (1.5 px, σ = 6) give 5.8 mm: the benchmark's ground, not a bound
@pytest.mark.parametrize("blur, noise", [(0.0, 0.0), (0.8, 3.0)])
def test_poses_of_generated_views_are_within_5_mm_and_half_a_degree(blur, noise):
    for k, eye in enumerate(EYES):
        R, t = look_at_pose(eye)
        image = render_view(BOARD, CAMERA, R, t, blur=blur, noise=noise, gain=0.9, seed=k)
        pose = solve_pose(*detect(image, BOARD), CAMERA)
        assert pose is not None and pose.markers >= 15
        position, degrees = pose_error(pose.R, pose.t, R, t)
        assert position < 0.005 and degrees < 0.5, (eye, position, degrees)


def test_a_pose_is_kept_a_few_frames_after_the_board_is_lost():
    R, t = look_at_pose(EYES[0])
    view = render_view(BOARD, CAMERA, R, t)
    blank = np.full_like(view, 128)
    poses = track([blank, view] + [blank] * (KEEP_FRAMES + 1), BOARD, CAMERA)
    assert poses[0] is None and poses[1].markers == 20
    assert all(p is not None and p.markers == 0 for p in poses[2 : 2 + KEEP_FRAMES])
    assert poses[-1] is None


def test_gl_matrices_project_as_opencv_with_an_off_centre_principal_point():
    import cv2

    R, t = look_at_pose(EYES[1])
    corners = np.concatenate(list(BOARD.markers.values()))
    expected, _ = cv2.projectPoints(corners, cv2.Rodrigues(R)[0], t, CAMERA.K, CAMERA.dist)
    clip = CAMERA.gl_projection(0.01, 10.0) @ gl_view(R, t) @ np.c_[corners, np.ones(len(corners))].T
    ndc = clip[:2] / clip[3]
    w, h = CAMERA.size
    pixels = np.stack([(ndc[0] + 1) / 2 * w - 0.5, (1 - ndc[1]) / 2 * h - 0.5], axis=1)  # OpenCV's pixel centres
    np.testing.assert_allclose(pixels, expected.reshape(-1, 2), atol=1e-6)


def test_the_commands_write_a_board_and_the_poses(tmp_path, capsys):
    from PIL import Image

    assert main(["ar", "board", "-o", str(tmp_path / "board.json"), "--image", str(tmp_path / "board.png")]) == 0
    board = Board.load(tmp_path / "board.json")
    assert len(board.markers) == 20 and (tmp_path / "board.png").exists()
    CAMERA.save(tmp_path / "camera.json")
    names = []
    for k, eye in enumerate(EYES[:2]):
        R, t = look_at_pose(eye)
        names.append(str(tmp_path / f"view{k}.png"))
        Image.fromarray(render_view(board, CAMERA, R, t, blur=0.5, noise=2.0)).save(names[-1])
    out = tmp_path / "poses.json"
    assert main(["ar", "track", *names, "--intrinsics", str(tmp_path / "camera.json"), "--board",
                 str(tmp_path / "board.json"), "-o", str(out)]) == 0  # fmt: skip
    views = json.loads(out.read_text())["views"]
    R, t = look_at_pose(EYES[1])
    position, degrees = pose_error(np.array(views[1]["R_world_to_cam"]), np.array(views[1]["t_world_to_cam"]), R, t)
    assert position < 0.005 and degrees < 0.5
    assert main(["ar", "track", names[0], "--intrinsics", str(tmp_path / "none.json"), "--board",
                 str(tmp_path / "board.json"), "-o", str(out), "--overwrite"]) == 2  # fmt: skip
    assert "none.json: --intrinsics: file not found" in capsys.readouterr().err
    assert main(["ar", "board", "-o", str(tmp_path / "b.json"), "--dictionary", "DICT_NOPE"]) == 2


def test_renderer_camera_of_a_pose_projects_like_opencv():
    """The scene camera built from K and a pose puts world points where cv2.projectPoints does (principal point
    off centre, fx ≠ fy)."""
    import cv2

    from reflets.ar.camera import camera_fields
    from reflets.scene.camera import project
    from reflets.scene.model import Camera

    K = np.array([[530.0, 0, 331.7], [0, 552.0, 228.4], [0, 0, 1]])
    intrinsics = Intrinsics(K, np.zeros(5), (640, 480))
    R, t = look_at_pose((0.3, 0.5, 0.6), (0.02, 0, -0.03))
    camera = Camera(**camera_fields(intrinsics, R, t))
    points = np.random.default_rng(1).uniform(-0.15, 0.15, (50, 3))
    expected = cv2.projectPoints(points, cv2.Rodrigues(R)[0], t, K, None)[0].reshape(-1, 2)
    # reflets' pixel centres are at half-integers, OpenCV's at integers
    assert np.abs(project(camera, points) - 0.5 - expected).max() < 1e-6
