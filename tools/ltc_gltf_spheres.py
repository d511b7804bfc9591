"""ltc on glTF materials. Constant ones, per fragment against the one-material table: six spheres under two quad
lights with shadows, each against the NumPy reference (4 × 4-pixel block means, relative MSE), with ``forward``'s
midpoint rule beside (the numbers of the ltc module docstring, docs/techniques/area-lights.md). With ``--helmet``:
the gallery's DamagedHelmet under quad lights (70_helmet_area.toml, 320 × 240), ltc against forward — relative MSE
per pixel and on blocks against the reference at 16 spp, and the persistent renderer's one-sample frame time
(medians of 12 interleaved frames; docs/assets.md).

    python tools/ltc_gltf_spheres.py [NAME ...]
    python tools/ltc_gltf_spheres.py --helmet
"""

from __future__ import annotations

import sys
import time
import warnings
from importlib import resources

import numpy as np

import reflets
from reflets.bench.assets import block_means as blocks
from reflets.brdf.gltf import Gltf
from reflets.metrics import relmse

W, H = 160, 120
MATERIALS = {
    "dielectric roughness 0.5": {"base_color": [0.8, 0.3, 0.2, 1], "metallic": 0.0, "roughness": 0.5},
    "dielectric roughness 0.2": {"base_color": [0.2, 0.5, 0.8, 1], "metallic": 0.0, "roughness": 0.2},
    "metal roughness 0.02": {"base_color": [0.95, 0.9, 0.8, 1], "metallic": 1.0, "roughness": 0.02},
    "metal roughness 0.3": {"base_color": [0.95, 0.6, 0.3, 1], "metallic": 1.0, "roughness": 0.3},
    "clear coat": {"base_color": [0.7, 0.1, 0.1, 1], "metallic": 0.0, "roughness": 0.6, "clearcoat": 1.0,
                   "clearcoat_roughness": 0.1},  # fmt: skip
    "sheen": {"base_color": [0.2, 0.2, 0.6, 1], "metallic": 0.0, "roughness": 0.8, "sheen_color": [0.9, 0.9, 0.9],
              "sheen_roughness": 0.4},  # fmt: skip
}


def scene(material: dict) -> reflets.Scene:
    return reflets.load_dict({
        "camera": {"position": [0, 0.6, 2.6], "look_at": [0, 0, 0], "size": [W, H]},
        "materials": {"m": {"type": "gltf", **material}, "floor": {"type": "lambert", "albedo": [0.5, 0.5, 0.5]}},
        "mesh": [{"shape": "sphere", "radius": 0.6, "material": "m"},
                 {"shape": "plane", "size": [6, 6], "material": "floor", "transform": {"translate": [0, -0.6, 0]}}],
        "light": [{"type": "quad", "corners": [[-0.8, 1.8, -0.6], [0.8, 1.8, -0.6], [-0.8, 1.8, 0.6]],
                   "radiance": [4, 4, 4]},
                  {"type": "quad", "corners": [[-1.2, -0.3, 2.8], [-1.2, 1.0, 2.8], [1.2, -0.3, 2.8]],
                   "radiance": [1.5, 1.5, 1.5]}],
    })  # fmt: skip


def ltc_error(s: reflets.Scene, ref, per_fragment: bool) -> float:
    """ltc's error with the per-fragment path forced on or off (``Gltf.fragment_ltc`` chooses it otherwise)."""
    own = Gltf.fragment_ltc
    Gltf.fragment_ltc = property(lambda self: per_fragment)
    try:
        return relmse(blocks(reflets.render(s, method="ltc", spp=16)), ref)
    finally:
        Gltf.fragment_ltc = own


def main(names: list[str]) -> None:
    warnings.simplefilter("ignore")
    print("| material | ltc per fragment | ltc one-material table | forward (8 × 8 midpoint) |\n|---|---|---|---|")
    for name, material in MATERIALS.items():
        if names and name not in names:
            continue
        s = scene(material)
        ref = blocks(reflets.reference(s, spp=16, pixel="box", adaptive_error=0.05, progress=False).image)
        forward = relmse(blocks(reflets.render(s, method="forward", spp=16)), ref)
        per_fragment, table = (ltc_error(s, ref, path) for path in (True, False))
        print(f"| {name} | {per_fragment:.2e} | {table:.2e} | {forward:.2e} |", flush=True)


def helmet() -> None:
    warnings.simplefilter("ignore")
    scene = reflets.load_scene(resources.files("reflets") / "data" / "scenes" / "70_helmet_area.toml")
    ref = reflets.reference(scene, spp=16, pixel="box", adaptive_error=0.05, progress=False).image
    renderers = {m: reflets.Renderer(scene, method=m) for m in ("forward", "ltc")}
    images = {m: r.render(spp=16) for m, r in renderers.items()}  # as the gallery renders it
    times = {m: [] for m in renderers}
    for _ in range(12):
        for m, r in renderers.items():
            start = time.perf_counter()
            r.render()
            times[m].append(time.perf_counter() - start)
    for m, image in images.items():
        print(f"{m}: relative MSE {relmse(image, ref):.2%} per pixel, {relmse(blocks(image), blocks(ref)):.2%} on "
              f"4 x 4 blocks; frame {1000 * np.median(times[m]):.1f} ms (median of 12)")


if __name__ == "__main__":
    helmet() if sys.argv[1:] == ["--helmet"] else main(sys.argv[1:])
