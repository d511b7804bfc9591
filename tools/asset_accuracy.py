"""docs/assets.md's accuracy table: textured glTF assets, the GPU against the NumPy reference (reflets.bench.assets).

    python tools/asset_accuracy.py ../shared/data/assets/gltf/WaterBottle/WaterBottle.gltf \
        ../shared/data/assets/gltf/DamagedHelmet/DamagedHelmet.glb [--size 320x240] [--spp 16] \
        [--reference-spp 16] [--adaptive-error 0.05]

For each file: every texture on; then (to locate a gap) only base colour + normal map + emission, and the
untextured factors. About 10 s a row here (2 cores, llvmpipe); more where the reference refines glints.
"""

from __future__ import annotations

import argparse
import warnings

import reflets
from reflets.bench.assets import asset_error, lit_for_comparison, without_textures

VARIANTS = {
    "all textures": None,
    "base colour + normal + emission": ("base_color_texture", "normal_texture", "emissive_texture"),
    "no texture": (),
}


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("files", nargs="+")
    parser.add_argument("--size", default="320x240")
    parser.add_argument("--spp", type=int, default=16, help="GPU supersampling (s² samples a pixel)")
    parser.add_argument("--reference-spp", type=int, default=16, help="reference samples a pixel before refining")
    parser.add_argument("--adaptive-error", type=float, default=0.05, help="the reference refines pixels noisier")
    args = parser.parse_args(argv)
    size = tuple(int(v) for v in args.size.split("x"))
    print("| asset | textures | relative MSE (4×4 blocks) | GPU mean | reference mean |\n|---|---|---|---|---|")
    for path in args.files:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            scene = lit_for_comparison(reflets.load_scene(path))
        for label, keep in VARIANTS.items():
            variant = scene if keep is None else without_textures(scene, keep)
            e = asset_error(variant, size, args.spp, args.reference_spp, args.adaptive_error)
            print(f"| {scene.title} | {label} | {e['relmse']:.2g} | {e['gpu_mean']:.4f} | {e['reference_mean']:.4f} |",
                  flush=True)  # fmt: skip
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
