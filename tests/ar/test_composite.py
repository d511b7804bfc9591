"""Compositing a virtual object into a photograph of the synthetic world (Mitsuba 3 path tracing the floor with
the printed board under the sky map): the object lands where its projection from the pose is, its shadow falls
under it, pixels neither reaches keep the photograph's codes, and against the ground truth (the same world
rendered with the object really in it) the differential mode beats the document's on the shadow."""

from __future__ import annotations

import numpy as np
import pytest

pytest.importorskip("cv2")
pytest.importorskip("mitsuba")

import reflets  # noqa: E402
from reflets.ar import capture  # noqa: E402
from reflets.ar.board import Board  # noqa: E402
from reflets.ar.camera import Intrinsics, camera_fields  # noqa: E402
from reflets.ar.composite import Compositor  # noqa: E402
from reflets.ar.synthetic import look_at_pose  # noqa: E402
from reflets.ar.world import SKY, World  # noqa: E402
from reflets.imageio import read_image  # noqa: E402
from reflets.scene import load_dict  # noqa: E402
from reflets.scene.camera import project  # noqa: E402
from reflets.scene.model import Camera  # noqa: E402

RADIUS, CENTRE = 0.05, (0.0, 0.05, 0.0)


@pytest.fixture(scope="module")
def setting():
    objects = load_dict({
        "camera": {"position": [0, 1, 1], "look_at": [0, 0, 0]},
        "materials": {"clay": {"type": "lambert", "albedo": [0.7, 0.5, 0.35]}},
        "mesh": [{"shape": "sphere", "radius": RADIUS, "transform": {"translate": list(CENTRE)}, "material": "clay"}],
    })  # fmt: skip
    world = World(Board.grid(), SKY)
    intrinsics = Intrinsics.from_fov((160, 120), 50, principal=(83.0, 57.5))
    R, t = look_at_pose((0.2, 0.3, 0.4), (0, 0.02, 0))
    camera = camera_fields(intrinsics, R, t)
    photo_linear = world.render(camera, spp=32)
    truth = world.render(camera, objects, spp=32)
    cube = capture.CubeMap.from_equirect(read_image(SKY), 32)  # the true sky: this tests the compositing alone
    return objects, intrinsics, R, t, camera, capture.quantise(photo_linear), truth, cube


@pytest.fixture(scope="module")
def composites(setting):
    objects, intrinsics, R, t, _, photo, _, cube = setting
    return {mode: Compositor(objects, mode, samples=4000, directions=200)(photo, intrinsics, R, t, cube)
            for mode in ("differential", "document")}  # fmt: skip


@pytest.mark.slow
@pytest.mark.parametrize("mode", ["differential", "document"])
def test_object_in_place_and_untouched_pixels(setting, composites, mode):
    _, intrinsics, _, _, camera, photo, _, _ = setting
    out = composites[mode]
    centre = project(Camera(**camera), np.array([CENTRE]))[0]  # continuous pixel coordinates
    assert out.coverage[int(centre[1]), int(centre[0])] == 1.0
    # the sphere's silhouette: its covered area within 5 % of the projected disc's (the sphere subtends a cone)
    distance = np.linalg.norm(np.array(camera["position"]) - CENTRE)
    f = intrinsics.K[1, 1]
    disc = np.pi * (f * np.tan(np.arcsin(RADIUS / distance))) ** 2
    assert abs(out.coverage.sum() / disc - 1) < 0.05
    # untouched: most of the frame, the far floor (beyond the local ground, 6 footprints across) entirely
    assert out.changed.mean() < 0.5
    assert not out.changed[:20].any()
    # the shadow: the ground just beside the sphere's foot, toward the camera's lower side, is darker
    below = (int(centre[1] + 0.9 * np.sqrt(disc / np.pi)) + 2, int(centre[0]))
    assert out.image[below].mean() < photo[below].mean()


@pytest.mark.slow
def test_differential_beats_document_on_the_shadow(setting, composites):
    *_, photo, truth, _ = setting
    photo_linear = capture.decode_response(photo / 255.0)
    either = composites["differential"].coverage + composites["document"].coverage
    truth_coded = capture.decode_response(capture.quantise(truth) / 255)
    shadow = (np.abs(truth_coded - photo_linear).max(axis=2) > 0.01) & (either == 0)
    assert shadow.sum() > 20
    error = {mode: reflets.compare(out.linear[shadow][None], truth_coded[shadow][None])["relmse"]
             for mode, out in composites.items()}  # fmt: skip
    assert error["differential"] < error["document"]


@pytest.mark.slow
def test_the_differential_renderers_follow_the_camera_under_the_same_map(setting):
    """A second frame under the same map moves the three renderers' cameras instead of making them again (no
    new map file, no new prefiltering): the composite is the one a fresh compositor makes for that pose."""
    objects, intrinsics, R, t, _, photo, _, cube = setting
    kept = Compositor(objects, "differential")
    kept(photo, intrinsics, R, t, cube)
    R2, t2 = look_at_pose((0.25, 0.28, 0.38), (0, 0.02, 0))
    second = kept(photo, intrinsics, R2, t2, cube)
    fresh = Compositor(objects, "differential")(photo, intrinsics, R2, t2, cube)
    assert second.timings["environment_ms"] == 0.0
    assert second.timings["prepare_ms"] < 0.5 * fresh.timings["prepare_ms"]
    np.testing.assert_allclose(second.linear, fresh.linear, atol=1e-5)
    assert np.array_equal(second.image, fresh.image)
    kept.release()
    assert kept._local is None


@pytest.mark.slow
def test_a_textured_object_is_composited_with_its_textures(setting, tmp_path):
    """A glTF material with a base colour texture (red left half, blue right half of its uv) on the virtual sphere:
    the differential composite shows both halves where the object is; the document's mode, whose model is Phong's,
    refuses it in one line."""
    from PIL import Image

    from reflets.errors import ArgumentError

    _, intrinsics, R, t, _, photo, _, cube = setting
    codes = np.zeros((4, 8, 3), np.uint8)
    codes[:, :4] = (220, 30, 30)
    codes[:, 4:] = (30, 30, 220)
    Image.fromarray(codes, "RGB").save(tmp_path / "halves.png")
    texture = {"texture": str(tmp_path / "halves.png"), "filter": "nearest"}
    objects = load_dict({
        "camera": {"position": [0, 1, 1], "look_at": [0, 0, 0]},
        "materials": {"painted": {"type": "gltf", "metallic": 0.0, "roughness": 0.7, "base_color_texture": texture}},
        "mesh": [{"shape": "sphere", "radius": RADIUS, "transform": {"translate": list(CENTRE)},
                  "material": "painted"}],
    })  # fmt: skip
    out = Compositor(objects, "differential", samples=4000, directions=200)(photo, intrinsics, R, t, cube)
    inside = out.coverage == 1.0
    assert inside.sum() > 50
    red, blue = out.linear[inside][:, 0], out.linear[inside][:, 2]
    assert (red > 2 * blue).sum() > 10 and (blue > 2 * red).sum() > 10  # both halves seen, each its colour
    with pytest.raises(ArgumentError, match="materials.painted: the document's mode shades"):
        Compositor(objects, "document", samples=4000, directions=200)(photo, intrinsics, R, t, cube)
