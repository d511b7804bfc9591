"""Scratches over a textured base (a glTF material with its textures): the scratches pass reads the base's textures
as the forward pass does (material_surface), and the reference's finite part reads them too; a base with mapped
colours is refused (the environment's split sum takes a scratched base's constant albedos)."""

from __future__ import annotations

import numpy as np
import pytest
from PIL import Image

import reflets
from reflets.metrics import relmse


def test_scratches_over_a_textured_gltf_base(tmp_path):
    checker = (np.indices((8, 8)).sum(axis=0) % 2 * 200 + 40).astype(np.uint8)
    Image.fromarray(np.dstack([checker, checker // 2, 255 - checker]), "RGB").save(tmp_path / "checker.png")
    untextured = {"type": "gltf", "metallic": 0.6, "roughness": 0.35}
    base = {**untextured, "base_color_texture": {"texture": str(tmp_path / "checker.png"), "filter": "nearest"}}

    def scene(coverage, material=base):
        scratched = {"type": "scratched", "preset": "3.14d", "profile": "quartic:0.5", "coverage": coverage,
                     "base": material, "alpha_size": 64, "table_size": 32, "rays": 2000}  # fmt: skip
        return reflets.load_dict({
            "camera": {"position": [0, 1.2, 2.0], "look_at": [0, 0, -0.2], "size": [96, 72]},
            "materials": {"s": scratched},
            "mesh": [{"shape": "plane", "size": [2.4, 2.4], "material": "s"}],
            "light": [{"type": "point", "position": [0.3, 1.0, -1.2], "intensity": [2, 2, 2]}],
        })  # fmt: skip

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


@pytest.mark.parametrize(
    ("maps", "named"),
    [({"albedo": {"texture": "x.png"}}, "albedo"), ({"normal_map": {"texture": "x.png"}}, "normal_map"),
     ({"emission": [1, 1, 1]}, "emission"), ({"occlusion": {"texture": "x.png"}}, "occlusion")],
)
def test_a_library_base_with_maps_or_emission_is_refused_in_one_line(maps, named, tmp_path):
    from reflets.errors import SceneError

    says = f"materials.s: a library base takes no texture maps nor emission \\({named}\\)"
    with pytest.raises(SceneError, match=says):
        reflets.load_dict({"camera": {"position": [0, 1, 2], "look_at": [0, 0, 0]},
                           "materials": {"s": {"type": "scratched", "base": {"type": "lambert", **maps}}},
                           "mesh": [{"shape": "plane", "material": "s"}]}, base_dir=tmp_path)  # fmt: skip
