"""Careless input to the viewer's events (issue 32): a script file (``reflets view --script``), the frame count
and the controller's own ``handle`` — every bad value one line naming the file, the event's index and the field,
all of a script checked before its first frame; valid scripts load. No window: load_script and the checks need
none (one controller, for what only a renderer shows)."""

from __future__ import annotations

import json
import re
from pathlib import Path

import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

import reflets
from reflets.errors import ArgumentError
from reflets.viewer import ViewerController
from reflets.viewer.events import (
    CONTROLLER_TYPES,
    MAX_EVENTS,
    MAX_FRAMES,
    as_script,
    check_frames,
    check_script,
    parse_event,
)
from reflets.viewer.window import load_script

from .test_controller import SCENE

DOCS = Path(__file__).parents[2] / "docs" / "viewer.md"
#: a script with every event type (in a scene with two meshes, two lights, materials floor and ball)
VALID = [
    {"type": "orbit", "dx": 12, "dy": 4},
    {"type": "wait", "frames": 2},
    {"type": "look", "dx": -3.5},
    {"type": "pan", "dx": 10, "dy": -4},
    {"type": "zoom", "factor": 1.5},
    {"type": "fly", "forward": 0.1, "right": 0, "up": -0.2},
    {"type": "fly_mode", "on": False},
    {"type": "pointer", "action": "down", "x": 48, "y": 30.5, "button": "left", "shift": False},
    {"type": "pointer", "action": "move", "x": -20, "y": 90},
    {"type": "pointer", "action": "up", "x": -20, "y": 90},
    {"type": "wheel", "dy": -2},
    {"type": "key", "key": "w"},
    {"type": "pick", "x": 48, "y": 36},
    {"type": "select", "mesh": 1},
    {"type": "material", "fields": {"alpha": 0.12}},
    {"type": "material", "name": "floor", "fields": {"albedo": [0.5, 0.5, 0.5]}},
    {"type": "select", "light": 0},
    {"type": "move", "offset": [0.1, 0.0, 0.0]},
    {"type": "light", "index": 1, "fields": {"intensity": [3, 3, 3]}},
    {"type": "transform", "index": 0, "fields": {"translate": [0, -0.1, 0]}},
    {"type": "select"},
    {"type": "method", "name": "auto", "params": {"area_method": "ltc"}},
    {"type": "shadows", "on": True},
    {"type": "exposure", "stops": -1.5},
    {"type": "tonemap", "mode": "aces"},
    {"type": "reference", "spp": 16},
    {"type": "show", "mode": "error"},
    {"type": "show_highlights", "on": False},
    {"type": "paint", "tool": None},
    {"type": "stroke", "centre": [0, 0, 0], "stroke": [1, 0, 0], "tool": "stencil", "radius": 0.2},
    {"type": "undo"},
    {"type": "redo"},
    {"type": "reset"},
    {"type": "frame"},
]


def write(tmp_path, data, name: str = "script.json") -> Path:
    path = tmp_path / name
    path.write_text(data if isinstance(data, str) else json.dumps(data), "utf-8")
    return path


def refused(call, *where: str) -> str:
    """The one-line ArgumentError ``call()`` raises, naming each of ``where``."""
    with pytest.raises(ArgumentError) as info:
        call()
    message = str(info.value)
    assert "\n" not in message and all(w in message for w in where), message
    return message


def test_every_event_type_has_a_model_and_the_valid_scripts_load(tmp_path):
    """The models cover every ``_on_*`` handler; a script using each, the docs' example and the replay of
    tests/viewer/test_window.py load unchanged, and what they load validates again (the controller's check)."""
    assert set(CONTROLLER_TYPES) == {name[4:] for name in dir(ViewerController) if name.startswith("_on_")}
    assert {e["type"] for e in VALID} == {*CONTROLLER_TYPES, "wait"}
    example = json.loads(re.search(r"```json\n(.*?)```", DOCS.read_text("utf-8"), re.S).group(1))
    replay = [{"type": "pointer", "action": "down", "x": 80, "y": 40, "shift": True}, {"type": "wait", "frames": 2}]
    for events in (VALID, example, replay):
        script = load_script(write(tmp_path, events))
        assert [e["type"] for e in script] == [e["type"] for e in events] and script.file == tmp_path / "script.json"
        for event in script:
            if event["type"] != "wait":
                parse_event(event)
    check_script(load_script(write(tmp_path, VALID)), reflets.load_dict(SCENE), (96, 72))


@pytest.mark.parametrize(
    "events, where",
    [
        ([{"type": "wait", "frames": "many"}], "[0].wait.frames: input should be a valid integer"),
        ([{"type": "orbit"}, {"type": "wait", "frames": 10**9}], "[1].wait.frames: input should be less than"),
        ([{"type": "wait", "frames": 0}], "[0].wait.frames"),
        ([{"type": "wait", "frames": 2.5}], "[0].wait.frames"),
        ([{"type": "wait", "frames": MAX_FRAMES}, {"type": "undo"}], f"at most {MAX_FRAMES:,}"),
        ([{"type": "zoom", "factor": 0}], "[0].zoom.factor: input should be greater than"),
        ([{"type": "zoom", "factor": -2}], "[0].zoom.factor"),
        ([{"type": "zoom"}], "[0].zoom.factor: field required"),
        ('[{"type": "zoom", "factor": 1e400}]', "[0].zoom.factor: input should be a finite number"),  # inf, parsed
        ([{"type": "orbit", "dx": 1e9}], "[0].orbit.dx"),
        ([{"type": "orbit", "yaw": 3}], "[0].orbit.yaw: extra inputs are not permitted"),
        ([{"type": "orbit", "dx": "3"}], "[0].orbit.dx: input should be a valid number"),
        ([{"type": "orbit", "dx": True}], "[0].orbit.dx"),
        ([{"type": "orbit", "dx": [1]}], "[0].orbit.dx"),
        ([{"type": "pan", "dx": None}], "[0].pan.dx"),
        ([{"type": "wheel", "dy": 1e6}], "[0].wheel.dy"),
        ([{"type": "exposure", "stops": 1000}], "[0].exposure.stops"),
        ([{"type": "fly", "forward": 1e300}], "[0].fly.forward"),
        ([{"type": "fly_mode", "on": "yes"}], "[0].fly_mode.on: input should be a valid boolean"),
        ([{"type": "pointer", "action": "drag", "x": 1, "y": 1}], "[0].pointer.action: unknown pointer action 'drag'"),
        ([{"type": "pointer", "action": "down", "x": 1}], "[0].pointer.y: field required"),
        ([{"type": "pointer", "action": "up", "x": 1, "y": 2, "button": 4}], "[0].pointer.button"),
        ([{"type": "pick", "x": -1e7, "y": 2}], "[0].pick.x"),
        ([{"type": "key", "key": 13}], "[0].key.key: input should be a valid string"),
        ([{"type": "key", "key": "k" * 100}], "[0].key.key"),
        ([{"type": "select", "mesh": -1}], "[0].select.mesh"),
        ([{"type": "select", "mesh": "0"}], "[0].select.mesh"),
        ([{"type": "select", "mesh": 0, "light": 0}], "[0].select: select a mesh or a light, not both"),
        ([{"type": "material", "fields": [1]}], "[0].material.fields"),
        ([{"type": "material", "fields": {"name": "x"}}], "[0].material.fields: 'name' is not a field to edit"),
        ([{"type": "light", "index": 0, "fields": {"index": 1}}], "[0].light.fields"),
        ([{"type": "transform", "index": 1.0, "fields": {}}], "[0].transform.index"),
        ([{"type": "move", "offset": [1, 2]}], "[0].move.offset"),
        ([{"type": "move", "offset": "up"}], "[0].move.offset"),
        ([{"type": "method", "name": 5}], "[0].method.name"),
        ([{"type": "method", "name": "ltc", "params": [1]}], "[0].method.params"),
        ([{"type": "tonemap", "mode": "reinhard"}], "[0].tonemap.mode: unknown tone mapping 'reinhard'; allowed: srgb"),
        ([{"type": "show", "mode": "wireframe"}], "allowed: image, reference, error"),
        ([{"type": "reference", "spp": 0}], "[0].reference.spp"),
        ([{"type": "reference", "spp": 10**6}], "[0].reference.spp"),
        ([{"type": "paint"}], "[0].paint.tool: field required"),
        ([{"type": "paint", "tool": "brush"}], "[0].paint.tool: unknown paint tool 'brush'; allowed: bend"),
        ([{"type": "paint", "tool": "bend", "radius": 0}], "[0].paint.radius"),
        ([{"type": "stroke", "centre": [0, 0, 0], "stroke": [0, 0, 0]}], "[0].stroke.stroke: the stroke direction"),
        ([{"type": "undo", "steps": 2}], "[0].undo.steps"),
        ([{"type": "teleport"}], "[0]: unknown event type 'teleport'; allowed: orbit, look"),
        ([{"type": None}], "[0]: unknown event type None"),
        ([{"dx": 3}], "[0]: an event is a dict (a JSON object) with a 'type'"),
        (["orbit"], "[0]: an event is a dict"),
        ([[{"type": "orbit"}]], "[0]: an event is a dict"),
        ({"type": "orbit"}, "input should be a valid list"),
        ('"orbit"', "input should be a valid list"),
    ],
)
def test_a_bad_script_is_one_line_naming_the_file_and_the_event(tmp_path, events, where):
    path = write(tmp_path, events)
    refused(lambda: load_script(path), f"{path}: --script: ", where)


@pytest.mark.parametrize(
    "text, where",
    [
        ("[" * 100_000 + "]" * 100_000, "nested too deeply"),
        ('[{"type": "orbit", "dx": NaN}]', "NaN is not JSON"),
        ('[{"type": "orbit", "dx": 1, "dx": 2}]', "'dx' is given twice"),
        ('[{"type": "orbit"', "not an event script"),
        ("", "not an event script"),
    ],
)
def test_a_script_that_is_not_strict_json_is_refused(tmp_path, text, where):
    path = write(tmp_path, text)
    refused(lambda: load_script(path), f"{path}: --script: ", where)


def test_a_missing_a_directory_and_a_binary_script(tmp_path):
    refused(lambda: load_script(tmp_path / "missing.json"), "missing.json: --script: file not found")
    refused(lambda: load_script(tmp_path), "--script: is a directory")
    (tmp_path / "binary.json").write_bytes(b"\xff\xfe[\x00")
    refused(lambda: load_script(tmp_path / "binary.json"), "binary.json: --script: not a text file")


def test_too_many_events_are_refused_with_the_limit():
    refused(lambda: as_script([{"type": "undo"}] * (MAX_EVENTS + 1)), "script: ", f"at most {MAX_EVENTS}")


@pytest.mark.parametrize(
    "event, where",
    [
        ({"type": "select", "mesh": 7}, "[1].select.mesh: no mesh[7]; the scene has mesh[0..1]"),
        ({"type": "select", "light": 2}, "[1].select.light: no light[2]"),
        ({"type": "light", "index": 5, "fields": {}}, "[1].light.index: no light[5]"),
        ({"type": "transform", "index": 2, "fields": {}}, "[1].transform.index: no mesh[2]"),
        (
            {"type": "material", "name": "glaze", "fields": {}},
            "[1].material.name: unknown material 'glaze'; the scene has: floor, ball",
        ),
        ({"type": "pick", "x": 96, "y": 10}, "[1].pick.x: pixel (96, 10) is outside the 96x72 view"),
        ({"type": "pick", "x": 5, "y": -0.5}, "[1].pick.y"),
        ({"type": "method", "name": "nope"}, "[1].method.name: unknown method 'nope'"),
        ({"type": "method", "name": "ltc", "params": {"bogus": 1}}, "[1].method.params: bogus: extra inputs"),
    ],
)
def test_what_only_the_scene_can_refuse_is_refused_before_the_first_frame(tmp_path, event, where):
    """Indices, names, methods and pixels against the scene and the view (the window's run, before its first
    frame): the file and the event's index named."""
    script = load_script(write(tmp_path, [{"type": "orbit", "dx": 1}, event]))
    refused(lambda: check_script(script, reflets.load_dict(SCENE), (96, 72)), f"{tmp_path / 'script.json'}: --script: ",
            where)  # fmt: skip


@pytest.mark.parametrize("frames", [0, -1, MAX_FRAMES + 1, 10**9, True, 1.5, "3"])
def test_frames_out_of_range_or_not_a_count_are_refused(frames):
    refused(lambda: check_frames(frames), "--frames: ")


def test_frames_in_range_pass():
    assert [check_frames(n) for n in (None, 1, MAX_FRAMES)] == [None, 1, MAX_FRAMES]


@pytest.fixture(scope="module")
def controller():
    from reflets.gpu import get_context

    get_context()
    c = ViewerController(reflets.load_dict(SCENE), method="forward")
    yield c
    c.release()


@pytest.mark.parametrize(
    "event, where",
    [
        ({"type": "zoom", "factor": 0}, "event: zoom.factor"),
        ({"type": "zoom", "factor": float("nan")}, "event: zoom.factor: input should be a finite number"),
        ({"type": "wheel", "dy": float("inf")}, "event: wheel.dy"),
        ({"type": "pick", "x": 500, "y": 3}, "event: pick.x: pixel (500, 3) is outside the 96x72 view"),
        ({"type": "wait", "frames": 3}, "unknown event type 'wait'"),
        ({"type": "select", "light": 9}, "event: select.light: no light[9]"),
        ({"type": "method", "name": "forward", "params": {"size": 3}}, "event: method.params: size: extra inputs"),
    ],
)
def test_the_controller_refuses_the_same_nonsense_from_the_api(controller, event, where):
    camera, selection = controller.scene.camera, controller.selection
    refused(lambda: controller.handle(event), where)
    assert controller.scene.camera == camera and controller.selection == selection


def test_a_move_the_scene_s_camera_refuses_is_undone(controller):
    """Zooming out 10⁴ times an event leaves the scene's bounds after a few: the refused move (one line) leaves
    the camera where it was, and the next move works."""
    import numpy as np

    with pytest.raises(reflets.errors.RefletsError) as info:
        for _ in range(5):
            controller.handle({"type": "zoom", "factor": 1e-4})
    assert "\n" not in str(info.value)
    distance = controller.camera.distance
    assert np.linalg.norm(np.subtract(controller.scene.camera.position, controller.scene.camera.look_at)) == (
        pytest.approx(distance))  # fmt: skip
    controller.handle({"type": "zoom", "factor": 1e4})
    assert controller.camera.distance == pytest.approx(distance / 1e4)
    controller.handle({"type": "reset"})


# ---------------------------------------------------------------------------------------------- fuzz
leaves = st.one_of(
    st.floats(allow_nan=True, allow_infinity=True),
    st.sampled_from([0, -1, 1e-300, 1e12, 1e13, 1e308, 10**9, 2**70, MAX_FRAMES + 1]),
    st.integers(min_value=-(2**70), max_value=2**70),
    st.text(max_size=8),
    st.booleans(),
    st.none(),
    st.sampled_from([*CONTROLLER_TYPES, "wait"]),
)
values = st.recursive(
    leaves,
    lambda inner: st.lists(inner, max_size=4) | st.dictionaries(st.text(max_size=6), inner, max_size=3),
    max_leaves=6,
)
#: what one mutation does to one event: a field's value replaced, removed or added, the type changed, the event
#: replaced
mutations = st.tuples(st.integers(0, len(VALID) - 1), st.sampled_from(["set", "delete", "add", "type", "event"]),
                      st.integers(0, 10), values)  # fmt: skip


@settings(derandomize=True, deadline=None, suppress_health_check=list(HealthCheck), database=None, max_examples=300)
@given(st.lists(mutations, min_size=1, max_size=3))
def test_a_mutated_script_loads_or_is_one_line(tmp_path_factory, changes):
    """Values turned into NaN, inf, huge numbers, strings, lists, nulls; keys removed and added; types changed:
    the script loads (and passes or fails the scene's check in one line) or is refused in one line — no other
    exception, in memory (NaN reaches the models) and from a file."""
    import copy

    events = copy.deepcopy(VALID)
    for index, action, pick, value in changes:
        event = events[index]
        if action == "event" or not isinstance(event, dict):
            events[index] = value
            continue
        keys = [k for k in event if k != "type"] or ["type"]
        key = keys[pick % len(keys)]
        if action == "set":
            event[key] = value
        elif action == "delete":
            event.pop(key, None)
        elif action == "add":
            event[str(value)[:8] if not isinstance(value, dict | list) else "extra"] = value
        else:
            event["type"] = value if pick % 2 else CONTROLLER_TYPES[pick % len(CONTROLLER_TYPES)]
    path = tmp_path_factory.getbasetemp() / "fuzzed.json"
    path.write_text(json.dumps(events), "utf-8")  # NaN and inf as JSON's non-standard constants: refused
    for load in (lambda: as_script(events), lambda: load_script(path)):
        try:
            script = load()
        except ArgumentError as exc:
            assert "\n" not in str(exc)
            continue
        try:
            check_script(script, reflets.load_dict(SCENE), (96, 72))
        except ArgumentError as exc:
            assert "\n" not in str(exc)
