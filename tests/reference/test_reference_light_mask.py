"""Quad-light masks in the references: the texture convention, the NumPy Monte Carlo (light samples, BRDF
samples and camera rays that hit the light) and the Mitsuba 3 bridge."""

from __future__ import annotations

import numpy as np
import pytest
from PIL import Image

import reflets
from reflets.reference.lights import PolygonSampler
from reflets.scene.camera import pixel_rays
from reflets.scene.lightmask import load_mask
from reflets.validation import polygon_irradiance

CORNERS = [[-0.5, 1.0, -0.5], [0.5, 1.0, -0.5], [-0.5, 1.0, 0.5]]  # faces down onto the plane y = 0
HALF = [CORNERS[0], [0.0, 1.0, -0.5], CORNERS[2]]  # u < ½: what a mask 1 on the left half emits
SIZE = (48, 36)


def scene(material: dict, light: dict) -> reflets.Scene:
    return reflets.load_dict(
        {
            "camera": {"position": [0, 3, 4], "look_at": [0, 0, 0], "fov_y": 45, "size": list(SIZE)},
            "materials": {"floor": material},
            "mesh": [{"shape": "plane", "size": [4, 4], "material": "floor"}],
            "light": [{"type": "quad", "radiance": [5, 5, 5], **light}],
        }
    )


def half_mask(tmp_path) -> str:
    mask = np.zeros((4, 6))
    mask[:, :3] = 1.0
    np.save(tmp_path / "half.npy", mask)
    return str(tmp_path / "half.npy")


def test_bottom_left_texel_sits_at_c1(tmp_path):
    """A PNG's bottom-left texel (white) lights the corner at c1, its top-right one (red) counts as its
    luminance, the others (black) emit nothing."""
    pixels = np.zeros((2, 3, 3), dtype=np.uint8)
    pixels[1, 0] = 255  # bottom-left
    pixels[0, 2] = (255, 0, 0)  # top-right: red, luminance 0.2126
    Image.fromarray(pixels).save(tmp_path / "corner.png")
    light = {"corners": CORNERS, "mask": "corner.png"}
    s = reflets.load_dict(
        {
            "camera": {"position": [0, 3, 4], "look_at": [0, 0, 0]},
            "light": [{"type": "quad", "radiance": [1, 2, 3], **light}],
        },
        base_dir=tmp_path,
    )
    sampler = PolygonSampler(s.light[0], load_mask(s, 0))
    c1, c2, c4 = (np.asarray(c) for c in CORNERS)
    e1, e2 = c2 - c1, c4 - c1
    points = np.array(
        [c1 + 0.1 * e1 + 0.1 * e2, c1 + 0.9 * e1 + 0.1 * e2, c1 + 0.9 * e1 + 0.9 * e2, c1 + 0.1 * e1 + 0.9 * e2]
    )
    np.testing.assert_allclose(sampler.radiance_at(points), [[1, 2, 3], [0, 0, 0], [0.2126, 0.4252, 0.6378], [0] * 3])


def exact_lambert_floor(corners, albedo: float = 0.8) -> np.ndarray:
    """Exact radiance (H, W, 3) of the Lambert plane y = 0 at the test camera's pixel centres (0 off it)."""
    s = scene({"type": "lambert", "albedo": [1, 1, 1]}, {"corners": corners})
    origin, dirs = pixel_rays(s.camera, SIZE)
    points = origin - (origin[1] / dirs[..., 1])[..., None] * dirs
    on = np.all(np.abs(points[..., [0, 2]]) < 2.0, axis=-1)
    e = polygon_irradiance(points[on], np.broadcast_to([0.0, 1.0, 0.0], points[on].shape), s.light[0].polygon())
    out = np.zeros(points.shape)
    out[on] = (albedo / np.pi * 5.0) * e[:, None]
    return out


def z_scores(a, b) -> np.ndarray:
    """(a − b) / combined standard error over the pixels noisy in both (not where a camera ray meets the back
    of the masked-off half of the light: the half light's scene sees the floor there)."""
    se = np.hypot(a.stderr, getattr(b, "stderr", 0.0))
    keep = (a.stderr > 0) & (getattr(b, "stderr", 1.0) > 0)
    return ((a.image - getattr(b, "image", b))[keep] / se[keep]).ravel()


def test_lambert_half_mask_is_the_exact_half_light(tmp_path):
    """The masked reference matches Lambert's formula for the half light within its standard error (light
    and BRDF samples both see the mask; camera rays that hit the emitter see its back and are excluded)."""
    lambert = {"type": "lambert", "albedo": [0.8, 0.8, 0.8]}
    masked = scene(lambert, {"corners": CORNERS, "mask": half_mask(tmp_path)})
    result = reflets.reference(masked, spp=32, progress=False, visibility=False)
    z = z_scores(result, exact_lambert_floor(HALF))
    assert len(z) > 3 * 800
    assert abs(z.mean()) < 0.1 and np.mean(np.abs(z) < 3) > 0.99, (z.mean(), np.mean(np.abs(z) < 3))
    whole = z_scores(result, exact_lambert_floor(CORNERS))  # the mask must matter: the whole light is far off
    assert whole.mean() < -3


def test_glossy_half_mask_reference_equals_the_half_light_reference(tmp_path):
    """Phong e = 100 (BRDF samples carry much of the highlight under MIS): the masked light's reference equals
    the half light's within 3 combined standard errors on average (mean z ≈ 0, ≥ 99 % of |z| < 3)."""
    phong = {"type": "phong", "kd": [0.2] * 3, "ks": [0.8] * 3, "exponent": 100}
    masked = reflets.reference(
        scene(phong, {"corners": CORNERS, "mask": half_mask(tmp_path)}), spp=32, progress=False, visibility=False
    )
    half = reflets.reference(scene(phong, {"corners": HALF}), spp=32, seed=1, progress=False, visibility=False)
    z = z_scores(masked, half)
    assert abs(z.mean()) < 0.1 and np.mean(np.abs(z) < 3) > 0.99, (z.mean(), np.mean(np.abs(z) < 3))


def test_camera_sees_the_mask_on_the_emitter(tmp_path):
    """Looking up at the light's emitting side: the half mask shows as the half light."""
    s = reflets.load_dict(
        {
            "camera": {"position": [0, 0, 0.01], "look_at": [0, 1, 0], "fov_y": 90, "size": [32, 32]},
            "light": [{"type": "quad", "corners": CORNERS, "radiance": [5, 5, 5], "mask": half_mask(tmp_path)}],
        }
    )
    image = reflets.reference(s, spp=1, progress=False).image[..., 0]
    lit = image > 0
    assert np.all(image[lit] == 5.0)
    half = reflets.reference(
        reflets.load_dict(
            {
                **s.model_dump(mode="json", exclude_none=True),
                "light": [{"type": "quad", "corners": HALF, "radiance": [5, 5, 5]}],
            }
        ),
        spp=1,
        progress=False,
    ).image[..., 0]
    assert lit.sum() > 100 and np.sum(lit != (half > 0)) <= 2 * 32  # at most the pixels along the mask's edge


def test_mitsuba_renders_the_mask(tmp_path):
    """The Mitsuba bridge's bitmap emitter (nearest texel, row v = 0 first) lights the floor as the NumPy
    reference does: same energy within 1 %, same image within 3 % relative MSE (Mitsuba's box pixels)."""
    pytest.importorskip("mitsuba")
    from reflets.reference.mitsuba_bridge import render_mitsuba

    mask = np.zeros((2, 2))
    mask[1, 0], mask[1, 1] = 1.0, 0.3  # bottom row: light near c1, dim near c2; nothing on the far half
    np.save(tmp_path / "m.npy", mask)
    lambert = {"type": "lambert", "albedo": [0.8, 0.8, 0.8]}
    s = scene(lambert, {"corners": CORNERS, "mask": str(tmp_path / "m.npy")})
    ours = reflets.reference(s, spp=64, progress=False, pixel="box").image
    theirs = render_mitsuba(s, spp=256)
    floor = np.zeros(ours.shape[:2], bool)
    floor[SIZE[1] // 2 :] = True  # the light itself is in the upper half of the image
    ratio = theirs[floor].sum() / ours[floor].sum()
    assert abs(ratio - 1.0) < 0.01, ratio
    assert np.mean((theirs[floor] - ours[floor]) ** 2) / np.mean(ours[floor] ** 2) < 3e-2
