"""``auto``: every material type under every light type in one frame; composed frames equal their parts."""

from __future__ import annotations

import numpy as np
import pytest

import reflets
from reflets.diagnostics import RefletsWarning
from reflets.metrics import compare

from .scenes import LIGHTS, MATERIALS, lambert_merl, sphere_scene

SIZE = (48, 36)


@pytest.fixture(scope="module")
def merl(tmp_path_factory):
    return lambert_merl(tmp_path_factory.mktemp("merl") / "lambert.binary")


@pytest.mark.parametrize("light", list(LIGHTS))
@pytest.mark.parametrize("material", [*MATERIALS, "measured"])
def test_every_material_under_every_light(ctx, material, light, merl):
    image = reflets.render(sphere_scene(material, light, size=SIZE, merl=merl))
    assert np.all(np.isfinite(image))
    sphere = image[12:24, 18:30]  # the sphere's middle, lit by every light of these scenes
    assert sphere.mean() > 1e-3, f"{material} under {light} renders black"


def region_relmse(a: np.ndarray, b: np.ndarray, mask: np.ndarray) -> float:
    return compare(a[mask][None], b[mask][None])["relmse"]


def test_each_object_of_a_composed_frame_equals_its_own_technique(ctx):
    """Translucent, scratched and GGX spheres side by side, apart (none shadows or reflects into another):
    each one's pixels in the auto frame equal the single-technique render of a scene with it alone."""
    size = (96, 40)
    materials = {k: MATERIALS[k] for k in ("translucent", "scratched", "microfacet")}
    meshes = [
        {
            "shape": "sphere",
            "radius": 0.6,
            "segments": [48, 24],
            "material": name,
            "transform": {"translate": [x, 0, 0]},
        }
        for name, x in zip(materials, (-1.5, 0.0, 1.5), strict=True)
    ]
    light = {"type": "point", "position": [0.0, 3.0, 3.0], "intensity": [15, 15, 15]}
    base = {"camera": {"position": [0, 0.3, 4.5], "look_at": [0, 0, 0], "fov_y": 35, "size": list(size)}}
    full = reflets.load_dict({**base, "materials": materials, "mesh": meshes, "light": [light]})
    composed = reflets.render(full, spp=8)
    methods = {"translucent": "translucent", "scratched": "scratches", "microfacet": "forward"}
    for mesh in meshes:
        alone = reflets.load_dict({**base, "materials": materials, "mesh": [mesh], "light": [light]})
        own = reflets.render(alone, method=methods[mesh["material"]], spp=8 if mesh["material"] == "scratched" else 1)
        mask = np.any(reflets.render(alone, method="position") != 0, axis=-1)
        assert region_relmse(composed, own, mask) < 1e-3, mesh["material"]


def test_the_pass_plan_follows_each_materials_techniques():
    """Materials say which technique takes each light type (Material.techniques); the plan follows: the showcase
    draws the marble by one translucent pass per point light plus its other lights added through the area
    method, the plate by scratches, the BRDF meshes with the emitters, the mirror last."""
    from reflets.demo import scene_path
    from reflets.renderer.compose import pass_plan

    scene = reflets.load_scene(scene_path("60_showcase.toml"))
    assert scene.materials["marble"].techniques(scene.mesh[2]) == {"point": "translucent", "directional": "translucent"}
    assert scene.materials["chrome"].techniques(scene.mesh[4].model_copy(update={"reflector": False})) == {}
    plan = [
        (m, [light.type for light in s.light], sorted(meshes), add) for m, s, meshes, add in pass_plan(scene, "ltc")
    ]
    assert plan == [
        ("translucent", ["point"], [2], False),
        ("ltc", ["quad", "environment"], [2], True),
        ("scratches", ["quad", "point", "environment"], [3], False),
        ("ltc", ["quad", "point", "environment"], [0, 1], False),
        ("fermat", ["quad", "point", "environment"], [4], False),
    ]
    # a translucent mesh without any light still gets drawn (black, occluding what is behind it)
    bare = scene.model_copy(update={"light": [], "mesh": scene.mesh[2:3]})
    assert [(m, sorted(meshes), add) for m, _, meshes, add in pass_plan(bare, "forward")] == [
        ("forward", [0], False),
        ("forward", [], False),
    ]


def test_a_light_facing_away_warns(ctx):
    scene = sphere_scene("lambert", "quad", size=(16, 12))
    c1, c2, c4 = scene["light"][0]["corners"]
    scene["light"][0]["corners"] = [c1, c4, c2]  # emits upwards, away from the sphere
    with pytest.warns(RefletsWarning, match=r"light\[0\] \(quad\) faces away from every mesh"):
        reflets.render(scene)


def test_a_method_that_ignores_a_material_warns(ctx):
    with pytest.warns(RefletsWarning, match=r"materials.m: method 'ltc' renders this translucent material"):
        reflets.render(sphere_scene("translucent", "quad", size=(16, 12)), method="ltc")
    with pytest.warns(RefletsWarning, match=r"method 'analytic' integrates only Lambertian parts"):
        reflets.render(sphere_scene("metal", "quad", size=(16, 12)), method="analytic")


def test_a_scratch_profile_without_a_mirror_peak_under_a_point_light_warns():
    """Dense V-grooves (walls at 45°) seen in the mirror direction of a point light render all black: warned;
    the quartic's flat bottom keeps a mirror peak: no warning."""
    from reflets.diagnostics import scene_warnings
    from reflets.scratches.profiles import parse_profile

    assert parse_profile("vgroove:0.5").flat_fraction() == 0.0
    assert parse_profile("quartic:0.5").flat_fraction() > 1e-3

    def scene(profile, light):
        return reflets.load_dict(
            {
                "camera": {"position": [0, 1.5, 2.5], "look_at": [0, 0, 0], "size": [16, 12]},
                "materials": {"s": {"type": "scratched", "preset": "3.14b", "profile": profile}},
                "mesh": [{"shape": "plane", "size": [2, 2], "material": "s"}],
                "light": [light],
            }
        )

    point = {"type": "point", "position": [0, 1.5, -2.5], "intensity": [5, 5, 5]}
    quad = {"type": "quad", "corners": [[-1, 2, -1], [1, 2, -1], [-1, 2, 1]], "radiance": [1, 1, 1]}
    (message,) = scene_warnings(scene("vgroove:0.5", point), "auto")
    assert message.startswith("materials.s: its scratch profile 'vgroove:0.5' has no flat part")
    assert scene_warnings(scene("quartic:0.5", point), "auto") == []
    assert scene_warnings(scene("vgroove:0.5", quad), "auto") == []


def test_the_cli_warns_in_one_line_and_exits_0(ctx, tmp_path, capsys):

    from reflets.cli import main

    scene = sphere_scene("lambert", "quad", size=(16, 12))
    c1, c2, c4 = scene["light"][0]["corners"]
    scene["light"][0]["corners"] = [c1, c4, c2]
    toml = tmp_path / "away.toml"
    toml.write_text(_toml(scene))
    assert main(["render", str(toml), "-o", str(tmp_path / "x.exr")]) == 0
    err = capsys.readouterr().err.strip().splitlines()
    assert err == [
        "reflets: warning: light[0] (quad) faces away from every mesh and lights nothing "
        "(reverse its corner order or set two_sided = true)"
    ]


def test_info_prints_how_auto_evaluates_each_pair(ctx, capsys):
    import json

    from reflets.cli import main

    assert main(["info", "--json"]) == 0
    rows = json.loads(capsys.readouterr().out)["auto"]
    pairs = {(r["material"], r["light"]) for r in rows}
    assert len(pairs) == 4 * 5 and all(r["evaluation"] for r in rows)


def test_api_spp_is_checked():
    from reflets.errors import ArgumentError

    with pytest.raises(ArgumentError, match="spp"):
        reflets.render(sphere_scene("lambert", "point"), spp=-1)


def _toml(scene: dict) -> str:
    """A scene dict as TOML (inline tables; enough for these scenes)."""

    def value(v):
        if isinstance(v, dict):
            return "{ " + ", ".join(f"{k} = {value(x)}" for k, x in v.items()) + " }"
        if isinstance(v, list | tuple):
            return "[" + ", ".join(value(x) for x in v) + "]"
        if isinstance(v, bool):
            return "true" if v else "false"
        if isinstance(v, str):
            return f'"{v}"'
        return repr(v)

    lines = [f"camera = {value(scene['camera'])}"]
    lines += [f"materials.{name} = {value(spec)}" for name, spec in scene["materials"].items()]
    lines += [f"mesh = {value(scene['mesh'])}", f"light = {value(scene['light'])}"]
    return "\n".join(lines) + "\n"


@pytest.mark.slow
def test_showcase_objects_equal_their_own_technique(ctx):
    """The showcase's bunny (ltc), plate (scratches) and marble (translucent: its point light through the
    light view, the quad light and sky through its far-field BRDF) equal renders of each alone — with the
    lights' shadows off, so that the other objects neither shadow it nor hide the sky from it (the marble's
    light view is its own shadow test: it sees the marble alone in both)."""
    from reflets.bench.renderer import nearest_surface, showcase_scene

    size = (128, 96)
    whole = showcase_scene(size, shadows=False)
    composed = reflets.render(whole, spp=8)
    for name, method, spp in (("bunny", "ltc", 1), ("plate", "scratches", 8), ("marble", "auto", 1)):
        part = showcase_scene(size, meshes={name}, shadows=False)
        mask = nearest_surface(part, whole)
        assert mask.sum() > 50, name
        own = reflets.render(part, method=method, spp=spp)
        assert region_relmse(composed, own, mask) < 1e-3, name
    # the marble's own technique, alone under the point light, is what auto draws for that light
    part = showcase_scene(size, meshes={"marble"}, lights={"point"})
    mask = nearest_surface(part, part)
    assert region_relmse(reflets.render(part), reflets.render(part, method="translucent"), mask) < 1e-6
