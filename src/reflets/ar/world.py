"""A synthetic AR world — the test data and the ground truth of the compositing (real photographs are not
available offline: these are generated, and say so). The marker board printed on a grey floor (y = 0) under a
distant environment map, seen by cameras with known poses, path traced by Mitsuba 3 (two bounces: the ground
truth includes the light the floor and a virtual object exchange, which no real-time method here models). The
same world with the virtual objects really in it is what a composite should look like."""

from __future__ import annotations

import tempfile
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from ..imageio import write_image
from ..reference.mitsuba_bridge import _transform, mitsuba_module, to_mitsuba_dict
from ..scene import Scene
from .board import Board
from .composite import local_scene

#: the world's default sky: the procedural sky with a sun of the demo scenes (tools/make_sky.py)
SKY = Path(__file__).resolve().parents[1] / "data" / "environments" / "sky.hdr"
#: the printed board's paper and ink (linear albedo)
PAPER, INK = 0.8, 0.03
#: the board's print sits this far above the floor (no coplanar surfaces for the path tracer)
PRINT_HEIGHT = 2e-4


@dataclass
class World:
    board: Board
    environment: Path  # an equirect HDR map (reflets' convention)
    environment_scale: float = 1.0
    floor_albedo: float = 0.3
    floor_size: float = 20.0

    def scene(self, camera: dict, objects: Scene | None = None) -> Scene:
        """The world (floor, environment) with ``objects``' meshes and materials, as a reflets scene seen by
        ``camera`` (scene-camera fields); the printed board is added when it is rendered."""
        floor = (0.0, 0.0, self.floor_size, self.floor_albedo)
        return local_scene(objects, camera, self.environment, scale=self.environment_scale, ground=floor)

    def render(self, camera: dict, objects: Scene | None = None, spp: int = 64, seed: int = 0) -> np.ndarray:
        """Linear radiance (H, W, 3) float32 of the world seen by ``camera`` (Mitsuba 3, path tracing)."""
        mi = mitsuba_module()
        scene = self.scene(camera, objects)
        with tempfile.TemporaryDirectory(prefix="reflets-ar-world-") as tmp:
            spec = to_mitsuba_dict(scene, Path(tmp), spp=spp, seed=seed)
            spec["integrator"] = {"type": "path", "max_depth": 3, "hide_emitters": False}
            spec["ar_board"] = self._board_shape(Path(tmp))
            image = np.array(mi.render(mi.load_dict(spec), spp=int(spp), seed=int(seed)), dtype=np.float32)
        return np.ascontiguousarray(image[..., :3])

    def _board_shape(self, workdir: Path) -> dict:
        """A rectangle over the board's image, textured with its paper and ink. Mitsuba's rectangle spans
        [−1, 1]² with uv = (local + 1) / 2 and its bitmap's row 0 at v = 0; local y maps to −z here (a proper
        rotation keeps the normal up), so the image is written bottom row first."""
        top, to_pixel = self.board.image()
        height, width = top.shape
        lo = -to_pixel[:, 2] / to_pixel[0, 0]  # board (x, z) of the image's top-left corner
        hi = lo + np.array([width, height]) / to_pixel[0, 0]
        albedo = INK + (PAPER - INK) * (top[::-1].astype(np.float32) / 255.0)
        path = write_image(workdir / "board.exr", np.repeat(albedo[..., None], 3, axis=2))
        centre, half = 0.5 * (lo + hi), 0.5 * (hi - lo)
        to_world = np.array(
            [[half[0], 0, 0, centre[0]], [0, 0, 1, PRINT_HEIGHT], [0, -half[1], 0, centre[1]], [0, 0, 0, 1]],
            np.float64,
        )
        return {
            "type": "rectangle",
            "to_world": _transform(to_world),
            "bsdf": {"type": "diffuse", "reflectance": {"type": "bitmap", "filename": str(path), "raw": True}},
        }
