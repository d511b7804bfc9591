"""Environment capture (004 "Environment map") on generated photos of a known sky (real photographs are not
available offline): OpenGL's cube-map layout, HDR accumulation with per-frame gains, the document's overwrite,
parallax correction, lens distortion, and the cube-map helpers of the lighting (mips, face means, the specular
level, the trilinear lookup, conversion to an equirect map)."""

from __future__ import annotations

import numpy as np
import pytest

pytest.importorskip("cv2", reason="the 'ar' extra (make test installs it)")

from reflets.ar.camera import Intrinsics  # noqa: E402
from reflets.ar.capture import (
    CLIPPED_WEIGHT,
    GREY,
    CubeMap,
    capture,
    environment_view,
    face_coordinates,
    face_means,
    filled,  # noqa: E402
    lookup,
    mips,
    project,
    specular_level,
    to_equirect,
)
from reflets.ar.synthetic import look_at_pose  # noqa: E402
from reflets.equirect import equirect_direction  # noqa: E402
from reflets.scene.environment import lookup as equirect_lookup  # noqa: E402
from reflets.scene.model import EnvironmentLight  # noqa: E402

CAMERA = Intrinsics.from_fov((160, 120), 90)
SUN = np.array([0.5, 0.6, -0.62]) / np.linalg.norm([0.5, 0.6, -0.62])


def sky(height: int = 128) -> np.ndarray:
    """A smooth HDR sky (radiance 0.13 .. 3.2): blue above, warm below, three azimuthal bands, a broad sun lobe
    that clips in the brighter frames."""
    width = 2 * height
    d = equirect_direction(((np.arange(width) + 0.5) / width)[None], ((np.arange(height) + 0.5) / height)[:, None])
    up = 0.5 * (d[..., 1:2] + 1)
    base = 0.08 + 0.35 * up * np.array([0.6, 0.8, 1.0]) + 0.1 * (1 - up) * np.array([1.0, 0.8, 0.5])
    phi = np.arctan2(d[..., 0], -d[..., 2])
    base = base * (1 + 0.3 * np.cos(3 * phi)[..., None] * np.sin(np.pi * up))
    sun = 3.0 * np.exp(12 * (d @ SUN - 1))[..., None] * np.array([1.0, 0.9, 0.7])
    return (base + sun).astype(np.float32)


SKY = sky()


def truth_at_texels(size: int) -> np.ndarray:
    return equirect_lookup(SKY, EnvironmentLight(type="environment", file="sky"), CubeMap.directions(size))


def view_towards(yaw_deg: float, pitch_deg: float, eye=(0.0, 0.0, 0.0)):
    yaw, pitch = np.radians(yaw_deg), np.radians(pitch_deg)
    forward = np.array([np.sin(yaw) * np.cos(pitch), np.sin(pitch), -np.cos(yaw) * np.cos(pitch)])
    return look_at_pose(eye, np.asarray(eye) + forward)


# ------------------------------------------------------------------------------------------------- GL layout


def gl_spec_face_st(d: np.ndarray):
    """OpenGL 4.6 table 8.19 transcribed literally (independent of the module's FACE_FRAMES)."""
    rx, ry, rz = d
    table = [
        (rx > 0, -rz, -ry, rx),
        (rx < 0, rz, -ry, rx),
        (ry > 0, rx, rz, ry),
        (ry < 0, rx, -rz, ry),
        (rz > 0, rx, -ry, rz),
        (rz < 0, -rx, -ry, rz),
    ]
    major = int(np.argmax(np.abs(d)))
    face = 2 * major + int(d[major] < 0)
    _, sc, tc, ma = table[face]
    return face, 0.5 * (sc / abs(ma) + 1), 0.5 * (tc / abs(ma) + 1)


def test_texel_directions_follow_the_gl_major_axis_table():
    n = 8
    dirs = CubeMap.directions(n)
    np.testing.assert_allclose(np.linalg.norm(dirs, axis=-1), 1.0, rtol=1e-12)
    axes = np.array([[1, 0, 0], [-1, 0, 0], [0, 1, 0], [0, -1, 0], [0, 0, 1], [0, 0, -1]])
    for f in range(6):
        assert np.all(dirs[f] @ axes[f] >= np.abs(dirs[f]).max(axis=-1) - 1e-12)  # the face's axis is the major one
    # s runs along columns, t down the rows (row 0 = t = 0): a flipped or transposed face fails here.
    # +x: s_c = −r_z, t_c = −r_y → the first texel of row 0 looks toward +z and +y.
    assert dirs[0, 0, 0, 2] > 0 and dirs[0, 0, 0, 1] > 0 and dirs[0, 0, -1, 2] < 0 and dirs[0, -1, 0, 1] < 0
    # +y: s_c = +r_x, t_c = +r_z → row 0 is toward −z, column 0 toward −x.
    assert dirs[2, 0, 0, 0] < 0 and dirs[2, 0, 0, 2] < 0 and dirs[2, -1, -1, 0] > 0 and dirs[2, -1, -1, 2] > 0
    # −z: s_c = −r_x → column 0 toward +x.
    assert dirs[5, 0, 0, 0] > 0 and dirs[5, 0, -1, 0] < 0
    # every texel centre maps back to itself through the spec's table
    centres = (np.arange(n) + 0.5) / n
    for f, j, i in [(f, j, i) for f in range(6) for j in (0, 3, 7) for i in (0, 5, 7)]:
        face, s, t = gl_spec_face_st(dirs[f, j, i])
        assert face == f and s == pytest.approx(centres[i]) and t == pytest.approx(centres[j])


def test_face_selection_matches_the_spec_table_on_random_directions(rng):
    d = rng.normal(size=(300, 3))
    face, s, t = face_coordinates(d)
    expected = np.array([gl_spec_face_st(x) for x in d])
    np.testing.assert_array_equal(face, expected[:, 0])
    np.testing.assert_allclose(np.c_[s, t], expected[:, 1:], atol=1e-12)


def test_the_gpu_samples_the_uploaded_array_as_the_numpy_lookup(ctx, rng):
    """The array goes to ``ctx.texture_cube`` as it is; textureLod (trilinear, seamless) on the GPU equals
    ``lookup`` over random directions and levels — GL's own mipmaps equal ``mips``."""
    import moderngl

    from reflets.gpu import release_objects

    n, count = 8, 64 * 64
    faces = rng.random((6, n, n, 3)).astype(np.float32)  # noise: any misplaced texel shows
    dirs = rng.normal(size=(count, 3))
    dirs /= np.linalg.norm(dirs, axis=1, keepdims=True)
    levels = np.where(np.arange(count) < count // 2, 0.0, rng.uniform(0, 3.5, count))
    queries = np.concatenate([dirs, levels[:, None]], axis=1).astype(np.float32)
    cube = ctx.texture_cube((n, n), 3, faces.tobytes(), dtype="f4")
    cube.build_mipmaps()
    cube.filter = (moderngl.LINEAR_MIPMAP_LINEAR, moderngl.LINEAR)
    query = ctx.texture((64, 64), 4, queries.tobytes(), dtype="f4")
    program = ctx.program(
        vertex_shader="""#version 430
        void main() {
            vec2 p = vec2((gl_VertexID << 1) & 2, gl_VertexID & 2);
            gl_Position = vec4(2.0 * p - 1.0, 0.0, 1.0);
        }""",
        fragment_shader="""#version 430
        uniform samplerCube env; uniform sampler2D queries; out vec4 colour;
        void main() {
            vec4 q = texelFetch(queries, ivec2(gl_FragCoord.xy), 0);
            colour = vec4(textureLod(env, q.xyz, q.w).rgb, 1.0);
        }""",
    )
    program["env"], program["queries"] = 0, 1
    target = ctx.simple_framebuffer((64, 64), components=4, dtype="f4")
    vao = ctx.vertex_array(program, [])
    seamless = 0x884F  # GL_TEXTURE_CUBE_MAP_SEAMLESS
    ctx.enable_direct(seamless)
    try:
        cube.use(0)
        query.use(1)
        target.use()
        vao.render(moderngl.TRIANGLES, vertices=3)
        gpu = np.frombuffer(target.read(components=4, dtype="f4"), np.float32).reshape(count, 4)[:, :3]
    finally:
        ctx.disable_direct(seamless)
        release_objects(ctx, [vao, target, program, query, cube])  # the default framebuffer bound first
    # llvmpipe: 5e-7; a GPU filters with fixed-point weights (NVIDIA H100: up to 5.0e-3 off the float lookup)
    np.testing.assert_allclose(gpu, lookup(faces, dirs, levels), atol=1e-2)


# ----------------------------------------------------------------------------------------------------- capture


def test_frames_of_varying_gain_merge_into_the_sky_and_the_gains_are_recovered():
    n = 64
    cube = CubeMap.empty(n)
    gains = [1.0, 0.6, 1.5, 0.8, 1.2, 0.7, 1.4, 0.9, 1.1, 0.65, 1.3, 1.0]
    estimated = []
    for k, gain in enumerate(gains):  # a sweep around the horizon, above then below, then the other way round
        pitch = (35 if k % 2 else -35) * (-1 if k >= 6 else 1)
        R, t = view_towards(k * 60 + (30 if k >= 6 else 0), pitch)
        estimated.append(capture(cube, environment_view(SKY, CAMERA, R, t, gain=gain), CAMERA, R, t))
    np.testing.assert_allclose(estimated, np.array(gains) / gains[0], rtol=0.02)  # measured ≤ 0.06 %
    truth = truth_at_texels(n) * gains[0]
    error = np.abs(cube.faces - truth) / truth
    covered = cube.weights > 0.5
    assert covered.mean() > 0.9
    never_clipped = covered & (truth.max(axis=-1) * max(gains) < 0.98)
    assert error[never_clipped].mean() < 0.005 and error[never_clipped].max() < 0.03  # measured 0.18 %, 1.0 %
    # The sun clips in the bright frames; the dark ones carry it (HDR from LDR frames).
    sometimes_clipped = covered & (truth.max(axis=-1) * max(gains) > 0.98) & (truth.max(axis=-1) * min(gains) < 0.98)
    assert sometimes_clipped.sum() > 100
    assert error[sometimes_clipped].max() < 0.05  # measured 1.4 %
    # never seen: the fallback grey
    np.testing.assert_array_equal(cube.faces[cube.weights == 0], GREY)


def test_clipped_pixels_carry_almost_no_weight():
    n = 32
    R, t = view_towards(0, 0)
    frame = np.full((120, 160, 3), 128, np.uint8)
    frame[:, 80:] = 255
    cube = CubeMap.empty(n)
    capture(cube, frame, CAMERA, R, t, border=0.0)
    u, v, usable = project(CubeMap.directions(n).reshape(-1, 3) @ R.T, CAMERA)
    weights = cube.weights.reshape(-1)
    rows = usable & (v > 0) & (v < 119)
    assert weights[rows & (u > 81) & (u < 159)].max() <= CLIPPED_WEIGHT + 1e-6
    assert weights[rows & (u > 0) & (u < 79)].min() > 0.99


def test_overwrite_reproduces_the_document_last_frame_wins():
    n = 32
    first, second = view_towards(0, 0), view_towards(50, 10)
    frame_a = environment_view(SKY, CAMERA, *first, gain=1.0)
    frame_b = environment_view(SKY, CAMERA, *second, gain=1.5)  # no exposure compensation in the document
    both = CubeMap.empty(n)
    assert capture(both, frame_a, CAMERA, *first, mode="overwrite") == 1.0
    capture(both, frame_b, CAMERA, *second, mode="overwrite")
    only_a, only_b = CubeMap.empty(n), CubeMap.empty(n)
    capture(only_a, frame_a, CAMERA, *first, mode="overwrite")
    capture(only_b, frame_b, CAMERA, *second, mode="overwrite")
    in_b = only_b.weights > 0
    in_a_only = (only_a.weights > 0) & ~in_b
    assert in_b.sum() > 500 and in_a_only.sum() > 500 and np.any((only_a.weights > 0) & in_b)
    np.testing.assert_array_equal(both.faces[in_b], only_b.faces[in_b])
    np.testing.assert_array_equal(both.faces[in_a_only], only_a.faces[in_a_only])
    np.testing.assert_array_equal(both.faces[both.weights == 0], GREY)
    assert set(np.unique(both.weights)) == {0.0, 1.0}


def test_parallax_correction_registers_a_nearby_environment():
    """The sky painted on a sphere of radius 2 about the origin, photographed from points up to 0.87 away:
    with the scene radius, every frame agrees with the truth at the texel directions; as a distant map they
    disagree."""
    n, radius = 64, 2.0
    truth = truth_at_texels(n)
    rng = np.random.default_rng(3)
    poses = [view_towards(k * 45, 30 if k % 2 else -30, eye=rng.uniform(-0.5, 0.5, 3)) for k in range(8)]
    frames = [environment_view(SKY, CAMERA, R, t, radius=radius) for R, t in poses]
    errors = {}
    for scene_radius in (radius, None):
        cube = CubeMap.empty(n)
        for frame, (R, t) in zip(frames, poses, strict=True):
            capture(cube, frame, CAMERA, R, t, radius=scene_radius, exposure=1.0)
        usable = (cube.weights > 0.5) & (truth.max(axis=-1) < 0.98)
        assert usable.mean() > 0.8
        errors[scene_radius] = (np.abs(cube.faces - truth) / truth)[usable].mean()
    assert errors[radius] < 0.005  # measured 0.22 %
    assert errors[None] > 0.05  # measured 9 %


def test_lens_distortion_is_applied_as_opencv_does(rng):
    import cv2

    camera = Intrinsics(CAMERA.K.copy(), np.array([-0.25, 0.08, 0.001, -0.0015, -0.01]), CAMERA.size)
    points = rng.normal(size=(300, 3))
    points[:, 2] = np.abs(points[:, 2]) + 0.5
    u, v, usable = project(points, camera)
    expected = cv2.projectPoints(points, np.zeros(3), np.zeros(3), camera.K, camera.dist)[0][:, 0]
    assert usable.mean() > 0.8  # the rest lie beyond the polynomial's fold
    np.testing.assert_allclose(np.c_[u, v][usable], expected[usable], atol=1e-9)
    # distorted photos, captured with the distortion: as accurate as the pinhole case; ignoring it is not
    n = 32
    truth = truth_at_texels(n)
    errors = []
    for lens in (camera, Intrinsics(camera.K, np.zeros(5), camera.size)):
        cube = CubeMap.empty(n)
        for k in range(3):
            R, t = view_towards(70 * k, 20 * k - 20)
            capture(cube, environment_view(SKY, camera, R, t), lens, R, t, exposure=1.0)
        usable = (cube.weights > 0.5) & (truth.max(axis=-1) < 0.98)
        errors.append((np.abs(cube.faces - truth) / truth)[usable].mean())
    assert errors[0] < 0.005 and errors[1] > 0.01  # measured 0.23 %, 3 %


# ------------------------------------------------------------------------------------------ cube-map helpers


def test_mips_and_face_means_of_a_constant_map_stay_constant():
    rgb = np.array([0.2, 0.5, 1.25], np.float32)
    chain = mips(CubeMap.constant(32, rgb))
    assert [level.shape[1] for level in chain] == [32, 16, 8, 4, 2, 1]
    for level in chain:
        np.testing.assert_allclose(level, np.broadcast_to(rgb, level.shape), rtol=1e-6)
    np.testing.assert_allclose(face_means(CubeMap.constant(32, rgb)), np.tile(rgb, (6, 1)), rtol=1e-6)
    # a box chain keeps each face's mean
    faces = np.random.default_rng(0).random((6, 16, 16, 3)).astype(np.float32)
    np.testing.assert_allclose(face_means(faces), faces.mean(axis=(1, 2)), rtol=1e-5)
    with pytest.raises(ValueError, match="power-of-two"):
        mips(np.zeros((6, 24, 24, 3)))


def test_an_empty_map_is_the_document_s_grey():
    cube = CubeMap.empty(16)
    np.testing.assert_array_equal(cube.faces, GREY)
    np.testing.assert_allclose(lookup(cube, [[0.3, -0.2, 0.9]], level=2.5), [[GREY] * 3])


def test_lookup_at_texel_centres_returns_the_texels():
    faces = np.random.default_rng(1).random((6, 8, 8, 3)).astype(np.float32)
    np.testing.assert_allclose(lookup(faces, CubeMap.directions(8)), faces, atol=1e-6)


def test_to_equirect_recovers_the_equirect_a_map_was_built_from():
    back = to_equirect(CubeMap.from_equirect(SKY, 64), 256)
    assert back.shape == (128, 256, 3) and back.dtype == np.float32
    error = np.abs(back - SKY) / SKY
    assert error.mean() < 0.002 and error.max() < 0.02  # measured 0.03 %, 0.7 %


def test_specular_level_for_the_document_s_materials():
    # λ = log2(512 √3) − ½ log2(Ns + 1): glossy (Ns 400) ≈ 5.47; mirror (Ns 1e6) −0.17 → level 0
    np.testing.assert_allclose(specular_level(400, 512), np.log2(512 * np.sqrt(3)) - 0.5 * np.log2(401), rtol=1e-12)
    assert specular_level(400, 512) == pytest.approx(5.4688, abs=1e-4)
    assert specular_level(1e6, 512) == 0.0
    assert specular_level(0, 512) == 9.0  # a Lambertian-wide lobe reads the 1 × 1 level
    # the mean texel solid angle at that level equals the normalised lobe's 2π / (Ns + 1)
    level = specular_level(400, 512)
    assert 4 * np.pi / (6 * 512**2) * 4**level == pytest.approx(2 * np.pi / 401)


def test_unseen_texels_are_filled_by_elevation():
    """A capture that saw only the horizon band: the zenith takes the highest band's mean, the seen texels
    stay as captured, and nothing seen leaves the map alone."""
    n = 16
    dirs = CubeMap.directions(n)
    elevation = np.degrees(np.arcsin(dirs[..., 1]))
    faces = np.stack([0.2 + 0.01 * np.clip(elevation, 0, None)] * 3, axis=-1)  # brighter upward
    band = (elevation > -20) & (elevation < 40)
    cube = CubeMap(faces, band.astype(np.float32))
    out = filled(cube)
    assert np.array_equal(out.faces[band], cube.faces[band])
    top = elevation >= 40
    highest = (elevation >= 30) & (elevation < 40)
    np.testing.assert_allclose(out.faces[top], faces[highest].mean(axis=0)[None].repeat(top.sum(), 0), rtol=1e-5)
    assert not np.any(out.faces[~band] == cube.fallback)
    empty = CubeMap.empty(n)
    assert filled(empty) is empty
