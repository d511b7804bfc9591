"""The comparison models against the explicit-geometry reference (figure 3.7 of the document, with numbers)."""

from __future__ import annotations

import numpy as np
import pytest

from reflets.brdf.microfacet import Microfacet
from reflets.metrics import flip, relmse
from reflets.scratches.models import (
    as00_material,
    full_model,
    mix,
    ndf_model,
    one_bounce_model,
    render_cone_model,
    render_material,
    smith_g1,
)
from reflets.scratches.profiles import parse_profile
from reflets.scratches.reference import (
    PlateView,
    ScratchFrame,
    reference_radiance,
    render_plate_reference,
    sky_lighting,
    sun_for_highlight,
)
from reflets.scratches.tracer2d import make_fresnel

IRON_EXACT = make_fresnel(conductor=(2.91, 3.09), model="exact")
IRON_LAZANYI = make_fresnel(conductor=(2.91, 3.09))  # the document's conductor Fresnel (monotonic in the angle)
M, RAYS = 128, 4000
THETAS = (0.0, np.pi / 6, np.pi / 3)
PHIS = -0.5 * np.pi + (np.array([21, 42, 60, 84, 96, 113]) + 0.5) * np.pi / M  # bin centres, −60° … 70°


@pytest.fixture(scope="module")
def sky():
    return sky_lighting()


def _rel_errors(model, spec, fresnel, frame, sky):
    out = {}
    for theta in THETAS:
        wo = frame.from_cone(np.full(PHIS.size, theta), PHIS)
        ref = reference_radiance(spec, fresnel, frame, wo, sky, rays=2048, seed=2)
        got = render_cone_model(model, frame, wo, sky, spp=2048, seed=3)
        noise = np.sqrt(ref.stderr**2 + got.stderr**2) / ref.mean
        out[theta] = (np.abs(got.mean / ref.mean - 1.0), noise)
    return out


@pytest.mark.slow
@pytest.mark.parametrize("spec", ["vgroove:0.5", "quartic:0.5"])
def test_full_model_matches_reference_at_several_elevations(spec, sky):
    """Outgoing radiance of ω_o = (θ, φ) under the sky, 6 φ per θ. Tolerance: 4σ plus a bias allowance of 0.8 %
    at θ = 0 and π/3 (the table's bins, M = 128) and 1.5 % at π/6, where ρ_s is the γ interpolation (measured:
    ≤ 0.7 % and ≤ 1.4 % at M = 128). The 1-bounce table of the same profile fails it."""
    frame = ScratchFrame.plate(30.0)
    full = full_model(spec, IRON_LAZANYI, size=M, rays=RAYS, seed=1)
    for theta, (err, noise) in _rel_errors(full, spec, IRON_LAZANYI, frame, sky).items():
        allowance = 0.015 if theta == THETAS[1] else 0.008
        assert np.all(err < allowance + 4.0 * noise), (spec, theta, err)
    one = one_bounce_model(spec, IRON_LAZANYI, size=M, rays=RAYS, seed=1)
    worst = max(float(np.max(e - 4.0 * n)) for e, n in _rel_errors(one, spec, IRON_LAZANYI, frame, sky).values())
    assert worst > 0.05


@pytest.mark.slow
def test_gamma_blend_cannot_follow_the_exact_conductor_dip(sky):
    """Exact iron Fresnel dips below F(0) (0.531 → 0.508 at cos 0.3) before rising: the power law
    F_γ ∈ [0, 1] blends ρ_s(0) towards ρ_m and cannot go below ρ_s(0), so at θ = π/3 the full model is
    2–6 % too bright (measured 2.9–4.5 %, mean 3.4 %) while it stays exact at θ = 0."""
    frame = ScratchFrame.plate(30.0)
    full = full_model("quartic:0.5", IRON_EXACT, size=M, rays=RAYS, seed=1)
    errs = _rel_errors(full, "quartic:0.5", IRON_EXACT, frame, sky)
    assert np.all(errs[0.0][0] < 0.008 + 4 * errs[0.0][1])
    assert 0.02 < np.mean(errs[THETAS[2]][0]) < 0.06


@pytest.fixture(scope="module")
def plate():
    view = PlateView(48, 32)
    sun = sun_for_highlight(view.frame, view.wo[16, 24], half_angle=np.radians(4.0), radiance=(60.0, 55.0, 48.0))
    light = sky_lighting(sun)
    ref = render_plate_reference("quartic:0.5", IRON_EXACT, view, light, rays=256, seed=1)
    return view, light, ref


@pytest.mark.slow
def test_full_model_beats_the_other_models_on_a_brushed_plate(plate):
    """Quartic:0.5 iron plate under the sky and a 4° sun (measured relMSE / FLIP: full 0.005 / 0.024,
    1-bounce 0.054 / 0.19, NDF 0.059 / 0.24, AS00 0.46 / 0.34)."""
    view, light, ref = plate
    models = {
        "full": full_model("quartic:0.5", IRON_EXACT, size=M, rays=RAYS, seed=2),
        "1-bounce": one_bounce_model("quartic:0.5", IRON_EXACT, size=M, rays=RAYS, seed=2),
        "NDF": ndf_model("quartic:0.5", IRON_EXACT, size=M, rays=RAYS, seed=2),
    }
    images = {k: render_cone_model(m, view.frame, view.wo, light, spp=64, seed=3).mean for k, m in models.items()}
    images["AS00"] = render_material(as00_material(IRON_EXACT), view.frame, view.wo, light, spp=64, seed=3).mean
    errors = {k: (relmse(img, ref.mean), flip(img, ref.mean)) for k, img in images.items()}
    print({k: (round(a, 4), round(b, 4)) for k, (a, b) in errors.items()})
    for other in ("1-bounce", "NDF", "AS00"):
        assert errors["full"][0] < 0.5 * errors[other][0], errors
        assert errors["full"][1] < 0.5 * errors[other][1], errors
    assert errors["full"][0] < 0.02


@pytest.mark.slow
def test_linear_mixing_reproduces_the_area_average(plate):
    """Eq. 3.4 with one layer: α L_s + (1 − α) L_b against the reference that averages scratch geometry and flat
    base by area (coverage rising 0 → 1 across the image); c² instead of c is rejected."""
    view, light, _ = plate
    base = Microfacet(alpha=0.25, fresnel="conductor", eta=(2.91,) * 3, k=(3.09,) * 3)
    c = view.coverage_ramp()
    ref = render_plate_reference("quartic:0.5", IRON_EXACT, view, light, rays=256, seed=4, coverage=c, base=base)
    scratch = render_cone_model(
        full_model("quartic:0.5", IRON_EXACT, size=M, rays=RAYS, seed=2), view.frame, view.wo, light, spp=64, seed=5
    )
    bare = render_material(base, view.frame, view.wo, light, spp=256, seed=6)
    good = relmse(mix(scratch, bare, c).mean, ref.mean)
    bad = relmse(mix(scratch, bare, c**2).mean, ref.mean)
    assert good < 0.01 and bad > 5 * good, (good, bad)
    # per column (one c): the mean difference is within noise, plus c × the full model's own bias (γ, bins)
    m = mix(scratch, bare, c)
    diff = (m.mean - ref.mean).mean(axis=0)
    se = np.sqrt((m.stderr**2 + ref.stderr**2).sum(axis=0)) / view.height
    z = np.abs(diff) / (se + 0.02 * c[0][:, None] * ref.mean.mean(axis=0))
    assert np.all(z < 4.0), z.max()


def test_ndf_model_equals_one_bounce_without_masking():
    """A shallow V (walls at 11°): near normal incidence nothing is masked or shadowed and no path bounces twice,
    so the NDF model's table equals the 1-bounce table there; Smith G₁ is 1 at normal incidence, < 1 at grazing."""
    spec, fres = "vgroove:0.1", make_fresnel(ior=1.5)
    ndf = ndf_model(spec, fres, size=32, rays=4000, seed=1).table
    one = one_bounce_model(spec, fres, size=32, rays=4000, seed=1).table
    cols = slice(12, 20)  # |φ_in| < 22.5°
    cos = np.cos(ndf.phi)[:, None] * np.pi / 32
    e_ndf = (ndf.rho_m[:, cols] * cos).sum(axis=0)
    e_one = (one.rho_m[:, cols] * cos).sum(axis=0)
    assert np.allclose(e_ndf, 1.0, atol=0.02) and np.allclose(e_one, 1.0, atol=0.02)
    assert np.allclose(ndf.rho_m[:, cols] * cos, one.rho_m[:, cols] * cos, atol=0.03)
    g1 = smith_g1(parse_profile("quartic:0.5"), [0.0, 1.4])
    assert g1[0] == pytest.approx(1.0) and g1[1] < 0.8


def test_as00_matches_the_metal_at_normal_incidence():
    mat = as00_material(IRON_EXACT)
    assert mat.nu == 1e4 and mat.nv == 2.0 and mat.rd == (0.0, 0.0, 0.0)
    assert mat.rs[0] == pytest.approx(float(IRON_EXACT(1.0)[0]))
