"""Virtual objects composited into a photograph, lit by the captured environment, with their shadow on the real
ground (the board's plane y = 0), in one of two modes:

- ``"document"`` (004): the object shaded by the document's model (``document.py``: face-constant diffuse with
  W_F and P_V, mip-map specular), the ground multiplied by the sphere decomposition's shadow texture;
- ``"differential"`` (Debevec 1998, beyond the document): the local scene — the ground as a white Lambert
  plane, and the object — rendered by reflets' renderer under the captured map (its prefiltered IBL, occluded
  by its 32 environment shadow views), once with and once without the object; the photograph's ground is
  multiplied by their ratio (the additive difference ρ (R_with − R_without) with the ground's albedo ρ taken
  from the photograph itself: ρ = photo / R_without), and the object's pixels are its render with the ground
  removed (the captured map's lower hemisphere is the ground's light on it).

Both work on s × s subpixels (``supersample``): each subpixel is object (a ray cast against the meshes), ground
or untouched, and the photograph's pixel is used for every ground subpixel of it, so edges are antialiased.
Pixels that neither the object nor a changed ground value reaches keep the photograph's codes exactly.
"""

from __future__ import annotations

import tempfile
import time
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from ..errors import ArgumentError
from ..reference.geometry import MESHES, SceneGeometry
from ..renderer import Renderer
from ..scene import Scene, load_dict
from ..scene.camera import pixel_rays, projection_matrix
from ..scene.geometry import bounding_boxes, camera_range
from ..scene.model import Camera
from ..scene.transform import look_at
from . import capture
from .camera import Intrinsics, camera_fields
from .document import (
    ObjectGeometry,
    face_weights,
    phong_terms,
    render_object,
    sample_shadow,
    shadow_texture,
    vertex_diffuse,
)
from .occlusion import self_occlusion
from .spheres import decompose, surface_samples

MODES = ("differential", "document")
#: the differential mode's local ground spans this many times the object's footprint
GROUND_EXTENT = 6.0
#: a ground subpixel whose ratio is within this of 1 leaves its pixel untouched
UNCHANGED = 1e-6


def local_scene(
    objects: Scene | None,
    camera: dict,
    environment: str | Path,
    *,
    scale: float = 1.0,
    ground: tuple[float, float, float, float] | None = None,
    with_objects: bool = True,
) -> Scene:
    """``objects``' meshes and materials (their own lights dropped: the environment lights them) under an
    environment map, seen by ``camera`` (scene-camera fields), on an optional square Lambert ground
    (centre x, centre z, side, albedo) at y = 0."""
    data = {} if objects is None else objects.model_dump(exclude={"base_dir"}, exclude_none=True)
    meshes = data.get("mesh", []) if with_objects else []
    data["camera"] = camera
    if ground is not None:
        x, z, side, albedo = ground
        data["materials"] = {**data.get("materials", {}), "ar_ground": {"type": "lambert", "albedo": [albedo] * 3}}
        meshes = [{"shape": "plane", "size": [side, side], "material": "ar_ground",
                   "transform": {"translate": [x, 0.0, z]}}, *meshes]  # fmt: skip
    data["mesh"] = meshes
    data["light"] = [{"type": "environment", "file": str(Path(environment).resolve()), "scale": scale}]
    data.pop("background", None)
    return load_dict(data, base_dir=None if objects is None else objects.base_dir)


@dataclass
class Composite:
    image: np.ndarray  # uint8 (H, W, 3): the photograph with the objects and their shadow
    linear: np.ndarray  # float32 (H, W, 3): the same in the photograph's linear units
    coverage: np.ndarray  # float32 (H, W): the objects' share of each pixel
    changed: np.ndarray  # bool (H, W): pixels whose codes differ from the photograph's
    timings: dict[str, float] = field(default_factory=dict)  # milliseconds per stage


class Compositor:
    """The per-object work done once (meshes, the document's P_V and spheres), then ``__call__`` per frame."""

    def __init__(self, objects: Scene, mode: str = "differential", *, supersample: int = 2,
                 method: str | None = None, weights: str = "exact", spheres: int = 100, samples: int = 20000,
                 directions: int = 1000, response="srgb", seed: int = 0):  # fmt: skip
        if mode not in MODES:
            raise ArgumentError(f"unknown mode {mode!r}; allowed: {', '.join(MODES)}", field="mode")
        if not isinstance(supersample, int) or not 1 <= supersample <= 4:
            raise ArgumentError(f"supersample must be 1 to 4, got {supersample!r}", field="supersample")
        self.objects, self.mode, self.supersample = objects, mode, supersample
        self.method, self.weights, self.response = method, weights, response
        self.timings: dict[str, float] = {}  # the precomputation's, milliseconds
        t0 = time.perf_counter()
        self.geometry = ObjectGeometry.of(objects)
        self.rays = SceneGeometry(objects)
        lo, hi = self.geometry.positions.min(axis=0), self.geometry.positions.max(axis=0)
        self.footprint = (0.5 * (lo[0] + hi[0]), 0.5 * (lo[2] + hi[2]), float(max(hi[0] - lo[0], hi[2] - lo[2])))
        if mode == "document":
            for name in self.geometry.material:
                phong_terms(objects, name)  # an unsupported material fails before the precomputation
            g = self.geometry
            self.face_weights = face_weights(g, weights)
            self.timings["weights_ms"] = 1e3 * (time.perf_counter() - t0)
            t0 = time.perf_counter()
            self.occlusion = self_occlusion(g.positions, g.normals, g.faces, directions=directions)
            self.timings["occlusion_ms"] = 1e3 * (time.perf_counter() - t0)
            t1 = time.perf_counter()
            self.centres, self.radii = decompose(surface_samples(g.positions, g.faces, samples, seed), spheres, seed)
            self.timings["spheres_ms"] = 1e3 * (time.perf_counter() - t1)
        self._shadow = None  # (the map, its shadow texture): rebuilt when another map comes, as the document
        #: the differential mode's renderers for one map: (the map, the folder of its file, {render: Renderer});
        #: the next frame under the same map only moves their cameras (a probe, or a capture that has stopped)
        self._local: tuple | None = None

    def __call__(self, photo: np.ndarray, intrinsics: Intrinsics, R: np.ndarray, t: np.ndarray, cube,
                 exposure: float = 1.0) -> Composite:  # fmt: skip
        """Composite into ``photo`` (uint8 (H, W, 3), the camera's response) seen with pose (R, t); ``cube`` the
        captured environment in the units of a frame of gain 1, ``exposure`` the photograph's gain."""
        photo = np.asarray(photo)
        if photo.dtype != np.uint8 or photo.ndim != 3 or photo.shape[2] != 3:
            raise ArgumentError(f"the photograph must be 8-bit RGB, got {photo.dtype} {photo.shape}")
        height, width = photo.shape[:2]
        if (width, height) != tuple(intrinsics.size):
            raise ArgumentError(
                f"the photograph is {width}x{height}, the intrinsics are for {intrinsics.size[0]}x{intrinsics.size[1]}"
            )
        s = self.supersample
        timings: dict[str, float] = {}
        t0 = time.perf_counter()
        camera = {**camera_fields(intrinsics, R, t), "size": [width * s, height * s]}
        origin, dirs = pixel_rays(Camera(**camera))
        flat = dirs.reshape(-1, 3)
        hits = self.rays.intersect(np.broadcast_to(origin, flat.shape), flat)
        with np.errstate(divide="ignore", invalid="ignore"):
            t_ground = np.where(flat[:, 1] < 0, -origin[1] / flat[:, 1], np.inf)
        on_object = (hits.kind == MESHES) & np.isfinite(hits.t) & (hits.t <= t_ground)  # the real ground hides
        on_ground = np.isfinite(t_ground) & ~on_object
        ground_points = origin + t_ground[on_ground, None] * flat[on_ground]
        timings["rays_ms"] = 1e3 * (time.perf_counter() - t0)

        ratio = np.ones((len(flat), 3))
        if self.mode == "differential":
            object_radiance = self._differential(camera, cube, ratio, on_ground, ground_points, timings)
        else:  # RGBA: a subpixel the rasteriser leaves empty at a silhouette (a ray-cast tie) is not object
            rgba = self._document(camera, cube, ratio, on_ground, ground_points, timings).reshape(-1, 4)
            on_object &= rgba[:, 3] > 0.5
            object_radiance = rgba[:, :3]
        t1 = time.perf_counter()
        linear_photo = capture.decode_response(np.arange(256) / 255.0, self.response)[photo]  # a table of codes
        sub = np.repeat(np.repeat(linear_photo, s, axis=0), s, axis=1).reshape(-1, 3) * ratio
        sub[on_object] = exposure * object_radiance.reshape(-1, 3)[on_object]
        linear = sub.reshape(height, s, width, s, 3).mean(axis=(1, 3))
        coverage = on_object.reshape(height, s, width, s).mean(axis=(1, 3))
        touched = on_object | np.any(np.abs(ratio - 1.0) > UNCHANGED, axis=1)
        changed = touched.reshape(height, s, width, s).any(axis=(1, 3))
        image = photo.copy()
        image[changed] = capture.quantise(linear[changed], self.response)
        timings["composite_ms"] = 1e3 * (time.perf_counter() - t1)
        return Composite(image, linear.astype(np.float32), coverage.astype(np.float32), changed, timings)

    # ------------------------------------------------------------------------------------------------ modes
    def _differential(self, camera, cube, ratio, on_ground, ground_points, timings) -> np.ndarray:
        x, z, side = self.footprint
        ground = (x, z, GROUND_EXTENT * max(side, 1e-3), 1.0)
        renderers = self._local_renderers(camera, cube, ground, timings)
        timings["shading_ms"] = 0.0
        renders = {}
        for name, renderer in renderers.items():
            prepares = renderer.stats["prepares"]
            renders[name] = renderer.render().reshape(-1, 3).astype(np.float64)
            timings["shading_ms"] += renderer.stats["frame_ms"]
            if renderer.stats["prepares"] > prepares:  # the camera move needed a new preparation (shadow views)
                timings["prepare_ms"] += renderer.stats["prepare_ms"]
        half = 0.5 * ground[2]
        inside = (np.abs(ground_points[:, 0] - x) < half) & (np.abs(ground_points[:, 2] - z) < half)
        index = np.flatnonzero(on_ground)[inside]
        with_object, without = renders["with"][index], renders["without"][index]
        ratio[index] = np.where(without > 1e-12, with_object / np.maximum(without, 1e-12), 1.0)
        return renders["object"]

    def _local_renderers(self, camera, cube, ground, timings) -> dict:
        """The three renders of the local scene (the objects alone, the ground with and without them) for ``cube``:
        made (its map written, the prefiltering done) when the map is new, else only their cameras moved."""
        if self._local is not None and self._local[0] is cube:
            t0 = time.perf_counter()
            for renderer in self._local[2].values():
                renderer.set_camera(**camera)
            timings["environment_ms"], timings["prepare_ms"] = 0.0, 1e3 * (time.perf_counter() - t0)
            return self._local[2]
        self.release()
        t0 = time.perf_counter()
        folder = tempfile.TemporaryDirectory(prefix="reflets-ar-")
        environment = Path(folder.name) / "captured.npy"  # read again if a camera move makes a renderer prepare
        np.save(environment, capture.to_equirect(cube, 4 * capture._faces_of(cube).shape[1]))
        timings["environment_ms"] = 1e3 * (time.perf_counter() - t0)
        renderers = {}
        for name, kwargs in (("object", {"ground": None}), ("with", {"ground": ground}),
                             ("without", {"ground": ground, "with_objects": False})):  # fmt: skip
            scene = local_scene(self.objects, camera, environment, **kwargs)
            renderers[name] = Renderer(scene, method=self.method, size=tuple(camera["size"]))
        timings["prepare_ms"] = sum(r.stats["prepare_ms"] for r in renderers.values())
        self._local = (cube, folder, renderers)
        return renderers

    def release(self) -> None:
        """Free the differential mode's renderers and their map's file (the next frame makes them again)."""
        if self._local is not None:
            _, folder, renderers = self._local
            self._local = None
            for renderer in renderers.values():
                renderer.release()
            folder.cleanup()

    def _document(self, camera, cube, ratio, on_ground, ground_points, timings) -> np.ndarray:
        t0 = time.perf_counter()
        if self._shadow is None or self._shadow[0] is not cube:
            self._shadow = (cube, shadow_texture(self.centres, self.radii, cube))
            timings["shadow_texture_ms"] = 1e3 * (time.perf_counter() - t0)
        t1 = time.perf_counter()
        ratio[np.flatnonzero(on_ground)] = sample_shadow(*self._shadow[1], ground_points)[:, None]
        timings["shadow_ms"] = 1e3 * (time.perf_counter() - t1)
        t2 = time.perf_counter()
        diffuse = vertex_diffuse(self.geometry, self.objects, cube, self.occlusion, self.face_weights)
        cam = Camera(**camera)
        near, far = camera_range(cam, bounding_boxes([self.geometry.positions]))
        view_proj = projection_matrix(cam, *cam.size, near, far) @ look_at(cam.position, cam.look_at, cam.up)
        rgba = render_object(self.geometry, self.objects, cube, diffuse, view_proj, cam.position, tuple(cam.size))
        timings["shading_ms"] = 1e3 * (time.perf_counter() - t2)
        return rgba.astype(np.float64)
