"""Quad-light masks (``QuadLight.mask``) on the GPU: a half mask is the half light, an all-ones mask is no mask,
the grid methods agree, the others refuse a masked light."""

from __future__ import annotations

import numpy as np
import pytest
from meunier_helpers import CORNERS, document_scene, phong, plane_pixels, relative_mse

import reflets
from reflets.errors import SceneError

LAMBERT = {"type": "lambert", "albedo": [0.8, 0.8, 0.8]}
SIZE = (64, 48)
#: the document's light cut in half along u (c1 → c2): what a mask 1 on the left half, 0 on the right emits
HALF = {"type": "quad", "corners": [CORNERS[0], [0.0, 1.0, -0.5], CORNERS[2]], "radiance": [5, 5, 5]}


def half_mask(path, shape=(6, 8)) -> str:
    """An (H, W) mask, 1 on the left half (u < ½), 0 on the right."""
    mask = np.zeros(shape)
    mask[:, : shape[1] // 2] = 1.0
    np.save(path, mask)
    return str(path)


def masked(material: dict, mask: str, **extra) -> reflets.Scene:
    light = {"type": "quad", "corners": CORNERS, "radiance": [5, 5, 5], "mask": mask, **extra}
    return document_scene(material, light=light, size=SIZE)


def lit(image: np.ndarray, mask: np.ndarray) -> np.ndarray:
    """Plane pixels where the image is above 10⁻³ of its maximum (the relative error means something)."""
    lum = image.sum(axis=-1)
    return mask & (lum > 1e-3 * lum[mask].max())


def test_half_mask_is_the_half_light(ctx, tmp_path):
    """brute 32² over the masked light = the 16 × 32 midpoint grid over the half light, against Lambert's exact
    formula for the half light (analytic): within 10⁻³ relative on every lit plane pixel."""
    scene = masked(LAMBERT, half_mask(tmp_path / "m.npy"))
    _, mask = plane_pixels(scene, SIZE)
    image = reflets.render(scene, method="brute", size=SIZE, grid=32)
    exact = reflets.render(document_scene(LAMBERT, light=HALF, size=SIZE), method="analytic", size=SIZE)
    sel = lit(exact, mask)
    assert sel.sum() > 1000
    err = np.abs(image[sel] - exact[sel]) / exact[sel]
    assert err.max() < 1e-3, err.max()  # measured 2.3e-4 (16²: 9.1e-4, 8²: 3.6e-3)
    unmasked = reflets.render(document_scene(LAMBERT, size=SIZE), method="brute", size=SIZE, grid=32)
    assert np.mean(np.abs(unmasked[sel] - exact[sel]) / exact[sel]) > 0.2  # the mask did something


def test_all_ones_mask_is_no_mask(ctx, tmp_path):
    """The fetch path with a mask of ones gives the unmasked image bit for bit (brute, adaptive, forward)."""
    np.save(tmp_path / "ones.npy", np.ones((3, 5)))
    material = phong(50, kd=0.3)
    for method, params in (("brute", {"grid": 6}), ("adaptive", {}), ("forward", {"area_samples": 6})):
        plain = reflets.render(document_scene(material, size=SIZE), method=method, size=SIZE, **params)
        ones = reflets.render(masked(material, str(tmp_path / "ones.npy")), method=method, size=SIZE, **params)
        np.testing.assert_array_equal(ones, plain, err_msg=method)


def test_half_mask_skips_the_masked_out_samples(ctx, tmp_path):
    scene = masked(LAMBERT, half_mask(tmp_path / "m.npy"))
    _, mask = plane_pixels(scene, SIZE)
    counts = reflets.render(scene, method="brute", size=SIZE, grid=8, output="samples")[..., 0]
    assert np.all(counts[mask] == 32)


def test_forward_samples_are_brutes_grid(ctx, tmp_path):
    """forward's masked midpoint samples are brute's masked grid: the same sums in another order."""
    scene = masked(phong(50, kd=0.3), half_mask(tmp_path / "m.npy", shape=(12, 16)))
    _, mask = plane_pixels(scene, SIZE)
    brute = reflets.render(scene, method="brute", size=SIZE, grid=16)
    forward = reflets.render(scene, method="forward", size=SIZE, area_samples=16)
    np.testing.assert_allclose(forward[mask], brute[mask], rtol=1e-4, atol=1e-6)  # float32 summation order


@pytest.mark.parametrize(
    ("material", "method", "params", "tolerance"),
    [
        # adaptive on Lambert: 2 × 2 grids (even n: the mask edge falls between samples), the midpoint error of
        # 2² samples — measured 1.3e-3, the unmasked light's 9.3e-4 against the exact formula (adaptive.py)
        (LAMBERT, "adaptive", {}, 3e-3),
        # biased, masked Lambert: the whole-light 8² grid; measured 3.8e-6
        (LAMBERT, "biased", {}, 1e-4),
        # biased, masked Phong + diffuse: diffuse on the whole-light 16² grid, the lobe on the cone's box, whose
        # grid straddles the mask edge (O(1/n) there); measured 1.1e-4 (unmasked 1.1e-5), 8²: 3.3e-4
        (phong(50, kd=0.3), "biased", {"grid": 16}, 3e-4),
    ],
)
def test_grid_methods_agree_with_brute(ctx, tmp_path, material, method, params, tolerance):
    scene = masked(material, half_mask(tmp_path / "m.npy", shape=(12, 16)))
    _, mask = plane_pixels(scene, SIZE)
    reference = reflets.render(scene, method="brute", size=SIZE, grid=32)
    image = reflets.render(scene, method=method, size=SIZE, **params)
    assert relative_mse(image, reference, mask) < tolerance


def test_biased_masked_light_is_not_the_exact_diffuse_of_the_whole_light(ctx, tmp_path):
    """biased's exact diffuse term cannot see a mask: the masked light must fall back to the grid (an exact
    term of the whole light would be twice as bright on average)."""
    scene = masked(LAMBERT, half_mask(tmp_path / "m.npy"))
    _, mask = plane_pixels(scene, SIZE)
    image = reflets.render(scene, method="biased", size=SIZE)
    half = reflets.render(document_scene(LAMBERT, light=HALF, size=SIZE), method="analytic", size=SIZE)
    assert relative_mse(image, half, mask) < 1e-4


@pytest.mark.parametrize("method", ["analytic", "ltc", "mc"])
def test_methods_without_mask_support_refuse(ctx, tmp_path, method):
    scene = masked(LAMBERT, half_mask(tmp_path / "m.npy"))
    with pytest.raises(SceneError, match=rf"light\[0\]\.mask: supported by forward, .*; not by {method}"):
        reflets.render(scene, method=method, size=(8, 6))


# ------------------------------------------------------------------------- bad masks: exit 2, one line, no file
SCENE_TOML = """
[camera]
position = [0, 3, 4]
look_at = [0, 0, 0]
size = [16, 12]

[materials.floor]
type = "lambert"
albedo = [0.8, 0.8, 0.8]

[[mesh]]
shape = "plane"
size = [4, 4]
material = "floor"

[[light]]
type = "quad"
corners = [[-0.5, 1, -0.5], [0.5, 1, -0.5], [-0.5, 1, 0.5]]
radiance = [5, 5, 5]
mask = "{mask}"
"""


def _write_bad(path, kind: str) -> str:
    """A bad mask of each kind, written next to the scene; returns its file name."""
    values = {"above one": [[0.5, 2.0]], "negative": [[0.5, -0.1]], "NaN": [[0.5, np.nan]], "all zero": [[0.0, 0.0]]}
    if kind == "missing":
        return "gone.png"
    if kind == "unreadable":
        (path / "broken.png").write_bytes(b"not a png")
        return "broken.png"
    np.save(path / "bad.npy", np.asarray(values[kind]))
    return "bad.npy"


@pytest.mark.parametrize(
    ("kind", "word"),
    [
        ("missing", "does not exist"),
        ("unreadable", "cannot decode"),
        ("above one", "[0, 1]"),
        ("negative", "[0, 1]"),
        ("NaN", "NaN"),
        ("all zero", "zero everywhere"),
    ],
)
def test_bad_mask_exits_2_with_one_line(capsys, tmp_path, kind, word):
    from reflets.cli import main

    name = _write_bad(tmp_path, kind)
    scene = tmp_path / "s.toml"
    scene.write_text(SCENE_TOML.replace("{mask}", name))
    out = tmp_path / "out.exr"
    code = main(["render", str(scene), "-o", str(out)])
    err = capsys.readouterr().err
    lines = err.strip().splitlines()
    assert code == 2 and len(lines) == 1 and "Traceback" not in err, err
    assert "light[0].mask" in lines[0] and name in lines[0] and word in lines[0], lines[0]
    assert not out.exists()


def test_relative_mask_path_resolves_against_the_scene_file(ctx, tmp_path, monkeypatch):
    (tmp_path / "masks").mkdir()
    absolute = half_mask(tmp_path / "masks" / "half.npy")
    (tmp_path / "rel.toml").write_text(SCENE_TOML.replace("{mask}", "masks/half.npy"))
    (tmp_path / "abs.toml").write_text(SCENE_TOML.replace("{mask}", absolute))
    monkeypatch.chdir(tmp_path / "masks")  # not the scene's folder: masks/half.npy does not exist from here
    relative = reflets.render(reflets.load_scene(tmp_path / "rel.toml"), method="brute", grid=4)
    np.testing.assert_array_equal(
        relative, reflets.render(reflets.load_scene(tmp_path / "abs.toml"), method="brute", grid=4)
    )
    plain = reflets.load_dict(
        {
            **reflets.load_scene(tmp_path / "abs.toml").model_dump(mode="json"),
            "light": [{"type": "quad", "corners": CORNERS, "radiance": [5, 5, 5]}],
        }
    )
    assert relative.sum() < 0.6 * reflets.render(plain, method="brute", grid=4).sum()


def test_visible_emitter_shows_its_mask(ctx, tmp_path):
    """Seen from below, a masked two-sided light draws its mask: the forward image of the emitter equals the
    image of the unmasked half light (same pixels lit, same radiance), as the references draw it."""
    camera = {"position": [0.0, -2.0, 0.001], "look_at": [0.0, 1.0, 0.0], "fov_y": 60, "size": [64, 48]}
    base = {"camera": camera, "materials": {"m": LAMBERT}, "mesh": []}
    mask = half_mask(tmp_path / "half.npy")
    masked_scene = reflets.load_dict(
        {
            **base,
            "light": [{"type": "quad", "corners": CORNERS, "radiance": [5, 5, 5], "mask": mask, "two_sided": True}],
        }
    )
    half_scene = reflets.load_dict({**base, "light": [{**HALF, "two_sided": True}]})
    image = reflets.render(masked_scene)
    assert (image > 0).any()
    np.testing.assert_array_equal(image, reflets.render(half_scene))
