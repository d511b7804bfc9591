"""Compact emitters of an environment map — a sun, a lamp — split off as lights (issue 29's first step).

A real HDR map puts most of its power in a few texels: kloppenheim_05's sun holds 65 % of the map's power in
2 × 10⁻⁴ sr. The split sum prefilters that sun into every lobe and reads it along one isotropic lobe about the
mirror direction, which is where its error lies (the issue measured 99 % of a sharp sphere's error in the sun's
highlight). Split off, the sun becomes an explicit light that every BRDF evaluates exactly and that casts a
shadow through the directional cascades; the smooth rest of the map is prefiltered as before.

The rule (:func:`find_emitters`), on luminance Y (Rec. 709) and texel solid angles ω:

1. the background level is the map's median luminance by solid angle, Ȳ; a texel is bright when Y > T = 64 Ȳ;
2. bright texels form regions by 8-connectivity (u wraps around);
3. a region is an emitter when it is compact — at most ``max_solid_angle`` (default 10⁻² sr: a cap of 3.2°) —
   and what it gives the light (step 4) is at least ``min_share`` (1 %) of the map's power Σ Y ω; at most
   ``max_count`` (8), the most powerful first;
4. each texel of an emitter keeps T of its luminance in the residual map (its colour scaled by T / Y): the map
   stays continuous at the region's edge, and the emitter's power is exactly what was taken, per channel —
   residual + emitters = the map, to rounding (tested). The emitter's direction is its power-weighted mean
   direction, its solid angle its texels'.

An emitter is rendered as a directional light of irradiance Σ (L − L_residual) ω (its power: the cap is small,
cos θ ≈ 1 over it), shadowed by the cascades — not yet as a cap of its angular size (no penumbra, a highlight
as sharp as a point's): ``EnvironmentLight.emitters``, "extract" by default ("keep": the whole map prefiltered).
The references always see the whole map.
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
#: the most emitters taken out of one map
MAX_COUNT = 8


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


def find_emitters(image: np.ndarray, rotate_y: float = 0.0, *, threshold: float = THRESHOLD,
                  max_solid_angle: float = MAX_SOLID_ANGLE, min_share: float = MIN_SHARE,
                  max_count: int = MAX_COUNT) -> tuple[list[MapEmitter], np.ndarray]:  # fmt: skip
    """The map's compact emitters (module docstring's rule) and the residual map (float32, the image's shape);
    ``rotate_y``: the environment light's rotation (the emitters' directions are in the world)."""
    img = np.asarray(image, np.float64)
    h, w, _ = img.shape
    omega = np.broadcast_to(row_solid_angles(h, w)[:, None], (h, w))
    lum = img @ LUMINANCE
    order = np.argsort(lum, axis=None)
    cumulative = np.cumsum(omega.ravel()[order])
    median = float(lum.ravel()[order][np.searchsorted(cumulative, cumulative[-1] / 2.0)])
    level = threshold * max(median, 1e-12)
    bright = lum > level
    residual = img.copy()
    if not bright.any():
        return [], residual.astype(np.float32)
    labels, _ = _regions(bright)
    total = float(np.sum(lum * omega))
    keep = np.where(bright, level / np.maximum(lum, 1e-300), 1.0)[..., None]
    taken = img * (1.0 - keep) * omega[..., None]  # per texel, per channel: what an emitter would take
    u = (np.arange(w) + 0.5) / w
    v = (np.arange(h) + 0.5) / h
    directions = equirect_direction(u[None, :], v[:, None])
    candidates = []
    for k in np.unique(labels[labels > 0]):
        region = labels == k
        solid = float(omega[region].sum())
        power = taken[region].sum(axis=0)
        if solid <= max_solid_angle and float(power @ LUMINANCE) >= min_share * total:
            candidates.append((float(power @ LUMINANCE), region, solid, power))
    candidates.sort(key=lambda c: -c[0])
    emitters = []
    for _, region, solid, power in candidates[:max_count]:
        weights = (taken[region] @ LUMINANCE)[:, None]
        local = np.sum(directions[region] * weights, axis=0)
        world = rotation_y(rotate_y) @ (local / np.linalg.norm(local))
        residual[region] = img[region] * keep[region]
        emitters.append(MapEmitter(tuple(float(c) for c in world), solid, tuple(float(c) for c in power),
                                   int(region.sum())))  # fmt: skip
    return emitters, residual.astype(np.float32)


@functools.lru_cache(maxsize=8)
def _split(path: Path, stamp: tuple, rotate_y: float) -> tuple[tuple[MapEmitter, ...], np.ndarray]:
    from ..imageio import read_image

    emitters, residual = find_emitters(read_image(path), rotate_y)
    residual.flags.writeable = False
    return tuple(emitters), residual


def split_map(scene: Scene) -> tuple[tuple[MapEmitter, ...], np.ndarray] | None:
    """The scene's environment map split (its emitters, and the residual map × the light's ``scale``), or None
    when it has no environment or keeps it whole (``emitters = "keep"``)."""
    light = scene.environment
    if light is None or light.emitters != "extract":
        return None
    path = scene.resolve(light.file)
    emitters, residual = _split(path, tuple(file_stamp(path) or ()), float(light.rotate_y))
    return emitters, residual * np.float32(light.scale)


def with_map_emitters(scene: Scene) -> Scene:
    """The scene the GPU renders: an environment with ``emitters = "extract"`` gives its compact emitters as
    directional lights (after the scene's own lights: their indices stay), shadowed as the map is; the map itself
    is then read as its residual (``load_environment(…, residual=True)``)."""
    split = split_map(scene)
    if not split:
        return scene
    light = scene.environment
    lights = [DirectionalLight(type="directional", direction=tuple(-c for c in emitter.direction),
                               irradiance=tuple(c * light.scale for c in emitter.power), shadows=light.shadows)
              for emitter in split[0]]  # fmt: skip
    return scene.model_copy(update={"light": [*scene.light, *lights]})
