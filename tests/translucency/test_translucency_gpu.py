"""The ``translucent`` GPU technique on a flat slab against the models' closed forms and NumPy twins."""

from __future__ import annotations

import numpy as np
import pytest

import reflets
from reflets.errors import ArgumentError
from reflets.scene.model import DirectionalLight, PointLight
from reflets.translucency import (
    Medium,
    half_space_single_scattering,
    multiple_fit,
    profile_rd,
    rings,
    total_reflectance,
)
from reflets.translucency.optics import fresnel_moment, fresnel_transmittance


def slab(material: dict, light: dict, camera=((0, 3, 0.001), (0, 0, 0)), size=(32, 32), fov=20):
    return reflets.load_dict(
        {
            "camera": {"position": list(camera[0]), "look_at": list(camera[1]), "fov_y": fov, "size": list(size)},
            "materials": {"m": {"type": "translucent", "mm_per_unit": 10.0, **material}},
            "mesh": [{"shape": "plane", "size": [10, 10], "material": "m"}],
            "light": [light],
        }
    )


OVERHEAD = {"type": "directional", "direction": [0, -1, 0], "irradiance": [1, 1, 1]}


@pytest.mark.parametrize("profile", ["multiple_fit", "dipole", "better_dipole", "normalized_diffusion"])
@pytest.mark.parametrize("preset", ["skin1", "marble"])
def test_multiple_scattering_on_a_uniformly_lit_slab_gives_the_total_reflectance(preset, profile):
    """Centre of a 100 mm slab lit from above, seen from above: F_T F_T R_total/(πc) within 3 % (product rule)."""
    scene = slab({"preset": preset, "profile": profile}, OVERHEAD)
    image = reflets.render(scene, method="translucent", terms=["multiple"])
    material = scene.materials["m"]
    f0 = 1 - fresnel_transmittance(1.0, material.eta)
    c = 1 - 2 * fresnel_moment(1, material.eta, inside=False)
    expected = (1 - f0) ** 2 * total_reflectance(profile, material.medium()) / (np.pi * c)
    measured = image[14:18, 14:18].reshape(-1, 3).mean(axis=0)
    np.testing.assert_allclose(measured, expected, rtol=0.03)


@pytest.mark.parametrize("profile", ["multiple_fit", "dipole", "better_dipole", "normalized_diffusion"])
def test_multiple_scattering_under_oblique_light_keeps_the_slab_energy(profile):
    """Light at 37° from the normal (index-matched, so F_T = 1): E cosθ R_total/π (× the Monte Carlo's
    incidence factor for ``multiple_fit``). Checks the stretch of true over plane distances, and the closed-form
    first cell of the product rule (a singular profile's energy)."""
    light = {"type": "directional", "direction": [0.6, -0.8, 0], "irradiance": [1, 1, 1]}
    scene = slab({"preset": "skin1", "profile": profile, "eta": 1.0}, light)
    image = reflets.render(scene, method="translucent", terms=["multiple"])
    medium = scene.materials["m"].medium()
    expected = 0.8 * total_reflectance(profile, medium) / np.pi
    if profile == "multiple_fit":
        expected = expected * multiple_fit.incidence_factor(medium, 0.8)
    np.testing.assert_allclose(image[14:18, 14:18].mean(axis=(0, 1)), expected, rtol=0.03)


def test_a_profile_vanishing_at_wide_rings_stays_finite():
    """The document's widest setting (1200 samples, 30 mean free paths of the widest channel) with normalised
    diffusion: skin1's blue profile underflows at the outer rings; the image stays finite and keeps the slab's
    energy (a 1/R_d of zero once made 0 × inf = NaN on the GPU)."""
    scene = slab({"preset": "skin1", "profile": "normalized_diffusion"}, OVERHEAD)
    image = reflets.render(scene, method="translucent", terms=["multiple"], rings=40, angles=30, radius_mfp=30.0)
    assert np.all(np.isfinite(image))
    material = scene.materials["m"]
    c = 1 - 2 * fresnel_moment(1, material.eta, inside=False)
    expected = fresnel_transmittance(1.0, material.eta) ** 2 * total_reflectance(
        "normalized_diffusion", material.medium()
    )
    np.testing.assert_allclose(image[14:18, 14:18].mean(axis=(0, 1)), expected / (np.pi * c), rtol=0.03)


@pytest.mark.parametrize("quadrature", ["product", "bilinear"])
def test_per_channel_ring_sets_keep_the_slab_energy_and_fit_each_channel(quadrature):
    """The document's β per channel: each channel integrated with its own rings (its own radius and β) keeps the
    uniformly lit slab's energy (product rule within 3 %; the bilinear rule within 3 % of its shared-ring value
    at 48 rings), and the layouts differ per channel (marble's red spreads wider than its blue)."""
    from reflets.techniques import get_technique
    from reflets.translucency.shading import ring_radii

    scene = slab({"preset": "marble", "profile": "better_dipole"}, OVERHEAD)
    rings_ = 48 if quadrature == "bilinear" else 12
    per, shared = (
        reflets.render(scene, method="translucent", terms=["multiple"], ms_quadrature=quadrature, rings=rings_,
                       ring_sets=sets)[14:18, 14:18].mean(axis=(0, 1))
        for sets in ("per_channel", "shared")
    )  # fmt: skip
    material = scene.materials["m"]
    c = 1 - 2 * fresnel_moment(1, material.eta, inside=False)
    expected = fresnel_transmittance(1.0, material.eta) ** 2 * total_reflectance("better_dipole", material.medium())
    np.testing.assert_allclose(per, expected / (np.pi * c) if quadrature == "product" else shared, rtol=0.03)
    params = get_technique("translucent").Params(ring_sets="per_channel")
    radii = ring_radii(params, material, material.medium())
    assert radii.shape == (3, 13) and radii[0, -1] > 1.2 * radii[2, -1]


def test_the_documents_bilinear_rule_overestimates_and_converges():
    """With the document's own profile and ring fit (the better dipole)."""
    scene = slab({"preset": "skin1", "profile": "better_dipole"}, OVERHEAD)
    coarse = reflets.render(scene, method="translucent", terms=["multiple"], ms_quadrature="bilinear")
    fine = reflets.render(scene, method="translucent", terms=["multiple"], ms_quadrature="bilinear", rings=48)
    product = reflets.render(scene, method="translucent", terms=["multiple"])
    c, f, p = (img[14:18, 14:18].mean(axis=(0, 1)) for img in (coarse, fine, product))
    assert np.all(c > p * 1.01) and np.all(np.abs(f / p - 1) < 0.01)


@pytest.mark.parametrize(
    "light, camera",
    [
        (OVERHEAD, ((0, 3, 0.001), (0, 0, 0))),
        ({"type": "directional", "direction": [0.6, -0.8, 0], "irradiance": [2, 2, 2]}, ((0, 3, 0.001), (0, 0, 0))),
        ({"type": "directional", "direction": [0, -0.9, 0.43589], "irradiance": [1, 1, 1]}, ((0, 2, 2), (0, 0, 0))),
    ],
)
def test_single_scattering_on_a_slab_matches_hanrahan_krueger(light, camera):
    scene = slab({"preset": "skin1", "g": 0.3}, light, camera=camera, size=(33, 33), fov=10)
    image = reflets.render(scene, method="translucent", terms=["single"])
    d = -np.asarray(light["direction"], dtype=np.float64)
    d /= np.linalg.norm(d)
    eye = np.asarray(camera[0], dtype=np.float64)
    view = eye / np.linalg.norm(eye)  # the centre pixel sees the origin
    phi = np.arctan2(view[2], view[0]) - np.arctan2(d[2], d[0]) if np.hypot(d[0], d[2]) > 1e-6 else 0.0
    medium = scene.materials["m"].medium()
    expected = half_space_single_scattering(medium, d[1], view[1], phi, irradiance=light["irradiance"][0])
    np.testing.assert_allclose(image[16, 16], expected, rtol=0.02)


def test_ring_weights_integrate_bilinear_functions_exactly():
    radii = rings.ring_radii(3.0, 7, 0.3)
    w = rings.ring_weights(radii, 12)
    a, b = 0.7, 1.3  # c = a + b ρ is reproduced exactly by the bilinear interpolant
    assert np.sum(w * 12 * (a + b * radii)) == pytest.approx(2 * np.pi * (a * 9 / 2 + b * 27 / 3), rel=1e-12)


def test_product_weights_integrate_the_profile():
    medium = Medium.preset("skin1")
    radii = rings.ring_radii(200.0 * float(np.max(medium.mean_free_path)), 12, 0.2)
    w = rings.product_weights(radii, 14, lambda r: profile_rd("better_dipole", np.asarray(r)[..., None], medium))
    np.testing.assert_allclose(14 * w.sum(axis=0), total_reflectance("better_dipole", medium), rtol=1e-4)


@pytest.mark.parametrize(
    "lights, message",
    [
        ([], "exactly one point or directional light"),
        ([OVERHEAD, OVERHEAD], "exactly one point or directional light"),
        (
            [{"type": "point", "position": [0, 0.1, 0], "intensity": [1, 1, 1]}],
            "outside the translucent meshes' bounding sphere",
        ),
    ],
)
def test_unsupported_lighting_is_a_clear_error(lights, message):
    built = [PointLight(**lt) if lt["type"] == "point" else DirectionalLight(**lt) for lt in lights]
    scene = slab({"preset": "skin1"}, OVERHEAD).model_copy(update={"light": built})
    with pytest.raises(ArgumentError, match=message):
        reflets.render(scene, method="translucent")


def test_cli_terms_and_lighting_errors(tmp_path, capsys):
    from reflets.cli import main

    scenes = __import__("reflets.demo", fromlist=["scene_path"]).scene_path
    out = tmp_path / "bunny.exr"
    code = main(
        ["render", str(scenes("31_translucent_bunny.toml")), "--method", "translucent", "--size", "40x30",
         "--param", "terms=single,multiple", "-o", str(out)]
    )  # fmt: skip
    assert code == 0 and out.exists()
    code = main(["render", str(scenes("04_bunny_arealight.toml")), "--method", "translucent", "-o", str(out),
                 "--overwrite"])  # fmt: skip
    err = capsys.readouterr().err
    assert code == 2 and "exactly one point or directional light" in err and "Traceback" not in err


def test_geometry_outputs_match_the_forward_pass():
    scene = slab({"preset": "skin1"}, OVERHEAD)
    for output in ("position", "normal", "uv"):
        ours = reflets.render(scene, method="translucent", output=output)
        np.testing.assert_allclose(ours, reflets.render(scene, method=output), atol=1e-6)


@pytest.mark.parametrize("direction", [[0, -1, 0], [0.6, -0.8, 0]])
def test_camera_view_blend_keeps_the_slab_energy(direction):
    """The document's light-/camera-view blend (λ → 0: half each): the camera view's estimate of the same slab
    agrees (wide camera so that the profile's support is on screen; index-matched). With the better dipole: the
    camera's 1.1 mm texels here are coarser than ``multiple_fit``'s peak (docs/techniques/translucency.md)."""
    light = {"type": "directional", "direction": direction, "irradiance": [1, 1, 1]}
    scene = slab({"preset": "skin1", "eta": 1.0, "profile": "better_dipole"}, light, size=(64, 64), fov=100)
    blended = reflets.render(scene, method="translucent", terms=["multiple"], view_blend=0.001)
    expected = -direction[1] * total_reflectance("better_dipole", scene.materials["m"].medium()) / np.pi
    np.testing.assert_allclose(blended[30:34, 30:34].mean(axis=(0, 1)), expected, rtol=0.05)
    light_only = reflets.render(scene, method="translucent", terms=["multiple"])
    assert np.abs(blended - light_only).max() > 1e-4  # the camera view did contribute
