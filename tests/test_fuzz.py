"""Fuzzing (issue 19), seeded and bounded: mutated scene dicts and TOML texts, and CLI arguments. Every outcome
is an image (or a successful command) or a RefletsError whose message is one line — no other exception type,
no abort. Hypothesis shrinks a failure to a small case; `derandomize` makes every run the same."""

from __future__ import annotations

import tomllib

import numpy as np
import pytest

hypothesis = pytest.importorskip("hypothesis")
from hypothesis import HealthCheck, given, settings  # noqa: E402
from hypothesis import strategies as st  # noqa: E402

import reflets  # noqa: E402
from reflets.cli import main  # noqa: E402
from reflets.demo import scene_path  # noqa: E402
from reflets.errors import RefletsError  # noqa: E402
from reflets.scene import load_dict, load_scene  # noqa: E402

SEEDS = ["01_plane_point.toml", "02_sphere_directional.toml", "03_shapes.toml", "06_materials.toml"]
BASES = {name: tomllib.loads(scene_path(name).read_text()) for name in SEEDS}
def fuzz(examples: int):
    """Seeded (the same cases every run), no deadline (llvmpipe renders), no example database written."""
    return settings(derandomize=True, deadline=None, suppress_health_check=list(HealthCheck), database=None,
                    max_examples=examples)

numbers = st.one_of(
    st.floats(allow_nan=True, allow_infinity=True),
    st.sampled_from([0.0, -1.0, 1e-300, 1e308, -1e308, 1e30, 3e38, 65536.0, 1e12, 1e13]),
    st.integers(min_value=-(2**70), max_value=2**70),
)
leaves = st.one_of(numbers, st.text(max_size=12), st.booleans(), st.sampled_from(["file:x.npy", "vgroove:0.5"]))
values = st.recursive(leaves, lambda inner: st.lists(inner, max_size=4) | st.dictionaries(st.text(max_size=6), inner,
                                                                                           max_size=3), max_leaves=8)


def _paths(data, prefix=()):
    """Every (path) to a value in a nested dict / list."""
    yield prefix
    if isinstance(data, dict):
        for key, value in data.items():
            yield from _paths(value, (*prefix, key))
    elif isinstance(data, list):
        for index, value in enumerate(data):
            yield from _paths(value, (*prefix, index))


def _mutate(data, path, action, value):
    import copy

    data = copy.deepcopy(data)
    if not path:
        return data
    parent = data
    for key in path[:-1]:
        parent = parent[key]
    key = path[-1]
    if action == "delete":
        del parent[key]
    elif action == "replace":
        parent[key] = value
    elif action == "add" and isinstance(parent, dict):
        parent[f"{key}_extra"] = value
    return data


def _leaf(data, path):
    for key in path:
        data = data[key]
    return data


@st.composite
def mutated_scenes(draw):
    """A built-in scene with 1–3 mutations: half the time a number replaced by another (extreme, negative, NaN,
    huge: scenes that often still validate and render), else any value replaced, deleted or added."""
    data = BASES[draw(st.sampled_from(SEEDS))]
    for _ in range(draw(st.integers(1, 3))):
        paths = list(_paths(data))
        numeric = [p for p in paths if p and type(_leaf(data, p)) in (int, float)]
        if numeric and draw(st.booleans()):
            data = _mutate(data, draw(st.sampled_from(numeric)), "replace", draw(numbers))
        else:
            path = draw(st.sampled_from(paths))
            data = _mutate(data, path, draw(st.sampled_from(["replace", "replace", "delete", "add"])), draw(values))
    return data


def _one_line(exc: RefletsError) -> None:
    text = str(exc)
    assert text and "\n" not in text, repr(text)


@fuzz(250)
@given(mutated_scenes())
def test_mutated_scene_dicts_validate_or_fail_in_one_line(data):
    try:
        load_dict(data)
    except RefletsError as exc:
        _one_line(exc)


@pytest.mark.slow
@fuzz(40)
@given(mutated_scenes())
def test_mutated_scenes_render_or_fail_in_one_line(data):
    try:
        image = reflets.render(data, size=(24, 18), method="forward")
    except RefletsError as exc:
        _one_line(exc)
        hypothesis.event("refused")
    else:
        assert image.shape == (18, 24, 3) and np.all(np.isfinite(image))
        hypothesis.event("rendered")


@fuzz(150)
@given(st.text(max_size=200))
def test_toml_text_loads_or_fails_in_one_line(tmp_path_factory, text):
    path = tmp_path_factory.mktemp("toml") / "scene.toml"
    path.write_text(text, encoding="utf-8", errors="surrogatepass")  # a lone surrogate as its own bytes
    try:
        load_scene(path)
    except RefletsError as exc:
        _one_line(exc)


ARGUMENT_VALUES = st.one_of(st.sampled_from(["0", "-1", "1e308", "nan", "65537", "32x24", "0x0", "x", "", "1.5",
                                             "[0,0]", "env_grid=[2,2]", "area_samples=-3", "spp=1"]),
                            st.text(max_size=8))  # fmt: skip


@pytest.mark.slow
@fuzz(60)
@given(st.sampled_from(["render", "reference", "compare", "schema", "info"]),
       st.lists(st.tuples(st.sampled_from(["--spp", "--size", "--method", "--param", "--seed", "--exposure",
                                           "--tonemap", "--json", "--engine"]), ARGUMENT_VALUES), max_size=3))
def test_cli_arguments_end_in_one_line(tmp_path_factory, capsys, command, options):  # fmt: skip
    folder = tmp_path_factory.mktemp("cli")
    scene = str(scene_path("01_plane_point.toml"))
    argv = {"render": [command, scene, "-o", str(folder / "o.png")],
            "reference": [command, scene, "-o", str(folder / "r.exr")],
            "compare": [command, scene, scene], "schema": [command], "info": [command]}[command]  # fmt: skip
    for flag, value in options:
        argv += [flag, value] if flag != "--json" else [flag]
    if command in ("render", "reference") and "--size" not in argv:
        argv += ["--size", "16x12"]
    if command == "reference" and "--spp" not in argv:
        argv += ["--spp", "1"]
    capsys.readouterr()  # the fixture lives across examples: start each with empty streams
    try:
        rc = main(argv)
    except SystemExit as exc:  # argparse's own error (one line: reflets.cli._Parser), exit 2
        assert exc.code == 2 and capsys.readouterr().err.count("\n") == 1
        return
    err = capsys.readouterr().err.strip()
    assert rc in (0, 2), (argv, rc, err)
    if rc == 2:
        lines = [line for line in err.splitlines() if not line.startswith("reflets: warning")]
        assert len(lines) == 1 and "Traceback" not in err, (argv, err)
