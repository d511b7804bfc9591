"""``ltc`` on a textured glTF material: the GGX table read at each fragment's roughness, the albedos of the
material's split sum (``material_ibl``) per fragment, the clear coat as a second lobe about its own normal —
against the NumPy reference, which reads the same textures."""

from __future__ import annotations

import numpy as np
from PIL import Image

import reflets
from reflets.bench.assets import block_means as blocks  # 4 x 4-pixel means: sub-pixel highlights aside
from reflets.metrics import relmse

W, H = 96, 72


def textured_scene(tmp_path, coat: float) -> reflets.Scene:
    """Two spheres: a checker base colour; roughness 0.15 / 0.7 and metallic 0 / 1 in stripes across each other;
    the right one under a clear coat. Two quad lights (overhead, and low behind the camera) over a grey floor."""
    u, v = np.meshgrid(np.arange(64), np.arange(64))
    base = np.where((((u // 8) + (v // 8)) % 2 == 0)[..., None], [230, 60, 40], [40, 90, 230]).astype(np.uint8)
    mr = np.zeros((64, 64, 3), np.uint8)
    mr[..., 1] = np.where((u // 16) % 2 == 0, round(0.15 * 255), round(0.7 * 255))
    mr[..., 2] = np.where((v // 16) % 2 == 0, 0, 255)
    Image.fromarray(base).save(tmp_path / "base.png")
    Image.fromarray(mr).save(tmp_path / "mr.png")
    material = {"type": "gltf", "metallic": 1.0, "roughness": 1.0,
                "base_color_texture": {"texture": str(tmp_path / "base.png")},
                "metallic_roughness_texture": {"texture": str(tmp_path / "mr.png")}}  # fmt: skip
    return reflets.load_dict({
        "camera": {"position": [0, 0.9, 3.2], "look_at": [0, 0, 0], "fov_y": 40, "size": [W, H]},
        "materials": {"plain": material, "coated": {**material, "clearcoat": coat, "clearcoat_roughness": 0.1},
                      "floor": {"type": "lambert", "albedo": [0.5, 0.5, 0.5]}},
        "mesh": [{"shape": "sphere", "radius": 0.55, "material": "plain", "transform": {"translate": [-0.6, 0, 0]}},
                 {"shape": "sphere", "radius": 0.55, "material": "coated", "transform": {"translate": [0.6, 0, 0]}},
                 {"shape": "plane", "size": [6, 6], "material": "floor", "transform": {"translate": [0, -0.55, 0]}}],
        "light": [{"type": "quad", "corners": [[-1, 1.8, -0.8], [1, 1.8, -0.8], [-1, 1.8, 0.6]], "radiance": [4, 4, 4]},
                  {"type": "quad", "corners": [[-1.5, -0.2, 3.4], [-1.5, 1.2, 3.4], [1.5, -0.2, 3.4]],
                   "radiance": [1.5, 1.5, 1.5]}],
    })  # fmt: skip


def test_ltc_reads_textures_per_fragment_against_the_reference(tmp_path):
    scene = textured_scene(tmp_path, coat=1.0)
    ltc = reflets.render(scene, method="ltc", spp=16)
    ref = reflets.reference(scene, spp=16, pixel="box", adaptive_error=0.05, progress=False).image
    assert relmse(blocks(ltc), blocks(ref)) < 0.003  # measured 4.4e-4 (forward's midpoint rule: 3.7e-4)
    # the textures matter: their constant factors alone (a white rough metal) are far off
    plain = {k: m.model_copy(update={"base_color_texture": None, "metallic_roughness_texture": None})
             if m.type == "gltf" else m for k, m in scene.materials.items()}  # fmt: skip
    constant = reflets.render(scene.model_copy(update={"materials": plain}), method="ltc", spp=16)
    assert relmse(blocks(constant), blocks(ref)) > 0.1  # measured 0.20
    # the coat's lobe: the coated sphere (right half) against the reference, and against itself uncoated
    uncoated = reflets.render(textured_scene(tmp_path, coat=0.0), method="ltc", spp=16)
    right = lambda image: blocks(image)[:, W // 8 :]  # noqa: E731
    assert relmse(right(ltc), right(ref)) < 0.0015  # measured 4.6e-4: a third of what the coat changes
    assert relmse(right(uncoated), right(ltc)) > 0.0025  # measured 3.6e-3
