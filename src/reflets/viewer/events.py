"""The viewer's events as data (docs/viewer.md): one pydantic model per event type, so that the controller refuses
nonsense from the API, the panels and the notebook in one place (:func:`parse_event`), and a script
(``reflets view --script``) is checked whole before its first frame (:func:`as_script`, :func:`check_script`) —
each refusal one line naming the event, its index in the script and the field.

Strict as JSON is: a number is a number (``"3"`` is not 3, ``true`` is not 1), a field no event has is refused
by name, every number is finite and bounded (below)."""

from __future__ import annotations

from typing import Annotated, Any, Literal, Union

import numpy as np
from pydantic import AfterValidator, BaseModel, BeforeValidator, ConfigDict, Field, RootModel, Strict, model_validator

from ..arguments import MAX_SPP, validated
from ..errors import ArgumentError
from ..imageio import MAX_EXPOSURE, TONEMAP_MODES
from ..quantities import JsonNumber as Number
from ..quantities import Positive
from .painting import PAINT_TOOLS

#: the most frames one run draws (``--frames``, or a script's events and waits): 100,000 is half an hour at 60
#: frames a second and a day on a software rasteriser — more is a typo, not a recording
MAX_FRAMES = 100_000
#: the most events a script holds (each takes a frame of its own)
MAX_EVENTS = MAX_FRAMES
#: the longest wait (no longer than a whole run)
MAX_WAIT_FRAMES = MAX_FRAMES
#: an orbit or look turns at most ten turns (more is the same view, and a yaw that large loses precision)
MAX_DEGREES = 3600.0
#: a pointer position, pick or pan in pixels: far beyond any view (MAX_IMAGE_SIDE), yet a drag may leave the window
MAX_PIXELS = 1e6
#: a zoom factor is in [1 / MAX_ZOOM, MAX_ZOOM]: the distance to the target changes by at most this in one event
MAX_ZOOM = 1e4
#: wheel notches in one event (×1.1 each: 100 notches zoom by about 1.4 × 10⁴)
MAX_NOTCHES = 100.0
#: a key's name (the notebook reports the browser's: "ArrowLeft", "Shift", …; keys the viewer has no use for do
#: nothing)
MAX_KEY_CHARS = 32
POINTER_ACTIONS = ("down", "move", "up")
BUTTONS = ("left", "right", "middle")
SHOW_MODES = ("image", "reference", "error")


def _short(value) -> str:
    """``repr(value)``, cut to fit in a one-line message."""
    text = repr(value)
    return text if len(text) <= 60 else text[:57] + "..."


def _bounded(low: float, high: float):
    """A finite JSON number (an integer too, not a string or a boolean) in [low, high]."""
    return Annotated[float, Strict(), Field(ge=low, le=high, allow_inf_nan=False)]


def _choice(what: str, options: tuple[str, ...]):
    """A string among ``options``, refused as "unknown <what> 'x'; allowed: …"."""

    def check(value: str) -> str:
        if value not in options:
            raise ValueError(f"unknown {what} {_short(value)}; allowed: {', '.join(options)}")
        return value

    return Annotated[str, AfterValidator(check)]


def _edits(target: str):
    """The fields an edit sets (the scene's models check them when the edit is applied: they depend on the
    material's or light's type); the event's own ``target`` (its name or index) is not one of them."""

    def check(fields: dict) -> dict:
        for key in fields:
            if key in ("self", target):
                raise ValueError(f"{key!r} is not a field to edit (the event's {target} says what it edits)")
        return fields

    return Annotated[dict[str, Any], AfterValidator(check)]


def _nonzero(vector: tuple[float, float, float]) -> tuple[float, float, float]:
    if not any(vector):
        raise ValueError("the stroke direction must not be zero")
    return vector


Degrees = _bounded(-MAX_DEGREES, MAX_DEGREES)
Pixels = _bounded(-MAX_PIXELS, MAX_PIXELS)
#: [x, y, z] (a list in JSON; a tuple or an array from the API)
Vector = Annotated[tuple[Number, Number, Number], Strict(False)]
Index = Annotated[int, Field(ge=0)]
Radius = Annotated[Positive, Strict()]


class _Event(BaseModel):
    """An event's fields as JSON gives them, checked; an unknown field is refused by name."""

    model_config = ConfigDict(extra="forbid", strict=True, frozen=True)

    @model_validator(mode="before")
    @classmethod
    def _plain(cls, data):
        """NumPy scalars (an API caller's index, flag or coordinate) as the Python values JSON would give."""
        if isinstance(data, dict):
            return {k: v.item() if isinstance(v, np.generic) else v for k, v in data.items()}
        return data

    def arguments(self) -> dict:
        """The controller's handler's keyword arguments (every field but the type)."""
        return {name: getattr(self, name) for name in type(self).model_fields if name != "type"}


# camera
class Orbit(_Event):
    type: Literal["orbit"]
    dx: Degrees = 0.0
    dy: Degrees = 0.0


class Look(Orbit):
    type: Literal["look"]


class Pan(_Event):
    type: Literal["pan"]
    dx: Pixels = 0.0
    dy: Pixels = 0.0


class Zoom(_Event):
    type: Literal["zoom"]
    factor: _bounded(1.0 / MAX_ZOOM, MAX_ZOOM)


class Fly(_Event):
    type: Literal["fly"]
    forward: Number = 0.0
    right: Number = 0.0
    up: Number = 0.0


class FlyMode(_Event):
    type: Literal["fly_mode"]
    on: bool


class Reset(_Event):
    type: Literal["reset"]


class Frame(_Event):
    type: Literal["frame"]


# raw input
class Pointer(_Event):
    type: Literal["pointer"]
    action: _choice("pointer action", POINTER_ACTIONS)
    x: Pixels
    y: Pixels
    button: _choice("button", BUTTONS) = "left"
    shift: bool = False


class Wheel(_Event):
    type: Literal["wheel"]
    dy: _bounded(-MAX_NOTCHES, MAX_NOTCHES)


class Key(_Event):
    type: Literal["key"]
    key: Annotated[str, Field(max_length=MAX_KEY_CHARS)]


# selection and edits
class Pick(_Event):
    type: Literal["pick"]
    x: Pixels
    y: Pixels


class Select(_Event):
    type: Literal["select"]
    mesh: Index | None = None
    light: Index | None = None

    @model_validator(mode="after")
    def _one(self):
        if self.mesh is not None and self.light is not None:
            raise ValueError("select a mesh or a light, not both")
        return self


class Material(_Event):
    type: Literal["material"]
    fields: _edits("name")
    name: str | None = None


class Light(_Event):
    type: Literal["light"]
    fields: _edits("index")
    index: Index | None = None


class Transform(_Event):
    type: Literal["transform"]
    fields: _edits("index")
    index: Index | None = None


class Move(_Event):
    type: Literal["move"]
    offset: Vector


# rendering
class Method(_Event):
    type: Literal["method"]
    name: str
    params: dict[str, Any] | None = None


class Shadows(_Event):
    type: Literal["shadows"]
    on: bool


class Exposure(_Event):
    type: Literal["exposure"]
    stops: _bounded(-MAX_EXPOSURE, MAX_EXPOSURE)


class Tonemap(_Event):
    type: Literal["tonemap"]
    mode: _choice("tone mapping", TONEMAP_MODES)


class Reference(_Event):
    type: Literal["reference"]
    spp: Annotated[int, Field(ge=1, le=MAX_SPP)] = 64


class Show(_Event):
    type: Literal["show"]
    mode: _choice("show mode", SHOW_MODES)


# highlight editing
class Paint(_Event):
    type: Literal["paint"]
    tool: _choice("paint tool", PAINT_TOOLS) | None
    radius: Radius | None = None


class Stroke(_Event):
    type: Literal["stroke"]
    centre: Vector
    stroke: Annotated[Vector, AfterValidator(_nonzero)]
    tool: _choice("paint tool", PAINT_TOOLS) | None = None
    radius: Radius | None = None


class Undo(_Event):
    type: Literal["undo"]


class Redo(_Event):
    type: Literal["redo"]


class ShowHighlights(_Event):
    type: Literal["show_highlights"]
    on: bool


# scripts only
class Wait(_Event):
    """Draw this many frames before the next event (the window's script loop; the controller has no use for it)."""

    type: Literal["wait"]
    frames: Annotated[int, Field(ge=1, le=MAX_WAIT_FRAMES)] = 1


#: what the controller handles
CONTROLLER_EVENTS = (Orbit, Look, Pan, Zoom, Fly, FlyMode, Reset, Frame, Pointer, Wheel, Key, Pick, Select, Material,
                     Light, Transform, Move, Method, Shadows, Exposure, Tonemap, Reference, Show, Paint, Stroke, Undo,
                     Redo, ShowHighlights)  # fmt: skip


def _type(model) -> str:
    return model.model_fields["type"].annotation.__args__[0]


def _any_of(models: tuple):
    """One of ``models`` by its ``type``; an unknown type is refused with the list of those allowed."""
    types = tuple(_type(m) for m in models)

    def known(event):
        if not isinstance(event, dict) or "type" not in event:
            raise ValueError(f"an event is a dict (a JSON object) with a 'type', got {_short(event)}; types: "
                             f"{', '.join(types)}")  # fmt: skip
        if not isinstance(event["type"], str) or event["type"] not in types:
            raise ValueError(f"unknown event type {_short(event['type'])}; allowed: {', '.join(types)}")
        return event

    return Annotated[Union[models], Field(discriminator="type"), BeforeValidator(known)]  # noqa: UP007


#: the type of every event the controller handles
CONTROLLER_TYPES = tuple(_type(m) for m in CONTROLLER_EVENTS)


class Event(RootModel[_any_of(CONTROLLER_EVENTS)]):
    """One controller event."""


class ScriptEvents(RootModel[Annotated[list[_any_of((*CONTROLLER_EVENTS, Wait))], Field(max_length=MAX_EVENTS)]]):
    """A script file's content: a JSON list of events (and waits), drawing at most MAX_FRAMES frames."""

    @model_validator(mode="after")
    def _bounded_run(self):
        frames = sum(event.frames if isinstance(event, Wait) else 1 for event in self.root)
        if frames > MAX_FRAMES:
            raise ValueError(f"the script draws {frames:,} frames (an event each, a wait its frames); at most "
                             f"{MAX_FRAMES:,}")  # fmt: skip
        return self

    def dicts(self) -> list[dict]:
        return [event.model_dump() for event in self.root]


class Script(list):
    """A script's events (validated dicts, in order) and the file they came from (a refusal names it)."""

    def __init__(self, events=(), file=None):
        super().__init__(events)
        self.file = file
        #: what a refusal names besides the file: the option that gave it, or the API's argument
        self.field = "script" if file is None else "--script"


def parse_event(event) -> _Event:
    """``event`` (a dict) as its model, or the first thing wrong with it as one ArgumentError (``event:
    zoom.factor: …``)."""
    return validated(Event, event, field="event").root


def as_script(events) -> Script:
    """A list of event dicts (an API caller's) checked, every event; a loaded :class:`Script` (checked as it was
    read: :func:`reflets.viewer.window.load_script`) as it is."""
    if isinstance(events, Script):
        return events
    script = Script(file=getattr(events, "file", None))
    script.extend(validated(ScriptEvents, events, file=script.file, field=script.field).dicts())
    return script


def check_in_scene(event: _Event, scene, size: tuple[int, int]) -> None:
    """What only the scene and the view can say of a well-formed event: its mesh or light index, material name,
    method and parameters, the pixel it picks — refused as one ArgumentError (``event: select.mesh: …``). What
    depends on the state at the time (the selection, the material's type) is the handler's to check."""
    kind = event.type

    def refuse(place: str, message: str):
        raise ArgumentError(f"{kind}.{place}: {message}", field="event")

    def index(place: str, value: int | None, items: list, what: str) -> None:
        if value is not None and value >= len(items):
            has = {0: "none", 1: f"{what}[0] only"}.get(len(items), f"{what}[0..{len(items) - 1}]")
            refuse(place, f"no {what}[{value}]; the scene has {has}")

    if kind == "select":
        index("mesh", event.mesh, scene.mesh, "mesh")
        index("light", event.light, scene.light, "light")
    elif kind == "light":
        index("index", event.index, scene.light, "light")
    elif kind == "transform":
        index("index", event.index, scene.mesh, "mesh")
    elif kind == "material" and event.name is not None and event.name not in scene.materials:
        refuse("name", f"unknown material {_short(event.name)}; the scene has: {', '.join(scene.materials) or 'none'}")
    elif kind == "pick":
        width, height = size
        if not (0 <= event.x < width and 0 <= event.y < height):
            refuse("x" if not 0 <= event.x < width else "y",
                   f"pixel ({event.x:g}, {event.y:g}) is outside the {width}x{height} view")  # fmt: skip
    elif kind == "method":
        from ..techniques import get_technique

        try:
            technique = get_technique(event.name)
            validated(technique.Params, event.params or {})
        except ArgumentError as exc:
            refuse("name" if exc.field == "method" else "params", exc.message)


def check_script(script: Script, scene, size: tuple[int, int]) -> None:
    """Every event of a script against the scene and the view, before its first frame (:func:`check_in_scene`):
    a refusal names the file and the event's index."""
    for index, event in enumerate(script):
        if event["type"] != "wait":
            try:
                check_in_scene(parse_event(event), scene, size)
            except ArgumentError as exc:
                raise ArgumentError(f"[{index}].{exc.message}", file=script.file, field=script.field) from None


def check_frames(frames, field: str = "--frames") -> int | None:
    """None (until the window closes), or a whole number of frames in 1..MAX_FRAMES."""
    if frames is None:
        return None
    if isinstance(frames, bool) or not isinstance(frames, int | np.integer):
        raise ArgumentError(f"expected a whole number of frames, got {_short(frames)}", field=field)
    if not 1 <= frames <= MAX_FRAMES:
        raise ArgumentError(f"{frames:,} is out of range; a run draws 1..{MAX_FRAMES:,} frames", field=field)
    return int(frames)
