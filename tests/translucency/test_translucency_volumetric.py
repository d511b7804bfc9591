"""The ``translucent`` technique against volumetric path tracing of the same medium (index-matched sphere)."""

from __future__ import annotations

import numpy as np
import pytest

import reflets
from reflets.errors import ArgumentError
from reflets.reference.volumetric import render_volumetric


def sphere_scene(eta=1.0, lights=None):
    return reflets.load_dict(
        {
            "camera": {"position": [0, 0.5, 3], "look_at": [0, 0, 0], "fov_y": 35, "size": [48, 36]},
            "materials": {"skin": {"type": "translucent", "preset": "skin1", "eta": eta, "mm_per_unit": 25.0}},
            "mesh": [{"shape": "sphere", "radius": 1.0, "material": "skin"}],
            "light": lights or [{"type": "point", "position": [2, 3, 2], "intensity": [20, 20, 20]}],
        }
    )


def test_default_technique_within_5_percent_relative_mse_of_volumetric_path_tracing():
    scene = sphere_scene()
    ref = render_volumetric(scene, spp=32, seed=1, progress=False)
    m = ref.mask
    noise = float(np.mean(ref.stderr[m] ** 2) / np.mean(ref.image[m] ** 2))
    assert noise < 0.02, f"reference too noisy for this check: {noise:.3f}"
    image = reflets.render(scene, method="translucent")
    error = float(np.mean((image[m] - ref.image[m]) ** 2) / np.mean(ref.image[m] ** 2))
    assert error < 0.05
    # and the two subsurface terms are both needed: either alone is far off
    for term in ("single", "multiple"):
        alone = reflets.render(scene, method="translucent", terms=[term])
        assert np.mean((alone[m] - ref.image[m]) ** 2) / np.mean(ref.image[m] ** 2) > 0.05


def test_volumetric_reference_is_deterministic_and_rejects_what_it_cannot_render():
    scene = sphere_scene()
    a = render_volumetric(scene, spp=1, seed=4, size=(16, 12), progress=False)
    b = render_volumetric(scene, spp=1, seed=4, size=(16, 12), progress=False)
    np.testing.assert_array_equal(a.image, b.image)
    with pytest.raises(ArgumentError, match="index-matched"):
        render_volumetric(sphere_scene(eta=1.3), spp=1, progress=False)
