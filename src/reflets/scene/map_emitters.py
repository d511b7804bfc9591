"""Compact emitters of an environment map — a sun, a lamp — split off as lights (issue 29's first step).

A real HDR map puts most of its power in a few texels: kloppenheim_05's sun holds 65 % of the map's power in 2.4 ×
10⁻³ sr (its halo included). The split sum prefilters that sun into every lobe and reads it along one isotropic lobe
about the mirror direction, which is where its error lies (the issue measured 99 % of a sharp sphere's error in the
sun's highlight). Split off, the sun becomes an explicit light that every BRDF evaluates exactly and that casts a
shadow through the directional cascades; the smooth rest of the map is prefiltered as before.

The rule (:func:`find_emitters`), on luminance Y (Rec. 709) and texel solid angles ω:

1. the background level is the map's median luminance by solid angle, Ȳ; a texel is bright when Y > T = 64 Ȳ;
2. bright texels form regions by 8-connectivity (u wraps around);
3. a region is an emitter when it is compact — at most ``max_solid_angle`` (default 10⁻² sr: a cap of 3.2°) —
   and what it gives the light (step 4) is at least ``min_share`` (1 %) of the map's power Σ Y ω; at most
   ``max_count`` (32), the most powerful first;
4. each texel of an emitter keeps T of its luminance in the residual map (its colour scaled by T / Y): the map
   stays continuous at the region's edge, and the emitter's power is exactly what was taken, per channel —
   residual + emitters = the map, to rounding (tested). The emitter's direction is its power-weighted mean
   direction, its solid angle its texels'.

An emitter is rendered as a directional light of irradiance Σ (L − L_residual) ω (its power: the cap is small,
cos θ ≈ 1 over it), shadowed — the two brightest through cascades, the others (a night map's lamps) through one
view of the whole scene each (``shadows.CASCADED_LIGHTS``) — not yet as a cap of its angular size (no penumbra,
a highlight as sharp as a point's): ``EnvironmentLight.emitters``, "extract" by default ("keep": the whole map
prefiltered). The references always see the whole map.
"""

from __future__ import annotations

import functools
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from ..cache import file_stamp
from ..equirect import equirect_direction, rotation_y, row_solid_angles
from .lightmask import LUMINANCE
from .model import DirectionalLight, Scene

#: a texel is bright above this many times the map's median luminance
THRESHOLD = 64.0
#: the largest solid angle of a compact emitter (sr): a cap of 3.2°
MAX_SOLID_ANGLE = 1e-2
#: the smallest share of the map's power an emitter holds
MIN_SHARE = 0.01
#: the most emitters taken out of one map (a night map's lamps: each is a light of the frame)
MAX_COUNT = 32


@dataclass(frozen=True)
class MapEmitter:
    """A compact emitter taken out of a map: the world direction towards it, its solid angle (sr), its power per
    channel (∫ of the radiance taken out over its texels, W m⁻² at normal incidence) and its texel count."""

    direction: tuple[float, float, float]
    solid_angle: float
    power: tuple[float, float, float]
    texels: int

    @property
    def radius(self) -> float:
        """The half-angle (radians) of the cap of its solid angle."""
        return float(np.arccos(1.0 - self.solid_angle / (2.0 * np.pi)))


def _regions(bright: np.ndarray) -> tuple[np.ndarray, int]:
    """Labels (0: none) of the 8-connected regions of a mask, merged across the u seam (first and last columns)."""
    from scipy.ndimage import label

    labels, count = label(bright, structure=np.ones((3, 3), bool))
    parent = np.arange(count + 1)

    def root(k: int) -> int:
        while parent[k] != k:
            parent[k] = parent[parent[k]]
            k = parent[k]
        return k

    h = bright.shape[0]
    for row in range(h):
        left = labels[row, 0]
        if not left:
            continue
        for other in labels[max(row - 1, 0) : row + 2, -1]:  # the last column's neighbours across the seam
            if other:
                a, b = root(int(left)), root(int(other))
                parent[max(a, b)] = min(a, b)
    roots = np.array([root(k) for k in range(count + 1)])
    return roots[labels], count


def find_emitters(image: np.ndarray, *, threshold: float = THRESHOLD, max_solid_angle: float = MAX_SOLID_ANGLE,
                  min_share: float = MIN_SHARE, max_count: int = MAX_COUNT) -> tuple[list[MapEmitter], np.ndarray]:
    """The map's compact emitters (module docstring's rule; directions in the map's own frame: ``map_emitters``
    turns them by the light's ``rotate_y``) and the residual map (float32, the image's shape). A map whose median
    is 0 (a black ground over half the sphere) has every lit texel bright: one region too wide, none taken."""
    img = np.asarray(image, np.float32)
    h, w, _ = img.shape
    omega = np.broadcast_to(row_solid_angles(h, w)[:, None], (h, w))
    lum = img.astype(np.float64) @ LUMINANCE
    order = np.argsort(lum, axis=None)
    cumulative = np.cumsum(omega.ravel()[order])
    median = float(lum.ravel()[order][np.searchsorted(cumulative, cumulative[-1] / 2.0)])
    level = threshold * max(median, 1e-12)
    bright = lum > level
    residual = img.copy()
    if not bright.any():
        return [], residual
    labels, count = _regions(bright)
    rows, cols = np.nonzero(bright)  # per bright texel: what an emitter would take, W m⁻² per channel
    keep = (level / lum[rows, cols])[:, None]
    taken = img[rows, cols].astype(np.float64) * (1.0 - keep) * omega[rows, cols][:, None]
    region = labels[rows, cols]
    solid = np.bincount(region, omega[rows, cols], minlength=count + 1)  # one pass over the bright texels
    power = np.stack([np.bincount(region, taken[:, c], minlength=count + 1) for c in range(3)], axis=-1)
    given = power @ LUMINANCE
    total = float(np.sum(lum * omega))
    chosen = [k for k in np.argsort(-given) if k and solid[k] <= max_solid_angle and given[k] >= min_share * total]
    directions = equirect_direction((cols + 0.5) / w, (rows + 0.5) / h)
    emitters = []
    for k in chosen[:max_count]:
        mine = region == k
        local = np.sum(directions[mine] * (taken[mine] @ LUMINANCE)[:, None], axis=0)
        residual[rows[mine], cols[mine]] = img[rows[mine], cols[mine]] * keep[mine].astype(np.float32)
        emitters.append(MapEmitter(tuple(float(c) for c in local / np.linalg.norm(local)), float(solid[k]),
                                   tuple(float(c) for c in power[k]), int(mine.sum())))  # fmt: skip
    return emitters, residual


@functools.lru_cache(maxsize=4)
def _split(path: Path, stamp: tuple) -> tuple[tuple[MapEmitter, ...], np.ndarray]:
    """A map file's emitters in its own frame and its residual (remembered by file: found once a map)."""
    from ..imageio import read_image

    emitters, residual = find_emitters(read_image(path))
    residual.flags.writeable = False
    return tuple(emitters), residual


def _split_of(scene: Scene) -> tuple[tuple[MapEmitter, ...], np.ndarray] | None:
    light = scene.environment
    if light is None or light.emitters != "extract":
        return None
    path = scene.resolve(light.file)
    return _split(path, tuple(file_stamp(path) or ()))


def map_emitters(scene: Scene) -> tuple[MapEmitter, ...]:
    """The compact emitters of the scene's environment map, in the world (turned by the light's ``rotate_y``); none
    when it has no environment or keeps it whole (``emitters = "keep"``)."""
    split = _split_of(scene)
    turn = rotation_y(scene.environment.rotate_y) if split else None
    return tuple(MapEmitter(tuple(float(c) for c in turn @ np.asarray(e.direction)), e.solid_angle, e.power, e.texels)
                 for e in (split[0] if split else ()))  # fmt: skip


def split_map(scene: Scene) -> tuple[tuple[MapEmitter, ...], np.ndarray] | None:
    """The scene's environment map split — its emitters (:func:`map_emitters`) and the residual map × the light's
    ``scale`` — or None when it has no environment or keeps it whole."""
    split = _split_of(scene)
    return None if split is None else (map_emitters(scene), split[1] * np.float32(scene.environment.scale))


def is_split(scene: Scene) -> bool:
    """Has the scene's environment had its emitters made lights (:func:`with_map_emitters`)?"""
    return scene.environment is not None and scene.environment._split


def with_map_emitters(scene: Scene) -> Scene:
    """The scene the GPU renders (every technique's ``prepare`` asks for it): an environment with ``emitters =
    "extract"`` gives its compact emitters as directional lights (after the scene's own lights: their indices stay)
    and is marked split — the prepared scene then lights by its residual map and shows the whole (one made from a
    scene without this keeps the whole map, its sun prefiltered). Idempotent."""
    emitters = () if is_split(scene) else map_emitters(scene)
    if not emitters:
        return scene
    light = scene.environment
    marked = light.model_copy()
    marked._split = True
    lights = [marked if item is light else item for item in scene.light]
    suns = [DirectionalLight(type="directional", direction=tuple(-c for c in emitter.direction),
                             irradiance=tuple(c * light.scale for c in emitter.power), shadows=light.shadows)
            for emitter in emitters]  # fmt: skip
    return scene.model_copy(update={"light": [*lights, *suns]})
