#!/usr/bin/env python3
"""Mean ratio per channel (technique / volumetric reference) and relative MSE of each diffusion profile on the
scenes of `reflets bench translucency`, without the benchmark's 38 minutes: the skin1 bunny at η = 1 (384×288)
and η = 1.3 (1024×768) against the references stored under benchmarks/results/references/, and an
index-matched 10 mm skin1 sphere against a fresh 32-spp volumetric reference (128×96).

The stored references are found by their fingerprints (reflets.reference.store.load), as the benchmark does.

Run: ``.venv/bin/python tools/translucency_ratios.py [--sphere]`` (about a minute; the sphere one more).
"""

from __future__ import annotations

import argparse
from pathlib import Path

import numpy as np

import reflets
from reflets.bench.translucency import _compared_pixels, _object_scene, _relmse
from reflets.reference import store
from reflets.reference.volumetric import VolumetricImage, render_volumetric

ROOT = Path(__file__).resolve().parents[1]
BUNNIES = {  # η: (stored reference, size, its spp and seed)
    1.0: ("translucency_bunny_eta1_384x288_48spp.npz", (384, 288), 48, 7),
    1.3: ("translucency_bunny_eta1.3_1024x768_32spp.npz", (1024, 768), 32, 11),
}
PROFILES = ("multiple_fit", "better_dipole", "dipole", "normalized_diffusion")


def stored(name: str, scene, spp: int, seed: int) -> VolumetricImage:
    found = store.load(ROOT / "benchmarks/results/references" / name, store.fingerprint(scene, spp=spp, seed=seed)[0])
    if found is None:
        raise SystemExit(f"{name}: no stored reference for this scene (run `reflets bench translucency`)")
    return found[0]


def report(label: str, scene_for, ref: VolumetricImage, pixels) -> None:
    keep, noise = pixels
    for profile in PROFILES:
        image = reflets.render(scene_for(profile), method="translucent", terms=["single", "multiple"])
        ratio = image[keep].mean(axis=0) / ref.image[keep].mean(axis=0)
        relmse = _relmse(image, ref.image, keep)
        ratios = ", ".join(f"{v:.3f}" for v in ratio)
        print(f"{label} | {profile} | {ratios} | {relmse:.2%} (reference noise {noise:.2%})", flush=True)


def sphere(profile: str):
    return reflets.load_dict(
        {
            "camera": {"position": [0, 0.5, 3], "look_at": [0, 0, 0], "fov_y": 35, "size": [128, 96]},
            "materials": {
                "m": {"type": "translucent", "preset": "skin1", "eta": 1.0, "mm_per_unit": 10.0, "profile": profile}
            },
            "mesh": [{"shape": "sphere", "radius": 1.0, "material": "m"}],
            "light": [{"type": "directional", "direction": [-1, -1, -0.6], "irradiance": [3, 3, 3]}],
        }
    )


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--sphere", action="store_true", help="also the 10 mm sphere (renders its reference)")
    args = parser.parse_args()
    print("scene | profile | mean ratio R, G, B | relative MSE")
    for eta, (name, size, spp, seed) in BUNNIES.items():

        def bunny(profile, eta=eta, size=size):
            return _object_scene("bunny.ply", "skin1", 100.0, size, eta=eta, profile=profile)

        ref = stored(name, bunny("multiple_fit"), spp, seed)
        keep, _, noise = _compared_pixels(ref)

        report(f"bunny η = {eta:g}, {size[0]}×{size[1]}", bunny, ref, (keep, noise))
    if args.sphere:
        ref = render_volumetric(sphere("better_dipole"), spp=32, seed=1, progress=False, workers=2)
        noise = float(np.mean(ref.stderr[ref.mask] ** 2) / np.mean(ref.image[ref.mask] ** 2))
        report("sphere 10 mm, η = 1, 128×96", sphere, ref, (ref.mask, noise))


if __name__ == "__main__":
    main()
