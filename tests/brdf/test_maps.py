"""Texture maps on the BRDF library's colours (reflets/brdf/maps.py): per-point evaluation in NumPy, the GLSL twin
reading the texels before brdf_eval, both renderers against each other, what cannot be mapped refused."""

from __future__ import annotations

import numpy as np
import pytest
from brdf_helpers import upper_hemisphere

import reflets
from reflets.bench import maps
from reflets.bench.assets import block_means as blocks
from reflets.bench.maps import (
    POINT,
    QUAD,
    affine_maps_scene,
    block_error,
    lobe_maps_scene,
    mapped_scene,
    other_lobe_maps_scene,
    reference_image,
    surface_maps_scene,
    unmapped,
    without_maps,
)
from reflets.brdf import MATERIALS
from reflets.brdf.maps import Mapped
from reflets.errors import SceneError
from reflets.metrics import relmse

UV_GRID = str(maps.UV_GRID)
MAPPED = {
    "lambert": {},
    "phong": {"ks": (0.3, 0.2, 0.1), "exponent": 40},
    "blinn_phong": {"ks": (0.3, 0.2, 0.1), "exponent": 40, "normalized": True},
    "microfacet": {"alpha": 0.3, "fresnel": "conductor", "diffuse": (0.2, 0.2, 0.2)},
    "ward": {"alpha": 0.2},
    "lafortune": {},
    "mirror": {"diffuse": (0.05, 0.05, 0.05), "reflectance": (0.1, 0.1, 0.1)},
}


#: models with colours they are affine in (a Schlick F₀, Ashikhmin-Shirley's rs and rd)
AFFINE = {"microfacet": {"alpha": 0.3, "fresnel": "schlick", "diffuse": (0.2, 0.2, 0.2)}, "ashikhmin_shirley": {}}


def mapped_fields():
    linear = [(name, field, MAPPED[name]) for name in MAPPED for field in MATERIALS[name].mappable(MAPPED[name])]
    return linear + [(name, field, AFFINE[name]) for name in AFFINE for field in
                     MATERIALS[name].affine_colours(AFFINE[name])]  # fmt: skip


def test_every_model_with_a_lambertian_or_linear_colour_takes_maps():
    mappable = {name for name, cls in MATERIALS.items() if issubclass(cls, Mapped) and cls.mappable(MAPPED.get(name))}
    assert mappable == set(MAPPED)
    assert MATERIALS["microfacet"].mappable({"fresnel": "schlick"}) == ("diffuse",)  # F0: affine, not linear


@pytest.mark.parametrize(("name", "field", "fields"), mapped_fields())
def test_at_evaluates_each_point_with_its_own_colour(name, field, fields, rng):
    """``at(uv)`` (arrays of colours through the model's own eval) equals the model with each point's colour as a
    constant: every model's eval broadcasts its colours, linear or affine."""
    factor = (0.7, 0.5, 0.9)
    material = MATERIALS[name](**{**fields, field: {"texture": UV_GRID, "factor": factor}})
    n = 64
    uv = rng.random((n, 2))
    wo, wi = upper_hemisphere(rng, n), upper_hemisphere(rng, n)
    colours = np.asarray(factor) * material.texels(field, uv)
    assert np.ptp(colours, axis=0).min() > 0.1  # the texture varies in every channel
    expected = np.array([
        MATERIALS[name](**{**fields, field: tuple(c)}).eval(wo[i : i + 1], wi[i : i + 1])[0]
        for i, c in enumerate(colours)
    ])  # fmt: skip
    np.testing.assert_allclose(material.at(uv).eval(wo, wi), expected, rtol=1e-12, atol=1e-15)
    # sampled as the factors are: a density wherever a point's BRDF is not zero (an unbiased estimator)
    points = material.at(uv)
    assert np.all(points.pdf(wo, wi)[points.eval(wo, wi).max(axis=-1) > 0] > 0)


@pytest.mark.parametrize(("field", "spec"), [("scale", {"factor": (0.7, 0.5, 0.9)}), ("exponent", {"factor": 60})])
def test_lafortune_lobes_take_maps_one_by_one(field, spec, rng):
    """A Lafortune lobe's scale or exponent from a map (written inside the lobe, kept as ``maps.lobe1_<field>``):
    ``at(uv)`` equals the model with each point's lobe as a constant, sampled where any point's BRDF is not zero; a
    dump reads back the same material."""
    lobes = [{"c": (-1.0, -1.0, 1.0), "exponent": 30}, {"c": (-0.5, -0.5, 0.8), "exponent": 5, "scale": (0.4,) * 3}]
    lobes[1][field] = {"texture": UV_GRID, **spec}
    material = MATERIALS["lafortune"](kd=(0.1, 0.1, 0.1), lobes=lobes)
    assert list(material.maps) == [f"lobe1_{field}"] and material.lobes[1].model_dump()[field] == spec["factor"]
    assert type(material).model_validate(material.model_dump()) == material
    n = 64
    uv = rng.random((n, 2))
    wo, wi = upper_hemisphere(rng, n), upper_hemisphere(rng, n)
    texels = material.texels(f"lobe1_{field}", uv)
    values = np.asarray(spec["factor"]) * (texels if field == "scale" else texels[:, 0])
    assert np.ptp(values, axis=0).min() > 0.1
    expected = []
    for i in range(n):
        lobe = {**lobes[1], field: tuple(values[i]) if field == "scale" else float(values[i])}
        constant = MATERIALS["lafortune"](kd=(0.1, 0.1, 0.1), lobes=[lobes[0], lobe])
        expected.append(constant.eval(wo[i : i + 1], wi[i : i + 1])[0])
    points = material.at(uv)
    np.testing.assert_allclose(points.eval(wo, wi), np.array(expected), rtol=1e-12, atol=1e-15)
    assert np.all(points.pdf(wo, wi)[points.eval(wo, wi).max(axis=-1) > 0] > 0)
    nodes, zeros = material.lobe_nodes(), material.affine_zeros()
    assert (nodes is None, zeros is None) == ((False, True) if field == "exponent" else (True, False))
    if zeros:
        assert zeros[0].lobes[1].scale == (0.0, 0.0, 0.0) and zeros[0].lobes[0] == material.lobes[0]


def test_a_mapped_material_round_trips_through_its_dump():
    material = MATERIALS["phong"](kd={"texture": UV_GRID, "factor": [0.5, 0.5, 0.5], "transform": {"scale": [2, 2]}})
    assert material.kd == (0.5, 0.5, 0.5) and material.maps["kd"].transform.scale == (2.0, 2.0)
    assert material.textured and not material.tabulated
    assert MATERIALS["phong"].model_validate(material.model_dump()) == material
    assert MATERIALS["lambert"](albedo={"texture": UV_GRID}).albedo == (1.0, 1.0, 1.0)  # factor 1: the texture


@pytest.mark.parametrize(
    ("material", "says"),
    [
        ({"type": "lafortune", "lobes": {"texture": UV_GRID}}, "materials.m: lobes cannot be a texture"),
        ({"type": "ashikhmin_shirley", "nu": {"texture": UV_GRID}, "nv": {"texture": UV_GRID, "uv": 1}},
         "nu and nv read different textures"),
        ({"type": "mirror", "normal_map": {"texture": UV_GRID}}, "a mirror takes no normal_map"),
        ({"type": "lambert", "normal_map": {"texture": UV_GRID, "scale": float("nan")}}, "normal_map.scale"),
        ({"type": "lambert", "occlusion": {"texture": UV_GRID, "strength": 2}}, "occlusion.strength"),
        ({"type": "lambert", "emission": [-1, 0, 0]}, "materials.m.emission"),
        ({"type": "mirror", "fresnel": "conductor", "reflectance": {"texture": UV_GRID}},
         "reflectance cannot be a texture"),
        ({"type": "lafortune", "lobes": [{"c": {"texture": UV_GRID}}]}, "lobes[0].c cannot be a texture"),
        ({"type": "lafortune", "lobes": [{}, {}], "maps": {"lobe2_scale": {"texture": UV_GRID}}},
         "lobe2_scale cannot be a texture"),
        ({"type": "lafortune", "lobes": [{"scale": {"texture": UV_GRID}}, {"scale": {"texture": UV_GRID, "uv": 1}}]},
         "the lobes' mapped scales read different textures"),
        ({"type": "ashikhmin_shirley", "rs": {"texture": UV_GRID}, "rd": {"texture": UV_GRID},
          "nu": {"texture": UV_GRID}}, "rs, rd and nu cannot all be textures"),
        ({"type": "lambert", "albedo": {"texture": "missing.png"}}, "materials.m.maps.albedo: texture not found"),
        ({"type": "lambert", "albedo": {"texture": UV_GRID, "factor": [2, 0, 0]}}, "materials.m.albedo"),
        ({"type": "lambert", "albedo": {"texture": UV_GRID, "uv": 3}}, "uv"),
        ({"type": "phong", "kd": {"texture": UV_GRID, "factor": []}}, "materials.m.kd.factor: wrong length: got 0"),
        ({"type": "lambert", "albedo": {"texture": "."}}, "materials.m.maps.albedo: texture is a directory"),
    ],
)
def test_what_cannot_be_mapped_is_refused_in_one_line(material, says, tmp_path):
    with pytest.raises(SceneError) as caught:
        reflets.load_dict({"camera": {"position": [0, 0, 3], "look_at": [0, 0, 0]}, "materials": {"m": material},
                           "mesh": [{"shape": "sphere", "material": "m"}]}, base_dir=tmp_path)  # fmt: skip
    assert says in str(caught.value) and "\n" not in str(caught.value)


def test_mapped_colours_under_a_point_and_a_quad_light_as_the_reference():
    """Forward (the quad light's midpoint samples) with the texels read before brdf_eval, against the reference's
    per-hit colours; shadows on."""
    scene = mapped_scene([POINT, QUAD])
    ref = reference_image(scene)
    assert block_error(scene, ref) < 1.5e-3  # measured 2.9e-4 (the reference's 32 spp of noise)
    assert block_error(unmapped(scene), ref) > 1.0  # the maps matter: 24


def test_mapped_colours_under_the_environment_add_no_error_to_the_split_sums(ctx):
    """The prefiltered environment scales the factors' albedos by the texels (exact for linear colours): the
    mapped scene is as far from its reference as the unmapped one from its own."""
    from reflets.scene.assets import default_environment

    scene = mapped_scene([{"type": "environment", "file": str(default_environment())}])
    assert block_error(scene) < min(1.2 * block_error(unmapped(scene)), 0.03)  # measured 7.5e-3, 1.3e-2 unmapped


def test_mapped_colours_are_exported_in_their_gltf_slots(tmp_path):
    """export-gltf: the colour that becomes the base colour carries its texture there (the Lambert floor: factor ×
    texture, as glTF reads it), the Phong ball's diffuse map too; read back, the same texels."""
    from reflets.gltf import export_gltf

    scene = mapped_scene([POINT])
    path, notes = export_gltf(scene, tmp_path / "mapped.glb")
    back = reflets.load_scene(path)
    floors = [m for m in back.materials.values() if m.base_color_texture is not None]
    assert len(floors) == 3  # the floor's and the ball's diffuse maps, the conductor's tint
    original = scene.materials["floor"].texture_data("albedo")
    assert any(np.array_equal(m.texture_data("base_color_texture").codes, original.codes) for m in floors)
    floor = next(m for m in floors if m.base_color_texture.transform is not None)
    assert floor.base_color[:3] == pytest.approx((0.9, 0.9, 0.9)) and floor.base_color_texture.transform.scale == (3, 3)


def test_a_map_on_the_second_uv_set_exports_that_set_and_a_translucent_albedo_map_is_noted(tmp_path):
    """A mapped colour reading uv set 1 of a sphere (one set: it reads the first) gets TEXCOORD_1 in the file, as a
    glTF texture on set 1 does; a translucent albedo map has no glTF slot: said, not dropped silently."""
    import pygltflib

    from reflets.gltf import export_gltf

    scene = reflets.load_dict({
        "camera": {"position": [0, 1, 3], "look_at": [0, 0, 0], "size": [32, 24]},
        "materials": {"m": {"type": "lambert", "albedo": {"texture": UV_GRID, "uv": 1}},
                      "t": {"type": "translucent", "preset": "marble", "albedo_texture": {"texture": UV_GRID}}},
        "mesh": [{"shape": "sphere", "radius": 0.5, "material": "m"},
                 {"shape": "sphere", "radius": 0.5, "material": "t", "transform": {"translate": [1, 0, 0]}}],
        "light": [POINT],
    })  # fmt: skip
    path, notes = export_gltf(scene, tmp_path / "out.glb")
    document = pygltflib.GLTF2.load(str(path))
    assert document.materials[0].pbrMetallicRoughness.baseColorTexture.texCoord == 1
    assert document.meshes[0].primitives[0].attributes.TEXCOORD_1 is not None
    assert "t.albedo_texture: its texture has no glTF slot in this export (not written)" in notes


# ----------------------------------------------------------------------------- normal map, emission, occlusion


def test_normal_maps_and_emission_under_a_point_and_a_quad_light_as_the_reference(tmp_path):
    """A bumpy Lambert floor and Phong ball (the frame turned by the map in both renderers) and a ball whose emission
    is the uv grid, against the reference (shadows on); the same without the normal maps is far from it."""
    scene = surface_maps_scene(tmp_path, [POINT, QUAD])
    ref = reference_image(scene)
    assert block_error(scene, ref) < 5e-3  # measured 1.1e-3
    assert block_error(surface_maps_scene(tmp_path, [POINT, QUAD], maps=False), ref) > 0.03  # normal maps: 0.086
    lamp = scene.model_copy(update={"light": [], "mesh": scene.mesh[2:]})  # the emission alone, in both renderers
    image, ref = reflets.render(lamp, spp=16), reflets.reference(lamp, spp=16, pixel="box", progress=False).image
    assert image.max() > 0.5 and relmse(blocks(image), blocks(ref)) < 2e-3  # measured 3.3e-4


def test_occlusion_darkens_the_environment_light_alone(tmp_path):
    """1 + strength (R − 1) × the environment's light (glTF's rule), a point light's untouched."""
    from PIL import Image

    from reflets.scene.assets import default_environment

    Image.fromarray(np.full((8, 8, 3), 128, np.uint8)).save(tmp_path / "ao.png")
    scene = mapped_scene([{"type": "environment", "file": str(default_environment())}], size=(32, 24))
    floor = scene.materials["floor"]
    occluded = type(floor).model_validate({**floor.model_dump(), "occlusion": {"texture": tmp_path / "ao.png",
                                                                                "strength": 0.5}})  # fmt: skip
    darker = scene.model_copy(update={"materials": {**scene.materials, "floor": occluded}})
    plain, dark = reflets.render(scene, spp=1), reflets.render(darker, spp=1)
    floor_pixels = plain[-6:].reshape(-1, 3)  # the bottom rows see the floor alone
    np.testing.assert_allclose(dark[-6:].reshape(-1, 3), floor_pixels * (1 + 0.5 * (128 / 255 - 1)), rtol=2e-3)
    lit = mapped_scene([POINT], size=(32, 24))
    lit_darker = lit.model_copy(update={"materials": {**lit.materials, "floor": occluded}})
    np.testing.assert_array_equal(reflets.render(lit_darker, spp=1), reflets.render(lit, spp=1))


def test_surface_maps_round_trip_through_the_dump_and_the_gltf_export(tmp_path):
    """normal_map / occlusion keep their scale and strength in a dump; export-gltf writes them, the emission and its
    map in glTF's slots (a factor over 1 through KHR_materials_emissive_strength): read back as glTF's material."""
    from reflets.gltf import export_gltf

    scene = surface_maps_scene(tmp_path, [POINT])
    ball = scene.materials["ball"]
    assert ball.normal_map.scale == 0.8 and not ball.textured and ball.tabulated  # the frame only: LTC still fits
    assert type(ball).model_validate(ball.model_dump()) == ball
    assert scene.materials["lamp"].constant_dump() == {"type": "lambert", "albedo": [0.2, 0.2, 0.2]}
    path, _ = export_gltf(scene, tmp_path / "maps.glb")
    back = {name.split("/")[-1]: m for name, m in reflets.load_scene(path).materials.items()}  # "m/ball"
    assert back["ball"].normal_scale == pytest.approx(0.8) and back["ball"].normal_texture is not None
    assert back["lamp"].emissive_strength == pytest.approx(2.0) and back["lamp"].emissive_texture is not None
    bumps = scene.materials["floor"].texture_data("normal_map").codes
    assert np.array_equal(back["floor"].texture_data("normal_texture").codes, bumps)


# ----------------------------------------------------------------------------- lobe shapes


@pytest.mark.parametrize(
    ("name", "field", "fields"),
    [("microfacet", "alpha", {"alpha": {"texture": UV_GRID, "factor": 0.6}, "fresnel": "conductor"}),
     ("microfacet", "alpha", {"alpha": {"texture": UV_GRID, "factor": [0.6, 0.2]}, "diffuse": (0.1, 0.1, 0.1)}),
     ("phong", "exponent", {"exponent": {"texture": UV_GRID, "factor": 80}, "kd": (0.2, 0.2, 0.2),
                            "normalized": True}),
     ("blinn_phong", "exponent", {"exponent": {"texture": UV_GRID, "factor": 80}, "normalized": True}),
     ("ward", "alpha", {"alpha": {"texture": UV_GRID, "factor": [0.4, 0.1]}, "kd": (0.2, 0.2, 0.2)}),
     ("ashikhmin_shirley", "nu", {"nu": {"texture": UV_GRID, "factor": 300}, "nv": 20})],
)
def test_at_evaluates_each_point_with_its_own_lobe(name, field, fields, rng):
    """A mapped roughness or exponent: ``at(uv)`` equals the model at each point's factor × R (at least the field's
    lowest value), and the sampling density — the texture's widest lobe — covers every point's BRDF."""
    material = MATERIALS[name](**fields)
    n = 64
    uv = rng.random((n, 2))
    wo, wi = upper_hemisphere(rng, n), upper_hemisphere(rng, n)
    values = material.lobe_values(field, material.texels(field, uv)[:, 0])
    constant = {k: v for k, v in fields.items() if k != field}
    expected = np.array([
        MATERIALS[name](**constant, **{field: tuple(float(v[i]) for v in values) if isinstance(values, tuple)
                                       else float(np.ravel(values)[i])}).eval(wo[i : i + 1], wi[i : i + 1])[0]
        for i in range(n)
    ])  # fmt: skip
    points = material.at(uv)
    np.testing.assert_allclose(points.eval(wo, wi), expected, rtol=1e-12, atol=1e-15)
    assert np.all(points.pdf(wo, wi)[points.eval(wo, wi).max(axis=-1) > 0] > 0)
    assert len(material.lobe_nodes()) == 8 and not material.tabulated


def test_mapped_lobe_shapes_under_lights_and_the_environment_as_the_reference(tmp_path):
    """A roughness-mapped conductor, an exponent-mapped Phong ball and a ball with both a mapped roughness and a
    mapped Schlick F₀: under a point + a quad light as the reference; under the studio map (the split sum's albedo
    curves at eight texel values, interpolated per fragment, and mixed with the same at F₀ = 0) no further from it than
    the same scene with the factors alone from its own reference, and far closer than with the F₀ map left out."""
    from reflets.scene.assets import default_environment

    ref = reference_image(lobe_maps_scene(tmp_path, [POINT, QUAD]))
    assert block_error(lobe_maps_scene(tmp_path, [POINT, QUAD]), ref) < 5e-4  # measured 1.8e-4
    assert block_error(lobe_maps_scene(tmp_path, [POINT, QUAD], maps=False), ref) > 0.03  # the maps matter: 0.14
    studio = [{"type": "environment", "file": str(default_environment())}]
    scene = lobe_maps_scene(tmp_path, studio)
    ref = reference_image(scene)
    mapped = block_error(scene, ref)
    assert mapped < min(1.3 * block_error(lobe_maps_scene(tmp_path, studio, maps=False)), 0.03)
    # measured 1.58e-2 mapped, 1.66e-2 with the factors
    front = scene.materials["front"]
    no_f0 = front.model_copy(update={"maps": {"alpha": front.maps["alpha"]}})
    assert block_error(scene.model_copy(update={"materials": {**scene.materials, "front": no_f0}}), ref) > 3 * mapped
    # measured 8.9e-2 with the F₀ map left out


def test_the_other_mapped_lobe_shapes_recompute_what_their_twins_derive(tmp_path):
    """Blinn-Phong's exponent (its normalisation), Ward's α (1/α and 1/(π α_x α_y)), Ashikhmin-Shirley's exponents
    (their normalisation) and a Lafortune material's lobe exponents (array elements of its twin's uniforms), each
    recomputed per fragment from the mapped value: as the reference."""
    scene = other_lobe_maps_scene(tmp_path, [POINT, QUAD])
    ref = reference_image(scene)
    error = block_error(scene, ref)
    assert error < 5e-4  # measured 1.7e-4
    assert block_error(without_maps(scene), ref) > 2 * error  # Lafortune's exponent maps left out: 6.0e-4


def test_mapped_affine_colours_under_lights_and_the_environment_as_the_reference():
    """A Schlick F₀, Ashikhmin-Shirley's rs and rd and a Lafortune lobe's scale from maps: under a point + a quad
    light as the reference; under the studio map (the albedo interpolated per channel between the curves at 0 and at
    the factors: exact for an affine colour, bilinear for two) no further from it than the factors alone from their
    own reference."""
    from reflets.scene.assets import default_environment

    scene = affine_maps_scene([POINT, QUAD])
    ref = reference_image(scene)  # (computed once, for every comparison)
    error = block_error(scene, ref)
    assert error < 5e-4  # measured 9.9e-5
    assert block_error(affine_maps_scene([POINT, QUAD], maps=False), ref) > 0.5  # the maps matter: 1.7
    assert block_error(without_maps(scene), ref) > 2 * error  # Lafortune's lobe scale map left out: 5.0e-4
    studio = [{"type": "environment", "file": str(default_environment())}]
    assert block_error(affine_maps_scene(studio)) < min(1.2 * block_error(affine_maps_scene(studio, maps=False)), 0.04)
    # measured 2.9e-2 mapped, 4.3e-2 with the factors


def test_affine_colour_maps_are_exported_where_glTF_has_a_slot(tmp_path):
    """Ashikhmin-Shirley's rs becomes KHR_materials_specular's tint (its factor and texture), a Schlick F₀ the same;
    rd has no slot: said, not written."""
    import pygltflib

    from reflets.gltf import export_gltf

    path, notes = export_gltf(affine_maps_scene([POINT], size=(32, 24)), tmp_path / "affine.glb")
    materials = {m.name: m for m in pygltflib.GLTF2.load(str(path)).materials}
    for name in ("metal", "ball"):
        assert "specularColorTexture" in materials[name].extensions["KHR_materials_specular"]
    assert "metal.maps.rd: its texture has no glTF slot in this export (not written)" in notes
