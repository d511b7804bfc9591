"""Scratches over a textured base (a glTF material with its textures): the scratches pass reads the base's textures
as the forward pass does (material_surface), and the reference's finite part reads them too; a base with mapped
colours, a normal map and emission takes them too (the pass includes the base's own twin)."""

from __future__ import annotations

import numpy as np
import pytest
from PIL import Image

import reflets
from reflets.metrics import relmse

POINT = {"type": "point", "position": [0.3, 1.0, -1.2], "intensity": [2, 2, 2]}


def plate(base: dict, coverage: float, light: dict, size):
    """A plate scratched at ``coverage`` over ``base``, lit by ``light``."""
    scratched = {"type": "scratched", "preset": "3.14d", "profile": "quartic:0.5", "coverage": coverage,
                 "base": base, "alpha_size": 64, "table_size": 32, "rays": 2000}  # fmt: skip
    return reflets.load_dict({
        "camera": {"position": [0, 1.2, 2.0], "look_at": [0, 0, -0.2], "size": list(size)},
        "materials": {"s": scratched},
        "mesh": [{"shape": "plane", "size": [2.4, 2.4], "material": "s"}],
        "light": [light],
        "background": [0, 0, 0],  # (the environment map's own pixels are no part of a weighted base)
    })  # fmt: skip


def test_scratches_over_a_textured_gltf_base(tmp_path):
    checker = (np.indices((8, 8)).sum(axis=0) % 2 * 200 + 40).astype(np.uint8)
    Image.fromarray(np.dstack([checker, checker // 2, 255 - checker]), "RGB").save(tmp_path / "checker.png")
    untextured = {"type": "gltf", "metallic": 0.6, "roughness": 0.35}
    base = {**untextured, "base_color_texture": {"texture": str(tmp_path / "checker.png"), "filter": "nearest"}}

    def scene(coverage, material=base):
        return plate(material, coverage, POINT, (96, 72))

    bare = scene(0.0)  # no scratch: the base alone, as forward shades it
    image = reflets.render(bare, method="scratches")
    alone = bare.model_copy(update={"materials": {"s": bare.materials["s"].base}})
    np.testing.assert_allclose(image, reflets.render(alone, method="forward"), rtol=1e-5, atol=1e-6)
    assert relmse(image, reflets.reference(bare, spp=4, progress=False).image) < 3e-6  # measured 3e-7
    covered = scene(0.02)  # the reference's finite part: the textured base × its uncovered share, exactly
    weight = covered.materials["s"].base_weight()
    finite = reflets.reference(covered, spp=4, progress=False).image
    np.testing.assert_allclose(finite, weight * reflets.reference(alone, spp=4, progress=False).image, rtol=1e-5,
                               atol=1e-7)  # fmt: skip
    assert weight < 0.99
    scratched = reflets.render(covered, method="scratches")
    assert relmse(reflets.render(scene(0.02, untextured), method="scratches"), scratched) > 0.1  # measured 0.35


def test_a_cut_out_or_blended_glTF_base_is_refused_in_one_line():
    from reflets.errors import SceneError

    light = {"type": "point", "position": [0, 1, 0], "intensity": [1, 1, 1]}
    for mode in ("mask", "blend"):
        with pytest.raises(SceneError, match=f'materials.s: a glTF base must be opaque \\(alpha_mode "{mode}"'):
            reflets.load_dict({"camera": {"position": [0, 1, 2], "look_at": [0, 0, 0]},
                               "materials": {"s": {"type": "scratched", "base": {"type": "gltf", "alpha_mode": mode}}},
                               "mesh": [{"shape": "plane", "material": "s"}], "light": [light]})  # fmt: skip


@pytest.mark.parametrize("affine", [False, True])
@pytest.mark.parametrize("environment", [False, True])
def test_scratches_over_a_library_base_with_maps(environment, affine, tmp_path):
    """A library base with a colour map, a mapped exponent (or two affine colours), a normal map and emission, under a
    point light or the studio map: with no scratch the scratches pass is the forward pass of the base (under the map
    too: the pass lights the base by the base's own split sum); scratched, forward by name shows the finite part, the
    base × w̄_b (its per-fragment split sum weighted in the twin); the reference's finite part is the mapped base × its
    uncovered share."""
    import warnings

    from reflets.bench.maps import UV_GRID, write_bumps
    from reflets.scene.assets import default_environment

    bumps = str(write_bumps(tmp_path / "bumps.png"))
    base = {"type": "phong", "kd": {"texture": str(UV_GRID), "factor": [0.6, 0.6, 0.6]}, "ks": [0.3, 0.3, 0.3],
            "exponent": {"texture": str(UV_GRID), "factor": 60}, "normalized": True, "normal_map": {"texture": bumps},
            "emission": [0.05, 0.02, 0.0]}  # fmt: skip
    if affine:  # colours the split sum interpolates between curves at 0 (weighted like the finite part by name)
        base = {"type": "ashikhmin_shirley", "rs": {"texture": str(UV_GRID), "factor": [0.3, 0.3, 0.3]},
                "rd": {"texture": str(UV_GRID), "factor": [0.6, 0.6, 0.6]}, "nu": 100, "nv": 100,
                "normal_map": {"texture": bumps}, "emission": [0.05, 0.02, 0.0]}  # fmt: skip
    light = {"type": "environment", "file": str(default_environment())} if environment else POINT

    def scene(coverage, material=base):
        return plate(material, coverage, light, (64, 48))

    bare = scene(0.0)
    alone = bare.model_copy(update={"materials": {"s": bare.materials["s"].base}})
    image = reflets.render(bare, method="scratches")
    np.testing.assert_allclose(image, reflets.render(alone, method="forward"), rtol=1e-4, atol=1e-5)
    dark = {k: v for k, v in base.items() if k != "emission"}  # (emission is not weighted by the share)
    covered = scene(0.02, dark)
    weight = covered.materials["s"].base_weight()  # = 1 − ᾱ everywhere: a constant coverage
    assert weight < 0.99
    plain = reflets.render(covered.model_copy(update={"materials": {"s": covered.materials["s"].base}}))
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # forward on a scratched material: its finite part, said
        np.testing.assert_allclose(reflets.render(covered, method="forward"), weight * plain, rtol=1e-4, atol=1e-5)
    if not environment:
        finite = reflets.reference(scene(0.02), spp=4, progress=False).image
        emitted = reflets.reference(alone.model_copy(update={"light": []}), spp=4, progress=False).image
        lit = reflets.reference(alone, spp=4, progress=False).image - emitted  # the share weights the BRDF alone
        np.testing.assert_allclose(finite, weight * lit + emitted, rtol=1e-4, atol=1e-6)
