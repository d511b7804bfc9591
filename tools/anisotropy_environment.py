"""KHR_materials_anisotropy under an environment: the split sum reads the isotropic lobe of the same area,
√(α_t α_b). How far that is from the truth: a brushed metal sphere (roughness 0.3) under the studio map at
anisotropy strength 0, 0.5 and 0.9, the GPU (16 spp) against the NumPy reference (64 spp, box pixels), relative MSE
on 4 × 4-pixel block means (docs/assets.md).

    python tools/anisotropy_environment.py
"""

from __future__ import annotations

import warnings
from importlib import resources

import reflets
from reflets.bench.assets import block_means as blocks
from reflets.metrics import relmse

W, H = 160, 120


def scene(strength: float) -> reflets.Scene:
    studio = resources.files("reflets") / "data" / "environments" / "studio.hdr"
    brushed = {"type": "gltf", "base_color": [0.95, 0.93, 0.88, 1], "metallic": 1.0, "roughness": 0.3,
               "anisotropy_strength": strength}  # fmt: skip
    return reflets.load_dict({
        "camera": {"position": [0, 0.3, 2.4], "look_at": [0, 0, 0], "size": [W, H]},
        "background": "environment",
        "materials": {"brushed": brushed},
        "mesh": [{"shape": "sphere", "radius": 0.7, "material": "brushed"}],
        "light": [{"type": "environment", "file": str(studio)}],
    })  # fmt: skip


if __name__ == "__main__":
    warnings.simplefilter("ignore")
    for strength in (0.0, 0.5, 0.9):
        s = scene(strength)
        ref = reflets.reference(s, spp=64, pixel="box", progress=False).image
        gpu = reflets.render(s, spp=16)
        print(f"anisotropy strength {strength}: relative MSE {relmse(blocks(gpu), blocks(ref)):.2%} (4 x 4 blocks)")
