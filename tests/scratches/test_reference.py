"""The explicit-geometry reference: mirror limit, energy, honest standard errors, area-averaged coverage."""

from __future__ import annotations

import numpy as np
import pytest

from reflets.brdf.microfacet import Microfacet
from reflets.fresnel import GOLD_ETA, GOLD_K
from reflets.scratches.reference import (
    ConeLight,
    Lighting,
    PlateView,
    ScratchFrame,
    mirror_radiance,
    reference_radiance,
    render_plate_reference,
    sky_lighting,
    sun_for_highlight,
)
from reflets.scratches.tracer2d import FresnelSpec, make_fresnel

IRON = make_fresnel(conductor=(2.91, 3.09), model="exact")


def _light(view: PlateView) -> Lighting:
    h, w = view.height // 2, view.width // 2
    return sky_lighting(sun_for_highlight(view.frame, view.wo[h, w], half_angle=np.radians(4.0), radiance=60.0))


@pytest.mark.parametrize(
    "fresnel",
    [make_fresnel(conductor=(GOLD_ETA, GOLD_K), model="exact"), make_fresnel(ior=1.5, model="exact")],
    ids=["gold", "glass"],
)
def test_flat_profile_is_a_fresnel_mirror(fresnel):
    view = PlateView(24, 16, angle_deg=20.0)
    light = _light(view)
    ref = render_plate_reference("flat", fresnel, view, light, rays=8, seed=3)
    exact = mirror_radiance(fresnel, view.frame, view.wo, light)
    assert ref.lost == 0 and ref.max_bounces == 1
    assert np.max(np.abs(ref.mean - exact)) < 1e-12 * np.max(exact)
    assert np.max(ref.stderr) < 1e-12
    # the sun is seen in the mirror for some pixels (the comparison covers the cone light too)
    assert np.max(exact) > 5.0 * np.median(exact)
    # and it has power: a V-groove is not a mirror
    grooved = render_plate_reference("vgroove:0.3", fresnel, view, light, rays=8, seed=3)
    assert np.max(np.abs(grooved.mean - exact)) > 0.1 * np.max(exact)


@pytest.mark.parametrize("spec", ["vgroove:0.8", "quartic:0.9"])
def test_lossless_white_furnace(spec):
    """F = 1 under a constant environment: every ray escapes with weight 1; Fresnel only removes energy."""
    frame = ScratchFrame.plate(10.0)
    wo = frame.from_cone(np.array([0.0, 0.5, -1.0, 1.2]), np.array([0.3, -1.2, 0.9, 0.0]))
    white = Lighting(np.ones((8, 16, 3)))
    ref = reference_radiance(spec, FresnelSpec(), frame, wo, white, rays=512, seed=1)
    assert ref.lost == 0 and ref.max_bounces >= 2
    assert np.allclose(ref.mean, 1.0, atol=1e-12)
    iron = reference_radiance(spec, IRON, frame, wo, white, rays=512, seed=1)
    assert np.all(iron.mean < 0.9) and np.all(iron.mean > 0.1)


@pytest.mark.slow
def test_standard_error_is_conservative_on_aggregate():
    """Against a 16× denser image, the RMS error is at most ~1.5 × the RMS reported standard error."""
    view = PlateView(24, 16)
    light = _light(view)
    a = render_plate_reference("quartic:0.5", IRON, view, light, rays=64, seed=1)
    b = render_plate_reference("quartic:0.5", IRON, view, light, rays=1024, seed=2)
    rms_err = np.sqrt(np.mean((a.mean - b.mean) ** 2))
    rms_se = np.sqrt(np.mean(a.stderr**2 + b.stderr**2))
    assert 0.2 * rms_se < rms_err < 1.5 * rms_se, (rms_err, rms_se)


def test_partial_coverage_is_the_area_average():
    """Coverage c of scratch geometry and 1 − c of base: the reference equals c ref(1) + (1 − c) ref(0)."""
    view = PlateView(16, 12)
    light = _light(view)
    base = Microfacet(alpha=0.25, fresnel="conductor", eta=(2.91,) * 3, k=(3.09,) * 3)
    c = view.coverage_ramp()
    full = render_plate_reference("quartic:0.5", IRON, view, light, rays=256, seed=1)
    bare = render_plate_reference("quartic:0.5", IRON, view, light, rays=256, seed=2, coverage=0.0, base=base)
    mixed = render_plate_reference("quartic:0.5", IRON, view, light, rays=256, seed=3, coverage=c, base=base)
    expect = c[..., None] * full.mean + (1 - c[..., None]) * bare.mean
    se = np.sqrt(mixed.stderr**2 + (c[..., None] * full.stderr) ** 2 + ((1 - c[..., None]) * bare.stderr) ** 2)
    assert np.sqrt(np.mean((mixed.mean - expect) ** 2)) < 2.0 * np.sqrt(np.mean(se**2))
    assert np.allclose(mixed.mean[:, -1], full.mean[:, -1], rtol=0.05, atol=0.01)  # c = 1 column
    with pytest.raises(ValueError):
        reference_radiance("flat", IRON, view.frame, view.wo, light, coverage=0.5)


def test_cone_light_sampling_and_frame():
    sun = ConeLight([0.3, 0.8, -0.2], np.radians(3.0), (2.0, 1.0, 0.5))
    w, pdf = sun.sample(np.random.default_rng(0).random(1000), np.random.default_rng(1).random(1000))
    assert np.all(sun.inside(w * (1 - 1e-12))) and np.allclose(pdf, 1 / sun.solid_angle)
    frame = ScratchFrame.plate(33.0)
    th, ph = np.array([0.2, -0.7]), np.array([1.1, -0.4])
    assert np.allclose(frame.cone(frame.from_cone(th, ph)), (th, ph))
    assert np.allclose(np.cross(frame.u, frame.v), frame.n)
