"""``reflets.Renderer``: a scene prepared once, then drawn, edited and drawn again.

``reflets.render()`` builds every GPU resource, draws, and frees them: right for one image, wasteful for a frame
loop (the ltc Phong table fit alone is seconds). A ``Renderer`` keeps the prepared technique and applies edits
by what they invalidate:

- ``set_camera``: the camera only — techniques move it without preparing again (a uniform and the clip planes);
- ``set_light`` / ``set_material`` / ``set_transform``: the technique prepares again, but meshes come from a
  content-keyed cache (``reflets.scene.geometry``: only the edited mesh is rebuilt), programs from the program
  cache and fitted tables (LTC, scratch tables) from theirs, so the cost is the upload, not the build.

After any sequence of edits the image is the one-shot ``reflets.render()`` of the edited scene (tested). Progressive
methods (``mc``, ``scratches``) go on accumulating frames across ``render()`` calls while nothing changes, and
restart after an edit, a new seed or a new spp.

A frame stays on the GPU: ``render_texture()`` draws it and returns the texture (a window draws it as it is),
``render()`` adds the one read-back, ``read()`` reads the last frame. Nothing in a frame waits for the GPU:
``stats`` holds ``cpu_ms`` (the frame's passes submitted: Python and driver work), ``image_ms`` (its image formed:
a progressive frame added to the frame sum), ``read_ms`` (the read-back, when asked), ``frame_ms`` (the call's
wall clock) and ``gpu_ms`` (each pass's GPU time from timer queries read two frames late: a real GPU's; empty on
llvmpipe, whose queries mean nothing). On llvmpipe a draw that samples a texture still being drawn waits for it,
so ``image_ms`` there holds the wait for the frame's fragments (docs/performance.md).

A Renderer draws in the GL context of the thread that made it (``reflets.gpu.context``: one per thread), so it is
used from that thread; from another, ``render``, ``set_camera`` and ``release`` raise
:class:`~reflets.errors.ContextThreadError` naming the owning thread. ``reflets.render()`` works from any thread.
"""

from __future__ import annotations

import itertools
import time
from pathlib import Path
from typing import Any

import numpy as np

from ..diagnostics import warn_scene
from ..errors import ArgumentError, SceneError
from ..gpu.context import turn
from ..scene import Scene, load_dict

#: the transform fields ``set_transform`` takes
TRANSFORM_FIELDS = ("translate", "rotate", "scale")


class Renderer:
    """A prepared scene and its technique: ``render()`` per frame, ``set_*`` to edit, ``release()`` (or ``with``).

    Parameters are those of :func:`reflets.render`; ``method=None`` takes the scene's method or ``auto``.
    """

    def __init__(
        self, scene: Scene | str | Path | dict, method: str | None = None, size: tuple[int, int] | None = None, **params
    ):
        from ..arguments import as_scene, check_size
        from ..gpu import get_context
        from ..techniques import get_technique
        from .compose import DEFAULT_METHOD

        self.scene = as_scene(scene)
        self.size = check_size(size)
        self.method = method or self.scene.method or DEFAULT_METHOD
        self._ctx = get_context()
        self._stale = True  # the technique must prepare (again) before the next frame
        self._accumulated: tuple | None = None  # progressive: the (seed, spp) of the frames summed on the GPU
        self._frames = 0  # frames in the current image
        self._draw_ms = 0.0  # the last frame's draw, before any read-back
        self.stats: dict[str, Any] = {"prepare_ms": 0.0, "frame_ms": 0.0, "cpu_ms": 0.0, "image_ms": 0.0,
                                      "read_ms": 0.0, "gpu_ms": {}, "frames": 0, "prepares": 0}  # fmt: skip
        with turn(self._ctx):
            self._technique = get_technique(self.method)(self._ctx, **params)
            warn_scene(self.scene, self.method)
            self._prepare()

    # ------------------------------------------------------------------ frames
    def render(self, seed: int = 0, spp: int | None = None) -> np.ndarray:
        """The current image: float32 (H, W, 3), linear radiance, row 0 = top (``render_texture()``, then ``read()``:
        one read-back). A progressive method adds this call's frames to those of earlier calls with the same seed
        and spp since the last edit."""
        self.render_texture(seed, spp)
        return self.read()

    def read(self) -> np.ndarray:
        """The last frame's image read back (float32 (H, W, 3), row 0 = top): the one read-back of a frame."""
        if self._technique is None:
            raise ArgumentError("this Renderer was released", field="read")
        if self._frames == 0:
            raise ArgumentError("no frame to read: call render_texture() or render() first", field="read")
        self._check_thread()
        t0 = time.perf_counter()
        with turn(self._ctx):
            array = self._technique.image(self._frames).read()
        self.stats["read_ms"] = 1e3 * (time.perf_counter() - t0)
        self.stats["frame_ms"] = self._draw_ms + self.stats["read_ms"]
        return array

    def render_texture(self, seed: int = 0, spp: int | None = None):
        """The current image on the GPU, nothing read back and nothing waited for: a moderngl texture (W × H
        float32 RGBA, OpenGL's rows: bottom first) of this renderer's context, valid until the next frame or edit
        (a window draws it; ``render()`` reads it). Frames accumulate as with ``render()``."""
        from ..arguments import check_spp

        check_spp(spp)
        if self._technique is None:
            raise ArgumentError("this Renderer was released", field="render")
        self._check_thread()
        with turn(self._ctx):
            return self._draw(seed, spp)

    def _draw(self, seed: int, spp: int | None):
        if self._stale:
            self._prepare()
        t0 = time.perf_counter()
        key = (int(seed), spp)
        technique = self._technique
        first = self._frames if technique.progressive and self._accumulated == key else 0
        try:
            drawn = technique.accumulate(size=self.size, seed=seed, spp=spp, first_frame=first)
            texture = technique.image(first + drawn).color
        except BaseException:  # the GPU sum holds part of this call's frames: start again next time
            self._frames, self._accumulated = 0, None
            raise
        self._frames = first + drawn
        self._accumulated = key if technique.progressive else None
        timer = technique.timer
        self._draw_ms = 1e3 * (time.perf_counter() - t0)
        self.stats["frame_ms"] = self._draw_ms
        self.stats["cpu_ms"] = sum(itertools.islice(reversed(timer.cpu_ms), drawn))  # this call's passes submitted
        self.stats["image_ms"] = sum(itertools.islice(reversed(timer.image_ms), drawn))  # its images formed
        self.stats["gpu_ms"] = dict(timer.pass_gpu_ms)  # by pass, of a frame two frames back (none on llvmpipe)
        self.stats["read_ms"] = 0.0
        self.stats["frames"] = self._frames
        return texture

    def finish(self) -> None:
        """Wait until the GPU has drawn all that was submitted (a benchmark's frame time; a frame loop never needs
        it: the read-back or the window's swap orders the work)."""
        self._check_thread()
        with turn(self._ctx):
            self._ctx.finish()

    @property
    def accumulated_spp(self) -> int:
        """Samples per pixel of the last image: a progressive method's frames since the last edit × its samples
        per frame (``reflets.render(scene, spp=this)`` gives the same image), else the method's default."""
        technique = self._technique
        if technique is None:
            return 0
        if technique.progressive:
            return int(self.stats["frames"]) * technique.default_spp
        return technique.default_spp

    # ------------------------------------------------------------------ edits
    def set_camera(self, **fields: Any) -> None:
        """Change camera fields (``position``, ``look_at``, ``up``, ``fov_y``, ``size``)."""
        camera = {**self.scene.camera.model_dump(exclude_none=True), **fields}
        # the camera alone is validated (the loader's messages and limits): nothing else of the scene changed, and
        # re-checking its files at every move cost 1.2 of the helmet's 24 ms orbit frame on llvmpipe
        camera = load_dict({"camera": camera}, source="<edit>").camera
        scene = self.scene.model_copy(update={"camera": camera})
        if not self._stale:
            self._check_thread()
        self.scene = scene
        self._accumulated = None
        if not self._stale and not self._move_camera():
            self._stale = True

    def set_light(self, index: int, **fields: Any) -> None:
        """Change fields of ``scene.light[index]`` (any field of that light's type)."""
        data = self._scene_dict()
        self._check_index(index, data["light"], "light")
        data["light"][index] = {**data["light"][index], **fields}
        self._edited(data)

    def set_material(self, name: str, **fields: Any) -> None:
        """Change fields of the material called ``name`` (any field of its type; ``type`` replaces the model)."""
        data = self._scene_dict()
        if name not in data["materials"]:
            allowed = ", ".join(data["materials"]) or "none"
            raise SceneError(f"unknown material {name!r}; the scene has: {allowed}", field="materials")
        base = {} if "type" in fields else data["materials"][name]
        data["materials"][name] = {**base, **fields}
        self._edited(data)

    def set_transform(self, index: int, **fields: Any) -> None:
        """Change ``scene.mesh[index].transform`` (``translate``, ``rotate`` in degrees, ``scale``)."""
        unknown = sorted(set(fields) - set(TRANSFORM_FIELDS))
        if unknown:
            raise SceneError(f"unknown transform field {unknown[0]!r}; allowed: {', '.join(TRANSFORM_FIELDS)}")
        data = self._scene_dict()
        self._check_index(index, data["mesh"], "mesh")
        mesh = data["mesh"][index]
        mesh["transform"] = {**mesh.get("transform", {}), **fields}
        self._edited(data)

    # ------------------------------------------------------------------ lifetime
    def release(self) -> None:
        """Free the GPU resources (the renderer cannot draw afterwards)."""
        if self._technique is not None:
            self._check_thread()
            with turn(self._ctx):
                self._technique.release()
            self._technique = None

    def __enter__(self) -> Renderer:
        return self

    def __exit__(self, *exc) -> None:
        self.release()

    # ------------------------------------------------------------------ internals
    def _move_camera(self) -> bool:
        """The technique moves its camera without preparing again, or says it cannot (False)."""
        with turn(self._ctx):
            return self._technique.set_camera(self.scene.camera)

    def _check_thread(self) -> None:
        from ..gpu.context import check_thread

        check_thread(self._ctx, "this Renderer")

    def _prepare(self) -> None:
        t0 = time.perf_counter()
        self._technique.prepare(self.scene)
        self._stale = False
        self._accumulated = None
        self._frames = 0  # the image went with the technique's resources
        self.stats["prepare_ms"] = 1e3 * (time.perf_counter() - t0)
        self.stats["prepares"] += 1

    def _scene_dict(self) -> dict:
        return self.scene.model_dump(exclude={"base_dir"}, exclude_none=True)

    def _validated(self, data: dict) -> Scene:
        return load_dict(data, base_dir=self.scene.base_dir, source="<edit>")

    def _edited(self, data: dict) -> None:
        self.scene = self._validated(data)
        warn_scene(self.scene, self.method)
        self._stale = True
        self._accumulated = None

    @staticmethod
    def _check_index(index: int, items: list, what: str) -> None:
        if not isinstance(index, int) or not 0 <= index < len(items):
            raise SceneError(f"no {what}[{index}]: the scene has {len(items)} (0…{len(items) - 1})", field=what)
