"""The reference's parametric mirror refinement (Bézier and height-field reflectors): it lands on the exact
surface from the mesh hit's uv, and planar patches reflect exactly like the ``plane`` reflector."""

from __future__ import annotations

import math

import numpy as np
import pytest

import reflets
from reflets.metrics import relmse
from reflets.reference.geometry import MESHES, SceneGeometry
from reflets.reference.mirrors import HIT_TOL, ImplicitReflector, MirrorBounce, ParametricReflector
from reflets.scene.model import Scene

SIZE = (64, 48)
W, D = 3.0, 2.0  # mirror extent along x and z


def scene_with(mirror: dict) -> Scene:
    """A mirror under ``mirror``'s shape with a red sphere and a green box standing on / above it; point lights
    only, so the reference is deterministic at 1 spp."""
    return reflets.load_dict(
        {
            "camera": {"position": [0.3, 2.2, 3.5], "look_at": [0, 0, -0.2], "size": list(SIZE)},
            "materials": {
                "chrome": {"type": "mirror", "reflectance": [0.9, 0.9, 0.9]},
                "red": {"type": "lambert", "albedo": [0.8, 0.1, 0.1]},
                "green": {"type": "lambert", "albedo": [0.1, 0.7, 0.2]},
            },
            "mesh": [
                {**mirror, "material": "chrome", "reflector": True},
                {"shape": "sphere", "radius": 0.45, "material": "red", "transform": {"translate": [-0.4, 0.7, -0.3]}},
                {"shape": "cube", "size": 0.5, "material": "green", "transform": {"translate": [0.8, 0.6, -0.6]}},
            ],
            "light": [
                {"type": "point", "position": [1.0, 3.0, 2.0], "intensity": [8, 8, 8]},
                {"type": "point", "position": [-2.0, 2.0, 0.5], "intensity": [3, 4, 5]},
            ],
            "background": [0.15, 0.2, 0.3],
        }
    )


def render(scene: Scene) -> np.ndarray:
    return reflets.reference(scene, spp=1, size=SIZE, visibility=False, progress=False).image


def flat_net(xs=(-1.0, -0.2, 0.5, 1.0), zs=(1.0, 0.1, -0.4, -1.0)) -> list:
    """Control points on the y = 0 rectangle [−W/2, W/2] × [−D/2, D/2], u along +x, v along −z; uneven spacing
    makes (u, v) ↦ point non-affine while the patch stays the plane."""
    return [[[0.5 * W * x, 0.0, 0.5 * D * z] for z in zs] for x in xs]


TILT = {"rotate": [12.0, 25.0, -8.0], "translate": [0.0, -0.1, 0.0]}


@pytest.fixture(scope="module")
def plane_image() -> np.ndarray:
    return render(scene_with({"shape": "plane", "size": [W, D], "transform": TILT}))


def test_flat_bezier_reflects_like_the_plane_mirror(plane_image):
    image = render(scene_with({"shape": "bezier", "control_points": flat_net(), "transform": TILT}))
    assert relmse(image, plane_image) < 1e-3
    # the mirror shows the reflection (not only the background): the scene without a reflector differs a lot
    without = render(scene_with({"shape": "plane", "size": [W, D], "transform": {"translate": [0, -50, 0]}}))
    assert relmse(without, plane_image) > 100 * max(relmse(image, plane_image), 1e-6)


def test_flat_heightfield_reflects_like_the_plane_mirror(plane_image):
    mesh = {"shape": "heightfield", "heights": np.zeros((4, 5)).tolist(), "size": [W, D], "transform": TILT}
    assert relmse(render(scene_with(mesh)), plane_image) < 1e-3


def test_sloped_heightfield_reflects_like_the_tilted_plane():
    """y = s x is a plane tilted about z: exercises the normal's dependence on the height derivatives."""
    slope = 0.3
    x = np.linspace(-0.5 * W, 0.5 * W, 6)
    heights = np.tile(slope * x, (4, 1))  # rows along z, columns along x; Catmull–Rom reproduces linear data
    field = render(scene_with({"shape": "heightfield", "heights": heights.tolist(), "size": [W, D]}))
    plane = render(
        scene_with(
            {
                "shape": "plane",
                "size": [W * math.hypot(1.0, slope), D],
                "transform": {"rotate": [0.0, 0.0, math.degrees(math.atan(slope))]},
            }
        )
    )
    assert relmse(field, plane) < 1e-3
    flat = render(scene_with({"shape": "plane", "size": [W, D]}))
    assert relmse(flat, plane) > 1e-2  # the tilt is visible


def curved_scene(shape: str) -> Scene:
    rng = np.random.default_rng(3)
    if shape == "bezier":
        net = np.array(flat_net())
        net[..., 1] = 0.4 * rng.standard_normal((4, 4))
        mesh = {"shape": "bezier", "control_points": net.tolist(), "segments": [32, 24]}
    else:
        heights = 0.3 * rng.standard_normal((5, 6))  # bumpy: the sample grid's own mesh would sag far off it
        mesh = {"shape": "heightfield", "heights": heights.tolist(), "size": [W, D], "segments": [50, 40]}
    return scene_with({**mesh, "transform": {"rotate": [10, 30, 5], "scale": [1.1, 0.9, 1.2]}})


@pytest.mark.parametrize("shape", ["bezier", "heightfield"])
def test_refinement_lands_on_the_exact_surface(shape):
    scene = curved_scene(shape)
    geometry = SceneGeometry(scene)
    bounce = MirrorBounce(scene, geometry.face_mesh)
    surface = bounce.surfaces[0]
    assert isinstance(surface, ParametricReflector)
    rng = np.random.default_rng(7)
    faces = np.nonzero(geometry.face_mesh == 0)[0]
    prim = rng.choice(faces, 2000)
    b = rng.dirichlet([1, 1, 1], len(prim))
    target = np.einsum("nk,nkc->nc", b, geometry.vertices[geometry.faces[prim]])
    origin = np.asarray(scene.camera.position, dtype=np.float64)
    d = target - origin
    d /= np.linalg.norm(d, axis=1, keepdims=True)
    hits = geometry.intersect(np.broadcast_to(origin, d.shape), d)
    on = (hits.kind == MESHES) & (geometry.face_mesh[np.maximum(hits.prim, 0)] == 0)
    assert on.sum() > 200  # the others are hidden by the objects or by the patch itself
    d = d[on]
    o = np.broadcast_to(origin, d.shape)
    uv0 = geometry.uv(hits.prim[on], hits.u[on], hits.v[on])
    t, u, v, err = surface.solve(o, d, hits.t[on], uv0)
    f = surface.surface.position(u, v)
    gap = np.linalg.norm(o + t[:, None] * d - f, axis=1)
    np.testing.assert_allclose(err, gap, rtol=1e-12, atol=1e-18)
    ok = gap <= HIT_TOL * (1.0 + np.abs(t))  # refine's criterion
    assert gap[ok].max() < 1e-9
    # the rest graze a bump or pass just outside the patch's curved border: no exact hit near the mesh hit
    assert ok.mean() > 0.99
    start = np.linalg.norm(o + hits.t[on, None] * d - surface.surface.position(uv0[:, 0], uv0[:, 1]), axis=1)
    assert np.median(start) > 1e5 * gap[ok].max()  # the mesh hit was not already there: the refinement moved it
    assert np.abs(np.stack([u, v], 1) - uv0).max() < 0.05  # near its start: the same sheet, not another crossing
    x, n = surface.refine(o, d, hits.t[on], uv0)
    np.testing.assert_allclose(x[ok], f[ok], atol=1e-12)
    np.testing.assert_allclose(x[~ok], o[~ok] + hits.t[on][~ok, None] * d[~ok], atol=1e-12)  # the mesh hit
    np.testing.assert_allclose(np.linalg.norm(n, axis=1), 1.0, atol=1e-12)
    assert np.all(np.sum(n * d, axis=1) < 0)
    cos = np.abs(np.sum(n[ok] * surface.surface.normal(u[ok], v[ok]), axis=1))
    np.testing.assert_allclose(cos, 1.0, atol=1e-12)
    if shape == "heightfield":  # independent: the point satisfies the field's implicit equation y = h(x, z)
        base = surface.surface.base
        assert np.abs(base.implicit(surface.surface._to_canonical(x[ok]))).max() < 1e-9


def test_existing_shapes_keep_the_implicit_refinement():
    scene = scene_with({"shape": "plane", "size": [W, D]})
    bounce = MirrorBounce(scene, SceneGeometry(scene).face_mesh)
    assert isinstance(bounce.surfaces[0], ImplicitReflector)


@pytest.mark.parametrize("shape", ["bezier", "heightfield"])
def test_reflected_rays_leave_their_own_tessellation(shape):
    """On concave parts the exact point lies behind the mesh: leaving from it, over half of these pixels' rays
    hit the reflector's own triangles at about the chord sag; lifted onto the hit triangle, none should."""
    from reflets.reference.mirrors import _above_mesh
    from reflets.reference.montecarlo import MonteCarloReference
    from reflets.scene.camera import camera_rays

    ref = MonteCarloReference(curved_scene(shape), visibility=False)
    rows, cols = np.divmod(np.arange(SIZE[0] * SIZE[1]), SIZE[0])
    origin, dirs = camera_rays(ref.scene.camera, cols + 0.5, rows + 0.5, *SIZE)
    hits = ref.geometry.intersect(np.broadcast_to(origin, dirs.shape), dirs)
    on = np.nonzero((hits.kind == MESHES) & (ref.geometry.face_mesh[np.maximum(hits.prim, 0)] == 0))[0]
    d = dirs[on]
    o = np.broadcast_to(origin, d.shape)
    x, n = ref.mirrors.surfaces[0].refine(o, d, hits.t[on], ref.geometry.uv(hits.prim[on], hits.u[on], hits.v[on]))
    r = d - 2.0 * np.sum(d * n, -1, keepdims=True) * n
    start = _above_mesh(ref.geometry, hits.prim[on], o + hits.t[on, None] * d, x, d)
    assert np.linalg.norm(start - x, axis=1).max() < 1e-2  # at most the sag (+ epsilon)
    again = ref.geometry.intersect(start, r)
    near_self = (again.kind == MESHES) & (ref.geometry.face_mesh[np.maximum(again.prim, 0)] == 0) & (again.t < 1e-2)
    assert near_self.mean() < 0.01
