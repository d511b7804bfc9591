"""Shadow maps of point and directional lights against the reference that traces shadow rays, in every technique.

Scene: a sphere on a floor, the shadowed light plus a dim fill light without shadows (so that shadowed pixels
are not black and a ratio is defined). Thresholds: the issue's acceptance, on a 160 × 120 image.
"""

from __future__ import annotations

import numpy as np
import pytest

import reflets
from scratches.plates import MATERIAL as SCRATCHED  # tests/scratches

SIZE = (160, 120)
LIGHTS = {
    "point": {"type": "point", "position": [1.0, 2.5, 0.5], "intensity": [8, 8, 8]},
    "grazing point": {"type": "point", "position": [2.2, 0.9, -0.6], "intensity": [8, 8, 8]},
    "directional": {"type": "directional", "direction": [-0.4, -1, -0.3], "irradiance": [2, 2, 2]},
}
FILL = {"type": "directional", "direction": [0.2, -1, 0.4], "irradiance": [0.3, 0.3, 0.3], "shadows": False}


def sphere_on_floor(light: dict, shadows: bool = True, floor: dict | None = None, ball: dict | None = None) -> dict:
    return {
        "camera": {"position": [0, 2.5, 4], "look_at": [0, 0.3, 0], "fov_y": 40, "size": list(SIZE)},
        "materials": {
            "floor": floor or {"type": "lambert", "albedo": [0.7, 0.7, 0.7]},
            "ball": ball or {"type": "microfacet", "alpha": 0.3, "diffuse": [0.4, 0.3, 0.2]},
        },
        "mesh": [
            {"shape": "plane", "size": [6, 6], "material": "floor"},
            {"shape": "sphere", "radius": 0.5, "material": "ball", "transform": {"translate": [0, 0.5, 0]}},
        ],
        "light": [{**light, "shadows": shadows}, FILL],
    }


def relmse(a, b) -> float:
    return float(np.mean((a - b) ** 2) / np.mean(b**2))


@pytest.mark.parametrize("name", LIGHTS)
def test_hard_shadows_match_the_reference_with_visibility(name, ctx):
    """Floor relative MSE ≤ 2 % (no acne on the lit floor, the shadow in place), and inside the hard shadow
    (where the reference loses over half of its light) the mean within 10 % of the reference's."""
    scene = reflets.load_dict(sphere_on_floor(LIGHTS[name]))
    image = reflets.render(scene, method="forward")
    ref = reflets.reference(scene, spp=4, progress=False).image
    unshadowed = reflets.render(reflets.load_dict(sphere_on_floor(LIGHTS[name], shadows=False)), method="forward")
    floor = reflets.render(reflets.load_dict({**sphere_on_floor(LIGHTS[name]), "mesh": [scene.mesh[0]]}))
    on_floor = np.any(floor != 0, axis=-1) & (np.abs(floor - image).sum(-1) < 1e-6)  # floor pixels not hidden
    assert relmse(image[on_floor], ref[on_floor]) < 0.02
    shadow = ref.sum(-1) < 0.5 * unshadowed.sum(-1)
    assert shadow.sum() > 100  # the scene really has a shadow in view
    assert abs(image[shadow].mean() / ref[shadow].mean() - 1) < 0.10
    assert np.all(unshadowed >= image - 1e-5)  # shadows only remove light


def test_a_light_without_shadows_is_unshadowed_in_both_renderers(ctx):
    """``shadows = false``: no shadow map on the GPU, no shadow ray in the reference — the two still agree."""
    scene = reflets.load_dict(sphere_on_floor(LIGHTS["point"], shadows=False))
    image = reflets.render(scene, method="forward")
    ref = reflets.reference(scene, spp=4, progress=False).image
    assert relmse(image, ref) < 1e-3
    shadowed = reflets.render(reflets.load_dict(sphere_on_floor(LIGHTS["point"])), method="forward")
    assert np.sum(np.abs(shadowed - image).sum(-1) > 0.05) > 100


@pytest.mark.parametrize(
    "method, floor",
    [("ltc", None), ("scratches", "scratched"), ("fermat", None), ("auto", "scratched")],
)
def test_every_technique_darkens_the_shadow(method, floor, ctx):
    """The area-light methods, the scratch lobes and Fermat (direct view and reflections) read the same maps:
    with a point light, the floor behind the sphere loses its light in each."""
    ball = {"type": "mirror", "reflectance": [0.9, 0.9, 0.9]} if method in ("fermat", "auto") else None
    data = sphere_on_floor(LIGHTS["point"], floor={**SCRATCHED, "profile": "quartic:0.5"} if floor else None, ball=ball)
    if ball is not None:
        data["mesh"][1]["reflector"] = True
    on, off = (
        reflets.render(reflets.load_dict({**data, "light": [{**data["light"][0], "shadows": s}, FILL]}), method=method)
        for s in (True, False)
    )
    darker = (off - on).sum(-1) > 0.1 * off.sum(-1)
    assert darker.sum() > 100
    assert np.all(on <= off + 1e-4 + 1e-3 * off)  # nowhere brighter (the scratch lobes: the same random streams)
    if method == "fermat":  # the floor's shadow seen in the mirror too
        mirror = reflets.render(reflets.load_dict({**data, "mesh": [data["mesh"][1]]}), method="position")
        assert np.any(darker & np.any(mirror != 0, axis=-1))


AREA_LIGHTS = {
    "quad": {"type": "quad", "corners": [[0.2, 1.5, -0.4], [1.0, 1.5, -0.4], [0.2, 1.5, 0.4]], "radiance": [6, 6, 6]},
    "polygon": {
        "type": "polygon",
        "vertices": [[0.6, 1.5, -0.5], [1.0, 1.5, 0.1], [0.5, 1.5, 0.5], [0.1, 1.5, 0.0]],
        "radiance": [6, 6, 6],
    },
    "two-sided quad": {
        "type": "quad",
        "corners": [[0.2, 1.5, -0.4], [0.2, 1.5, 0.4], [1.0, 1.5, -0.4]],
        "radiance": [6, 6, 6],
        "two_sided": True,
    },
}


@pytest.mark.parametrize("name", AREA_LIGHTS)
def test_soft_shadows_of_area_lights_match_the_reference(name, ctx):
    """The ratio estimator over the emitter's sample views (LTC for the unshadowed part): floor relative MSE
    ≤ 2 % against the reference with visibility, ≤ 5 % over the shadow and its penumbra; the penumbra is real
    (many pixels strictly between lit and umbra)."""
    scene = reflets.load_dict(sphere_on_floor(AREA_LIGHTS[name]))
    image = reflets.render(scene, method="ltc")
    ref = reflets.reference(scene, spp=64, progress=False).image
    unshadowed = reflets.render(reflets.load_dict(sphere_on_floor(AREA_LIGHTS[name], shadows=False)), method="ltc")
    fill = reflets.render(reflets.load_dict({**sphere_on_floor(AREA_LIGHTS[name]), "light": [FILL]}), method="ltc")
    floor = reflets.render(reflets.load_dict({**sphere_on_floor(AREA_LIGHTS[name]), "mesh": [scene.mesh[0]]}))
    on_floor = np.any(floor != 0, axis=-1) & (np.abs(floor - unshadowed).sum(-1) < 1e-6)
    assert relmse(image[on_floor], ref[on_floor]) < 0.02
    shadowed = on_floor & ((unshadowed - ref).sum(-1) > 0.05 * (unshadowed - fill).sum(-1))
    assert relmse(image[shadowed], ref[shadowed]) < 0.05
    visible = ((image - fill) / np.maximum(unshadowed - fill, 1e-6)).mean(-1)  # the light's seen fraction
    assert np.sum(on_floor & (visible > 0.15) & (visible < 0.85)) > 150


def test_an_area_light_without_shadows_is_unshadowed_in_both_renderers(ctx):
    scene = reflets.load_dict(sphere_on_floor(AREA_LIGHTS["quad"], shadows=False))
    image = reflets.render(scene, method="ltc")
    ref = reflets.reference(scene, spp=64, progress=False).image
    assert relmse(image, ref) < 2e-3


def test_pcss_the_compared_design_shadows_too_but_less_accurately(ctx):
    """``soft_shadows = "pcss"`` (one view at the emitter's centre) darkens the same shadow, further from the
    reference than the ratio estimator (benchmarks/results/shadows.md measures both)."""
    scene = reflets.load_dict(sphere_on_floor(AREA_LIGHTS["quad"]))
    ref = reflets.reference(scene, spp=64, progress=False).image
    ratio = reflets.render(scene, method="ltc")
    pcss = reflets.render(scene, method="auto", soft_shadows="pcss")
    unshadowed = reflets.render(reflets.load_dict(sphere_on_floor(AREA_LIGHTS["quad"], shadows=False)), method="ltc")
    floor = reflets.render(reflets.load_dict({**sphere_on_floor(AREA_LIGHTS["quad"]), "mesh": [scene.mesh[0]]}))
    on_floor = np.any(floor != 0, axis=-1) & (np.abs(floor - unshadowed).sum(-1) < 1e-6)
    error = {name: relmse(img[on_floor], ref[on_floor]) for name, img in (("ratio", ratio), ("pcss", pcss))}
    assert error["pcss"] < 0.25 * relmse(unshadowed[on_floor], ref[on_floor])
    assert error["ratio"] < error["pcss"]


def large_floor() -> dict:
    """The sphere on a 400 × 400 floor under the directional light: one map of the whole scene has 0.28-unit
    texels, a quarter of the sphere's radius."""
    data = sphere_on_floor(LIGHTS["directional"])
    data["mesh"][0] = {**data["mesh"][0], "size": [400, 400]}
    return data


def test_cascades_keep_a_small_shadow_on_a_large_floor_in_place(ctx):
    """The camera's cascades: the floor within 2 % of the reference and the shadow's mean within 10 %, as on
    the small floor; one map of the whole scene alone (``shadow_cascades = 1``) smears the shadow (over 10× the
    error)."""
    from reflets.techniques.prepared import PreparedScene

    scene = reflets.load_dict(large_floor())
    prepared = PreparedScene(ctx, scene)
    try:
        assert prepared.shadows.cascade_count(scene.light[0]) >= 2
        assert prepared.shadows.cascade_count(scene.light[1]) == 0  # the fill light casts no shadow
    finally:
        prepared.release()
    image = reflets.render(scene, method="forward")
    ref = reflets.reference(scene, spp=4, progress=False).image
    unshadowed = reflets.render(
        reflets.load_dict({**large_floor(), "light": [{**LIGHTS["directional"], "shadows": False}, FILL]})
    )
    floor = np.any(reflets.render(scene, method="position") != 0, axis=-1)
    assert relmse(image[floor], ref[floor]) < 0.02
    shadow = ref.sum(-1) < 0.5 * unshadowed.sum(-1)
    assert shadow.sum() > 100
    assert abs(image[shadow].mean() / ref[shadow].mean() - 1) < 0.10
    single = reflets.render(scene, method="forward", shadow_cascades=1)
    assert relmse(single[floor], ref[floor]) > 10 * relmse(image[floor], ref[floor])


@pytest.mark.parametrize("method", ["forward", "auto"])
def test_moving_the_camera_refits_the_cascades_without_preparing_again(method, ctx):
    """A persistent renderer's camera move redraws the cascades only, and its frame is the one-shot render of the
    moved camera (bit for bit)."""
    moved = {"position": [1.5, 1.5, 4.0], "look_at": [0.2, 0.4, 0.0]}
    with reflets.Renderer(reflets.load_dict(large_floor()), method=method) as renderer:
        renderer.render()
        renderer.set_camera(**moved)
        image = renderer.render()
        assert renderer.stats["prepares"] == 1
    data = large_floor()
    data["camera"] = {**data["camera"], **moved}
    np.testing.assert_array_equal(image, reflets.render(reflets.load_dict(data), method=method))


def test_cutout_holes_let_light_through_in_the_shadow_maps_and_the_reference(tmp_path, ctx):
    """A glTF alphaMode MASK card (half its texels under the cut-off: stripes) shadows the floor under a
    directional light from outside the camera's view: light comes through its holes on the GPU as in the
    reference — the shadow's mean is about half the unshadowed floor's in both, and the images agree on 8 × 8-pixel
    block means."""
    from PIL import Image

    stripes = np.zeros((64, 64, 4), np.uint8)
    stripes[..., :3] = 200
    stripes[..., 3] = np.where((np.arange(64) // 8) % 2 == 0, 255, 0)[None, :]  # alpha: 8-texel stripes
    Image.fromarray(stripes, "RGBA").save(tmp_path / "stripes.png")
    card = {"type": "gltf", "alpha_mode": "mask", "metallic": 0.0, "roughness": 0.8,
            "base_color_texture": {"texture": str(tmp_path / "stripes.png")}}  # fmt: skip
    light = {"type": "directional", "direction": [-2.0, -1.0, 0.0], "irradiance": [2, 2, 2]}
    data = {  # the camera looks down at the floor; the card hangs outside its view, its shadow inside
        "camera": {"position": [0, 6, 0.01], "look_at": [0, 0, 0], "fov_y": 20, "size": [96, 96]},
        "materials": {"floor": {"type": "lambert", "albedo": [0.7, 0.7, 0.7]}, "card": card},
        "mesh": [{"shape": "plane", "size": [6, 6], "material": "floor"},
                 {"shape": "plane", "size": [1.6, 1.6], "material": "card", "transform": {"translate": [2, 1, 0]}}],
        "light": [light],
    }  # fmt: skip
    scene = reflets.load_dict(data)
    gpu = reflets.render(scene, method="forward")
    ref = reflets.reference(scene, spp=16, progress=False).image
    opaque = reflets.load_dict({**data, "materials": {**data["materials"], "card": {**card, "alpha_mode": "opaque"}}})
    blocked = reflets.render(opaque, method="forward")
    lit = reflets.render(reflets.load_dict({**data, "mesh": data["mesh"][:1]}), method="forward")
    shadow = blocked.sum(-1) < 0.2 * lit.sum(-1)  # where the opaque card's shadow falls
    assert shadow.sum() > 100
    for image in (gpu, ref):
        ratio = image[shadow].mean() / lit[shadow].mean()
        assert 0.35 < ratio < 0.65, ratio  # the holes' share of the light comes through
    blocks = lambda image: image.reshape(12, 8, 12, 8, 3).mean(axis=(1, 3))  # noqa: E731
    assert relmse(blocks(gpu), blocks(ref)) < 0.02  # measured 0.6 % (per pixel 4 %: PCF softens the stripes' edges)
    clear = {"type": "gltf", "alpha_mode": "mask", "base_color": [1, 1, 1, 0.2]}  # untextured, all under the cut-off
    unseen = reflets.render(reflets.load_dict({**data, "materials": {**data["materials"], "card": clear}}),
                            method="forward")  # fmt: skip
    np.testing.assert_allclose(unseen[shadow], lit[shadow], rtol=1e-5)  # casts no shadow at all


def test_spot_cone_falls_off_as_gltf_defines_it_in_both_renderers_and_round_trips(tmp_path, ctx):
    """A point light with a glTF spot cone over a Lambert floor, a ball in its beam: the floor's radiance is the
    isotropic light's × KHR_lights_punctual's t², t = (cos θ − cos θ_o) / (cos θ_i − cos θ_o) clamped to [0, 1]
    (transcribed here); the GPU agrees with the reference (shadow included); export-gltf writes a spot light that
    reads back as the same cone."""
    from reflets.gltf import export_gltf

    spot = {"direction": [0.3, -1.0, 0.1], "inner_deg": 15.0, "outer_deg": 35.0}
    data = {
        "camera": {"position": [0, 4, 0.01], "look_at": [0, 0, 0], "fov_y": 60, "size": [96, 96]},
        "materials": {"floor": {"type": "lambert", "albedo": [0.7, 0.7, 0.7]}},
        "mesh": [{"shape": "plane", "size": [6, 6], "material": "floor"}],
        "light": [{"type": "point", "position": [0, 1.5, 0], "intensity": [5, 5, 5], "spot": spot}],
    }
    coned = reflets.render(reflets.load_dict(data), method="forward")
    isotropic = reflets.render(reflets.load_dict({**data, "light": [{**data["light"][0], "spot": None}]}),
                               method="forward")  # fmt: skip
    floor = reflets.render(reflets.load_dict(data), method="position")
    from_light = floor - np.array([0, 1.5, 0])
    from_light /= np.linalg.norm(from_light, axis=-1, keepdims=True)
    axis = np.array(spot["direction"]) / np.linalg.norm(spot["direction"])
    cos_i, cos_o = np.cos(np.radians(15.0)), np.cos(np.radians(35.0))
    expected = np.clip((from_light @ axis - cos_o) / (cos_i - cos_o), 0, 1) ** 2
    inside = np.any(floor != 0, axis=-1)
    assert np.allclose(coned[inside], isotropic[inside] * expected[inside][:, None], rtol=1e-3, atol=1e-5)
    assert (expected[inside] == 0).sum() > 100 and (expected[inside] == 1).sum() > 100  # both sides of the cone
    ball = {"shape": "sphere", "radius": 0.2, "material": "floor", "transform": {"translate": [0.2, 0.6, 0]}}
    scene = reflets.load_dict({**data, "mesh": [*data["mesh"], ball]})
    gpu = reflets.render(scene, method="forward")
    ref = reflets.reference(scene, spp=4, progress=False).image
    blocks = lambda image: image.reshape(12, 8, 12, 8, 3).mean(axis=(1, 3))  # noqa: E731
    assert relmse(blocks(gpu), blocks(ref)) < 0.02
    path, _ = export_gltf(reflets.load_dict(data), tmp_path / "spot.glb")
    light = next(light for light in reflets.load_scene(path).light if light.type == "point")
    # export-gltf writes candela (W/sr × 683 lm/W), reading divides by 683 (docs/assets.md): the same light back
    assert light.intensity == pytest.approx((5,) * 3)
    assert light.spot is not None
    assert light.spot.inner_deg == pytest.approx(15.0) and light.spot.outer_deg == pytest.approx(35.0)
    assert np.allclose(np.array(light.spot.direction) / np.linalg.norm(light.spot.direction), axis, atol=1e-6)
