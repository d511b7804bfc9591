"""`analytic`: exact Lambert polygon irradiance with horizon clipping."""

from __future__ import annotations

import copy

import numpy as np

import reflets
from reflets.reference.geometry import MESHES, SceneGeometry
from reflets.scene.camera import pixel_rays
from reflets.validation import polygon_irradiance

SCENE = {
    "camera": {"position": [0, 3, 4], "look_at": [0, 0, 0], "fov_y": 45, "size": [160, 120]},
    "materials": {"floor": {"type": "lambert", "albedo": [0.8, 0.6, 0.4]}},
    "mesh": [{"shape": "plane", "size": [4, 4], "material": "floor"}],
    "light": [{"type": "quad", "corners": [[-0.5, 1, -0.5], [0.5, 1, -0.5], [-0.5, 1, 0.5]], "radiance": [5, 5, 5]}],
}


def plane_hits(scene):
    """World points of pixels whose camera ray hits the plane first (not an emitter)."""
    origin, dirs = pixel_rays(scene.camera)
    hits = SceneGeometry(scene).intersect(np.broadcast_to(origin, dirs.shape).reshape(-1, 3), dirs.reshape(-1, 3))
    on_plane = (hits.kind == MESHES).reshape(dirs.shape[:2])
    points = origin + hits.t.reshape(dirs.shape[:2])[..., None] * dirs
    return on_plane, points


def test_analytic_matches_the_exact_polygon_formula_to_1e_3():
    scene = reflets.load_dict(SCENE)
    image = reflets.render(scene, method="analytic")
    on_plane, points = plane_hits(scene)
    e = polygon_irradiance(points[on_plane], np.tile([0.0, 1.0, 0.0], (on_plane.sum(), 1)), scene.light[0].polygon())
    exact = np.array([0.8, 0.6, 0.4]) / np.pi * 5 * e[:, None]
    rel = np.abs(image[on_plane] - exact) / exact
    assert on_plane.sum() > 8000
    assert rel.max() < 1e-3, rel.max()


def test_horizon_clipping_agrees_with_the_unoccluded_reference():
    """A two-sided light crossing the plane: half of it is below every point's horizon."""
    scene_dict = copy.deepcopy(SCENE)
    scene_dict["camera"]["size"] = [80, 60]
    scene_dict["light"] = [
        {
            "type": "quad",
            "corners": [[-0.5, -0.3, 0.2], [0.5, -0.3, 0.2], [-0.5, 0.7, 0.2]],
            "radiance": [3, 3, 3],
            "two_sided": True,
        }
    ]
    scene = reflets.load_dict(scene_dict)
    image = reflets.render(scene, method="analytic")
    ref = reflets.reference(scene, spp=128, visibility=False, progress=False)
    on_plane, _ = plane_hits(scene)
    keep = on_plane & (ref.stderr[..., 0] > 0)
    z = ((image - ref.image)[keep] / ref.stderr[keep]).ravel()
    assert keep.sum() > 1000
    assert abs(z.mean()) < 0.15 and np.abs(z).mean() < 1.0


def test_one_sided_light_seen_from_behind_gives_nothing():
    scene_dict = copy.deepcopy(SCENE)
    c = scene_dict["light"][0]["corners"]
    scene_dict["light"][0]["corners"] = [c[0], c[2], c[1]]  # swapped: emits upwards
    scene = reflets.load_dict(scene_dict)
    image = reflets.render(scene, method="analytic")
    on_plane, _ = plane_hits(scene)
    assert np.all(image[on_plane] == 0)
    assert np.allclose(image[~on_plane & np.any(image > 0, axis=-1)], 5.0)  # the emitter itself, facing the camera
