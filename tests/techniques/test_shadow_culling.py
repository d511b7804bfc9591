"""Shadow lookups left out of a mesh's draw where no caster can darken it — the environment's occlusion
(shadows.py ``environment_occludes``) or every lookup (``shadowed``): the geometry it rests on, where it applies,
and that it changes nothing."""

from __future__ import annotations

import numpy as np
import pytest

import reflets
from reflets.demo import scene_path
from reflets.metrics import relmse
from reflets.scene.geometry import mesh_data, self_shadowing
from reflets.techniques.prepared import PreparedScene
from reflets.techniques.shadows import swept_box_meets

SKY = {"type": "environment", "file": "../environments/sky.hdr"}


def scene_of(meshes: list[dict], position=(0.0, 0.6, 4.0), size=(64, 48), light: dict = SKY) -> reflets.Scene:
    return reflets.load_dict(
        {
            "camera": {"position": list(position), "look_at": [0, 0.5, 0], "fov_y": 40, "size": list(size)},
            "materials": {"m": {"type": "microfacet", "alpha": 0.3, "diffuse": [0.4, 0.4, 0.4]}},
            "mesh": [{**mesh, "material": "m"} for mesh in meshes],
            "light": [light],
        },
        base_dir=scene_path("12_ref_sphere_env.toml").parent,
    )


@pytest.mark.parametrize(
    "shape, expected",
    [({"shape": "sphere"}, "inside"), ({"shape": "cube"}, "inside"), ({"shape": "cylinder"}, "inside"),
     ({"shape": "plane"}, "none"), ({"shape": "torus"}, "any"), ({"shape": "sphere", "segments": [16, 8]}, "inside")],
)  # fmt: skip
def test_a_mesh_that_cannot_hide_itself_is_told_apart(shape, expected):
    """Flat meshes never hide themselves, closed convex ones only from inside their hull (seams' repeated
    vertices and −0 merged), a torus anywhere; half a sphere is open (its inside hides itself), a convex mesh
    wound inwards or with inward normals shows its inside (the shaders turn a back face's normal to the camera)."""
    mesh = mesh_data(scene_of([shape]), 0)
    assert self_shadowing(mesh.positions, mesh.indices, mesh.normals) == expected
    if expected == "inside":
        assert self_shadowing(mesh.positions, mesh.indices[: len(mesh.indices) // 2]) == "any"
        assert self_shadowing(mesh.positions, mesh.indices[:, ::-1]) == "any"
        assert self_shadowing(mesh.positions, mesh.indices, -mesh.normals) == "any"


def test_a_face_doubled_back_to_back_is_no_closed_solid():
    corners = np.array([[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]])
    sides = np.array([[0, 2, 1], [0, 1, 3], [0, 3, 2], [1, 2, 3]])  # a tetrahedron, wound outwards
    assert self_shadowing(corners, sides) == "inside"
    assert self_shadowing(corners, np.concatenate([sides[:1], sides[:1, ::-1], sides[1:]])) == "any"


def test_a_box_swept_along_a_direction_meets_what_lies_ahead():
    box = np.array([[0.0, 0.0, 0.0], [1.0, 1.0, 1.0]])
    ahead = box + [[0.0, 3.0, 0.0]]  # above
    directions = np.array([[0, 1, 0], [0, -1, 0], [1, 0, 0], [0.3, 0.954, 0], [0.6, 0.8, 0], [0.9, 0.3, 0.3]], float)
    np.testing.assert_array_equal(swept_box_meets(box, directions, ahead), [True, False, False, True, False, False])
    np.testing.assert_array_equal(swept_box_meets(box, directions, box + [[0.5, 0.5, 0.5]]), [True] * 6)  # overlap


def occludes(scene, shadowed: bool = False) -> list[bool]:
    """Per mesh: ShadowMaps.environment_occludes (or ``shadowed``)."""
    from reflets.gpu import get_context
    from reflets.scene.map_emitters import with_map_emitters

    prepared = PreparedScene(get_context(), with_map_emitters(scene))
    try:
        test = prepared.shadows.shadowed if shadowed else prepared.shadows.environment_occludes
        return [test(i) for i in range(len(scene.mesh))]
    finally:
        prepared.release()


def draws_occlusion(scene, uniform: str = "u_env_dir") -> bool:
    """Does the forward pass's program for the scene's first mesh look the environment's views up (or, with
    ``uniform = "u_shadow_atlas"``, any shadow map)?"""
    from reflets.gpu import get_context
    from reflets.techniques.forward import Forward

    forward = Forward(get_context())
    forward.prepare(scene)
    try:
        return uniform in forward._shaded[0].program
    finally:
        forward.release()


def test_a_convex_mesh_alone_draws_no_occlusion_and_looks_the_same(ctx, monkeypatch):
    """A sphere alone under the sky: nothing can hide the environment from it, its draw's program leaves the
    occlusion out — the same frame as looking every view up (the test off); set on a floor, both the floor and
    the sphere look their views up; the camera inside a closed box: its walls do too."""
    from reflets.techniques import shadows

    sphere = {"shape": "sphere", "radius": 0.5, "transform": {"translate": [0, 0.5, 0]}}
    alone = scene_of([sphere])
    assert occludes(alone) == [False]
    assert not draws_occlusion(alone)
    culled = reflets.render(alone)
    with monkeypatch.context() as patch:
        patch.setattr(shadows, "CULL_MESHES", 0)
        assert occludes(alone) == [True]
        assert draws_occlusion(alone)
        looked_up = reflets.render(alone)
    assert relmse(culled, looked_up) < 1e-6
    floor = {"shape": "plane", "size": [6, 6]}
    assert occludes(scene_of([floor, sphere])) == [True, True]
    assert occludes(scene_of([floor])) == [False]
    room = {"shape": "cube", "transform": {"scale": 10}}
    assert occludes(scene_of([room], position=(0.0, 0.6, 3.0))) == [True]
    assert occludes(scene_of([room], position=(0.0, 0.6, 30.0))) == [False]


def test_a_camera_entering_a_convex_mesh_prepares_again(ctx):
    """Moving the camera into a closed convex mesh's box turns its occlusion on (the renderer prepares again):
    the frame equals a fresh renderer's there (not preparing again leaves the walls lit from outside)."""
    room = {"shape": "cube", "transform": {"scale": 4}}
    outside = scene_of([room], position=(0.0, 0.6, 9.0))
    renderer = reflets.Renderer(outside)
    try:
        renderer.render()
        renderer.set_camera(position=[0.0, 0.6, 1.5])
        moved = renderer.render()
    finally:
        renderer.release()
    fresh = reflets.render(outside.model_copy(update={"camera": renderer.scene.camera}))
    np.testing.assert_allclose(moved, fresh, rtol=1e-5, atol=1e-6)


@pytest.mark.parametrize("light", [{"type": "point", "position": [1.0, 3.0, 2.0], "intensity": [20, 20, 20]},
                                   {"type": "directional", "direction": [-0.3, -1.0, -0.2], "irradiance": [3, 3, 3]}])
def test_a_lit_convex_mesh_alone_draws_no_shadow_lookup(light, ctx, monkeypatch):
    """A sphere alone under a point or a directional light cannot shadow itself: its draw has no shadow lookup,
    the same frame as with them (the test off); on a floor, both the floor and the sphere look theirs up."""
    from reflets.techniques import shadows

    sphere = {"shape": "sphere", "radius": 0.5, "transform": {"translate": [0, 0.5, 0]}}
    alone = scene_of([sphere], light=light)
    assert not draws_occlusion(alone, "u_shadow_atlas")
    culled = reflets.render(alone)
    with monkeypatch.context() as patch:
        patch.setattr(shadows, "CULL_MESHES", 0)
        assert draws_occlusion(alone, "u_shadow_atlas")
        looked_up = reflets.render(alone)
    assert relmse(culled, looked_up) < 1e-6
    on_floor = scene_of([sphere, {"shape": "plane", "size": [6, 6]}], light=light)
    assert draws_occlusion(on_floor, "u_shadow_atlas")
    assert occludes(on_floor, shadowed=True) == [True, True]


def test_a_see_through_or_normal_mapped_convex_mesh_keeps_its_shadows(ctx, tmp_path):
    """A blended glTF sphere alone shows its inside through its front, which the front can shadow; a normal map
    turns the shading normal past the geometric horizon, where the sphere hides itself: their draws keep their
    lookups."""
    from reflets.bench.maps import write_bumps

    light = {"type": "directional", "direction": [-0.3, -1.0, -0.2], "irradiance": [3, 3, 3]}
    scene = scene_of([{"shape": "sphere", "radius": 0.5}], light=light)
    glass = {"type": "gltf", "base_color": [0.8, 0.8, 0.8, 0.5], "alpha_mode": "blend", "double_sided": True}
    blended = scene.model_copy(update={"materials": {"m": reflets.load_dict(
        {"camera": {"position": [0, 0, 3], "look_at": [0, 0, 0]}, "materials": {"m": glass}}).materials["m"]}})
    assert not draws_occlusion(scene, "u_shadow_atlas")
    assert draws_occlusion(blended, "u_shadow_atlas")
    bumps = str(write_bumps(tmp_path / "bumps.png"))
    bumpy = {"type": "lambert", "albedo": [0.5, 0.5, 0.5], "normal_map": {"texture": bumps}}
    bumped = reflets.load_dict({"camera": {"position": [0, 0, 3], "look_at": [0, 0, 0]}, "materials": {"m": bumpy}})
    assert draws_occlusion(scene.model_copy(update={"materials": bumped.materials}), "u_shadow_atlas")


def test_a_camera_whose_near_plane_cuts_a_convex_mesh_sees_its_inside(ctx):
    """A closed box the eye is outside of but the near plane cuts (the camera's own ``near``), or any convex mesh
    under an orthographic camera: its draw keeps its shadow lookups."""
    room = {"shape": "cube", "transform": {"scale": 2}}
    light = {"type": "directional", "direction": [-0.3, -1.0, -0.2], "irradiance": [3, 3, 3]}
    far = scene_of([room], position=(0.0, 0.6, 9.0), light=light)
    assert occludes(far, shadowed=True) == [False]
    cut = far.model_copy(update={"camera": far.camera.model_copy(update={"near": 8.5})})
    assert occludes(cut, shadowed=True) == [True]
    flat = far.model_copy(update={"camera": far.camera.model_copy(update={"projection": "orthographic",
                                                                          "ortho_height": 4.0})})
    assert occludes(flat, shadowed=True) == [True]
