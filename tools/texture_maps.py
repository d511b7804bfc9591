"""Texture maps against the reference: library materials with mapped colours (a Lambert floor, a Phong ball with a
diffuse map, a conductor with a specular map) under a point + a quad light and under the studio map; mapped lobe
shapes (a conductor's roughness, a Phong exponent) under the same lights, and the others (Blinn-Phong, Ward,
Ashikhmin-Shirley) under the point + quad; affine colours (a Schlick F₀, Ashikhmin-Shirley's rs and rd) under a
point + a quad light and the studio map; normal maps and a mapped emission under a point + a quad light (and the
maps left out against the mapped reference: how much they change the image); a striped translucent marble under a
quad light, the studio map (rough interface) and a point light (against the volumetric reference) — each beside the
same scene without its maps against its own reference (docs/assets.md). Relative MSE (reflets.metrics.relmse) on
4 × 4-pixel block means for the library scenes (96 × 72), per pixel for the marble's frame (64 × 48), as the tests
measure them.

    python tools/texture_maps.py
"""

from __future__ import annotations

import tempfile

import reflets
from reflets.bench.assets import block_means as blocks
from reflets.bench.maps import (
    MARBLE_POINT,
    MARBLE_QUAD,
    POINT,
    QUAD,
    affine_maps_scene,
    lobe_maps_scene,
    mapped_scene,
    other_lobe_maps_scene,
    striped_marble,
    surface_maps_scene,
    unmapped,
)
from reflets.metrics import relmse
from reflets.scene.assets import default_environment

ENV = {"type": "environment", "file": str(default_environment())}


def reference(scene, **kw):
    return reflets.reference(scene, progress=False, **kw).image


def main() -> None:
    for name, lights in (("point + quad", [POINT, QUAD]), ("studio map", [ENV])):
        for label, scene in (("mapped", mapped_scene(lights)), ("unmapped", unmapped(mapped_scene(lights)))):
            error = relmse(blocks(reflets.render(scene, spp=16)), blocks(reference(scene, spp=32, pixel="box")))
            print(f"library materials, {name}, {label}: {error:.2e}")
    with tempfile.TemporaryDirectory() as directory:
        both = {"point + quad": [POINT, QUAD], "studio map": [ENV]}
        for kind, make, lighting in (("lobe shapes", lobe_maps_scene, both),
                                     ("normal maps + emission", surface_maps_scene, {"point + quad": [POINT, QUAD]})):
            for name, lights in lighting.items():
                refs = {}
                for mapped in (True, False):
                    scene = make(directory, lights, maps=mapped)
                    refs[mapped] = ref = reference(scene, spp=32, pixel="box")
                    image = blocks(reflets.render(scene, spp=16))
                    print(f"library {kind}, {name}, {'mapped' if mapped else 'unmapped'}: "
                          f"{relmse(image, blocks(ref)):.2e}")  # fmt: skip
                print(f"library {kind}, {name}, the maps left out, against the mapped reference: "
                      f"{relmse(image, blocks(refs[True])):.2e}")  # fmt: skip
        scene = other_lobe_maps_scene(directory, [POINT, QUAD])
        error = relmse(blocks(reflets.render(scene, spp=16)), blocks(reference(scene, spp=32, pixel="box")))
        print(f"library lobe shapes (Blinn-Phong, Ward, Ashikhmin-Shirley), point + quad, mapped: {error:.2e}")
        for name, lights in (("point + quad", [POINT, QUAD]), ("studio map", [ENV])):
            refs = {}
            for mapped in (True, False):
                scene = affine_maps_scene(lights, maps=mapped)
                refs[mapped] = reference(scene, spp=32, pixel="box")
                image = blocks(reflets.render(scene, spp=16))
                print(f"library affine colours, {name}, {'mapped' if mapped else 'unmapped'}: "
                      f"{relmse(image, blocks(refs[mapped])):.2e}")  # fmt: skip
            print(f"library affine colours, {name}, the maps left out, against the mapped reference: "
                  f"{relmse(image, blocks(refs[True])):.2e}")  # fmt: skip
        for name, light, roughness, engine in (("quad", MARBLE_QUAD, 0.0, "numpy"), ("studio map", ENV, 0.3, "numpy"),
                                               ("point", MARBLE_POINT, 0.0, "volumetric")):  # fmt: skip
            for mapped in (True, False):
                scene = striped_marble(directory, light, mapped=mapped, roughness=roughness)
                ref = reference(scene, spp=16, engine="volumetric", workers=2) if engine == "volumetric" \
                    else reference(scene, spp=64)  # fmt: skip
                error = relmse(reflets.render(scene, spp=16), ref)
                print(f"marble, {name} ({engine} reference), {'mapped' if mapped else 'unmapped'}: {error:.2e}")


if __name__ == "__main__":
    main()
