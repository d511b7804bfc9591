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
