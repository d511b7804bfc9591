"""Our NumPy reference vs Mitsuba 3 (scalar_rgb, `direct` integrator) on the three reference scenes.

Both average over each pixel (box filter). Mitsuba's noise is estimated from two renders with different seeds.
"""

from __future__ import annotations

import numpy as np
import pytest

import reflets
from reflets.demo import scene_path
from reflets.metrics import relmse
from reflets.reference import reference

pytest.importorskip("mitsuba", reason="the Mitsuba cross-check needs the [reference] extra")

SIZE, SPP = (64, 48), 256


@pytest.mark.parametrize("name", ["10_ref_plane_quad.toml", "11_ref_ggx_sphere_quad.toml", "12_ref_sphere_env.toml"])
def test_numpy_reference_agrees_with_mitsuba(name):
    scene = reflets.load_scene(scene_path(name))
    ours = reference(scene, spp=SPP, size=SIZE, pixel="box", progress=False)
    m1 = reference(scene, spp=SPP, size=SIZE, engine="mitsuba", seed=1).image
    m2 = reference(scene, spp=SPP, size=SIZE, engine="mitsuba", seed=2).image
    mitsuba = 0.5 * (m1 + m2)
    sigma = np.sqrt(ours.stderr.astype(np.float64) ** 2 + (0.5 * np.abs(m1 - m2)) ** 2)
    keep = sigma > 1e-6
    z = (ours.image - mitsuba)[keep] / sigma[keep]
    assert relmse(ours.image, mitsuba) < 1e-3
    assert abs(z.mean()) < 0.25, f"bias: mean z = {z.mean():.3f}"
    assert np.abs(z).mean() < 1.0
