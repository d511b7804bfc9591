"""What the window and the notebook widget share: the persistent renderer, the camera, the selection, the edits,
the accumulation and the overlays, driven by events.

An event is a dict with a ``type`` (JSON-able: a script replays a list of them, ``reflets view --script``):

- raw input, as the window and the widget report it: ``pointer`` (``action`` down / move / up, ``x``, ``y`` in
  pixels from the top-left, ``button`` left / right / middle, ``shift``), ``wheel`` (``dy`` notches), ``key``
  (``key``: r reset, f frame, w a s d q e fly, l fly mode, arrows orbit). A left drag orbits (in fly mode:
  turns the view about the eye), a right or middle drag pans,
  a shift + left drag moves the selection (a light, or a mesh's transform) in the view plane, a click (down and
  up within 3 pixels) picks what the pixel shows;
- camera: ``orbit`` (``dx``, ``dy`` degrees), ``look`` (the same about the eye), ``pan`` (``dx``, ``dy``
  pixels), ``zoom`` (``factor``), ``fly`` (``forward``, ``right``, ``up`` scene units), ``fly_mode`` (``on``),
  ``reset`` (the scene's camera), ``frame`` (the selection, or the whole scene);
- selection and edits (what the panels' widgets send): ``pick`` (``x``, ``y``), ``select`` (``mesh`` or
  ``light`` index, or neither: nothing), ``material`` (``fields``; ``name``, default the selected mesh's
  material), ``light`` (``fields``; ``index``, default the selected light), ``move`` (``offset`` [x, y, z]:
  the selected light, or the selected mesh's translation), ``transform`` (``fields``; ``index``, default the
  selected mesh);
- highlight editing: ``paint`` (``tool`` bend / expand / stencil / light or null, ``radius``: the selected
  mesh's field is painted by left drags, the stroke solved between frames; the light tool moves the light),
  ``stroke`` (``centre``, ``stroke`` direction, ``tool``,
  ``radius``: one stroke), ``undo``, ``redo``, ``show_highlights`` (``on``: the potential highlight curves,
  a line integral convolution of ℓ, over the selected mesh);
- rendering: ``method`` (``name``, optional ``params``), ``shadows`` (``on``: every light's), ``exposure``
  (``stops``), ``tonemap`` (``mode``), ``reference`` (``spp``: start computing the reference of this view in
  the background), ``show`` (``mode``: image / reference / error).

Every event is checked before it is applied (viewer/events.py: a model per type, with the fields' types and
ranges; the scene's indices and names): an unknown event or field, or a value out of range, is an
:class:`ArgumentError` naming it, and changes nothing (one the renderer refuses as it applies it leaves the camera
as it was).
"""

from __future__ import annotations

import math
import statistics
import time
import warnings
from pathlib import Path

import numpy as np

from ..errors import ArgumentError, RefletsError, RefletsWarning
from ..imageio import tonemap
from ..metrics import relmse
from .camera import OrbitCamera
from .painting import Painting
from .reference import ReferenceJob

#: a pointer that moves less than this between down and up is a click
CLICK_PIXELS = 3.0
#: a click this close to a point light's marker selects the light
MARKER_PIXELS = 8.0
ORBIT_DEGREES_PER_PIXEL = 0.3
WHEEL_ZOOM = 1.1
#: a fly key moves this fraction of the scene's radius
FLY_STEP = 0.05
ORBIT_KEY_DEGREES = 5.0
#: frame times kept for the overlay's median
HISTORY = 60


class ViewerController(Painting):
    """A scene in a persistent renderer, and the state a viewer shows of it (see the module docstring; highlight
    editing: ``Painting``)."""

    def __init__(self, scene, method: str | None = None, size: tuple[int, int] | None = None, **params):
        from ..arguments import as_scene
        from ..renderer import Renderer

        scene = as_scene(scene)
        self.params = dict(params)
        self.renderer = Renderer(scene, method=method, size=size, **params)
        self.size = tuple(size or scene.camera.size)
        self.home = scene.camera.model_copy(update={"size": self.size})  # what reset goes back to
        self.camera = OrbitCamera.from_camera(self.home)
        #: ("mesh", i), ("light", i) or None
        self.selection: tuple[str, int] | None = None
        self.exposure, self.tonemap_mode, self.show = 0.0, "srgb", "image"
        #: a left drag turns the view about the eye (fly) instead of orbiting the target
        self.fly_mode = False
        #: paint mode (highlight editing): the tool a left drag on the selected mesh applies, its brush radius
        self.paint_tool: str | None = None
        self.paint_radius = 0.0
        self._paint = None  # the EditSession of the painted mesh
        self._pending_stroke: dict | None = None  # applied before the next frame (the solver between frames)
        self._fields_dir: Path | None = None  # the painted fields' files (removed by release)
        self.last_hit: np.ndarray | None = None
        #: blend the selected mesh's potential highlight curves (a line integral convolution of ℓ) into the view
        self.show_highlights = False
        self.texture = None  # the last frame, on the GPU
        self._image: np.ndarray | None = None  # … and read back, once asked for
        self.frame_ms: list[float] = []
        self.reference: ReferenceJob | None = None
        self._pointer: dict | None = None
        self._geometry = None  # for picking: built on the first click, dropped by an edit

    # ------------------------------------------------------------------ state
    @property
    def scene(self):
        return self.renderer.scene

    @property
    def method(self) -> str:
        return self.renderer.method

    def status(self) -> dict:
        """What the overlay shows: method, median frame time, accumulated frames, selection, reference."""
        from ..gpu import gl_info

        status = {
            "method": self.method,
            "frame_ms": statistics.median(self.frame_ms) if self.frame_ms else float("nan"),
            "cpu_ms": float(self.renderer.stats["cpu_ms"]),  # the last frame's submission
            "gpu_ms": sum(self.renderer.stats["gpu_ms"].values()) or None,  # its passes (a real GPU's queries)
            "frames": int(self.renderer.stats["frames"]),
            "spp": self.renderer.accumulated_spp,
            "renderer": gl_info()["renderer"],
            "selection": self.selection_label(),
            "show": self.show,
        }
        if self.reference is not None:
            status["reference_progress"] = self.reference.progress
            if self.reference.error:
                status["reference_error"] = self.reference.error
            if self.reference.image is not None and self.image is not None:
                key = (id(self.image), id(self.reference.image))  # the panels ask every frame: once per pair
                if getattr(self, "_relmse_key", None) != key:
                    self._relmse_key, self._relmse = key, relmse(self.image, self.reference.image)
                status["relmse"] = self._relmse
        return status

    def selection_label(self) -> str:
        if self.selection is None:
            return "nothing"
        kind, index = self.selection
        if kind == "mesh":
            mesh = self.scene.mesh[index]
            what = mesh.name or getattr(mesh, "shape", None) or Path(str(mesh.file)).name
            return f"mesh[{index}] ({what}, {mesh.material})"
        return f"light[{index}] ({self.scene.light[index].type})"

    # ------------------------------------------------------------------ frames
    def draw(self):
        """The next frame, on the GPU (returned: a texture of the renderer's context, OpenGL's rows); nothing is
        read back until ``image`` is asked for. A progressive method accumulates while nothing changes."""
        if self._pending_stroke is not None:
            stroke, self._pending_stroke = self._pending_stroke, None
            try:
                self._on_stroke(**stroke)
            except RefletsError as exc:  # a drag the brush cannot take (along the normal, off the mesh): skipped
                warnings.warn(f"the paint stroke is skipped: {exc.message}", RefletsWarning, stacklevel=2)
        t = time.perf_counter()
        self.texture = self.renderer.render_texture()
        self._image = None
        self.frame_ms = [*self.frame_ms[-(HISTORY - 1) :], 1e3 * (time.perf_counter() - t)]
        return self.texture

    def render(self) -> np.ndarray:
        """The next frame as an array (float32 HDR, row 0 at the top): ``draw()``, then one read-back."""
        self.draw()
        return self.image

    @property
    def image(self) -> np.ndarray | None:
        """The last frame (float32 HDR, row 0 at the top), read back on first use; None before any frame."""
        if self._image is None and self.texture is not None:
            self._image = self.renderer.read()
        return self._image

    def shown_texture(self):
        """The frame's texture when the view shows it as drawn (no reference, error map or highlight curves over
        it: those are made on the CPU), else None."""
        if self.texture is None:
            self.draw()
        if self.show_highlights or (self.show != "image" and self.reference is not None
                                    and self.reference.image is not None):  # fmt: skip
            return None
        return self.texture

    def shown(self) -> np.ndarray:
        """The HDR image the view shows: the frame, the reference, or the error map (|frame − reference| /
        (reference + 0.01), in the red channel)."""
        if self.image is None:
            self.render()
        if self.show_highlights:
            curves, mask = self.highlight_curves()
            if mask.any():
                lic = curves[..., None].astype(np.float32)  # streaks modulate the frame, and show on dark parts
                shaded = self.image * (0.4 + 0.6 * lic) + 0.06 * lic
                return np.where(mask[..., None], shaded, self.image)
        if self.show == "image" or self.reference is None or self.reference.image is None:
            return self.image
        if self.show == "reference":
            return self.reference.image
        err = np.abs(self.image - self.reference.image).mean(-1) / (self.reference.image.mean(-1) + 0.01)
        return np.stack([err, np.zeros_like(err), np.zeros_like(err)], axis=-1).astype(np.float32)

    def snapshot(self) -> np.ndarray:
        """What the view shows, tone mapped: uint8 (H, W, 3)."""
        return tonemap(self.shown(), self.exposure, self.tonemap_mode)

    # ------------------------------------------------------------------ events
    def handle(self, event: dict) -> None:
        """Apply one event (see the module docstring), checked first (viewer/events.py: the models a script is
        loaded with, and the scene's indices and names): refused there, it changes nothing; refused as it applies, the
        camera is left as it was."""
        import dataclasses

        from .events import check_in_scene, parse_event

        event = parse_event(event)
        check_in_scene(event, self.scene, self.size)
        camera = dataclasses.replace(self.camera)
        try:
            getattr(self, f"_on_{event.type}")(**event.arguments())
        except RefletsError:
            self.camera = camera  # a move the scene's camera refuses (too far away) is undone
            raise

    def replay(self, events: list[dict], render_each: bool = False) -> None:
        for event in events:
            self.handle(event)
            if render_each:
                self.render()

    # camera
    def _on_orbit(self, dx: float = 0.0, dy: float = 0.0) -> None:
        self.camera.orbit(dx, dy)
        self._camera_moved()

    def _on_look(self, dx: float = 0.0, dy: float = 0.0) -> None:
        self.camera.look(dx, dy)
        self._camera_moved()

    def _on_fly_mode(self, on: bool) -> None:
        self.fly_mode = bool(on)

    def _on_pan(self, dx: float = 0.0, dy: float = 0.0) -> None:
        self.camera.pan(dx, dy)
        self._camera_moved()

    def _on_zoom(self, factor: float) -> None:
        self.camera.zoom(factor)
        self._camera_moved()

    def _on_fly(self, forward: float = 0.0, right: float = 0.0, up: float = 0.0) -> None:
        self.camera.fly(forward, right, up)
        self._camera_moved()

    def _on_reset(self) -> None:
        self.camera = OrbitCamera.from_camera(self.home)
        self._camera_moved()

    def _on_frame(self) -> None:
        centre, radius = self._bounds(self.selection)
        self.camera.frame(centre, radius)
        self._camera_moved()

    # raw input
    def _on_pointer(self, action: str, x: float, y: float, button: str = "left", shift: bool = False) -> None:
        if action == "down":
            self._pointer = {"x": x, "y": y, "start": (x, y), "button": button, "shift": shift, "moved": 0.0}
            if self.paint_tool is not None and button == "left" and not shift:  # a stroke starts on the mesh?
                hit = self.pick(x, y)
                self._pointer["surface"] = self.last_hit if hit == ("mesh", self._paint.index) else None
        elif action == "move" and self._pointer is not None:
            p = self._pointer
            dx, dy = x - p["x"], y - p["y"]
            p["x"], p["y"] = x, y
            p["moved"] = max(p["moved"], math.hypot(x - p["start"][0], y - p["start"][1]))
            if p["moved"] < CLICK_PIXELS:
                return
            if p["button"] == "left" and self.paint_tool is not None and p.get("surface") is not None:
                self._paint_drag(p, x, y)
            elif p["button"] == "left" and p["shift"] and self.selection is not None:
                self._drag_selection(dx, dy)
            elif p["button"] == "left" and self.fly_mode:
                self._on_look(dx * ORBIT_DEGREES_PER_PIXEL, dy * ORBIT_DEGREES_PER_PIXEL)
            elif p["button"] == "left":
                self._on_orbit(dx * ORBIT_DEGREES_PER_PIXEL, dy * ORBIT_DEGREES_PER_PIXEL)
            else:
                self._on_pan(dx, dy)
        elif action == "up" and self._pointer is not None:
            if self._pointer["moved"] < CLICK_PIXELS and self._pointer["button"] == "left":
                self._on_pick(x, y)
            self._pointer = None

    def _on_wheel(self, dy: float) -> None:
        self._on_zoom(WHEEL_ZOOM**dy)

    def _on_key(self, key: str) -> None:
        step = FLY_STEP * self._bounds(None)[1]
        moves = {"w": (step, 0, 0), "s": (-step, 0, 0), "d": (0, step, 0), "a": (0, -step, 0)}
        moves |= {"e": (0, 0, step), "q": (0, 0, -step)}
        orbits = {"left": (-ORBIT_KEY_DEGREES, 0), "right": (ORBIT_KEY_DEGREES, 0)}
        orbits |= {"up": (0, ORBIT_KEY_DEGREES), "down": (0, -ORBIT_KEY_DEGREES)}
        key = key.lower()
        if key in moves:
            self._on_fly(*moves[key])
        elif key in orbits:
            self._on_orbit(*orbits[key])
        elif key == "l":
            self.fly_mode = not self.fly_mode
        elif key == "r":
            self._on_reset()
        elif key == "f":
            self._on_frame()
        # other keys: nothing (a window reports every key)

    # selection
    def _on_pick(self, x: float, y: float) -> None:
        self.selection = self.pick(x, y)

    def _on_select(self, mesh: int | None = None, light: int | None = None) -> None:
        if mesh is not None:
            self.selection = ("mesh", mesh)
        elif light is not None:
            self.selection = ("light", light)
        else:
            self.selection = None

    def pick(self, x: float, y: float) -> tuple[str, int] | None:
        """What pixel (x, y) (from the top-left) shows: ("light", i) near a point light's marker or on an area
        light's emitter, ("mesh", i), or None (also outside the view: a drag may end there). A ray cast on the CPU
        (Embree, the reference's geometry)."""
        from ..reference.geometry import EMITTERS, MESHES, SceneGeometry
        from ..scene.camera import pixel_rays

        self.last_hit = None
        if not (0 <= x < self.size[0] and 0 <= y < self.size[1]):
            return None
        for index, pixel in self.light_pixels().items():  # a point light's marker (it has no surface to hit)
            if self.scene.light[index].type == "point" and math.hypot(pixel[0] - x, pixel[1] - y) <= MARKER_PIXELS:
                return "light", index
        if self._geometry is None:
            self._geometry = SceneGeometry(self.scene)
        camera = self.scene.camera
        origin, dirs = pixel_rays(camera, self.size, offsets=(x - math.floor(x), y - math.floor(y)))
        col, row = math.floor(x), math.floor(y)
        origin = np.broadcast_to(origin, dirs.shape)[row, col]  # an orthographic camera's rays start per pixel
        hits = self._geometry.intersect(origin[None], dirs[row, col][None])
        self.last_hit = origin + hits.t[0] * dirs[row, col] if hits.kind[0] >= 0 else None
        if hits.kind[0] == MESHES:
            return "mesh", int(self._geometry.face_mesh[hits.prim[0]])
        if hits.kind[0] == EMITTERS:
            owner = self._geometry.emitter_owner[hits.prim[0]]
            return "light", int(self._geometry.lights[owner][0])
        return None

    def light_pixels(self) -> dict[int, tuple[float, float]]:
        """Where each point and area light (its centre) is in the view, in pixels from the top-left: the panels
        draw a marker there (a gizmo to click, then shift-drag)."""
        from ..scene.camera import project

        points = {}
        for index, light in enumerate(self.scene.light):
            if light.type == "point":
                points[index] = np.asarray(light.position, np.float64)
            elif light.type in ("quad", "polygon"):
                points[index] = np.asarray(light.polygon(), np.float64).mean(axis=0)
        if not points:
            return {}
        pixels = project(self.scene.camera, np.array(list(points.values())), self.size)
        return {i: (float(p[0]), float(p[1])) for i, p in zip(points, pixels, strict=True) if np.all(np.isfinite(p))}

    # edits
    def _on_material(self, fields: dict, name: str | None = None) -> None:
        if name is None:
            if self.selection is None or self.selection[0] != "mesh":
                raise ArgumentError("no mesh is selected: name the material", field="event.material.name")
            name = self.scene.mesh[self.selection[1]].material
        self.renderer.set_material(name, **fields)
        self._edited()

    def _on_light(self, fields: dict, index: int | None = None) -> None:
        index = self._selected("light", index)
        self.renderer.set_light(index, **fields)
        self._edited()

    def _on_transform(self, fields: dict, index: int | None = None) -> None:
        index = self._selected("mesh", index)
        self.renderer.set_transform(index, **fields)
        self._edited()

    def _on_move(self, offset: list[float]) -> None:
        if self.selection is None:
            raise ArgumentError("nothing is selected to move", field="event.move")
        offset = np.asarray(offset, np.float64)
        kind, index = self.selection
        if kind == "mesh":
            translate = np.asarray(self.scene.mesh[index].transform.translate, np.float64) + offset
            self._on_transform({"translate": translate.tolist()}, index)
            return
        light = self.scene.light[index]
        if light.type == "point":
            fields = {"position": (np.asarray(light.position) + offset).tolist()}
        elif light.type == "quad":
            fields = {"corners": (np.asarray(light.corners) + offset).tolist()}
        elif light.type == "polygon":
            fields = {"vertices": (np.asarray(light.vertices) + offset).tolist()}
        else:
            raise ArgumentError(f"a {light.type} light has no position to move", field="event.move")
        self._on_light(fields, index)

    def _drag_selection(self, dx: float, dy: float) -> None:
        """Move the selection in the view plane by a pointer drag (its depth keeps the pointer on it)."""
        centre, _ = self._bounds(self.selection)
        right, up, forward = self.camera.basis()
        depth = max(float(np.dot(centre - self.camera.eye(), forward)), 1e-6)
        size = self.camera.pixel_size(depth)
        self._on_move((size * (dx * right - dy * up)).tolist())

    # rendering
    def _on_method(self, name: str, params: dict | None = None) -> None:
        from ..renderer import Renderer

        scene, size = self.scene, self.size
        self.params = dict(params or {})
        renderer = Renderer(scene, method=name, size=size, **self.params)  # errors leave the old one in place
        self.renderer.release()
        self.renderer = renderer
        self.texture, self._image = None, None  # the released renderer's frame
        self._camera_moved()

    def _on_shadows(self, on: bool) -> None:
        for index, light in enumerate(self.scene.light):
            if light.shadows != bool(on):
                self.renderer.set_light(index, shadows=bool(on))
        self._edited()

    def _on_exposure(self, stops: float) -> None:
        self.exposure = float(stops)

    def _on_tonemap(self, mode: str) -> None:
        self.tonemap_mode = mode

    def _on_reference(self, spp: int = 64) -> None:
        if self.reference is not None:
            self.reference.cancel()
        self.reference = ReferenceJob(self.scene, self.size, spp)

    def _on_show(self, mode: str) -> None:
        self.show = mode

    # ------------------------------------------------------------------ saving
    def save_screenshot(self, path: str | Path) -> Path:
        """The view as shown: PNG (tone mapped as shown) or EXR / NPY / HDR (linear)."""
        from ..imageio import write_image

        return write_image(Path(path), self.shown(), exposure=self.exposure, tonemap=self.tonemap_mode)

    def save_scene(self, path: str | Path, overwrite: bool = False) -> Path:
        """The current scene, edits and camera included, as TOML (an existing file is not replaced unless
        ``overwrite``)."""
        from ..outputs import atomic_write, check_output
        from ..scene import load_dict, save_scene

        scene, path = self.scene, Path(path)
        if self._fields_dir is not None:  # a painted field lives in a temporary folder: a copy beside the scene
            materials = {}
            for name, material in scene.materials.items():
                field = getattr(material, "orientation", None)
                if field is not None and Path(field).parent == self._fields_dir:
                    copy = check_output(path.with_name(f"{path.stem}.{name}.npz"), (".npz",),
                                        inputs=self.scene.input_files(), overwrite=overwrite)  # fmt: skip
                    atomic_write(copy, Path(field).read_bytes())
                    material = material.model_copy(update={"orientation": copy.resolve()})
                materials[name] = material
            data = scene.model_dump(exclude={"base_dir"}, exclude_none=True)
            data["materials"] = {n: m.model_dump(exclude_none=True) for n, m in materials.items()}
            scene = load_dict(data, base_dir=scene.base_dir)
        return save_scene(scene, path, overwrite=overwrite)

    def save_camera(self, path: str | Path, overwrite: bool = False) -> Path:
        """The current camera as JSON (the scene's ``[camera]`` fields)."""
        from .. import jsonio
        from ..outputs import check_output

        path = check_output(path, (".json",), inputs=self.scene.input_files(), overwrite=overwrite)
        return jsonio.write(path, self.scene.camera.model_dump(), indent=2)

    def release(self) -> None:
        import shutil

        if self.reference is not None:
            self.reference.cancel()
        self.renderer.release()
        if self._fields_dir is not None:
            shutil.rmtree(self._fields_dir, ignore_errors=True)

    # ------------------------------------------------------------------ internals
    def _camera_moved(self) -> None:
        self.renderer.set_camera(**self.camera.fields())
        self._stale_reference()

    def _edited(self) -> None:
        self._geometry = None
        self._stale_reference()

    def _stale_reference(self) -> None:
        """A reference of another view or scene no longer applies."""
        if self.reference is not None and self.reference.key != _key(self.scene, self.size, self.reference.spp):
            self.reference.cancel()
            self.reference = None
            self.show = "image"

    def _selected(self, kind: str, index: int | None) -> int:
        if index is not None:  # in range: events.check_in_scene
            return index
        if self.selection is None or self.selection[0] != kind:
            raise ArgumentError(f"no {kind} is selected: give its index", field=f"event.{kind}.index")
        return self.selection[1]

    def _bounds(self, selection) -> tuple[np.ndarray, float]:
        """Bounding sphere of the selection (a mesh, a light), or of the whole scene."""
        from ..scene.geometry import bounding_sphere, mesh_data

        scene = self.scene
        if selection is not None and selection[0] == "mesh":
            points = mesh_data(scene, selection[1]).positions
        elif selection is not None and selection[0] == "light":
            light = scene.light[selection[1]]
            points = (
                light.polygon() if hasattr(light, "polygon") else np.asarray([getattr(light, "position", (0, 0, 0))])
            )
        else:
            points = np.concatenate(
                [mesh_data(scene, i).positions for i in range(len(scene.mesh))] or [np.zeros((1, 3))]
            )
        centre, radius = bounding_sphere(np.asarray(points, np.float64))
        return centre, max(radius, 1e-3)


def _key(scene, size, spp: int) -> str:
    from .reference import reference_key

    return reference_key(scene, size, spp)
