"""Texture maps against the reference: library materials with mapped colours (a Lambert floor, a Phong ball with a
diffuse map, a conductor with a specular map) under a point + a quad light and under the studio map; mapped lobe
shapes (a conductor's roughness, a Phong exponent) under the same lights, and the others (Blinn-Phong, Ward,
Ashikhmin-Shirley, Lafortune's lobe exponents) under the point + quad; affine colours (a Schlick F₀,
Ashikhmin-Shirley's rs and rd, a Lafortune lobe's scale) under a point + a quad light and the studio map; normal
maps and a mapped emission under a point + a quad light (and the maps left out against the mapped reference: how
much they change the image); a striped translucent marble under a
quad light, the studio map (rough interface) and a point light (against the volumetric reference) — each beside the
same scene without its maps against its own reference (docs/assets.md). Relative MSE (reflets.metrics.relmse) on
4 × 4-pixel block means for the library scenes (96 × 72), per pixel for the marble's frame (64 × 48), as the tests
measure them.

    python tools/texture_maps.py
"""

from __future__ import annotations

import tempfile
from functools import partial

import reflets
from reflets.bench.maps import (
    MARBLE_POINT,
    MARBLE_QUAD,
    POINT,
    QUAD,
    affine_maps_scene,
    block_error,
    lobe_maps_scene,
    mapped_scene,
    other_lobe_maps_scene,
    reference_image,
    striped_marble,
    surface_maps_scene,
    unmapped,
    without_maps,
)
from reflets.metrics import relmse
from reflets.scene.assets import default_environment

ENV = {"type": "environment", "file": str(default_environment())}
BOTH = {"point + quad": [POINT, QUAD], "studio map": [ENV]}


def compare(kind: str, make, lighting: dict) -> dict:
    """For each lighting: the mapped scene and the factors alone each against its own reference, and the factors
    alone against the mapped reference (how much the maps change the image). ``make(lights, maps=…)``. Returns the
    mapped scenes' references by lighting."""
    refs = {}
    for name, lights in lighting.items():
        mapped, factors = make(lights, maps=True), make(lights, maps=False)
        ref = refs[name] = reference_image(mapped)
        print(f"library {kind}, {name}, mapped: {block_error(mapped, ref):.2e}")
        print(f"library {kind}, {name}, unmapped: {block_error(factors):.2e}")
        print(f"library {kind}, {name}, the maps left out, against the mapped reference: "
              f"{block_error(factors, ref):.2e}")  # fmt: skip
    return refs


def main() -> None:
    compare("materials", lambda lights, maps: mapped_scene(lights) if maps else unmapped(mapped_scene(lights)), BOTH)
    with tempfile.TemporaryDirectory() as directory:
        compare("lobe shapes", partial(lobe_maps_scene, directory), BOTH)
        compare("normal maps + emission", partial(surface_maps_scene, directory), {"point + quad": [POINT, QUAD]})
        scene = other_lobe_maps_scene(directory, [POINT, QUAD])
        ref = reference_image(scene)
        what = "library lobe shapes (Blinn-Phong, Ward, Ashikhmin-Shirley, Lafortune), point + quad"
        print(f"{what}, mapped: {block_error(scene, ref):.2e}")
        print(f"{what}, Lafortune's maps left out: {block_error(without_maps(scene), ref):.2e}")
        refs = compare("affine colours", affine_maps_scene, BOTH)
        for name, lights in BOTH.items():
            error = block_error(without_maps(affine_maps_scene(lights)), refs[name])
            print(f"library affine colours, {name}, Lafortune's scale map left out: {error:.2e}")
        for name, light, roughness, engine in (("quad", MARBLE_QUAD, 0.0, "numpy"), ("studio map", ENV, 0.3, "numpy"),
                                               ("point", MARBLE_POINT, 0.0, "volumetric")):  # fmt: skip
            for mapped in (True, False):
                scene = striped_marble(directory, light, mapped=mapped, roughness=roughness)
                ref = reflets.reference(scene, spp=16, engine="volumetric", workers=2, progress=False) \
                    if engine == "volumetric" else reflets.reference(scene, spp=64, progress=False)  # fmt: skip
                error = relmse(reflets.render(scene, spp=16), ref.image)
                print(f"marble, {name} ({engine} reference), {'mapped' if mapped else 'unmapped'}: {error:.2e}")


if __name__ == "__main__":
    main()
