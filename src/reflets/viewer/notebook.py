"""``reflets.Viewer``: the viewer as a Jupyter widget (jupyter_rfb's remote frame buffer). The renderer draws
in its own headless context (EGL), the widget sends each tone-mapped frame to the browser and its pointer,
wheel and key events come back to the same :class:`ViewerController` the desktop window drives."""

from __future__ import annotations

import numpy as np

from ..errors import ArgumentError
from .controller import ViewerController
from .events import MAX_NOTCHES

try:
    from jupyter_rfb import RemoteFrameBuffer
except ImportError as exc:  # the 'viewer' extra
    raise ArgumentError(
        f"reflets.Viewer needs the 'viewer' extra ({exc.name} is missing): pip install 'reflets[viewer]'"
    ) from None

#: the browser's buttons (1 left, 2 right, 3 middle) as the controller names them
BUTTONS = {1: "left", 2: "right", 3: "middle"}
#: pixels of a browser wheel event per zoom notch
WHEEL_PIXELS = 100.0


class Viewer(RemoteFrameBuffer):
    """An interactive view of a scene in a notebook: ``Viewer(scene, method=None, size=None, **params)``.

    Drag to orbit (right / middle: pan; shift: move the selection), click to select, wheel to zoom, keys as in
    the window; ``handle({...})`` applies any controller event (docs/viewer.md), ``snapshot()`` returns the
    current frame (uint8 (H, W, 3), as shown), ``controller`` is the shared controller."""

    _event_compatibility = 2  # jupyter_rfb's new-style events ('type', 'timestamp', 'ratio')

    def __init__(self, scene, method: str | None = None, size: tuple[int, int] | None = None, **params):
        super().__init__()
        self.controller = ViewerController(scene, method=method, size=size, **params)
        width, height = self.controller.size
        self.css_width, self.css_height = f"{width}px", f"{height}px"
        self.resizable = False

    # ------------------------------------------------------------------ jupyter_rfb
    def get_frame(self) -> np.ndarray:
        """The frame jupyter_rfb sends (called only for a frame it sends: the one read-back is of that frame)."""
        self.controller.draw()
        return self.controller.snapshot()

    def handle_event(self, event: dict) -> None:
        """A browser event (jupyter_rfb's) as a controller event; anything else is ignored, and one the controller
        refuses (a drag that leaves the view, …) is a warning: the widget goes on."""
        import warnings

        from ..errors import RefletsError, RefletsWarning

        try:
            self._browser_event(event)
        except RefletsError as exc:
            warnings.warn(str(exc), RefletsWarning, stacklevel=2)

    def _browser_event(self, event: dict) -> None:
        kind = event.get("type", "")
        shown = self._scale(event)
        if kind in ("pointer_down", "pointer_move", "pointer_up"):
            if kind == "pointer_move" and not event.get("buttons"):
                return  # hovering
            button = BUTTONS.get(event.get("button"), "left")
            if kind == "pointer_move":
                button = BUTTONS.get(event["buttons"][0], "left")
            self.handle({"type": "pointer", "action": kind[8:], **shown, "button": button,
                         "shift": "Shift" in event.get("modifiers", ())})  # fmt: skip
        elif kind == "wheel":
            notches = -float(event.get("dy", 0.0)) / WHEEL_PIXELS
            self.handle({"type": "wheel", "dy": max(-MAX_NOTCHES, min(MAX_NOTCHES, notches))})
        elif kind == "key_down":
            self.handle({"type": "key", "key": str(event.get("key", "")).replace("Arrow", "").lower()})

    # ------------------------------------------------------------------ API
    def handle(self, event: dict) -> None:
        """Apply a controller event and redraw."""
        self.controller.handle(event)
        self.request_draw()

    def snapshot(self) -> np.ndarray:
        """The current frame as shown: uint8 (H, W, 3) (a progressive method adds a frame)."""
        return self.get_frame()

    def close(self, *args, **kwargs) -> None:
        self.controller.release()
        super().close(*args, **kwargs)

    def _scale(self, event: dict) -> dict:
        """Pointer position in image pixels (the widget may be shown at another size)."""
        if "x" not in event:
            return {}
        width, height = self.controller.size
        shown_w = float(self.css_width[:-2]) if self.css_width.endswith("px") else width
        shown_h = float(self.css_height[:-2]) if self.css_height.endswith("px") else height
        return {"x": float(event["x"]) * width / shown_w, "y": float(event["y"]) * height / shown_h}
