"""A material's own textures never take the fixed texture units (shadow maps, Fermat's G-buffer, the prefiltered
environment, the frame copy): a glTF material with every slot filled used to put its 10th texture on a shadow
map's unit, darkening what its shadows should not."""

from __future__ import annotations

from pathlib import Path

import reflets
from reflets.bench.assets import block_means as blocks
from reflets.brdf.gltf import SLOTS
from reflets.metrics import relmse
from reflets.reflections.technique import GBUFFER_UNITS, GRID_UNIT
from reflets.techniques.forward import BEHIND_UNITS, MATERIAL_UNITS
from reflets.techniques.ibl import IBL_UNITS
from reflets.techniques.shadows import SHADOW_DEPTH_UNIT, SHADOW_NEAREST_UNIT, SHADOW_UNIT

UV_GRID = str(Path(__file__).parents[1] / "data" / "gltf" / "TextureTransformTest" / "UV.png")


def test_material_units_avoid_every_fixed_unit():
    fixed = {0, SHADOW_UNIT, SHADOW_DEPTH_UNIT, SHADOW_NEAREST_UNIT, *GBUFFER_UNITS, GRID_UNIT, *IBL_UNITS,
             *BEHIND_UNITS}  # fmt: skip
    assert not fixed & set(MATERIAL_UNITS)
    assert len(MATERIAL_UNITS) >= len(SLOTS) + 3  # every glTF slot, its table and ltc's two


def test_a_material_with_every_texture_keeps_its_shadows():
    opaque = [field for field, *_ in SLOTS if field not in ("transmission_texture", "thickness_texture")]
    heavy = {"type": "gltf", "roughness": 0.8, "clearcoat": 0.5, "sheen_color": [0.2, 0.2, 0.2],
             "anisotropy_strength": 0.3, **{field: {"texture": UV_GRID} for field in opaque}}  # fmt: skip
    scene = reflets.load_dict({
        "camera": {"position": [0, 2, 2.5], "look_at": [0, 0, 0], "size": [64, 48]},
        "materials": {"heavy": heavy, "ball": {"type": "lambert"}},
        "mesh": [{"shape": "plane", "size": [3, 3], "material": "heavy"},
                 {"shape": "sphere", "radius": 0.3, "material": "ball", "transform": {"translate": [0, 0.5, 0]}}],
        "light": [{"type": "point", "position": [0, 2, 0], "intensity": [10, 10, 10]}],
    })  # fmt: skip
    ref = reflets.reference(scene, spp=16, pixel="box", progress=False).image
    assert relmse(blocks(reflets.render(scene, method="forward")), blocks(ref)) < 0.05  # measured 0.021 (0.093)
