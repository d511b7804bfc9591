"""The ``scratched`` material (parameters, α maps, caches, GLSL twin) and the NumPy twin of the per-pixel estimator
(the issue's acceptance tests: α = 1 / α = 0, white furnace, unbiased importance sampling, thickened-light limit)."""

from __future__ import annotations

from types import SimpleNamespace

import numpy as np
import pytest

from reflets.brdf import Lambert
from reflets.errors import SceneError
from reflets.scene import load_dict
from reflets.scene.environment import environment_grid
from reflets.scratches import build_table, shading
from reflets.scratches.material import PRESETS, Scratched, bake_layer, cached_alpha, mip_levels
from reflets.scratches.tracer2d import phi_bins

SMALL = dict(profile="vgroove:0.5", table_size=32, rays=2000, alpha_size=64)


@pytest.fixture(scope="module")
def table():
    return build_table("vgroove:0.5", conductor=(2.91, 3.09), size=32, rays=2000)


@pytest.fixture(scope="module")
def mirror_table():
    return build_table("quartic:0.5", ior=None, size=32, rays=2000)  # F = 1: lossless ρ_m


@pytest.fixture(autouse=True)
def _cache(tmp_path, monkeypatch):
    monkeypatch.setenv("XDG_CACHE_HOME", str(tmp_path / "cache"))


# ---------------------------------------------------------------------------------------------- parameters
def test_presets_and_overrides():
    assert Scratched().layer_parameters == PRESETS["3.14b"]
    m = Scratched(preset="3.14d", count=3, density=0.1)
    assert m.layer_parameters == (3, 360.0, 0.3, 3e-4, 0.1)
    angles = m.layer_angles()
    assert angles.shape == (3,) and np.all(np.abs(angles) <= np.pi)
    assert np.all(np.abs(Scratched(preset="3.14b").layer_angles()) <= np.radians(3.5))
    assert len(PRESETS) == 11


@pytest.mark.parametrize(
    "bad",
    [
        {"conductor": {"eta": 2.0, "k": 3.0}, "ior": 1.5},
        {"fresnel": "none", "ior": 1.5},
        {"profile": "zigzag:1"},
        {"alpha_size": 100},
        {"base": {"type": "mirror"}},
        {"base": {"type": "scratched"}},
        {"preset": "3.99z"},
        {"density": 0.0},
    ],
)
def test_bad_parameters_are_scene_errors(minimal_scene, bad):
    minimal_scene["materials"]["floor"] = {"type": "scratched", **bad}
    with pytest.raises(SceneError):
        load_dict(minimal_scene)


def test_scene_with_nested_base(minimal_scene):
    from reflets.gpu.programs import read_source

    minimal_scene["materials"]["floor"] = {
        "type": "scratched",
        "preset": "3.11f",
        "base": {"type": "microfacet", "alpha": 0.2, "fresnel": "schlick", "specular": [0.5, 0.5, 0.5]},
        "conductor": {"eta": [2.9, 2.9, 2.6], "k": [3.1, 2.9, 2.8]},
    }
    material = load_dict(minimal_scene).materials["floor"]
    assert material.base.type == "microfacet" and '#include "reflets/brdf/glsl/microfacet.glsl"' in read_source(
        material.brdf_source)  # the finite part over the base's twin
    args = material.fresnel_arguments()
    assert args["conductor"][0] == (2.9, 2.9, 2.6) and args["fresnel"] == "auto"


# ---------------------------------------------------------------------------------------------- α maps
def test_alpha_layer_matches_expected_coverage():
    """A sparse layer: mean α = 1 − exp(−π d²) (the Boolean model), isolated scratches along u_k."""
    m = Scratched(count=1, spread=0, length=0.05, width=2e-3, density=0.15, alpha_size=128)
    alpha = bake_layer(0, 0.0, m)
    expected = 1.0 - np.exp(-np.pi * 0.15**2)
    assert alpha.mean() == pytest.approx(expected, rel=0.08)
    # scratches run along u (columns): α is far more correlated along a row than along a column
    a = alpha - alpha.mean()
    along_u = np.mean(a[:, :-1] * a[:, 1:])
    along_v = np.mean(a[:-1, :] * a[1:, :])
    assert along_u > 3.0 * abs(along_v)


def test_mip_levels_keep_the_mean_and_cache(tmp_path):
    m = Scratched(preset="3.14d", count=2, alpha_size=32)
    maps = m.alpha_maps()
    assert maps.shape == (2, 32, 32) and maps.dtype == np.float32
    levels = mip_levels(maps)
    assert [lv.shape[-1] for lv in levels] == [32, 16, 8, 4, 2, 1]
    np.testing.assert_allclose(levels[-1][:, 0, 0], maps.mean(axis=(1, 2)), rtol=1e-6)
    assert cached_alpha(m) is maps  # memory cache
    assert list((tmp_path / "cache" / "reflets" / "scratches").glob("alpha-*.npz"))  # disk cache


def test_table_cache(tmp_path):
    m = Scratched(**SMALL)
    t = m.table()
    assert t.size == 32 and m.table() is t
    assert list((tmp_path / "cache" / "reflets" / "scratches").glob("table-*.npz"))


# ---------------------------------------------------------------------------------------------- finite part
def test_eval_is_weighted_base_and_glsl_twin(ctx):
    from reflets.brdf.gpu_eval import eval_glsl

    rng = np.random.default_rng(3)
    wo = rng.normal(size=(500, 3))
    wi = rng.normal(size=(500, 3))
    wo[:, 2], wi[:, 2] = np.abs(wo[:, 2]), np.abs(wi[:, 2])
    wo /= np.linalg.norm(wo, axis=1, keepdims=True)
    wi /= np.linalg.norm(wi, axis=1, keepdims=True)
    for base in ({"type": "lambert", "albedo": [0.2, 0.4, 0.6]}, {"type": "microfacet", "alpha": [0.1, 0.3]}):
        m = Scratched(coverage=0.2, count=3, base=base, **SMALL)
        assert m.base_weight() == pytest.approx(0.4)
        np.testing.assert_allclose(m.eval(wo, wi), 0.4 * m.base.eval(wo, wi))
        gpu = eval_glsl(m, wo, wi, ctx=ctx)
        ref = m.eval(wo, wi)
        np.testing.assert_allclose(gpu, ref, rtol=1e-3, atol=1e-5)
    dense = Scratched(preset="3.14b", alpha_size=32, **{k: v for k, v in SMALL.items() if k != "alpha_size"})
    assert dense.base_weight() < 0.1  # 4 layers of 68 % mean coverage: the base barely shows


# ---------------------------------------------------------------------------------------------- the twin
def _wo(theta, phi, angle=0.0):
    return shading.from_cone(theta, phi, angle)


def _env(w):
    """A smooth, non-constant environment in local directions."""
    return np.stack([1.0 + 2.0 * np.maximum(w[..., 0], 0.0), 1.0 + w[..., 1], 0.5 + w[..., 2] ** 2], axis=-1)


def test_alpha_one_is_scratch_brdf_alpha_zero_is_base(table):
    wo = _wo(np.array([0.3, -0.5, 0.1]), np.array([0.2, -0.6, 1.0]))
    lights = shading.Lights(
        directional=[(np.array([0.3, 0.2, 0.9]) / np.linalg.norm([0.3, 0.2, 0.9]), [2.0, 2.0, 2.0])]
    )
    lights.env = _env
    base = Lambert(albedo=(0.5, 0.5, 0.5))
    layer = shading.env_layer(table, 0.4, wo, _env) + shading.light_layer(
        table, 0.4, wo, np.broadcast_to(lights.directional[0][0], (3, 3)), np.full((3, 3), 2.0), np.radians(2.0)
    )
    one = shading.shade(table, [0.4], [1.0], wo, lights, base=base)
    np.testing.assert_allclose(one, layer, rtol=1e-12)
    zero = shading.shade(table, [0.4], [0.0], wo, lights, base=base)
    wl, E = lights.directional[0]
    np.testing.assert_allclose(zero, base.eval(wo, np.broadcast_to(wl, (3, 3))) * (wl[2] * 2.0), rtol=1e-12)
    assert np.all(one > 0) and not np.allclose(one, zero)


def test_white_furnace(mirror_table):
    """Environment = 1: the layered BRDF reflects at most what it receives, for random α vectors."""
    image = np.ones((16, 32, 3), np.float32)
    dirs, power = environment_grid(image, SimpleNamespace(rotate_y=0.0), (32, 16))
    frame = np.array([[1.0, 0, 0], [0, 0, -1.0], [0, 1.0, 0]])  # rows t, b, n of a plate: world → local
    lights = shading.Lights(env=lambda w: np.ones(w.shape), env_grid=(dirs @ frame.T, power))
    rng = np.random.default_rng(7)
    wo = _wo(rng.uniform(-1.2, 1.2, 40), rng.uniform(-1.3, 1.3, 40))
    base = Lambert(albedo=(0.9, 0.9, 0.9))
    for _ in range(5):
        alpha = rng.uniform(0, 0.7, (40, 4)) * (rng.random((40, 4)) < 0.7)
        L = shading.shade(mirror_table, rng.uniform(-np.pi, np.pi, 4), alpha, wo, lights, base=base)
        assert L.max() <= 1.0 + 1e-3 and L.min() > 0.5
    one = shading.shade(mirror_table, [0.0], [1.0], wo, lights)
    assert np.all(one <= 1.0 + 1e-6) and one.mean() > 0.95  # lossless profile, F = 1: all of it


def test_importance_sampling_is_unbiased(table):
    """The table-CDF estimator (with the Fresnel weight) and uniform cone sampling agree with the quadrature."""
    n = 40000
    wo = _wo(np.full(n, 0.5), np.full(n, -0.3), 0.2)
    rng = np.random.default_rng(11)
    expected = shading.env_layer(table, 0.2, wo[:1], _env)[0]
    for mode in ("estimate", "uniform"):
        est = shading.env_layer(table, 0.2, wo, _env, mode, u=rng.random(n))
        mean, err = est.mean(axis=0), est.std(axis=0) / np.sqrt(n)
        assert np.all(np.abs(mean - expected) < 4.0 * err + 1e-9), (mode, mean, expected, err)
    is_var = shading.env_layer(table, 0.2, wo, _env, "estimate", u=rng.random(n)).var(axis=0)
    uni_var = shading.env_layer(table, 0.2, wo, _env, "uniform", u=rng.random(n)).var(axis=0)
    assert np.all(is_var < uni_var)


def test_layer_sampling_is_unbiased(table):
    """Splitting the environment budget over layers ∝ α_k converges to the sum of the layer integrals."""
    n = 20000
    wo = _wo(np.full(n, 0.3), np.full(n, 0.4))
    alpha = np.array([0.5, 0.3, 0.0, 0.6])
    angles = np.array([0.0, 0.7, 1.0, -1.2])
    lights = shading.Lights(env=_env)
    expected = shading.shade(table, angles, alpha, wo[:1], lights)[0]
    est = shading.shade(table, angles, alpha, wo, lights, mode="estimate", samples=4, rng=np.random.default_rng(5))
    mean, err = est.mean(axis=0), est.std(axis=0) / np.sqrt(n)
    assert np.all(np.abs(mean - expected) < 4.0 * err), (mean, expected, err)


def test_thickened_light_converges_to_the_delta_light(table):
    """∫ L_k dθ_o → ρ_s(φ_o, φ_ℓ) cos φ_ℓ E / cos θ_ℓ (the δ light's answer) as H → 0; culled beyond H."""
    phis = phi_bins(table.size)
    b, j = 20, int(np.argmax(table.rho_m[20]))  # a lit cell; at bin centres the nearest-bin table is constant
    phi_o, phi_l, theta_l = phis[b], phis[j], 0.35
    wl = _wo(theta_l, phi_l)
    E = np.array([1.0, 2.0, 3.0])
    errors = []
    for H in np.radians([2.0, 0.5, 0.125]):
        theta_o = -theta_l + np.linspace(-H, H, 801)
        wo = _wo(theta_o, np.full(theta_o.size, phi_o))
        L = shading.light_layer(table, 0.0, wo, np.broadcast_to(wl, wo.shape), np.broadcast_to(E, wo.shape), H)
        integral = np.trapezoid(L, theta_o, axis=0)
        limit = shading.rho_s_cells(table, -theta_l, b, j) * np.cos(phi_l) * E / np.cos(theta_l)
        errors.append(np.max(np.abs(integral / limit - 1.0)))
        beyond = _wo(np.array([-theta_l + 1.01 * H]), np.array([phi_o]))
        outside = shading.light_layer(table, 0.0, beyond, wl[None], E[None], H)
        assert np.all(outside == 0.0)
    assert errors[-1] < 0.01 and errors[0] > errors[1] > errors[2], errors
