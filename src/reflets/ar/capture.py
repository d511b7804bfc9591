"""Environment capture (004 "Environment map"): camera frames reprojected into a cube map, accumulated over
frames, and the cube-map helpers the document's lighting reads (box mips, face means, the specular mip level,
a NumPy reference of the GPU's trilinear cube lookup, conversion to reflets' equirect maps).

Layout: ``faces`` is (6, N, N, 3) float32 linear radiance in OpenGL's face order +x, −x, +y, −y, +z, −z, texel
``[f, j, i]`` at s = (i + ½)/N, t = (j + ½)/N — row 0 is t = 0, which is the first row glTexImage2D reads, so
``ctx.texture_cube((N, N), 3, faces.tobytes(), dtype="f4")`` uploads the array as it is. OpenGL's major-axis
table (GL 4.6 §8.13, table 8.19), s = ½ (s_c / |m_a| + 1), t = ½ (t_c / |m_a| + 1):

====== ======= ======= ======
face    s_c     t_c     m_a
====== ======= ======= ======
+x      −r_z    −r_y    r_x
−x      +r_z    −r_y    r_x
+y      +r_x    +r_z    r_y
−y      +r_x    −r_z    r_y
+z      +r_x    −r_y    r_z
−z      −r_x    −r_y    r_z
====== ======= ======= ======

Capture, the document's loop made robust: each texel direction d (or, with a scene radius R_s, the point R_s d of
the sphere the environment is assumed to lie on: parallax correction) is projected with K, the 5 OpenCV
distortion coefficients (the model of ``cv2.projectPoints``, applied in NumPy) and the pose; the frame is
linearised through the camera response; instead of overwriting (kept as ``mode="overwrite"``), each frame's
gain relative to the map is estimated (median of ratios over texels both cover well) and divided out, and the
frame is blended in with a weight = well-exposedness (0 at the clipped codes 0 and 255) × a smooth falloff toward
the image border. Texels never seen keep a fallback radiance (the document's grey 0.5).
"""

from __future__ import annotations

from dataclasses import dataclass, field
from functools import lru_cache
from pathlib import Path

import numpy as np

from ..equirect import equirect_direction
from ..imageio import linear_to_srgb, srgb_to_linear
from ..scene.environment import lookup as equirect_lookup
from ..scene.model import EnvironmentLight
from .board import _aruco
from .camera import Intrinsics

#: for each face (GL order): the major axis, and the world vectors that s_c and t_c multiply (table above)
FACE_FRAMES = np.array(
    [
        [[1, 0, 0], [0, 0, -1], [0, -1, 0]],
        [[-1, 0, 0], [0, 0, 1], [0, -1, 0]],
        [[0, 1, 0], [1, 0, 0], [0, 0, 1]],
        [[0, -1, 0], [1, 0, 0], [0, 0, -1]],
        [[0, 0, 1], [1, 0, 0], [0, -1, 0]],
        [[0, 0, -1], [-1, 0, 0], [0, -1, 0]],
    ],
    np.float64,
)
#: the document's start value, a mid grey
GREY = 0.5
#: Rec. 709 luminance, for the exposure ratios
LUMINANCE = np.array([0.2126, 0.7152, 0.0722])
#: an observation through clipped codes keeps this much weight: better than the fallback grey where a texel is
#: never seen otherwise (a saturated sun), negligible beside any well-exposed observation
CLIPPED_WEIGHT = 1e-3
#: fewer texels than this in common with the map: the gain is not estimated (the previous frame's is kept)
MIN_OVERLAP = 32


@dataclass
class CubeMap:
    """A captured environment: ``faces`` (6, N, N, 3) float32 linear radiance (GL layout, module docstring),
    ``weights`` (6, N, N) the accumulated capture weight; a weight-0 texel holds ``fallback``. ``gain`` is the
    last captured frame's gain relative to the map, ``frames`` the number of frames captured."""

    faces: np.ndarray
    weights: np.ndarray
    fallback: np.ndarray = field(default_factory=lambda: np.full(3, GREY, np.float32))
    gain: float = 1.0
    frames: int = 0

    def __post_init__(self):
        self.faces = np.array(self.faces, np.float32)  # own copies: capture writes in place
        self.weights = np.array(self.weights, np.float32)
        self.fallback = np.broadcast_to(np.asarray(self.fallback, np.float32), (3,)).copy()
        n = self.faces.shape[1]
        if self.faces.shape != (6, n, n, 3) or self.weights.shape != (6, n, n):
            raise ValueError(f"a cube map is (6, N, N, 3) + (6, N, N), got {self.faces.shape} + {self.weights.shape}")
        self.faces[self.weights <= 0] = self.fallback

    @property
    def size(self) -> int:
        return self.faces.shape[1]

    @classmethod
    def empty(cls, size: int, fallback=GREY) -> CubeMap:
        """Nothing captured: every texel is ``fallback`` (the document starts at grey 0.5)."""
        return cls(np.zeros((6, size, size, 3), np.float32), np.zeros((6, size, size), np.float32), fallback)

    @classmethod
    def constant(cls, size: int, rgb, weight: float = 0.0) -> CubeMap:
        """A uniform sky of radiance ``rgb``; with the default weight 0 it is also the fallback, so a capture
        replaces it wherever it sees."""
        rgb = np.broadcast_to(np.asarray(rgb, np.float32), (3,))
        faces = np.broadcast_to(rgb, (6, size, size, 3))
        return cls(faces, np.full((6, size, size), weight, np.float32), rgb)

    @classmethod
    def from_equirect(cls, image: np.ndarray, size: int, rotate_y: float = 0.0, weight: float = 1.0) -> CubeMap:
        """An equirect map (reflets' convention, bilinear like the GPU) resampled at the texel centres."""
        light = EnvironmentLight(type="environment", file=Path("captured"), rotate_y=rotate_y)
        faces = equirect_lookup(image, light, CubeMap.directions(size))
        return cls(faces, np.full((6, size, size), weight, np.float32))

    @staticmethod
    def directions(size: int) -> np.ndarray:
        """Unit world directions (6, N, N, 3) of the texel centres (read-only, cached per size)."""
        return _directions(size)


@lru_cache(maxsize=8)
def _directions(size: int) -> np.ndarray:
    coord = 2.0 * (np.arange(size) + 0.5) / size - 1.0
    t_c, s_c = np.meshgrid(coord, coord, indexing="ij")  # [j, i]: row j is t
    axis, s_vec, t_vec = FACE_FRAMES[:, 0], FACE_FRAMES[:, 1], FACE_FRAMES[:, 2]
    d = axis[:, None, None] + s_c[None, ..., None] * s_vec[:, None, None] + t_c[None, ..., None] * t_vec[:, None, None]
    d /= np.linalg.norm(d, axis=-1, keepdims=True)
    d.flags.writeable = False
    return d


def face_coordinates(dirs: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """GL's face selection: the face index (0..5) and (s, t) in [0, 1] of directions (..., 3) (ties go to x,
    then y)."""
    dirs = np.asarray(dirs, np.float64)
    major = np.argmax(np.abs(dirs), axis=-1)
    m_a = np.take_along_axis(dirs, major[..., None], axis=-1)[..., 0]
    face = 2 * major + (m_a < 0)
    frames = FACE_FRAMES[face]
    scale = 0.5 / np.maximum(np.abs(m_a), 1e-300)
    s = np.einsum("...k,...k->...", dirs, frames[..., 1, :]) * scale + 0.5
    t = np.einsum("...k,...k->...", dirs, frames[..., 2, :]) * scale + 0.5
    return face, s, t


# ------------------------------------------------------------------------------------------------ camera model


def _to_linear(frame: np.ndarray, response) -> tuple[np.ndarray, np.ndarray]:
    """The frame as linear float32 (H, W, 3) and its well-exposedness (H, W): for 8-bit frames smooth ramps
    on the darkest and the brightest channel (0 at the clipped codes 0 and 255, 1 over 24..231); float frames
    are linear already (1)."""
    frame = np.asarray(frame)
    if frame.ndim != 3 or frame.shape[2] != 3:
        raise ValueError(f"a frame is (H, W, 3), got {frame.shape}")
    if frame.dtype != np.uint8:
        linear = np.asarray(frame, np.float32)
        return linear, np.ones(frame.shape[:2], np.float32)
    codes = np.arange(256)
    table = decode_response(codes / 255.0, response).astype(np.float32)
    dark = _smoothstep(0.0, 24.0, codes).astype(np.float32)
    bright = _smoothstep(255.0, 231.0, codes).astype(np.float32)
    lowest = np.minimum(np.minimum(frame[..., 0], frame[..., 1]), frame[..., 2])
    highest = np.maximum(np.maximum(frame[..., 0], frame[..., 1]), frame[..., 2])
    well_exposed = np.maximum(dark[lowest] * bright[highest], CLIPPED_WEIGHT)
    return table[frame], well_exposed


def _apply_response(values, response, srgb_curve, exponent) -> np.ndarray:
    values = np.asarray(values, np.float64)
    if isinstance(response, str):
        if response == "srgb":
            return srgb_curve(values)
        if response == "linear":
            return values
        raise ValueError(f"unknown camera response {response!r}: 'srgb', 'linear' or a gamma number")
    return np.maximum(values, 0.0) ** exponent(float(response))


def decode_response(encoded, response="srgb") -> np.ndarray:
    """Camera codes in [0, 1] → linear: ``"srgb"`` (exact piecewise curve), ``"linear"``, or a gamma number γ
    (linear = code^γ)."""
    return _apply_response(encoded, response, srgb_to_linear, lambda gamma: gamma)


def encode_response(linear, response="srgb") -> np.ndarray:
    """Inverse of :func:`decode_response` (not clamped)."""
    return _apply_response(linear, response, linear_to_srgb, lambda gamma: 1.0 / gamma)


def quantise(linear, response="srgb") -> np.ndarray:
    """Linear radiance → the camera's 8-bit codes: clipped to [0, 1], encoded, rounded (a photograph)."""
    codes = encode_response(np.clip(linear, 0.0, 1.0), response) * 255.0
    return np.clip(np.round(codes), 0, 255).astype(np.uint8)


def _smoothstep(edge0: float, edge1: float, x) -> np.ndarray:
    t = np.clip((np.asarray(x, np.float64) - edge0) / (edge1 - edge0), 0.0, 1.0)
    return t * t * (3.0 - 2.0 * t)


def _monotone_radius(dist: np.ndarray) -> float:
    """The normalised radius up to which the radial distortion r (1 + k1 r² + k2 r⁴ + k3 r⁶) still grows: beyond
    it the polynomial folds back and would map points far outside the view into the image."""
    k1, k2, _, _, k3 = dist
    r = np.linspace(0.0, 10.0, 20001)
    slope = 1 + 3 * k1 * r**2 + 5 * k2 * r**4 + 7 * k3 * r**6
    bad = np.nonzero(slope <= 0)[0]
    return float(r[bad[0]]) if len(bad) else np.inf


def project(points_cam: np.ndarray, intrinsics: Intrinsics) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Pixel coordinates (OpenCV: pixel centres at integers) of camera-space points (M, 3), with the 5 OpenCV
    distortion coefficients (as ``cv2.projectPoints``; K's skew is honoured), and whether each is usable (in
    front of the camera, inside the distortion's monotone range)."""
    p = np.asarray(points_cam, np.float64)
    z = p[:, 2]
    front = z > 1e-12
    safe_z = np.where(front, z, 1.0)
    x, y = p[:, 0] / safe_z, p[:, 1] / safe_z
    dist = np.asarray(intrinsics.dist, np.float64).reshape(-1)
    if np.any(dist != 0):
        k1, k2, p1, p2, k3 = dist[:5]
        r2 = x * x + y * y
        front &= r2 <= _monotone_radius(dist[:5]) ** 2
        radial = 1 + r2 * (k1 + r2 * (k2 + r2 * k3))
        x, y = (
            x * radial + 2 * p1 * x * y + p2 * (r2 + 2 * x * x),
            y * radial + p1 * (r2 + 2 * y * y) + 2 * p2 * x * y,
        )
    K = intrinsics.K
    return K[0, 0] * x + K[0, 1] * y + K[0, 2], K[1, 1] * y + K[1, 2], front


# ----------------------------------------------------------------------------------------------------- capture


def capture(
    cube: CubeMap,
    frame: np.ndarray,
    intrinsics: Intrinsics,
    R: np.ndarray,
    t: np.ndarray,
    radius: float | None = None,
    response="srgb",
    exposure: float | None = None,
    mode: str = "blend",
    border: float = 0.1,
) -> float:
    """Reproject one camera frame into ``cube`` (in place) and return the frame's gain relative to the map.

    ``frame``: (H, W, 3) uint8 through the camera ``response`` ("srgb", "linear" or a gamma number), or float
    linear radiance. Pose: x_cam = R x_world + t (OpenCV axes). ``radius``: the environment lies on a sphere of
    that radius about the world origin (texel d sees the point R_s d: parallax correction); None: at infinity.
    ``exposure``: the frame's known gain relative to the map (linear factor); None estimates it — the median of
    frame / map luminance over texels both cover with a weight ≥ ½; the first frame (a map with no weight yet)
    sets the reference, gain 1. Blending divides the frame by its gain; too little overlap keeps the last gain.
    ``mode="blend"``: weighted running mean, weight = well-exposedness × border falloff (``border``: width of
    the falloff as a fraction of the image's smaller side); ``"overwrite"``: the document — every texel the
    frame sees takes its value, no weights, no exposure estimate.
    """
    if mode not in ("blend", "overwrite"):
        raise ValueError(f"unknown capture mode {mode!r}: 'blend' or 'overwrite'")
    cv2 = _aruco()
    linear, well_exposed = _to_linear(frame, response)
    height, width = linear.shape[:2]
    R = np.asarray(R, np.float64)
    t = np.asarray(t, np.float64).reshape(3)
    n = cube.size
    distant = radius is None or radius <= 0
    face_ids = _facing_faces(intrinsics, R, t, None if distant else float(radius))
    texels = (face_ids[:, None] * (n * n) + np.arange(n * n)).ravel()  # flat indices of those faces' texels
    dirs = CubeMap.directions(n)[face_ids].reshape(-1, 3)
    points_cam = dirs @ R.T if distant else (float(radius) * dirs) @ R.T + t
    u, v, usable = project(points_cam, intrinsics)
    inside = usable & (u >= -0.5) & (u <= width - 0.5) & (v >= -0.5) & (v <= height - 0.5)
    map_u = np.where(inside, u, -10.0).astype(np.float32).reshape(-1, n)
    map_v = np.where(inside, v, -10.0).astype(np.float32).reshape(-1, n)
    faces = cube.faces.reshape(-1, 3)
    weights = cube.weights.reshape(-1)

    if mode == "overwrite":
        sampled = cv2.remap(linear, map_u, map_v, cv2.INTER_LINEAR, borderMode=cv2.BORDER_REPLICATE).reshape(-1, 3)
        gain = 1.0 if exposure is None else float(exposure)
        faces[texels[inside]] = sampled[inside] / gain
        weights[texels[inside]] = 1.0
        cube.gain, cube.frames = gain, cube.frames + 1
        return gain

    # Weighted bilinear sampling that ignores clipped pixels: resample (w L, w) and divide.
    pixel_weight = well_exposed * _border_falloff(width, height, border)
    stack = np.concatenate([linear * pixel_weight[..., None], pixel_weight[..., None]], axis=2)
    sampled = cv2.remap(stack, map_u, map_v, cv2.INTER_LINEAR, borderMode=cv2.BORDER_CONSTANT, borderValue=0)
    sampled = sampled.reshape(-1, 4)
    hit = np.nonzero(sampled[:, 3] > 1e-6)[0]
    seen = texels[hit]
    frame_weight = sampled[hit, 3]
    frame_value = sampled[hit, :3] / frame_weight[:, None]
    map_value, map_weight = faces[seen], weights[seen]

    if exposure is not None:
        gain = float(exposure)
    elif not np.any(weights > 0):
        gain = 1.0
    else:
        gain = _relative_gain(frame_value, frame_weight, map_value, map_weight, cube.gain)

    total = map_weight + frame_weight
    faces[seen] = (map_value * map_weight[:, None] + frame_value * (frame_weight / gain)[:, None]) / total[:, None]
    weights[seen] = total
    cube.gain, cube.frames = gain, cube.frames + 1
    return gain


def _facing_faces(intrinsics: Intrinsics, R: np.ndarray, t: np.ndarray, radius: float | None) -> np.ndarray:
    """The faces the camera may see (a conservative cone test, so a frame costs its faces, not all six): a
    face's directions lie within acos(1/√3) of its axis, the view within the image corners' angle of the optical
    axis, and with a scene radius the ray to R_s d within asin(|c| / R_s) of d."""
    spread = np.arccos(1.0 / np.sqrt(3.0))
    dist = np.asarray(intrinsics.dist, np.float64).reshape(-1)
    if np.any(dist != 0):
        spread += np.arctan(_monotone_radius(dist[:5]))
    else:
        width, height = intrinsics.size
        corners = np.array(
            [[-0.5, -0.5, 1], [width - 0.5, -0.5, 1], [-0.5, height - 0.5, 1], [width - 0.5, height - 0.5, 1]]
        )
        normalised = np.linalg.solve(intrinsics.K, corners.T)
        spread += np.arctan(np.max(np.hypot(normalised[0], normalised[1]) / normalised[2]))
    if radius is not None:
        centre = np.linalg.norm(R.T @ t)
        spread += np.arcsin(centre / radius) if centre < radius else np.pi
    if spread >= np.pi:
        return np.arange(6)
    cos_angle = FACE_FRAMES[:, 0] @ R[2]  # R's third row: the optical axis in world coordinates
    return np.nonzero(cos_angle >= np.cos(spread) - 1e-9)[0]


def _relative_gain(frame_value, frame_weight, map_value, map_weight, previous: float) -> float:
    """Median of frame / map luminance over texels both cover well (weight ≥ ½: inside the image's flat part,
    well exposed); too little overlap keeps the previous frame's gain (auto-exposure drifts slowly)."""
    frame_lum = frame_value @ LUMINANCE
    map_lum = map_value @ LUMINANCE
    common = (frame_weight >= 0.5) & (map_weight >= 0.5) & (map_lum > 1e-6) & (frame_lum > 1e-6)
    if np.count_nonzero(common) < MIN_OVERLAP:
        return previous
    return float(np.median(frame_lum[common] / map_lum[common]))


@lru_cache(maxsize=8)
def _border_falloff_cached(width: int, height: int, border: float) -> np.ndarray:
    margin = max(border * min(width, height), 1e-6)
    x = np.minimum(np.arange(width) + 0.5, width - 0.5 - np.arange(width))
    y = np.minimum(np.arange(height) + 0.5, height - 0.5 - np.arange(height))
    falloff = np.minimum(y[:, None], x[None, :])
    out = _smoothstep(0.0, margin, falloff).astype(np.float32)
    out.flags.writeable = False
    return out


def _border_falloff(width: int, height: int, border: float) -> np.ndarray:
    """1 inside, easing to 0 over ``border`` × the smaller side toward the edges: seams between frames fade
    instead of showing the frames' edges."""
    return _border_falloff_cached(int(width), int(height), float(border))


# ---------------------------------------------------------------------------------------------- mips, lookups


def filled(cube: CubeMap, band_degrees: float = 10.0) -> CubeMap:
    """The map with its never-seen texels (weight 0) filled by elevation: each takes the weighted mean of the
    seen texels in its band of elevation, or of the nearest band seen — a sky varies mostly with elevation, and
    a handheld capture misses the zenith and the nadir (the document leaves them grey, 0.5, which lights the
    object and shades the ground as if the zenith were a mid-grey sky). Nothing seen: the map as it is."""
    seen = cube.weights > 0
    if not np.any(seen) or np.all(seen):
        return cube
    elevation = np.degrees(np.arcsin(np.clip(CubeMap.directions(cube.size)[..., 1], -1.0, 1.0)))
    bands = np.minimum(((elevation + 90.0) // band_degrees).astype(int), int(180 // band_degrees) - 1)
    count = int(bands.max()) + 1
    weight = np.bincount(bands[seen], cube.weights[seen], minlength=count)
    means = np.stack([np.bincount(bands[seen], cube.weights[seen] * cube.faces[seen][:, c], minlength=count)
                      for c in range(3)], axis=1)  # fmt: skip
    has = np.flatnonzero(weight > 0)
    nearest = has[np.argmin(np.abs(np.arange(count)[:, None] - has[None, :]), axis=1)]
    band_mean = means[nearest] / weight[nearest, None]
    out = CubeMap(cube.faces, cube.weights, cube.fallback, cube.gain, cube.frames)
    out.faces[~seen] = band_mean[bands[~seen]]
    return out


def _faces_of(cube) -> np.ndarray:
    return cube.faces if isinstance(cube, CubeMap) else np.asarray(cube, np.float32)


def mips(cube) -> list[np.ndarray]:
    """The box-filtered mip chain (2 × 2 texels per face, the document's; glGenerateMipmap's usual filter),
    level 0 first, down to 1 × 1; N must be a power of two."""
    level = _faces_of(cube)
    n = level.shape[1]
    if n < 1 or n & (n - 1):
        raise ValueError(f"mips need a power-of-two face size, got {n}")
    chain = [level]
    while level.shape[1] > 1:
        half = level.shape[1] // 2
        quads = level.reshape(6, half, 2, half, 2, -1)
        level = 0.25 * ((quads[:, :, 0, :, 0] + quads[:, :, 0, :, 1]) + (quads[:, :, 1, :, 0] + quads[:, :, 1, :, 1]))
        chain.append(level)
    return chain


def face_means(cube) -> np.ndarray:
    """The document's L̄_F: the coarsest mip, (6, 3) — each face's plain texel mean (not solid-angle weighted:
    corner texels subtend less than centre ones)."""
    return mips(cube)[-1].reshape(6, -1)


def specular_level(exponent, size: int) -> np.ndarray:
    """McGuire et al. 2013's mip level for a Phong exponent: λ = log2(N √3) − ½ log2(Ns + 1), clamped to
    [0, log2 N] (as textureLod clamps). N is the level-0 face width (the document's code reads textureSize of
    the cube map): at level λ a texel's mean solid angle 4π / (6 N²) · 4^λ equals ∫ cos^Ns dω = 2π / (Ns + 1)."""
    level = np.log2(size * np.sqrt(3.0)) - 0.5 * np.log2(np.asarray(exponent, np.float64) + 1.0)
    return np.clip(level, 0.0, np.log2(size))


@lru_cache(maxsize=16)
def _border_sources(size: int) -> np.ndarray:
    """For the (6, N + 2, N + 2) faces with a one-texel border: the flat index (into (6 N², C)) of the texel
    each border texel copies — GL's seamless filtering takes the neighbouring face's texel across the edge;
    found by selecting the face of the border texel's (extended-plane) direction. Corners: -1 (averaged)."""
    coord = 2.0 * (np.arange(-1, size + 1) + 0.5) / size - 1.0
    t_c, s_c = np.meshgrid(coord, coord, indexing="ij")
    axis, s_vec, t_vec = FACE_FRAMES[:, 0], FACE_FRAMES[:, 1], FACE_FRAMES[:, 2]
    d = axis[:, None, None] + s_c[None, ..., None] * s_vec[:, None, None] + t_c[None, ..., None] * t_vec[:, None, None]
    face, s, t = face_coordinates(d)
    i = np.clip(np.floor(s * size), 0, size - 1).astype(np.int64)
    j = np.clip(np.floor(t * size), 0, size - 1).astype(np.int64)
    sources = (face * size + j) * size + i
    for row in (0, -1):
        for col in (0, -1):
            sources[:, row, col] = -1
    sources.flags.writeable = False
    return sources


def _with_border(level: np.ndarray) -> np.ndarray:
    """(6, n + 2, n + 2, C): the level with its neighbours' texels around each face; each corner is the mean of
    the three texels that exist there (the GL specification's recommended rule)."""
    n = level.shape[1]
    flat = level.reshape(6 * n * n, -1)
    padded = flat[_border_sources(n)].astype(np.float64)
    for row, inner in ((0, 1), (-1, -2)):
        for col, inner_col in ((0, 1), (-1, -2)):
            padded[:, row, col] = (padded[:, row, inner_col] + padded[:, inner, col] + padded[:, inner, inner_col]) / 3
    return padded


def _bilinear(padded: np.ndarray, face, s, t) -> np.ndarray:
    n = padded.shape[1] - 2
    x = s * n + 0.5  # = s n − ½ in face texels, + 1 for the border
    y = t * n + 0.5
    x0 = np.clip(np.floor(x).astype(np.int64), 0, n)
    y0 = np.clip(np.floor(y).astype(np.int64), 0, n)
    fx, fy = (x - x0)[..., None], (y - y0)[..., None]
    top = padded[face, y0, x0] * (1 - fx) + padded[face, y0, x0 + 1] * fx
    bottom = padded[face, y0 + 1, x0] * (1 - fx) + padded[face, y0 + 1, x0 + 1] * fx
    return top * (1 - fy) + bottom * fy


def lookup(cube, dirs: np.ndarray, level=0.0, chain: list[np.ndarray] | None = None) -> np.ndarray:
    """NumPy reference of ``textureLod(samplerCube, dir, level)`` with LINEAR_MIPMAP_LINEAR filtering and
    seamless cube filtering: (..., 3) float64 for directions (..., 3). Across an edge the bilinear footprint
    takes the neighbouring face's texels, as GL_TEXTURE_CUBE_MAP_SEAMLESS does; at a cube corner the missing
    texel is the mean of the three others (the spec's recommendation; drivers may differ there). Levels clamp
    to [0, log2 N]; ``chain`` reuses precomputed :func:`mips`."""
    dirs = np.asarray(dirs, np.float64)
    face, s, t = face_coordinates(dirs)
    if chain is None:
        chain = mips(cube) if np.any(np.asarray(level) > 0) else [_faces_of(cube)]
    top = len(chain) - 1
    level = np.clip(np.broadcast_to(np.asarray(level, np.float64), face.shape), 0.0, top)
    lower = np.floor(level).astype(np.int64)
    upper = np.minimum(lower + 1, top)
    blend = level - lower
    out = np.zeros((*face.shape, chain[0].shape[-1]))
    for k in np.unique(np.concatenate([lower.ravel(), upper.ravel()])):
        weight = np.where(lower == k, 1.0 - blend, 0.0) + np.where(upper == k, blend, 0.0)
        use = weight > 0
        if np.any(use):
            out[use] += weight[use, None] * _bilinear(_with_border(chain[k]), face[use], s[use], t[use])
    return out


def to_equirect(cube, width: int, level: float | None = None) -> np.ndarray:
    """The cube map as a (width / 2, width) float32 equirect image in reflets' convention (``equirect.py``), for
    an ``environment`` light (rotate_y 0) and its prefiltered IBL. ``level`` None: the mip whose texels match
    the equirect's pixels at the equator (0 when the equirect is the finer)."""
    faces = _faces_of(cube)
    height = width // 2
    if level is None:
        level = max(0.0, float(np.log2(np.pi * faces.shape[1] / width)))
    u = (np.arange(width) + 0.5) / width
    v = (np.arange(height) + 0.5) / height
    dirs = equirect_direction(u[None, :], v[:, None])
    return lookup(faces, dirs, level).astype(np.float32)


# ------------------------------------------------------------------------------------------- synthetic frames


def environment_view(
    equirect_image: np.ndarray,
    intrinsics: Intrinsics,
    R: np.ndarray,
    t: np.ndarray,
    gain: float = 1.0,
    response="srgb",
    radius: float | None = None,
) -> np.ndarray:
    """The 8-bit photo (H, W, 3) a camera at pose (R, t) takes of an equirect environment (reflets' convention,
    bilinear): radiance × ``gain`` through the camera ``response``, clipped and quantised — capture's test data
    (generated: no real photographs offline). ``radius`` None: the environment is at infinity; else it lies on a
    sphere of that radius about the origin (the camera inside), each ray reading the map at its hit point's
    direction. The intrinsics' distortion is honoured (pixel rays undistorted by ``cv2.undistortPoints``)."""
    width, height = intrinsics.size
    u, v = np.meshgrid(np.arange(width, dtype=np.float64), np.arange(height, dtype=np.float64))
    K = intrinsics.K
    y = (v.ravel() - K[1, 2]) / K[1, 1]
    x = (u.ravel() - K[0, 2] - K[0, 1] * y) / K[0, 0]
    dist = np.asarray(intrinsics.dist, np.float64).reshape(-1)
    if np.any(dist != 0):
        cv2 = _aruco()
        criteria = (cv2.TERM_CRITERIA_COUNT | cv2.TERM_CRITERIA_EPS, 100, 1e-12)
        undistorted = cv2.undistortPoints(np.stack([x, y], axis=1)[:, None], np.eye(3), dist, criteria=criteria)
        x, y = undistorted[:, 0, 0], undistorted[:, 0, 1]
    R = np.asarray(R, np.float64)
    rays = np.stack([x, y, np.ones_like(x)], axis=1) @ R  # = (R^T ray)^T: world directions
    rays /= np.linalg.norm(rays, axis=1, keepdims=True)
    if radius is not None:
        centre = -R.T @ np.asarray(t, np.float64).reshape(3)
        if np.linalg.norm(centre) >= radius:
            raise ValueError("the camera must be inside the environment's sphere")
        b = rays @ centre
        s = -b + np.sqrt(b * b - centre @ centre + radius * radius)
        rays = (centre + s[:, None] * rays) / radius
    light = EnvironmentLight(type="environment", file=Path("synthetic"))
    radiance = equirect_lookup(equirect_image, light, rays) * gain
    return quantise(radiance, response).reshape(height, width, 3)
