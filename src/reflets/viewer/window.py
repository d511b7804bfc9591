"""``reflets view``: a desktop window (moderngl-window's GLFW backend) over a :class:`ViewerController`.

The window creates the OpenGL context and reflets draws in it (``reflets.gpu.use_context``): the display pass
tone maps the renderer's frame texture as it is (nothing read back; the reference, error and highlight views are
arrays, uploaded). Input goes to the controller as the same
events a script replays. Keys beyond the controller's: p saves a screenshot, t the scene (TOML, edits
included), c the camera (JSON) — into the current folder under new names, never over a file; m cycles the
method; x toggles shadows; v cycles image / reference / error (after g, which starts the reference); + / −
change the exposure; b paints the selected mesh's highlight (bend; u undo, y redo); h hides the panels
(viewer/panels.py: the same as widgets); Escape closes. Input over a panel is the panel's. The title shows the
method, the last frame's CPU time (its passes submitted) and GPU time (timer queries, a GPU's), the frames, the
GL renderer and the selection (and the reference's progress and relative MSE).
"""

from __future__ import annotations

import sys
import time
from pathlib import Path

import numpy as np

from ..errors import ArgumentError, GLUnavailableError, RefletsError
from .events import Script, ScriptEvents, as_script, check_frames, check_script
from .panels import METHODS  # what m cycles through: the panel's list


def load_script(path: str | Path) -> Script:
    """A recorded event list (docs/viewer.md: a JSON list of events; ``{"type": "wait", "frames": n}`` waits),
    every event checked as the controller checks it, all before the window opens (the scene's indices and names:
    ``run``, before the first frame)."""
    from ..arguments import read_model

    events = read_model(ScriptEvents, path, field="--script", what="an event script (a JSON list of events)")
    return Script(events.dicts(), file=path)


def _free_name(stem: str, suffix: str) -> Path:
    k = 1
    while Path(f"{stem}-{k}{suffix}").exists():
        k += 1
    return Path(f"{stem}-{k}{suffix}")


class ViewerWindow:
    """The window, its controller and the display pass (one per process: the window's context becomes reflets')."""

    def __init__(
        self, scene, method: str | None = None, size: tuple[int, int] | None = None, panels: bool = True, **params
    ):
        from ..arguments import as_scene
        from ..gpu.context import use_context
        from .controller import ViewerController
        from .display import Display

        scene = as_scene(scene)
        size = tuple(size or scene.camera.size)
        try:
            import moderngl_window as mglw

            window_cls = mglw.get_local_window_cls("glfw")
            self.wnd = window_cls(title="reflets", size=size, gl_version=(4, 3), vsync=False, resizable=False)
        except ImportError as exc:
            raise GLUnavailableError(
                f"the viewer needs the 'viewer' extra ({exc.name} is missing): pip install 'reflets[viewer]'"
            ) from None
        except Exception as exc:  # GLFW: no display, no GLX
            raise GLUnavailableError(
                f"cannot open a window ({str(exc).strip() or type(exc).__name__}); without a display run it under "
                "xvfb-run, or use reflets.Viewer in Jupyter"
            ) from None
        mglw.activate_context(window=self.wnd)
        self.ctx = self.wnd.ctx
        use_context(self.ctx)
        self.controller = ViewerController(scene, method=method, size=size, **params)
        self.display = Display(self.ctx)
        self.panels = None
        if panels:
            from .panels import Panels

            self.panels = Panels(self.wnd)
        self.frames = 0
        self._bind_input()

    # ------------------------------------------------------------------ loop
    def run(
        self,
        frames: int | None = None,
        screenshot: str | Path | None = None,
        script: list[dict] | None = None,
        save_scene: str | Path | None = None,
        overwrite: bool = False,
    ) -> dict:
        """Draw until the window closes, or — with ``frames`` (at most MAX_FRAMES) — until that many frames are
        drawn and the script is replayed (one event per frame); then write the screenshot (the window's pixels for
        PNG, the shown HDR image otherwise) and the scene. Every event of the script is checked before the first
        frame; one the state refuses later (a material edit with nothing selected) ends the run, naming its index,
        with nothing written. Returns the controller's status and the frame times."""
        times, latencies = [], []
        first_frame = None
        try:
            frames = check_frames(frames, field="frames")
            events = as_script(script or [])
            check_script(events, self.controller.scene, self.controller.size)
            next_event, wait = 0, 0
            while not self.wnd.is_closing:
                t = time.perf_counter()
                handled = False
                if wait > 0:
                    wait -= 1
                elif next_event < len(events):
                    event, next_event = events[next_event], next_event + 1
                    if event["type"] == "wait":
                        wait = event["frames"] - 1
                    else:
                        self._replay(event, next_event - 1, events)
                        handled = True
                self.draw()
                done = frames is not None and self.frames >= frames and next_event == len(events) and wait <= 0
                if done and screenshot is not None:
                    self.save_screenshot(screenshot)  # the view, without the panels drawn over it
                self.draw_panels()
                self.wnd.swap_buffers()  # also polls the window's events
                times.append(1e3 * (time.perf_counter() - t))
                if handled:  # from the event to its frame on screen
                    latencies.append(times[-1])
                if first_frame is None:
                    first_frame = time.time()  # wall clock: a caller that started the process compares
                if done:
                    break
            if save_scene is not None:
                self.controller.save_scene(save_scene, overwrite=overwrite)
        finally:
            status = self.controller.status()
            self.close()
        status["event_latency_ms"] = latencies
        status["first_frame_at"] = first_frame
        return {**status, "window_frame_ms": times}

    def _replay(self, event: dict, index: int, script: Script) -> None:
        """A script's event; a refusal names the script and the event's index in it."""
        try:
            self.controller.handle(event)
        except RefletsError as exc:
            raise ArgumentError(f"[{index}] ({event['type']}): {exc}", file=script.file, field=script.field) from None

    def draw(self) -> None:
        controller = self.controller
        controller.draw()
        self.wnd.use()
        self.ctx.viewport = (0, 0, *self.wnd.buffer_size)
        texture = controller.shown_texture()
        if texture is not None:  # the frame as drawn: straight from the GPU, nothing read back
            self.display.draw_texture(texture, controller.exposure, controller.tonemap_mode)
        else:
            self.display.draw(controller.shown(), controller.exposure, controller.tonemap_mode)
        self.frames += 1
        if self.frames % 10 == 1:
            self.wnd.title = self.title()

    def draw_panels(self) -> None:
        """The panels over the view; their widgets' events go to the controller, their saves to new files."""
        if self.panels is None:
            return
        for event in self.panels.draw(self.controller):
            self._safe(event)
        for what in self.panels.saves:
            self._save(what)

    def _save(self, what: str) -> None:
        c = self.controller
        if what == "screenshot":
            path = self.save_screenshot(_free_name("reflets-view", ".png"))
        elif what == "scene":
            path = c.save_scene(_free_name("reflets-view", ".toml"))
        elif what == "field":
            path = c.save_field(_free_name("reflets-field", ".npz"))
        else:
            path = c.save_camera(_free_name("reflets-camera", ".json"))
        print(f"wrote {path}")

    def title(self) -> str:
        s = self.controller.status()
        gpu = f", GPU {s['gpu_ms']:.1f} ms" if s["gpu_ms"] is not None else ""
        text = (f"reflets — {s['method']} — CPU {s['cpu_ms']:.1f} ms{gpu} — {s['frames']} frame(s) — "
                f"{s['renderer']}")  # fmt: skip
        text += f" — {s['selection']}"
        if "reference_progress" in s:
            text += f" — reference {100 * s['reference_progress']:.0f} %"
        if "relmse" in s:
            text += f" — relMSE {s['relmse']:.2e} ({s['show']})"
        return text

    def save_screenshot(self, path: str | Path) -> Path:
        """PNG: the window's pixels as shown; EXR / NPY / HDR: the shown HDR image."""
        from ..imageio import write_png8

        path = Path(path)
        if path.suffix.lower() != ".png":
            return self.controller.save_screenshot(path)
        width, height = self.wnd.buffer_size
        data = self.wnd.fbo.read(viewport=(0, 0, width, height), components=3)
        pixels = np.frombuffer(data, np.uint8).reshape(height, width, 3)[::-1]
        return write_png8(path, np.ascontiguousarray(pixels))

    def close(self) -> None:
        from ..gpu.context import use_context

        self.controller.release()
        self.display.release()
        if self.panels is not None:
            self.panels.release()
        use_context(None)
        self.wnd.destroy()

    # ------------------------------------------------------------------ input
    def _bind_input(self) -> None:
        wnd, handle = self.wnd, self._safe
        buttons = {wnd.mouse.left: "left", wnd.mouse.right: "right", wnd.mouse.middle: "middle"}
        ui = self.panels.renderer if self.panels is not None else None

        def pointer(action: str, forward):
            def callback(x, y, *rest):
                if ui is not None:
                    forward(x, y, *rest)
                    if self.panels.wants_mouse and action != "up":
                        return  # over a panel: the panel's
                button = buttons.get(rest[-1], "left") if action != "move" else "left"
                handle({"type": "pointer", "action": action, "x": x, "y": y, "button": button,
                        "shift": bool(wnd.modifiers.shift)})  # fmt: skip

            return callback

        def scroll(dx, dy):
            if ui is not None:
                ui.mouse_scroll_event(dx, dy)
                if self.panels.wants_mouse:
                    return
            handle({"type": "wheel", "dy": dy})

        wnd.mouse_press_event_func = pointer("down", ui.mouse_press_event if ui else None)
        wnd.mouse_release_event_func = pointer("up", ui.mouse_release_event if ui else None)
        wnd.mouse_drag_event_func = pointer("move", ui.mouse_drag_event if ui else None)
        if ui is not None:
            wnd.mouse_position_event_func = ui.mouse_position_event
            wnd.unicode_char_entered_func = ui.unicode_char_entered
        wnd.mouse_scroll_event_func = scroll
        wnd.key_event_func = self._key

    def _key(self, key, action, modifiers) -> None:
        keys = self.wnd.keys
        if self.panels is not None:
            self.panels.renderer.key_event(key, action, modifiers)
            if self.panels.wants_keyboard:
                return
        if action != keys.ACTION_PRESS:
            return
        named = {keys.LEFT: "left", keys.RIGHT: "right", keys.UP: "up", keys.DOWN: "down"}
        letters = {getattr(keys, c.upper()): c for c in "wasdqerfl"}
        c = self.controller
        if key == keys.ESCAPE:
            self.wnd.close()
        elif key in named or key in letters:
            self._safe({"type": "key", "key": named.get(key) or letters[key]})
        elif key == keys.P:
            self._save("screenshot")
        elif key == keys.T:
            self._save("scene")
        elif key == keys.C:
            self._save("camera")
        elif key == keys.B:
            self._safe({"type": "paint", "tool": None if c.paint_tool else "bend"})
        elif key == keys.U:
            self._safe({"type": "undo"})
        elif key == keys.Y:
            self._safe({"type": "redo"})
        elif key == keys.H and self.panels is not None:
            self.panels.visible = not self.panels.visible
        elif key == keys.M:
            current = METHODS.index(c.method) if c.method in METHODS else -1
            self._safe({"type": "method", "name": METHODS[(current + 1) % len(METHODS)]})
        elif key == keys.X:
            self._safe({"type": "shadows", "on": not all(light.shadows for light in c.scene.light)})
        elif key == keys.G:
            self._safe({"type": "reference", "spp": 64})
        elif key == keys.V:
            modes = ("image", "reference", "error")
            self._safe({"type": "show", "mode": modes[(modes.index(c.show) + 1) % 3]})
        elif key in (keys.EQUAL, keys.MINUS):
            self._safe({"type": "exposure", "stops": c.exposure + (0.5 if key == keys.EQUAL else -0.5)})

    def _safe(self, event: dict) -> None:
        """Interactive input: a refused event (a method that does not apply, …) prints and the viewer goes on."""
        try:
            self.controller.handle(event)
        except RefletsError as exc:
            print(f"reflets: {exc}", file=sys.stderr)
