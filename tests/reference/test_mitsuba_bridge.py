"""The Mitsuba 3 bridge: every convention it relies on, checked against closed forms and our own NumPy camera.

Mitsuba renders with a box pixel filter (radiance averaged over each pixel's square), so the closed forms
here are averaged over a K × K grid of sub-pixel positions before comparing.
"""

from __future__ import annotations

import sys
from pathlib import Path
from types import SimpleNamespace

import numpy as np
import pytest
from scipy.ndimage import binary_dilation, uniform_filter

pytest.importorskip("mitsuba", reason="Mitsuba 3 is not installed (pip install 'reflets[reference]')")

import reflets  # noqa: E402
from reflets.errors import SceneError  # noqa: E402
from reflets.metrics import relmse  # noqa: E402
from reflets.reference.mitsuba_bridge import (  # noqa: E402
    MitsubaUnavailableError,
    environment_for_mitsuba,
    material_to_mitsuba,
    mitsuba_module,
    render_mitsuba,
    to_mitsuba_dict,
)
from reflets.scene import load_dict  # noqa: E402
from reflets.scene.camera import camera_basis, pixel_rays, project  # noqa: E402
from reflets.validation import analytic_image  # noqa: E402

SIZE = (64, 48)
K = 4  # sub-pixel grid for box-filtered closed forms


# ----------------------------------------------------------------------------------------------- helpers


def subpixel_rays(camera, size=SIZE, k=K):
    """Origin and (k*k, H, W, 3) ray directions on a k × k grid inside every pixel."""
    rays = [pixel_rays(camera, size, offsets=((a + 0.5) / k, (b + 0.5) / k)) for b in range(k) for a in range(k)]
    return rays[0][0], np.stack([d for _, d in rays])


def polygon_irradiance(x: np.ndarray, n: np.ndarray, polygon: np.ndarray) -> np.ndarray:
    """Lambert's (1760) exact irradiance per unit radiance from a polygon above the tangent plane of x.

    E/L = −½ Σ Θ_i (Γ_i · n), u_i = normalize(p_i − x), Θ_i = acos(u_i · u_{i+1}), Γ_i = normalize(u_i × u_{i+1}),
    for vertices counter-clockwise seen from x (our emitting-side winding; the minus sign is that winding's:
    Arvo writes the sum for the opposite order). Seen from behind the winding flips and the value is negative.
    """
    u = polygon[None, :, :] - x[:, None, :]
    u /= np.linalg.norm(u, axis=-1, keepdims=True)
    v = np.roll(u, -1, axis=1)
    theta = np.arccos(np.clip(np.sum(u * v, axis=-1), -1.0, 1.0))
    gamma = np.cross(u, v)
    gamma /= np.maximum(np.linalg.norm(gamma, axis=-1, keepdims=True), 1e-300)
    return -0.5 * np.sum(theta * np.sum(gamma * n[:, None, :], axis=-1), axis=1)


def plane_area_light_exact(scene, polygons, radiance, albedo, two_sided, half):
    """Box-filtered radiance (H, W, 3) of the Lambert plane y = 0 (|x|, |z| < half) lit by polygon lights, and
    the mask of pixels whose every sub-pixel ray hits the plane well inside its border and no light first."""
    origin, dirs = subpixel_rays(scene.camera)
    t = -origin[1] / np.where(dirs[..., 1] < 0, dirs[..., 1], np.nan)
    hit = origin + t[..., None] * dirs
    ok = np.isfinite(t) & (np.abs(hit[..., 0]) < half - 0.05) & (np.abs(hit[..., 2]) < half - 0.05)
    pts = hit.reshape(-1, 3)
    normal = np.broadcast_to([0.0, 1.0, 0.0], pts.shape)
    e = np.zeros(len(pts))
    seen = np.zeros(dirs.shape[1:3], dtype=bool)
    for poly in polygons:
        seen |= _hits_polygon(origin, dirs, poly, t).any(axis=0)
        value = polygon_irradiance(np.nan_to_num(pts), normal, poly)
        e += np.abs(value) if two_sided else np.maximum(value, 0.0)
    radiance_img = (np.asarray(albedo) / np.pi * np.asarray(radiance))[None, :] * e[:, None]
    radiance_img = radiance_img.reshape(dirs.shape[:-1] + (3,)).mean(axis=0)
    # a pixel next to one that sees a light may see a sliver of it that no sub-pixel ray found
    return radiance_img, ok.all(axis=0) & ~binary_dilation(seen, iterations=2)


def _hits_polygon(origin, dirs, poly, t_max):
    """Rays (…, 3) from origin crossing the convex polygon (grown by 3 %) before t_max."""
    c = poly.mean(axis=0)
    n = np.cross(poly[1] - poly[0], poly[2] - poly[0])
    n /= np.linalg.norm(n)
    denom = dirs @ n
    with np.errstate(divide="ignore", invalid="ignore"):
        t = ((c - origin) @ n) / denom
    p = origin + t[..., None] * dirs
    inside = np.ones(t.shape, dtype=bool)
    grown = c + 1.03 * (poly - c)
    for a, b in zip(grown, np.roll(grown, -1, axis=0), strict=True):
        inside &= (np.cross(b - a, p - a) @ n) >= 0
    return inside & (t > 0) & (t < np.nan_to_num(t_max, nan=np.inf))


def env_lookup(image: np.ndarray, dirs: np.ndarray, rotate_y: float) -> np.ndarray:
    """Bilinear lookup between texel centres, u wrapping, v clamped, of world directions (Mitsuba's layout)."""
    a = np.radians(rotate_y)
    rot = np.array([[np.cos(a), 0.0, np.sin(a)], [0.0, 1.0, 0.0], [-np.sin(a), 0.0, np.cos(a)]])
    d = dirs @ rot  # world → environment frame (rows · R = Rᵀ d)
    h, w, _ = image.shape
    u = np.mod(np.arctan2(d[..., 0], -d[..., 2]) / (2 * np.pi), 1.0)
    v = np.arccos(np.clip(d[..., 1], -1.0, 1.0)) / np.pi
    fx, fy = u * w - 0.5, v * h - 0.5
    x0, y0 = np.floor(fx), np.floor(fy)
    wx, wy = (fx - x0)[..., None], (fy - y0)[..., None]
    x0 = x0.astype(int) % w
    x1 = (x0 + 1) % w
    y1 = np.clip(y0.astype(int) + 1, 0, h - 1)
    y0 = np.clip(y0.astype(int), 0, h - 1)
    top = (1 - wx) * image[y0, x0] + wx * image[y0, x1]
    bottom = (1 - wx) * image[y1, x0] + wx * image[y1, x1]
    return (1 - wy) * top + wy * bottom


def plane_scene(light, albedo=(0.7, 0.5, 0.3), half=2.0, camera=None):
    return load_dict(
        {
            "camera": camera or {"position": [0, 3, 4], "look_at": [0, 0, -0.5], "fov_y": 45, "size": list(SIZE)},
            "materials": {"floor": {"type": "lambert", "albedo": list(albedo)}},
            "mesh": [{"shape": "plane", "size": [2 * half, 2 * half], "material": "floor"}],
            "light": [light],
        }
    )


def noise_check(a, b, exact, mask):
    """Two independent renders a, b vs the exact image: pooled squared error of their mean over its variance
    (≈ 1 when unbiased), mean |z| with a smoothed per-pixel standard error (≈ 0.8 for Gaussian noise), mean
    relative error and the relative bias of the image sum."""
    m = 0.5 * (a + b)
    keep = mask[..., None] & (exact > 1e-3 * exact.max())
    err2 = ((m - exact) ** 2)[keep]
    var_m = ((a - b) ** 2 / 4.0)[keep]  # E[(a − b)²/4] = var(m)
    ratio = float(err2.sum() / var_m.sum())
    # per-pixel standard error, smoothed over 5 × 5 neighbours (a single pair is one degree of freedom)
    se = np.sqrt(uniform_filter((a - b) ** 2 / 4.0, size=(5, 5, 1), mode="nearest"))[keep]
    z = float(np.mean(np.sqrt(err2) / np.maximum(se, 1e-12)))
    rel = float(np.mean(np.abs(m - exact)[keep] / exact[keep]))
    bias = float(np.sum((m - exact)[keep]) / np.sum(exact[keep]))
    return ratio, z, rel, bias


# ------------------------------------------------------------------------------------------------ tests


def test_camera_pixel_convention_and_emitting_side():
    """Small area lights parallel to the image plane land where ``project`` says (centroid), with the flux
    their projected area predicts (checks fov_y / fov_axis), only on their emitting side, and reflect nothing."""
    camera = {"position": [1, 2, 5], "look_at": [0, 0.5, 0], "fov_y": 40, "size": list(SIZE)}
    cam = load_dict({"camera": camera}).camera
    right, up, back = camera_basis(cam)
    s = 0.12
    blobs = []  # (centre, light dict, area, visible)

    def rect(c, a, b, **kw):
        return {"type": "quad", "corners": [list(c - a - b), list(c + a - b), list(c - a + b)], **kw}

    c = np.array([-1.2, 1.3, 0.5])
    blobs.append((c, rect(c, s * right, s * up, radiance=[20, 10, 5]), 4 * s * s, True))  # rectangle
    c = np.array([1.0, -0.2, -0.5])
    shear = s * right + 0.6 * s * up  # a parallelogram: the mesh path
    blobs.append((c, rect(c, s * right, shear, radiance=[5, 20, 10]), 4 * s * s * 0.6, True))
    c = np.array([1.4, 1.4, 0.0])
    ang = np.radians(60.0 * np.arange(6))
    hexagon = c + 1.2 * s * (np.cos(ang)[:, None] * right + np.sin(ang)[:, None] * up)
    hexagon_light = {"type": "polygon", "vertices": hexagon.tolist(), "radiance": [10, 5, 20]}
    blobs.append((c, hexagon_light, 1.5 * np.sqrt(3) * (1.2 * s) ** 2, True))
    c = np.array([-0.8, -0.3, -1.5])  # facing away, two-sided: visible
    blobs.append((c, rect(c, s * up, s * right, radiance=[10, 10, 10], two_sided=True), 4 * s * s, True))
    c = np.array([-1.3, 0.0, 1.0])  # facing away, one-sided: black
    blobs.append((c, rect(c, s * up, s * right, radiance=[10, 10, 10]), 4 * s * s, False))

    # a point light at the eye shines on every light's camera-facing side: light geometry must reflect nothing
    eye_light = {"type": "point", "position": camera["position"], "intensity": [500, 500, 500]}
    scene = load_dict({"camera": camera, "light": [b[1] for b in blobs] + [eye_light]})
    image = render_mitsuba(scene, spp=256, seed=3)
    assert image.shape == (SIZE[1], SIZE[0], 3) and image.dtype == np.float32
    expected = project(cam, np.array([b[0] for b in blobs]))
    assert np.all((expected > 7) & (expected < np.array(SIZE) - 7))
    gaps = np.linalg.norm(expected[:, None] - expected[None], axis=-1) + 100 * np.eye(len(blobs))
    assert gaps.min() > 13
    lum = image.sum(axis=-1)
    assert lum[lum > 0].size > 0
    f_px = SIZE[1] / (2 * np.tan(np.radians(cam.fov_y) / 2))  # focal length in pixels
    errors, flux_errors = [], []
    covered = np.zeros(lum.shape, dtype=bool)
    for (centre, light, area, visible), (x, y) in zip(blobs, expected, strict=True):
        i0, j0 = int(y) - 6, int(x) - 6
        win = lum[i0 : i0 + 13, j0 : j0 + 13]
        covered[i0 : i0 + 13, j0 : j0 + 13] = True
        if not visible:
            assert win.max() == 0.0, "a one-sided light is visible from its back"
            continue
        ii, jj = np.mgrid[i0 : i0 + 13, j0 : j0 + 13]
        cx, cy = (win * (jj + 0.5)).sum() / win.sum(), (win * (ii + 0.5)).sum() / win.sum()
        errors.append(np.hypot(cx - x, cy - y))
        depth = -(centre - np.asarray(cam.position)) @ back
        flux = win.sum() / sum(light["radiance"])  # covered pixel area
        flux_errors.append(flux / (area * (f_px / depth) ** 2) - 1)
    assert lum[~covered].max() == 0.0  # nothing anywhere else
    print(f"centroid offsets (px): {np.round(errors, 3)}; projected-area errors: {np.round(flux_errors, 4)}")
    assert max(errors) < 0.5, errors
    assert max(abs(e) for e in flux_errors) < 0.03, flux_errors


def test_lambert_plane_point_light_matches_closed_form():
    scene = plane_scene({"type": "point", "position": [0.3, 1.5, -0.2], "intensity": [10, 8, 6]})
    image = render_mitsuba(scene, spp=128, seed=1)
    exact, mask = analytic_image(scene, (SIZE[0] * K, SIZE[1] * K))
    exact = exact.reshape(SIZE[1], K, SIZE[0], K, 3).mean(axis=(1, 3))
    mask = mask.reshape(SIZE[1], K, SIZE[0], K).all(axis=(1, 3))
    assert mask.sum() > 0.35 * mask.size
    rel = np.abs(image - exact)[mask] / exact[mask]
    bias = (image - exact)[mask].sum(axis=0) / exact[mask].sum(axis=0)
    print(f"point light: mean rel {rel.mean():.2e}, max rel {rel.max():.2e}, bias {bias}")
    assert rel.mean() < 5e-3
    assert np.all(np.abs(bias) < 5e-4)
    assert np.all(image >= 0) and np.all(np.isfinite(image))
    assert render_mitsuba(scene, spp=2, size=(32, 20)).shape == (20, 32, 3)  # size overrides the camera's


def test_lambert_sphere_directional_light_and_vertex_normals(tmp_path):
    """Directional light (``direction`` = where the light travels) on a tessellated Lambert sphere, against the
    exact sphere; and the mesh Mitsuba loads carries exactly our positions, normals, uv and triangles."""
    scene = load_dict(
        {
            "camera": {"position": [0.5, 1.0, 4], "look_at": [0, 0, 0], "fov_y": 35, "size": list(SIZE)},
            "materials": {"m": {"type": "lambert", "albedo": [0.6, 0.5, 0.4]}},
            "mesh": [{"shape": "sphere", "radius": 1.0, "material": "m", "transform": {"translate": [0.1, 0, 0]}}],
            "light": [{"type": "directional", "direction": [-0.6, -1.0, -0.5], "irradiance": [3, 2.5, 2]}],
        }
    )
    image = render_mitsuba(scene, spp=128, seed=4)
    exact, mask = analytic_image(scene, (SIZE[0] * K, SIZE[1] * K))
    exact = exact.reshape(SIZE[1], K, SIZE[0], K, 3).mean(axis=(1, 3))
    mask = mask.reshape(SIZE[1], K, SIZE[0], K).all(axis=(1, 3))
    assert mask.sum() > 300
    rel = np.abs(image - exact)[mask] / exact[mask]
    bias = (image - exact)[mask].sum(axis=0) / exact[mask].sum(axis=0)
    print(f"directional light on sphere: mean rel {rel.mean():.2e}, max {rel.max():.2e}, bias {bias}")
    assert rel.mean() < 5e-3 and np.all(np.abs(bias) < 2e-3)

    from reflets.scene.geometry import mesh_data

    mi = mitsuba_module()
    params = mi.traverse(mi.load_dict(to_mitsuba_dict(scene, tmp_path)).shapes()[0])
    ours = mesh_data(scene, 0)
    for key, value in [
        ("vertex_positions", ours.positions),
        ("vertex_normals", ours.normals),
        ("vertex_texcoords", ours.uvs),
        ("faces", ours.indices),
    ]:
        assert np.allclose(np.array(params[key]).reshape(value.shape), value, rtol=0, atol=1e-6), key


def _area_light_check(scene, polygons, radiance, two_sided, spp=128):
    albedo = scene.materials["floor"].albedo
    exact, mask = plane_area_light_exact(scene, polygons, radiance, albedo, two_sided, half=2.0)
    a = render_mitsuba(scene, spp=spp, seed=1)
    b = render_mitsuba(scene, spp=spp, seed=2)
    assert mask.sum() > 0.4 * mask.size
    return noise_check(a, b, exact, mask), a, exact, mask


def test_polygon_irradiance_formula_sanity():
    """The closed form itself: a tiny, distant square gives E ≈ A cosθ cosθ′ / r²; its back gives −E."""
    x = np.array([[0.0, 0.0, 0.0]])
    n = np.array([[0.0, 1.0, 0.0]])
    c, h = np.array([1.0, 3.0, 0.5]), 1e-3
    # horizontal, facing down (c2 − c1) × (c4 − c1) ∝ −y
    square = np.array([c + [-h, 0, -h], c + [h, 0, -h], c + [h, 0, h], c + [-h, 0, h]])
    assert np.allclose(np.cross(square[1] - square[0], square[3] - square[0]) / (4 * h * h), [0, -1, 0])
    r = np.linalg.norm(c)
    approx = 4 * h * h * (c[1] / r) * (c[1] / r) / r**2
    assert polygon_irradiance(x, n, square)[0] == pytest.approx(approx, rel=1e-4)
    assert polygon_irradiance(x, n, square[::-1])[0] == pytest.approx(-approx, rel=1e-4)


def test_lambert_plane_quad_light_matches_lambert_formula():
    corners = [[-0.1, 1.5, -0.6], [0.8, 1.5, -0.6], [-0.1, 1.5, 0.2]]  # faces down: (c2−c1)×(c4−c1) ∝ −y
    light = {"type": "quad", "corners": corners, "radiance": [6, 5, 4]}
    scene = plane_scene(light)
    poly = scene.light[0].polygon()
    (ratio, z, rel, bias), *_ = _area_light_check(scene, [poly], light["radiance"], two_sided=False)
    print(f"quad light: bias²/var {ratio:.3f}, mean |z| {z:.3f}, mean rel err {rel:.2e}, bias {bias:.1e}")
    assert ratio < 1.5  # an unbiased estimate gives ≈ 1
    assert z < 1.2  # ≈ 0.8 for Gaussian noise
    assert rel < 0.02
    assert abs(bias) < 0.003


@pytest.mark.parametrize("two_sided", [True, False])
def test_vertical_polygon_light_sides(two_sided):
    """A vertical pentagon standing on the plane: both halves of the plane lit when two-sided, one when not."""
    ang = np.radians(90 + 72 * np.arange(5))
    pentagon = np.stack([0.35 * np.cos(ang), 0.7 + 0.35 * np.sin(ang), 0 * ang], axis=1)  # CCW seen from +z
    light = {"type": "polygon", "vertices": pentagon.tolist(), "radiance": [5, 5, 5], "two_sided": two_sided}
    camera = {"position": [3.5, 3, 1.0], "look_at": [0, 0, 0], "fov_y": 50, "size": list(SIZE)}
    scene = plane_scene(light, camera=camera)
    (ratio, z, rel, bias), image, exact, mask = _area_light_check(scene, [pentagon], light["radiance"], two_sided)
    print(f"polygon two_sided={two_sided}: bias²/var {ratio:.3f}, mean |z| {z:.3f}, rel {rel:.2e}, bias {bias:.1e}")
    # two-sided lights are two emitters, and Mitsuba picks one uniformly: half the light samples see a back
    # face, so the noise is several times larger at the same spp (unbiased all the same)
    assert ratio < 1.5 and z < 1.2 and rel < (0.08 if two_sided else 0.02) and abs(bias) < 0.01
    lit = binary_dilation(exact[..., 0] > 0, iterations=1)  # pixels straddling the light's plane excluded
    back = mask & ~lit
    if not two_sided:
        assert back.sum() > 100 and image[back].max() == 0.0
    else:
        assert back.sum() == 0


@pytest.mark.parametrize(
    "rotate_y, camera",
    [
        (0.0, {"position": [0, 0, 0], "look_at": [0.3, 0.1, -1], "fov_y": 70, "size": list(SIZE)}),
        (30.0, {"position": [0, 0, 0], "look_at": [1, 1.6, 0.4], "fov_y": 70, "size": list(SIZE)}),
        (-75.0, {"position": [0, 0, 0], "look_at": [-1, -1.2, 0.5], "fov_y": 80, "size": list(SIZE)}),
    ],
)
def test_environment_orientation(tmp_path, rotate_y, camera):
    """Background pixels = our bilinear lookup of the map along the camera rays (Mitsuba's envmap layout)."""
    from reflets.imageio import write_image

    rng = np.random.default_rng(7)
    env = rng.uniform(0.2, 2.0, size=(12, 24, 3)).astype(np.float32)  # coarse: any half-texel slip shows
    write_image(tmp_path / "env.exr", env)
    scene = load_dict(
        {"camera": camera, "light": [{"type": "environment", "file": "env.exr", "scale": 1.5, "rotate_y": rotate_y}]},
        base_dir=tmp_path,
    )
    image = render_mitsuba(scene, spp=256, seed=5)
    _, dirs = subpixel_rays(scene.camera, k=8)
    expected = env_lookup(1.5 * env.astype(np.float64), dirs, rotate_y).mean(axis=0)
    rel = np.abs(image - expected) / expected
    print(f"environment rotate_y={rotate_y}: mean rel err {rel.mean():.2e}, max {rel.max():.2e}")
    # what is left is Mitsuba's noise (pixel jitter over texels): it falls as 1/√spp (5e-4 mean at 1024 spp);
    # Mitsuba's own row placement (no 2H + 1 resampling) would give 4–13 % here
    assert rel.mean() < 3e-3
    assert rel.max() < 0.1
    mirrored = env_lookup(1.5 * env.astype(np.float64), dirs * [-1, 1, 1], rotate_y).mean(axis=0)
    assert np.mean(np.abs(image - mirrored) / mirrored) > 10 * rel.mean()  # the test can tell a flip


def test_environment_resampling_is_exact():
    """Mitsuba's lookup of the 2H + 1-row image equals our bilinear lookup of the H-row one (no rendering)."""
    rng = np.random.default_rng(1)
    env = rng.uniform(0.0, 1.0, size=(5, 8, 3))
    big = environment_for_mitsuba(env).astype(np.float64)
    d = rng.normal(size=(2000, 3))
    d /= np.linalg.norm(d, axis=1, keepdims=True)
    u = np.mod(np.arctan2(d[:, 0], -d[:, 2]) / (2 * np.pi), 1.0)
    v = np.arccos(d[:, 1]) / np.pi
    # Mitsuba's eval_spectrum: x − ½/W wrapped, times W over W + 1 padded columns; y times (rows − 1)
    h2, w = big.shape[:2]
    padded = np.concatenate([big, big[:, :1]], axis=1)
    x = np.mod(u - 0.5 / w, 1.0) * w
    y = v * (h2 - 1)
    px, py = np.minimum(x.astype(int), w - 1), np.minimum(y.astype(int), h2 - 2)
    wx, wy = (x - px)[:, None], (y - py)[:, None]
    mitsuba = (1 - wy) * ((1 - wx) * padded[py, px] + wx * padded[py, px + 1]) + wy * (
        (1 - wx) * padded[py + 1, px] + wx * padded[py + 1, px + 1]
    )
    assert np.allclose(mitsuba, env_lookup(env, d, 0.0), atol=1e-12)


def test_background_colour_is_seen_not_lighting(tmp_path):
    scene = plane_scene({"type": "point", "position": [0.3, 1.5, -0.2], "intensity": [10, 8, 6]}, half=1.0)
    scene.background = (0.2, 0.3, 0.4)
    image = render_mitsuba(scene, spp=32, seed=1)
    origin, dirs = subpixel_rays(scene.camera)
    t = -origin[1] / np.where(dirs[..., 1] < 0, dirs[..., 1], np.nan)
    hit = origin + np.nan_to_num(t)[..., None] * dirs
    hits = (np.isfinite(t) & (np.abs(hit[..., 0]) < 1.0) & (np.abs(hit[..., 2]) < 1.0)).any(axis=0)
    miss = ~binary_dilation(hits, iterations=1)  # pixels the plane cannot reach
    assert miss.sum() > 100
    assert np.abs(image[miss] - [0.2, 0.3, 0.4]).max() < 1e-6
    plain = scene.model_copy(update={"background": None})
    exact, mask = analytic_image(plain, (SIZE[0] * K, SIZE[1] * K))
    exact = exact.reshape(SIZE[1], K, SIZE[0], K, 3).mean(axis=(1, 3))
    mask = mask.reshape(SIZE[1], K, SIZE[0], K).all(axis=(1, 3))
    assert np.mean(np.abs(image - exact)[mask] / exact[mask]) < 5e-3  # the background adds no light
    assert to_mitsuba_dict(scene, tmp_path)["background"]["type"] == "constant"  # the standalone-dict form
    assert "background" not in to_mitsuba_dict(scene, tmp_path, background="alpha")


def test_unsupported_materials_raise_scene_error(tmp_path):
    scene = load_dict(
        {
            "camera": {"position": [0, 3, 4], "look_at": [0, 0, 0], "size": list(SIZE)},
            "materials": {"shiny": {"type": "blinn_phong", "kd": [0.5, 0.5, 0.5], "exponent": 50}},
            "mesh": [{"shape": "plane", "material": "shiny"}],
        }
    )
    with pytest.raises(SceneError) as info:
        to_mitsuba_dict(scene, tmp_path)
    message = str(info.value)
    assert "shiny" in message and "Mitsuba bridge does not support" in message and "\n" not in message
    assert not list(tmp_path.iterdir())  # nothing written before the error
    base = dict(type="microfacet", distribution="ggx", alpha=0.3, fresnel="none", specular=(1, 1, 1))
    base |= dict(eta=1.5, k=(0, 0, 0), masking="separable", diffuse=(0, 0, 0))
    for change, word in [
        ({"masking": "correlated"}, "correlated"),
        ({"diffuse": (0.1, 0.0, 0.0)}, "diffuse"),
        ({"fresnel": "schlick"}, "schlick"),
        ({"distribution": "phong"}, "phong"),
    ]:
        with pytest.raises(SceneError, match=word):
            material_to_mitsuba("m", SimpleNamespace(**(base | change)))
    # an unsupported material that no mesh uses is ignored
    scene.mesh = []
    assert "mesh_0" not in to_mitsuba_dict(scene, tmp_path)


def _ggx_reference(wo, wi, ax, ay, f):
    h = (wo + wi) / np.linalg.norm(wo + wi)
    d = 1.0 / (np.pi * ax * ay * ((h[0] / ax) ** 2 + (h[1] / ay) ** 2 + h[2] ** 2) ** 2)

    def lam(w):
        return 0.5 * (np.sqrt(1.0 + ((w[0] * ax) ** 2 + (w[1] * ay) ** 2) / w[2] ** 2) - 1.0)

    return f * d / ((1 + lam(wo)) * (1 + lam(wi))) / (4 * wo[2] * wi[2])


def _fresnel_exact(cos, eta, k):
    n = np.asarray(eta, dtype=complex) + 1j * np.asarray(k)
    cos_t = np.sqrt(n * n - (1 - cos * cos)) / n
    rs = (cos - n * cos_t) / (cos + n * cos_t)
    rp = (n * cos - cos_t) / (n * cos + cos_t)
    return 0.5 * (np.abs(rs) ** 2 + np.abs(rp) ** 2)


def _mitsuba_brdf(bsdf_dict, wo, wi):
    """f_r(wo, wi) of a Mitsuba BSDF in the local frame x = tangent, y = bitangent, z = normal."""
    mi = mitsuba_module()
    bsdf = mi.load_dict(bsdf_dict)
    si = mi.SurfaceInteraction3f()
    si.sh_frame = mi.Frame3f(mi.ScalarVector3f(1, 0, 0), mi.ScalarVector3f(0, 1, 0), mi.ScalarVector3f(0, 0, 1))
    out = []
    for o, i in zip(wo, wi, strict=True):
        si.wi = mi.ScalarVector3f(*o)
        out.append(np.array(bsdf.eval(mi.BSDFContext(), si, mi.ScalarVector3f(*i))) / i[2])  # Mitsuba: f·cos
    return np.array(out)


def _directions(rng, n):
    w = rng.normal(size=(2, n, 3))
    w[..., 2] = np.abs(w[..., 2]) + 0.05
    return w / np.linalg.norm(w, axis=-1, keepdims=True)


@pytest.mark.parametrize("fresnel", ["none", "dielectric", "conductor"])
def test_microfacet_mapping_matches_ggx_formula(fresnel):
    """roughconductor with our parameters = D·G·F/(4 cos cos) with anisotropic GGX, separable Smith masking,
    alpha_x along the tangent, F = 1 / exact dielectric / exact conductor Fresnel, times ``specular``."""
    eta, k = ((0.2, 0.9, 1.5), (3.9, 2.4, 2.2)) if fresnel == "conductor" else (1.5, (0.0, 0.0, 0.0))
    mat = SimpleNamespace(
        type="microfacet", distribution="ggx", alpha=[0.15, 0.45], fresnel=fresnel, specular=(1.0, 0.9, 0.8),
        eta=eta, k=k, masking="separable", diffuse=(0.0, 0.0, 0.0),
    )  # fmt: skip
    wo, wi = _directions(np.random.default_rng(11), 64)
    ours = []
    for o, i in zip(wo, wi, strict=True):
        c = o @ ((o + i) / np.linalg.norm(o + i))
        f = np.ones(3) if fresnel == "none" else _fresnel_exact(c, np.broadcast_to(eta, (3,)), k)
        ours.append(_ggx_reference(o, i, 0.15, 0.45, f * np.array(mat.specular)))
    got = _mitsuba_brdf(material_to_mitsuba("m", mat), wo, wi)
    assert np.allclose(got, np.array(ours), rtol=2e-5, atol=0)


def test_microfacet_class_matches_mitsuba():
    """With the real Microfacet class (when it exists): its NumPy eval equals Mitsuba's roughconductor."""
    module = pytest.importorskip("reflets.brdf.microfacet", reason="reflets.brdf.microfacet is not written yet")
    rng = np.random.default_rng(5)
    wo, wi = _directions(rng, 48)
    cases = [
        dict(distribution="ggx", alpha=[0.1, 0.4], fresnel="none"),
        dict(distribution="ggx", alpha=0.3, fresnel="conductor", eta=(0.2, 0.9, 1.5), k=(3.9, 2.4, 2.2)),
        dict(distribution="ggx", alpha=[0.5, 0.2], fresnel="dielectric", eta=1.5, specular=(1.0, 0.5, 0.25)),
        dict(distribution="beckmann", alpha=[0.2, 0.35], fresnel="conductor", eta=(0.2, 0.9, 1.5), k=(3.9, 2.4, 2.2)),
        dict(distribution="ggx", alpha=0.2, fresnel="conductor"),  # default eta, k (gold)
        dict(distribution="ggx", alpha=0.25, fresnel="dielectric"),  # default eta 1.5
        dict(distribution="ggx", alpha=0.4, fresnel="dielectric", eta=0.7),  # total internal reflection
        dict(distribution="ggx", alpha=[0.05, 0.3], fresnel="none", specular=(1.5, 2.0, 0.5)),  # scale > 1
    ]
    for case in cases:
        mat = module.Microfacet(masking="separable", diffuse=(0.0, 0.0, 0.0), **case)
        got = _mitsuba_brdf(material_to_mitsuba("m", mat), wo, wi)
        ours = np.asarray(mat.eval(wo, wi))
        # Mitsuba's Beckmann masking uses Walter's rational fit of G1 (≤ 0.4 % off the erf form)
        tol = 5e-3 if case["distribution"] == "beckmann" else 2e-4
        err = np.max(np.abs(got - ours) / np.maximum(ours, 1e-6))
        print(f"{case}: max rel diff {err:.2e}")
        assert err < tol, case


def test_missing_mitsuba_names_the_extra(monkeypatch):
    monkeypatch.setitem(sys.modules, "mitsuba", None)  # makes `import mitsuba` raise ImportError
    with pytest.raises(MitsubaUnavailableError, match=r"pip install 'reflets\[reference\]'"):
        mitsuba_module()


def test_a_light_without_shadows_is_refused_before_anything_is_written(tmp_path):
    scene = load_dict(
        {
            "camera": {"position": [0, 3, 4], "look_at": [0, 0, 0], "size": list(SIZE)},
            "materials": {"m": {"type": "lambert"}},
            "mesh": [{"shape": "plane", "material": "m"}],
            "light": [{"type": "point", "position": [0, 2, 0], "intensity": [1, 1, 1], "shadows": False}],
        }
    )
    with pytest.raises(SceneError, match=r"light\[0\]\.shadows.*NumPy reference|NumPy reference.*light\[0\]"):
        to_mitsuba_dict(scene, tmp_path / "work")
    assert not (tmp_path / "work").exists()


def test_an_orientation_field_is_refused(tmp_path):
    """Mitsuba takes tangents from the uv: a material oriented by a per-vertex field would be ignored silently."""
    np.savez(tmp_path / "u.npz", u=np.zeros((4, 3)))
    material = load_dict(
        {
            "camera": {"position": [0, 3, 4], "look_at": [0, 0, 0], "size": list(SIZE)},
            "materials": {"m": {"type": "microfacet", "alpha": [0.1, 0.3], "orientation": str(tmp_path / "u.npz")}},
            "mesh": [{"shape": "plane", "material": "m"}],
            "light": [{"type": "point", "position": [0, 2, 0], "intensity": [1, 1, 1]}],
        }
    ).materials["m"]
    with pytest.raises(SceneError, match="orientation field"):
        material_to_mitsuba("m", material)


@pytest.mark.slow
@pytest.mark.parametrize("asset, bound", [("TextureCoordinateTest", 1.5e-3), ("DamagedHelmet", 5e-3)])
def test_textured_gltf_assets_through_mitsuba_match_the_numpy_reference(asset, bound):
    """glTF materials as Mitsuba's principled BSDF with bitmap textures (uv transform, filter, wrap), the normal map
    through ``normalmap`` and the emission as an area emitter: the two references agree on 4 × 4 blocks (measured
    4.3e-4 and 2.0e-3: the helmet is mostly metal, where Disney's BSDF is Appendix B's; its diffuse differs, below)."""
    from reflets.bench.assets import block_means, lit_for_comparison
    from reflets.scene.assets import asset_path

    path = Path(__file__).parents[1] / "data" / "gltf" / asset / f"{asset}.glb"
    scene = lit_for_comparison(reflets.load_scene(path if path.exists() else asset_path(f"{asset}/{asset}.glb")))
    scene = scene.model_copy(update={"camera": scene.camera.model_copy(update={"size": (160, 120)})})
    mitsuba = render_mitsuba(scene, spp=64)
    numpy_ref = reflets.reference(scene, spp=16, progress=False, pixel="box").image
    assert relmse(block_means(mitsuba), block_means(numpy_ref)) < bound


@pytest.mark.slow
@pytest.mark.parametrize(
    "metallic, roughness, low, high",
    [(0.0, 0.2, 1.01, 1.05), (0.0, 0.5, 1.04, 1.08), (0.0, 0.9, 1.08, 1.14), (1.0, 0.3, 0.985, 1.0)],
)
def test_principled_differs_from_appendix_b_by_its_diffuse_only(metallic, roughness, low, high):
    """Disney's diffuse (Burley's retro-reflection) is brighter than Appendix B's Lambert on rough dielectrics,
    more so the rougher (mean over the sphere +2.8 %, +6.2 %, +10.8 % at roughness 0.2, 0.5, 0.9: docs/reference.md);
    a metal agrees within 1 % (0.990)."""
    scene = load_dict({
        "camera": {"position": [0, 0.5, 2.5], "look_at": [0, 0, 0], "size": [96, 72]},
        "materials": {"m": {"type": "gltf", "base_color": [0.8, 0.5, 0.3, 1], "metallic": metallic,
                            "roughness": roughness}},
        "mesh": [{"shape": "sphere", "radius": 0.7, "material": "m"}],
        "light": [{"type": "point", "position": [1.5, 2, 2], "intensity": [4, 4, 4]},
                  {"type": "directional", "direction": [1, -0.3, -0.5], "irradiance": [1, 1, 1]}],
    })  # fmt: skip
    seen = np.any(reflets.render(scene, method="position") != 0, axis=-1)
    mitsuba = render_mitsuba(scene, spp=256)[seen].mean()
    ratio = mitsuba / reflets.reference(scene, spp=64, progress=False, pixel="box").image[seen].mean()
    assert low < ratio < high, ratio


def test_gltf_features_principled_cannot_express_are_refused_in_one_line(tmp_path):
    from reflets.brdf.gltf import Gltf

    for change, word in [({"clearcoat": 0.5}, "clear coat"), ({"sheen_color": (1, 1, 1)}, "sheen"),
                         ({"anisotropy_strength": 0.5}, "anisotropy"), ({"unlit": True}, "unlit"),
                         ({"alpha_mode": "mask"}, "MASK"), ({"specular": 0.5}, "KHR_materials_specular"),
                         ({"transmission": 1.0}, "transmission")]:  # fmt: skip
        with pytest.raises(SceneError, match=word) as info:
            material_to_mitsuba("g", Gltf(**change))
        assert "\n" not in str(info.value) and "materials.g" in str(info.value.field)


def test_an_orthographic_camera_matches_the_numpy_reference(tmp_path):
    """The orthographic sensor scaled to the camera's window: a lit plane as the NumPy reference sees it (box
    pixels), and a window of half the height would differ by far more."""
    camera = {"position": [0.5, 3, 3], "look_at": [0, 0, 0], "projection": "orthographic", "ortho_height": 3.0,
              "size": list(SIZE)}  # fmt: skip
    light = {"type": "point", "position": [0.3, 1.5, -0.2], "intensity": [10, 8, 6]}
    scene = plane_scene(light, camera=camera)
    image = render_mitsuba(scene, spp=64, seed=1)
    ref = reflets.reference(scene, spp=64, pixel="box", progress=False).image
    assert relmse(image, ref) < 1e-3  # measured 1.5e-4
    half = plane_scene(light, camera={**camera, "ortho_height": 1.5})
    assert relmse(image, reflets.reference(half, spp=16, pixel="box", progress=False).image) > 0.1  # measured 0.27
    shifted = plane_scene(light, camera={**camera, "principal_offset": [0.1, 0.0]})
    workdir = Path(tmp_path) / "mitsuba"
    with pytest.raises(SceneError, match="principal point"):
        to_mitsuba_dict(shifted, workdir)
    assert not workdir.exists()  # refused before anything is written
