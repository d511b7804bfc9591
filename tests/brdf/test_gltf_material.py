"""glTF 2.0's metallic-roughness BRDF (Appendix B) against an independent transcription of the specification."""

from __future__ import annotations

import numpy as np
import pytest
from brdf_checks import (
    albedo_sampled,
    albedo_uniform,
    check_glsl_parity,
    direction,
    run_standard_checks,
    upper_hemisphere,
)

from reflets.brdf import Gltf
from reflets.brdf.gltf import IBL_TABLE_SIZE, ibl_table

CASES = [
    dict(base_color=(0.8, 0.5, 0.2, 1.0), metallic=0.0, roughness=0.5),
    dict(base_color=(0.95, 0.64, 0.54, 1.0), metallic=1.0, roughness=0.2),
    dict(base_color=(0.3, 0.6, 0.9, 1.0), metallic=0.4, roughness=0.08),
    dict(base_color=(1.0, 1.0, 1.0, 1.0), metallic=1.0, roughness=1.0),
]


def appendix_b(base, metallic, roughness, wo, wi, ior=1.5, specular_weight=1.0, specular_color=(1.0, 1.0, 1.0)):
    """The specification's formulas as written there (n = +z, v = wo, l = wi), with V_GGX of its sample code;
    ``ior``: KHR_materials_ior's dielectric F0 = ((ior − 1) / (ior + 1))²; ``specular_weight``, ``specular_color``:
    KHR_materials_specular's fresnel_mix (F0 tinted and clamped at 1, the base weighed by 1 − w max(F))."""
    n_l, n_v = wi[:, 2], wo[:, 2]
    h = (wo + wi) / np.linalg.norm(wo + wi, axis=1, keepdims=True)
    n_h, v_h = h[:, 2], np.sum(wo * h, axis=1)
    a2 = max(roughness**2, 1e-3) ** 2
    d = a2 / (np.pi * (n_h * n_h * (a2 - 1) + 1) ** 2)
    v = 0.5 / (n_l * np.sqrt(n_v * n_v * (1 - a2) + a2) + n_v * np.sqrt(n_l * n_l * (1 - a2) + a2))
    lobe = (v * d)[:, None]
    base = np.asarray(base[:3])
    fresnel = (1 - np.abs(v_h)) ** 5
    metal = lobe * (base + (1 - base) * fresnel[:, None])
    f0 = np.minimum(((ior - 1) / (ior + 1)) ** 2 * np.asarray(specular_color), 1.0)
    f_d = f0 + (1 - f0) * fresnel[:, None]  # (N, 3)
    dielectric = (1 - specular_weight * f_d.max(axis=1, keepdims=True)) * base / np.pi + specular_weight * f_d * lobe
    return (1 - metallic) * dielectric + metallic * metal


@pytest.mark.parametrize("params", CASES)
def test_gltf_equals_the_specifications_formulas(params, rng):
    wo, wi = upper_hemisphere(rng, 4000), upper_hemisphere(rng, 4000)
    m = Gltf(**params)
    expected = appendix_b(params["base_color"], params["metallic"], params["roughness"], wo, wi)
    assert np.allclose(m.eval(wo, wi), expected, rtol=1e-9, atol=1e-12), params


@pytest.mark.parametrize("params", CASES)
def test_gltf_standard_checks(params, rng):
    run_standard_checks(Gltf(**params), rng)


def test_gltf_dielectric_exceeds_one_at_grazing_as_the_specification_does(rng):
    """Why energy_conserving is False for dielectrics: Appendix B's mix gives > 1 at θo = 1.4 (not our bug)."""
    m = Gltf(base_color=(0.95, 0.95, 0.95, 1.0), metallic=0.0, roughness=0.05)
    albedo, err = albedo_sampled(m, direction(1.4), rng, 400000)
    assert not m.energy_conserving
    assert albedo[0] - 3 * err[0] > 1.2


@pytest.mark.parametrize("params", CASES[:3])
def test_gltf_glsl_matches_numpy(params, ctx, rng):
    check_glsl_parity(Gltf(**params), ctx, rng)


def test_gltf_split_sum_table_gives_the_lobe_albedo(rng):
    """F0 A + B from the table equals the GGX lobe's albedo integrated by uniform sampling (metal: F0 = colour),
    and 0.96 (1 − P) the dielectric's diffuse albedo."""
    table = ibl_table(side=48)
    for i, j in [(3, 28), (16, 16), (31, 4)]:
        roughness, mu = (i + 0.5) / IBL_TABLE_SIZE, (j + 0.5) / IBL_TABLE_SIZE
        wo = np.array([np.sqrt(1 - mu * mu), 0.0, mu])
        metal = Gltf(base_color=(1.0, 0.0, 0.5, 1.0), metallic=1.0, roughness=roughness)
        albedo, err = albedo_uniform(metal, wo, rng, 400000)
        a, b, _, _ = table[i, j]
        assert abs(albedo[0] - (a + b)) < 4 * err[0] + 0.01, (roughness, mu, albedo, a + b)
        assert abs(albedo[1] - b) < 4 * err[1] + 0.002, (roughness, mu, albedo, b)
        assert abs(albedo[2] - (0.5 * a + b)) < 4 * err[2] + 0.01
    # the diffuse share: a black-lobed dielectric cannot be built, so check P against its definition directly
    mu = (20 + 0.5) / IBL_TABLE_SIZE
    wo = np.array([np.sqrt(1 - mu * mu), 0.0, mu])
    wi = upper_hemisphere(rng, 400000)
    h = (wo + wi) / np.linalg.norm(wo + wi, axis=1, keepdims=True)
    p = np.mean((1 - np.sum(wo * h, axis=1)) ** 5 * wi[:, 2] * 2)
    assert abs(table[10, 20, 2] - p) < 0.002


COATED = [
    dict(base_color=(0.5, 0.02, 0.01, 1.0), metallic=0.0, roughness=0.44, clearcoat=1.0, clearcoat_roughness=0.03),
    dict(base_color=(0.9, 0.6, 0.3, 1.0), metallic=1.0, roughness=0.6, clearcoat=0.7, clearcoat_roughness=0.3),
]


def clearcoat_extension(params, wo, wi):
    """KHR_materials_clearcoat as its text writes it (coat normal = n): mix(base, coat_brdf, c · F_c(v·n))."""
    base = appendix_b(params["base_color"], params["metallic"], params["roughness"], wo, wi)
    coat = appendix_b((1.0, 1.0, 1.0, 1.0), 1.0, params["clearcoat_roughness"], wo, wi)  # a white metal: D V
    weight = (params["clearcoat"] * (0.04 + 0.96 * (1 - wo[:, 2]) ** 5))[:, None]
    return (1 - weight) * base + weight * coat


@pytest.mark.parametrize("params", COATED)
def test_clearcoat_equals_the_extensions_formula(params, rng):
    wo, wi = upper_hemisphere(rng, 4000), upper_hemisphere(rng, 4000)
    assert np.allclose(Gltf(**params).eval(wo, wi), clearcoat_extension(params, wo, wi), rtol=1e-9, atol=1e-12)
    bare = {k: v for k, v in params.items() if not k.startswith("clearcoat")}
    assert not np.allclose(Gltf(**params).eval(wo, wi), Gltf(**bare).eval(wo, wi))


#: ClearCoatTest's coat roughness 0.03 (α = 1e-3) is a spike that uniform sampling misses and float32 holds to
#: 1.6e-3 only: the sampling and GPU checks take the same coat at roughness 0.15
CHECKED = [COATED[1], {**COATED[0], "clearcoat_roughness": 0.15}]


@pytest.mark.parametrize("params", CHECKED)
def test_clearcoat_standard_checks(params, rng):
    run_standard_checks(Gltf(**params), rng)


@pytest.mark.parametrize("params", CHECKED)
def test_clearcoat_glsl_matches_numpy(params, ctx, rng):
    check_glsl_parity(Gltf(**params), ctx, rng)


def test_clearcoat_normal_of_its_own_is_lit_by_its_own_cosine(rng):
    """A coat normal tilted from the shading normal (a coat normal map): its lobe peaks at the coat's mirror
    direction, and times the base's cosine it is D V (n_c·l), as Khronos' sample viewer lights it."""
    from reflets.brdf.gltf import GltfPoints

    tilt = np.array([np.sin(0.3), 0.0, np.cos(0.3)])
    points = GltfPoints(base=np.zeros((1, 3)), metallic=np.ones(1), alpha=np.ones(1), coat=np.ones(1),
                        coat_alpha=np.full(1, 0.05), coat_normal=tilt[None])  # fmt: skip
    wo = np.array([[0.0, 0.0, 1.0]])
    mirror = 2 * tilt[2] * tilt - wo[0]
    at_mirror = points.eval(wo, mirror[None])[0, 0] * mirror[2]
    at_z = points.eval(wo, wo)[0, 0] * wo[0, 2]
    assert at_mirror > 50 * at_z


def test_midpoint_samples_of_a_quad_light_meet_on_a_near_mirror():
    """A roughness-0.02 metal sphere under a quad light, forward's 8 × 8 midpoint samples: each sample's lobe is
    widened by its patch (gltf.glsl, brdf_eval_patch), so the mirror shows the light, not 64 dots. Measured 6.0 %
    against the reference (15.9 % unwidened)."""
    import reflets
    from reflets.reference import reference

    scene = {
        "camera": {"position": [0, 0.2, 3], "look_at": [0, 0, 0], "fov_y": 30, "size": [128, 96]},
        "materials": {"m": {"type": "gltf", "base_color": [0.9, 0.9, 0.9, 1], "metallic": 1.0, "roughness": 0.02}},
        "mesh": [{"shape": "sphere", "radius": 0.8, "material": "m"}],
        "light": [{"type": "quad", "corners": [[-0.6, 1.5, 0.2], [0.6, 1.5, 0.2], [-0.6, 1.5, 1.4]],
                   "radiance": [5, 5, 5]}],  # fmt: skip
        "background": [0, 0, 0],
    }
    gpu = reflets.render(scene, method="forward", spp=16)
    ref = reference(scene, spp=64, pixel="box", progress=False).image
    assert reflets.compare(gpu, ref)["relmse"] < 0.09
    assert abs(gpu.sum() / ref.sum() - 1.0) < 0.02  # the widening moves light, it does not add any


SHEENED = [
    dict(base_color=(0.5, 0.1, 0.1, 1.0), metallic=0.0, roughness=0.6, sheen_color=(0.9, 0.6, 0.6),
         sheen_roughness=0.4),  # fmt: skip
    dict(base_color=(0.2, 0.2, 0.6, 1.0), metallic=1.0, roughness=0.3, sheen_color=(0.3, 0.8, 0.2),
         sheen_roughness=0.8),  # fmt: skip
    dict(base_color=(0.7, 0.7, 0.7, 1.0), metallic=0.0, roughness=0.5, sheen_color=(1.0, 1.0, 1.0),
         sheen_roughness=0.15, clearcoat=0.6, clearcoat_roughness=0.2),  # fmt: skip
]


def sheen_extension(params, wo, wi):
    """KHR_materials_sheen as its text writes it (Charlie D and λ, albedo scaling with E at n·v and n·l) over
    Appendix B, the clear coat over both; E from reflets' table (the extension leaves it to a table)."""
    from reflets.brdf.gltf import sheen_albedo

    r = max(params["sheen_roughness"], 0.07)
    alpha = r * r
    n_v, n_l = wo[:, 2], wi[:, 2]
    h = (wo + wi) / np.linalg.norm(wo + wi, axis=1, keepdims=True)
    d = (2 + 1 / alpha) * (1 - h[:, 2] ** 2) ** (1 / alpha * 0.5) / (2 * np.pi)

    def exponent(x):
        t = (1 - alpha) ** 2
        a, b = 21.5473 * (1 - t) + 25.3245 * t, 3.82987 * (1 - t) + 3.32435 * t
        c, dd, e = 0.19823 * (1 - t) + 0.16801 * t, -1.97760 * (1 - t) - 1.27393 * t, -4.32054 * (1 - t) - 4.85967 * t
        return a / (1 + b * x**c) + dd * x + e

    def lam(x):
        return np.where(x < 0.5, np.exp(exponent(x)), np.exp(2 * exponent(0.5) - exponent(1 - x)))

    v = 1 / ((1 + lam(n_v) + lam(n_l)) * (4 * n_v * n_l))
    color = np.asarray(params["sheen_color"])
    peak = color.max()
    scaling = np.maximum(np.minimum(1 - peak * sheen_albedo(n_v, r), 1 - peak * sheen_albedo(n_l, r)), 0)
    base = appendix_b(params["base_color"], params["metallic"], params["roughness"], wo, wi)
    value = color * (d * v)[:, None] + base * scaling[:, None]
    if params.get("clearcoat", 0) > 0:
        coat = appendix_b((1.0, 1.0, 1.0, 1.0), 1.0, params["clearcoat_roughness"], wo, wi)
        weight = (params["clearcoat"] * (0.04 + 0.96 * (1 - n_v) ** 5))[:, None]
        value = (1 - weight) * value + weight * coat
    return value


@pytest.mark.parametrize("params", SHEENED)
def test_sheen_equals_the_extensions_formula(params, rng):
    wo, wi = upper_hemisphere(rng, 4000), upper_hemisphere(rng, 4000)
    assert np.allclose(Gltf(**params).eval(wo, wi), sheen_extension(params, wo, wi), rtol=1e-9, atol=1e-12)
    bare = {k: v for k, v in params.items() if not k.startswith("sheen")}
    assert not np.allclose(Gltf(**params).eval(wo, wi), Gltf(**bare).eval(wo, wi))


def test_sheen_table_holds_the_lobes_albedo(rng):
    """E in the table's fourth channel (a midpoint rule over the hemisphere) is ∫ D_s V_s cos dω of the lobe
    (C = 1; the lobe itself checked against the extension's text above) by uniform Monte Carlo sampling."""
    from reflets.brdf.gltf import IBL_TABLE_SIZE, charlie_d, ibl_table_cached, sheen_visibility

    table = ibl_table_cached()
    for i, j in [(4, 30), (12, 12), (28, 6), (20, 25), (1, 3)]:
        roughness, mu = (i + 0.5) / IBL_TABLE_SIZE, (j + 0.5) / IBL_TABLE_SIZE
        wo = np.array([np.sqrt(1 - mu * mu), 0.0, mu])
        wi = upper_hemisphere(rng, 400000)
        h = (wo + wi) / np.linalg.norm(wo + wi, axis=1, keepdims=True)
        alpha = max(roughness, 0.07) ** 2
        est = charlie_d(h[:, 2], alpha) * sheen_visibility(np.full(len(wi), mu), wi[:, 2], alpha) * wi[:, 2]
        est *= 2 * np.pi
        err = est.std() / np.sqrt(len(wi))
        assert abs(est.mean() - table[i, j, 3]) < 4 * err + 2e-3, (roughness, mu, est.mean(), table[i, j, 3])


@pytest.mark.parametrize("params", SHEENED)
def test_sheen_standard_checks(params, rng):
    run_standard_checks(Gltf(**params), rng)


@pytest.mark.parametrize("params", SHEENED)
def test_sheen_glsl_matches_numpy(params, ctx, rng):
    check_glsl_parity(Gltf(**params), ctx, rng)


IORS = [
    dict(base_color=(0.2, 0.5, 0.8, 1.0), metallic=0.0, roughness=0.3, ior=1.33),  # water
    dict(base_color=(0.9, 0.9, 0.9, 1.0), metallic=0.3, roughness=0.5, ior=2.42),  # diamond, partly metal
    dict(base_color=(0.5, 0.5, 0.5, 1.0), metallic=0.0, roughness=0.6, ior=0.0),  # F = 1: the lobe alone
]


@pytest.mark.parametrize("params", IORS)
def test_ior_equals_the_extensions_formula(params, rng):
    """KHR_materials_ior: the dielectric's F0 = ((ior − 1) / (ior + 1))² in Appendix B's Fresnel mix (0 gives F = 1:
    no diffuse lobe at all)."""
    wo, wi = upper_hemisphere(rng, 4000), upper_hemisphere(rng, 4000)
    expected = appendix_b(params["base_color"], params["metallic"], params["roughness"], wo, wi, params["ior"])
    assert np.allclose(Gltf(**params).eval(wo, wi), expected, rtol=1e-9, atol=1e-12)
    assert not np.allclose(Gltf(**params).eval(wo, wi), Gltf(**{**params, "ior": 1.5}).eval(wo, wi))


@pytest.mark.parametrize("params", IORS[:2])
def test_ior_standard_checks_and_glsl(params, ctx, rng):
    run_standard_checks(Gltf(**params), rng)
    check_glsl_parity(Gltf(**params), ctx, rng)


@pytest.mark.parametrize("ior", [0.5, -1.0, float("nan"), 1e300])
def test_ior_between_0_and_1_or_unbounded_is_refused(ior):
    from pydantic import ValidationError

    with pytest.raises(ValidationError):
        Gltf(ior=ior)


def test_unlit_shows_its_base_colour_whatever_the_lights(ctx):
    """KHR_materials_unlit: a textured unlit plane under a point light and the studio map is its base colour ×
    texture, on the GPU and in the reference (no light reflected, none added — not by its coat or sheen either)."""
    from pathlib import Path

    import reflets
    from reflets.scene.assets import default_environment

    texture = {"texture": str(Path(__file__).parents[1] / "data" / "gltf" / "SheenTest" / "sheen.png")}  # stripes
    scene = reflets.load_dict({
        "camera": {"position": [0, 0, 2], "look_at": [0, 0, 0], "fov_y": 30, "size": [32, 24]},
        "materials": {"m": {"type": "gltf", "unlit": True, "base_color": [0.5, 0.8, 1.0, 1.0],
                            "base_color_texture": texture, "clearcoat": 0.8, "sheen_color": [1, 1, 1]}},
        "mesh": [{"shape": "plane", "size": [4, 4], "material": "m", "transform": {"rotate": [90, 0, 0]}}],
        "light": [{"type": "point", "position": [0.5, 0.5, 1], "intensity": [50, 50, 50]},
                  {"type": "environment", "file": str(default_environment())}],
    })  # fmt: skip
    gpu = reflets.render(scene, spp=16)
    ref = reflets.reference(scene, spp=16, pixel="box", progress=False).image
    uv = reflets.render(scene, method="uv", spp=1)[..., :2].reshape(-1, 2)
    expected = scene.materials["m"].emitted(uv).reshape(gpu.shape)
    assert np.mean((ref - gpu) ** 2) / np.mean(ref**2) < 5e-5  # measured 4.4e-6 (4.2e-4 when the GPU lit the coat)
    assert np.mean(np.abs(ref - expected)) / np.mean(expected) < 0.05  # ... its centre's texel but at the edges
    lit = reflets.render(scene.model_copy(update={"materials": {"m": scene.materials["m"].model_copy(
        update={"unlit": False})}}), spp=16)  # fmt: skip
    assert np.mean(np.abs(lit - gpu)) > 0.05  # lit, the same material is something else


SPECULARS = [
    dict(base_color=(0.6, 0.3, 0.2, 1.0), metallic=0.0, roughness=0.35, specular=0.5, specular_color=(1.0, 0.5, 2.0)),
    dict(base_color=(0.2, 0.2, 0.2, 1.0), metallic=0.2, roughness=0.6, specular=1.0, specular_color=(10.0, 20.0, 30.0),
         ior=1.6),  # fmt: skip  # F0 clamped at 1 in every channel
]


@pytest.mark.parametrize("params", SPECULARS)
def test_specular_equals_the_extensions_formula(params, rng):
    """KHR_materials_specular's fresnel_mix: F0 = min(F0(ior) × colour, 1), the lobe × w F, the base × (1 − w max F)."""
    wo, wi = upper_hemisphere(rng, 4000), upper_hemisphere(rng, 4000)
    expected = appendix_b(params["base_color"], params["metallic"], params["roughness"], wo, wi,
                          params.get("ior", 1.5), params["specular"], params["specular_color"])  # fmt: skip
    assert np.allclose(Gltf(**params).eval(wo, wi), expected, rtol=1e-9, atol=1e-12)


@pytest.mark.parametrize("params", SPECULARS)
def test_specular_standard_checks_and_glsl(params, ctx, rng):
    run_standard_checks(Gltf(**params), rng)
    check_glsl_parity(Gltf(**params), ctx, rng)


def test_a_smooth_sheen_is_not_energy_conserving(rng):
    """A white metal under a white, smooth sheen reflects more than it receives at grazing views (the extension's
    λ makes E > 1 there): the library's energy checks must not be asked of it."""
    m = Gltf(base_color=(1.0, 1.0, 1.0, 1.0), metallic=1.0, roughness=0.5, sheen_color=(1.0, 1.0, 1.0),
             sheen_roughness=0.07)  # fmt: skip
    albedo, err = albedo_uniform(m, direction(np.arccos(0.02)), rng, 400000)
    assert not m.energy_conserving and albedo[0] - 4 * err[0] > 1.2


ANISOTROPIC = [
    dict(base_color=(0.95, 0.64, 0.54, 1.0), metallic=1.0, roughness=0.3, anisotropy_strength=0.7,
         anisotropy_rotation=0.4),
    dict(base_color=(0.5, 0.4, 0.9, 1.0), metallic=0.0, roughness=0.2, anisotropy_strength=1.0,
         anisotropy_rotation=-2.0),
    dict(base_color=(0.8, 0.8, 0.8, 1.0), metallic=0.5, roughness=0.05, anisotropy_strength=0.3),
]  # fmt: skip


def anisotropic_lobe(params, wo, wi):
    """KHR_materials_anisotropy's D and V as the extension writes them (t = the turned direction, b = n × t,
    α_t = mix(α_b, 1, s²), α_b = roughness²)."""
    r, s = params.get("anisotropy_rotation", 0.0), params["anisotropy_strength"]
    t, b = np.array([np.cos(r), np.sin(r), 0.0]), np.array([-np.sin(r), np.cos(r), 0.0])
    ab = max(params["roughness"] ** 2, 1e-3)
    at = ab + s * s * (1.0 - ab)
    h = (wo + wi) / np.linalg.norm(wo + wi, axis=1, keepdims=True)
    d = 1.0 / (np.pi * at * ab * ((h @ t / at) ** 2 + (h @ b / ab) ** 2 + h[:, 2] ** 2) ** 2)
    length = lambda w: np.sqrt((at * (w @ t)) ** 2 + (ab * (w @ b)) ** 2 + w[:, 2] ** 2)  # noqa: E731
    v = 0.5 / (wi[:, 2] * length(wo) + wo[:, 2] * length(wi))
    return d, v, h


@pytest.mark.parametrize("params", ANISOTROPIC)
def test_anisotropy_equals_the_extensions_formula(params, rng):
    wo, wi = upper_hemisphere(rng, 4000), upper_hemisphere(rng, 4000)
    d, v, h = anisotropic_lobe(params, wo, wi)
    base, m = np.asarray(params["base_color"][:3]), params["metallic"]
    fresnel = ((1 - np.sum(wo * h, axis=1)) ** 5)[:, None]
    f_d = 0.04 + 0.96 * fresnel
    lobe = (d * v)[:, None]
    expected = (1 - m) * ((1 - f_d) * base / np.pi + f_d * lobe) + m * (base + (1 - base) * fresnel) * lobe
    assert np.allclose(Gltf(**params).eval(wo, wi), expected, rtol=1e-9, atol=1e-12)
    isotropic = Gltf(**{**params, "anisotropy_strength": 0.0}).eval(wo, wi)
    assert np.mean(np.abs(isotropic - expected)) > 1e-3 * np.mean(expected)  # the lobe is stretched


@pytest.mark.parametrize("params", ANISOTROPIC)
def test_anisotropy_standard_checks_and_glsl(params, ctx, rng):
    run_standard_checks(Gltf(**params), rng)
    check_glsl_parity(Gltf(**params), ctx, rng)


def test_the_area_light_methods_lobe_summary_follows_unlit_and_specular():
    """analytic / biased light a constant glTF material by its summary: an unlit one reflects nothing, and the
    diffuse albedo is c (1 − m)(1 − w max F₀) — KHR_materials_specular's weight and tint included (it was 1 − 0.04
    whatever they were)."""
    from reflets.brdf.gltf import Gltf

    assert Gltf(unlit=True).lobe_summary()[:2] == ((0.0, 0.0, 0.0), 0)
    base = (0.8, 0.2, 0.2, 1.0)
    assert Gltf(base_color=base, metallic=0.0, specular=0.0).lobe_summary()[0] == pytest.approx((0.8, 0.2, 0.2))
    tinted = Gltf(base_color=base, metallic=0.5, specular_color=(2.0, 1.0, 1.0)).lobe_summary()[0]
    assert tinted == pytest.approx(tuple(c * 0.5 * (1 - 0.08) for c in base[:3]))


TRANSMITTING = [
    dict(base_color=(0.8, 0.5, 0.2, 1.0), metallic=0.0, roughness=0.4, transmission=0.7),
    dict(base_color=(0.3, 0.6, 0.9, 1.0), metallic=0.3, roughness=0.2, transmission=1.0, thickness=0.5),
]


@pytest.mark.parametrize("params", TRANSMITTING)
def test_transmission_takes_its_share_of_the_diffuse_lobe(params, ctx, rng):
    """KHR_materials_transmission: base = mix(diffuse, btdf, t) — what is reflected keeps (1 − t) of the diffuse
    lobe (the transmitted part goes through: the renderers' own paths, reference/transmission.py)."""
    wo, wi = upper_hemisphere(rng, 4000), upper_hemisphere(rng, 4000)
    t = params["transmission"]
    full = appendix_b(params["base_color"], params["metallic"], params["roughness"], wo, wi)
    specular = appendix_b((0.0, 0.0, 0.0), 0.0, params["roughness"], wo, wi)  # the dielectric's lobe alone
    diffuse = full - (1 - params["metallic"]) * specular - params["metallic"] * appendix_b(
        params["base_color"], 1.0, params["roughness"], wo, wi)  # fmt: skip
    assert np.allclose(Gltf(**params).eval(wo, wi), full - t * diffuse, rtol=1e-9, atol=1e-12)
    run_standard_checks(Gltf(**params), rng)
    check_glsl_parity(Gltf(**params), ctx, rng)
