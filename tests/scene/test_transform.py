"""Object transforms, the view matrix and the projection, plus MeshData.transformed."""

from __future__ import annotations

import math

import numpy as np
import pytest

from reflets.errors import SceneError
from reflets.scene.shapes import sphere
from reflets.scene.transform import look_at, perspective, transform_matrix


def apply(m: np.ndarray, p) -> np.ndarray:
    return (m @ np.append(np.asarray(p, dtype=float), 1.0))[:3]


def test_defaults_give_identity():
    np.testing.assert_array_equal(transform_matrix(), np.eye(4))


@pytest.mark.parametrize(
    ("rotate", "point", "expected"),
    [
        ((90, 0, 0), (0, 1, 0), (0, 0, 1)),  # right-handed about +x: y -> z
        ((0, 90, 0), (0, 0, 1), (1, 0, 0)),  # about +y: z -> x
        ((0, 0, 90), (1, 0, 0), (0, 1, 0)),  # about +z: x -> y
    ],
)
def test_single_axis_rotations_are_right_handed_in_degrees(rotate, point, expected):
    np.testing.assert_allclose(apply(transform_matrix(rotate=rotate), point), expected, atol=1e-12)


@pytest.mark.parametrize(
    ("point", "expected"),
    [
        # x: Rx keeps x, Ry(90) takes x to -z, Rz keeps -z.  (Z first would give +z.)
        ((1, 0, 0), (0, 0, -1)),
        # y: Rx takes y to z, Ry takes z to x, Rz takes x to y.
        ((0, 1, 0), (0, 1, 0)),
        # z: Rx takes z to -y, Ry keeps -y, Rz takes -y to x.
        ((0, 0, 1), (1, 0, 0)),
    ],
)
def test_rotation_is_applied_about_x_then_y_then_z(point, expected):
    np.testing.assert_allclose(apply(transform_matrix(rotate=(90, 90, 90)), point), expected, atol=1e-12)


def test_scale_vector_is_applied_first_and_translation_last():
    np.testing.assert_allclose(apply(transform_matrix(scale=(2, 3, 4)), (1, 1, 1)), (2, 3, 4))
    m = transform_matrix(translate=(1, 2, 3), rotate=(0, 0, 90), scale=(2, 5, 7))
    np.testing.assert_allclose(apply(m, (1, 0, 0)), (1, 4, 3), atol=1e-12)
    np.testing.assert_allclose(m[3], (0, 0, 0, 1))


@pytest.mark.parametrize(
    ("kwargs", "message"),
    [
        ({"scale": 0.0}, r"scale: must be non-zero"),
        ({"scale": (1, 2)}, r"scale: must be a number or three numbers"),
        ({"rotate": (1, 2)}, r"rotate: must be three numbers"),
        ({"translate": (0, float("inf"), 0)}, r"translate: must be three numbers"),
    ],
)
def test_transform_matrix_rejects_bad_values(kwargs, message):
    with pytest.raises(SceneError, match=message):
        transform_matrix(**kwargs)


def test_transformed_normals_stay_perpendicular_under_non_uniform_scale():
    abc = np.array([1.0, 3.0, 0.5])
    mesh = sphere(1.0, (64, 32)).transformed(transform_matrix(translate=(1, -2, 3), rotate=(0, 0, 0), scale=abc))
    local = mesh.positions.astype(float) - (1, -2, 3)
    gradient = local / abc**2  # ellipsoid x²/a² + y²/b² + z²/c² = 1
    gradient /= np.linalg.norm(gradient, axis=1, keepdims=True)
    np.testing.assert_allclose(mesh.normals, gradient, atol=1e-5)
    assert np.abs(np.sum(mesh.normals * mesh.tangents[:, :3], axis=1)).max() < 1e-5
    p, idx = mesh.positions.astype(float), mesh.indices.astype(int)
    face = np.cross(p[idx[:, 1]] - p[idx[:, 0]], p[idx[:, 2]] - p[idx[:, 0]])
    assert np.all(np.sum(face * mesh.normals[idx].sum(axis=1), axis=1) > 0)


def test_mirror_flips_winding_and_handedness_but_keeps_normals_outwards():
    original = sphere(1.0, (16, 8))
    mirrored = original.transformed(transform_matrix(scale=(-1, 1, 1)))
    np.testing.assert_array_equal(mirrored.indices, original.indices[:, ::-1])
    np.testing.assert_array_equal(mirrored.tangents[:, 3], -original.tangents[:, 3])
    assert np.all(np.sum(mirrored.normals * mirrored.positions, axis=1) > 0.99)
    p, idx = mirrored.positions.astype(float), mirrored.indices.astype(int)
    face = np.cross(p[idx[:, 1]] - p[idx[:, 0]], p[idx[:, 2]] - p[idx[:, 0]])
    assert np.all(np.sum(face * mirrored.normals[idx].sum(axis=1), axis=1) > 0)


def test_look_at_maps_eye_to_origin_and_target_onto_negative_z():
    eye, target = np.array([1.0, 2.0, 3.0]), np.array([4.0, -1.0, 0.5])
    view = look_at(eye, target, up=(0, 1, 0))
    np.testing.assert_allclose(apply(view, eye), 0.0, atol=1e-12)
    np.testing.assert_allclose(apply(view, target), (0, 0, -np.linalg.norm(target - eye)), atol=1e-12)
    np.testing.assert_allclose(view[:3, :3] @ view[:3, :3].T, np.eye(3), atol=1e-12)
    assert np.linalg.det(view[:3, :3]) == pytest.approx(1.0)
    assert apply(view, eye + (0, 1, 0))[1] > 0  # world up stays up on screen


def test_look_at_rejects_degenerate_camera():
    with pytest.raises(SceneError, match=r"target: must differ from the camera eye"):
        look_at((1, 1, 1), (1, 1, 1))
    with pytest.raises(SceneError, match=r"up: must be non-zero and not parallel"):
        look_at((0, 0, 0), (0, 5, 0), up=(0, 1, 0))


def test_perspective_maps_frustum_edges_to_ndc_bounds():
    fov, aspect, near, far = 60.0, 1.5, 0.1, 100.0
    proj = perspective(fov, aspect, near, far)
    depth = 5.0
    half_h = depth * math.tan(math.radians(fov / 2))

    def ndc(p):
        clip = proj @ np.append(p, 1.0)
        return clip[:3] / clip[3]

    assert ndc([0.0, half_h, -depth])[1] == pytest.approx(1.0)
    assert ndc([aspect * half_h, 0.0, -depth])[0] == pytest.approx(1.0)
    assert ndc([0.0, 0.0, -near])[2] == pytest.approx(-1.0)
    assert ndc([0.0, 0.0, -far])[2] == pytest.approx(1.0)


@pytest.mark.parametrize(
    ("args", "message"),
    [
        ((180.0, 1.0, 0.1, 10.0), r"fov_y: must be in \(0, 180\)"),
        ((60.0, 0.0, 0.1, 10.0), r"aspect: must be > 0"),
        ((60.0, 1.0, 1.0, 1.0), r"near: need 0 < near < far"),
        ((60.0, 1.0, float("nan"), 1.0), r"near: must be a finite number"),
    ],
)
def test_perspective_rejects_bad_parameters(args, message):
    with pytest.raises(SceneError, match=message):
        perspective(*args)
