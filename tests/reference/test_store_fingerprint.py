"""Stored references stay valid while what determines the image stays: captions and default-valued keys added
later (``shadows = true``, what older references traced) do not change a fingerprint; a real change does."""

from __future__ import annotations

import reflets
from reflets.reference.store import fingerprint


def scene(**changes):
    data = {
        "title": "a plane",
        "camera": {"position": [0, 1, 3], "look_at": [0, 0, 0], "size": [8, 6]},
        "materials": {"m": {"type": "lambert"}},
        "mesh": [{"shape": "plane", "material": "m"}],
        "light": [{"type": "point", "position": [0, 2, 0], "intensity": [1, 1, 1]}],
    }
    return reflets.load_dict({**data, **changes})


def test_captions_and_default_shadows_keep_the_fingerprint_a_real_change_does_not():
    base = fingerprint(scene(), spp=4, seed=0)[0]
    assert fingerprint(scene(title="another caption", description="words"), spp=4, seed=0)[0] == base
    unshadowed = [{"type": "point", "position": [0, 2, 0], "intensity": [1, 1, 1], "shadows": False}]
    assert fingerprint(scene(light=unshadowed), spp=4, seed=0)[0] != base
    assert fingerprint(scene(), spp=8, seed=0)[0] != base


def test_the_stored_benchmark_references_still_match_their_scenes():
    """Every volumetric reference under benchmarks/results/references (one took 38 minutes) is found for the
    benchmark scene it was made from: fields added to the scene model since (at their defaults), a caption, a
    translucent material's real-time profile do not invalidate it."""
    from pathlib import Path

    from reflets.bench import translucency
    from reflets.bench.renderer import showcase_scene
    from reflets.reference import store

    folder = Path(__file__).resolve().parents[2] / "benchmarks" / "results" / "references"
    cases = [(showcase_scene((160, 120), meshes={"marble"}, lights={light}),
              f"renderer_marble_{'' if light == 'point' else light + '_'}160x120_32spp.npz", 32, 0)
             for light in ("point", "quad", "environment")]  # fmt: skip
    cases += [(translucency._object_scene("bunny.ply", "skin1", 100.0, size, eta=eta),
               f"translucency_bunny_eta{eta:g}_{size[0]}x{size[1]}_{spp}spp.npz", spp, seed)
              for eta, size, spp, seed in ((1.0, (384, 288), 48, 7), (1.3, (1024, 768), 32, 11))]  # fmt: skip
    for scene, name, spp, seed in cases:
        digest, _ = store.fingerprint(scene, spp=spp, seed=seed)
        assert store.load(folder / name, digest) is not None, name


def test_a_texture_nested_in_a_material_is_fingerprinted_by_content(tmp_path):
    """A scratched material's base texture edited in place (same path) makes a new fingerprint, as a top-level one."""
    from PIL import Image

    def scene():
        return reflets.load_dict({
            "camera": {"position": [0, 1, 2], "look_at": [0, 0, 0], "size": [16, 12]},
            "materials": {"s": {"type": "scratched", "coverage": 0.1, "alpha_size": 16, "table_size": 32,
                                "base": {"type": "lambert", "albedo": {"texture": str(tmp_path / "a.png")}}}},
            "mesh": [{"shape": "plane", "material": "s"}],
            "light": [{"type": "point", "position": [0, 1, 0], "intensity": [1, 1, 1]}],
        })  # fmt: skip

    Image.new("RGB", (4, 4), (200, 10, 10)).save(tmp_path / "a.png")
    before = fingerprint(scene())[0]
    Image.new("RGB", (4, 4), (10, 200, 10)).save(tmp_path / "a.png")
    assert fingerprint(scene())[0] != before
