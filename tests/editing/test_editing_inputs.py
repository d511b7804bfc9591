"""Issue 32: the inputs of ``reflets highlights`` and ``reflets edit-highlights`` (a strokes file, a targets .npz,
--iterations, --mesh, --light). Each bad one is one line on stderr naming the file, option and place, exit
status 2, nothing written; odd but valid ones (a brush smaller than a triangle, one across the mesh's border,
huge target rows) give a finite result. Validation is tested without solving wherever it can be."""

from __future__ import annotations

import copy
import json

import numpy as np
import pytest

import reflets
from reflets.cli import main
from reflets.demo import scene_path
from reflets.editing.highlights import check_targets, load_targets
from reflets.editing.solver import MAX_ITERATIONS
from reflets.editing.strokes import MAX_STROKES, EditSession, load_strokes
from reflets.editing.tools import Brush, warp_targets
from reflets.errors import ArgumentError

PLATE = scene_path("53_spun_plate.toml")  # an 80 × 80 grid (6,561 vertices) in y = 0, normal +y
VERTICES = 81 * 81
STROKE = {"tool": "bend", "centre": [-0.5, 0.0, 0.05], "radius": 0.35, "stroke": [0.0, 0.0, -1.0]}


def refused(capsys, *names: str) -> str:
    """The one line a refused command printed (it names each of ``names``)."""
    err = capsys.readouterr().err.strip()
    assert "\n" not in err and "Traceback" not in err, err
    assert all(name in err for name in names), err
    return err


def edit(tmp_path, *options: str, scene=PLATE) -> int:
    return main(["edit-highlights", str(scene), "--mesh", "0", *options, "-o", str(tmp_path / "out.npz")])


def write_strokes(tmp_path, strokes) -> str:
    path = tmp_path / "strokes.json"
    path.write_text(json.dumps(strokes))
    return str(path)


@pytest.fixture(scope="module")
def session():
    return EditSession(reflets.load_scene(PLATE), 0, iterations=3)


# ------------------------------------------------------------------ strokes files (checked before the scene)
@pytest.mark.parametrize(
    ("change", "place", "words"),
    [
        ({"tool": ["bend"]}, "[1].tool", "valid string"),
        ({"tool": "smudge"}, "[1].tool", "allowed: bend, expand, stencil"),
        ({"radius": "0.3"}, "[1].radius", "valid number"),
        ({"radius": None}, "[1].radius", "valid number"),
        ({"radius": 0}, "[1].radius", "greater than 0"),
        ({"centre": [0.0, 1.0]}, "[1].centre", "at least 3 items"),
        ({"stroke": [0, 0, 0]}, "[1].stroke", "zero vector"),
        ({"extra": 1}, "[1].extra", "not permitted"),
    ],
)
def test_a_bad_stroke_is_named_by_its_place_before_the_scene_is_read(tmp_path, capsys, change, place, words):
    strokes = write_strokes(tmp_path, [STROKE, {**STROKE, **change}])
    assert edit(tmp_path, "--strokes", strokes, scene=tmp_path / "no-such-scene.toml") == 2
    refused(capsys, strokes, "--strokes", place, words)
    assert not (tmp_path / "out.npz").exists()


def test_too_many_strokes_are_refused_with_the_limit(tmp_path, capsys):
    strokes = write_strokes(tmp_path, [STROKE] * (MAX_STROKES + 1))
    assert edit(tmp_path, "--strokes", strokes, scene=tmp_path / "no-such-scene.toml") == 2
    refused(capsys, strokes, f"at most {MAX_STROKES}")


def test_a_stencil_needs_no_direction(tmp_path):
    strokes = write_strokes(tmp_path, [{**STROKE, "tool": "stencil", "stroke": [0, 0, 0]}])
    assert load_strokes(strokes) == [{**STROKE, "tool": "stencil", "stroke": [0.0, 0.0, 0.0]}]


# ------------------------------------------------------------------ strokes the mesh refuses, before any solve
@pytest.mark.parametrize(
    ("change", "words"),
    [
        ({"stroke": [0.0, 2.0, 0.0]}, "along the surface normal"),  # the plate's normal: no direction on it
        ({"centre": [-500.0, 0.0, 0.0]}, "off the mesh"),
    ],
)
def test_a_stroke_the_mesh_cannot_take_is_named(tmp_path, capsys, change, words):
    strokes = write_strokes(tmp_path, [STROKE, {**STROKE, **change}])
    assert edit(tmp_path, "--strokes", strokes, "--iterations", "1") == 2
    refused(capsys, strokes, "--strokes", "strokes[1]", words)
    assert not (tmp_path / "out.npz").exists()


def test_brushes_about_a_triangle_s_size_or_across_the_border_give_finite_fields(session):
    """A brush smaller than a triangle made qhull fail (no triangle to interpolate in): now it holds the vertex
    nearest its centre and takes the nearest ℓ. One across the plate's edge made NaN targets (ℓ carried from
    beyond the mesh): now no target there."""
    energy = session.stroke("bend", (-0.51, 0.0, 0.06), 1e-4, np.array([0.0, 0.0, 1.0]))  # tuple, array: the API's
    assert np.isfinite(energy).all() and np.isfinite(session.phi).all()
    session.undo()
    ell = session.mesh.field(session.phi)  # any tangent field will do
    targets, inside = warp_targets(session.mesh, ell, Brush(np.array([0.95, 0, 0]), 0.3, np.array([-1.0, 0, 0])))
    assert inside.sum() > 100 and np.isfinite(targets).all()
    assert (np.linalg.norm(targets[inside], axis=1) == 0).any()  # those carried from beyond the edge: none


def test_the_viewer_s_stroke_is_checked_as_a_file_s(session):
    with pytest.raises(ArgumentError, match="stroke: radius: input should be a finite number"):
        session.stroke("bend", [-0.5, 0.0, 0.05], float("nan"), [0.0, 0.0, 1.0])
    with pytest.raises(ArgumentError, match="zero vector"):
        session.stroke("expand", [-0.5, 0.0, 0.05], 0.3, [0.0, 0.0, 0.0])
    assert session.stroke("stencil", [-0.5, 0.0, 0.05], 0.3, [0.0, 0.0, 0.0]) == (0.0, 0.0)
    session.undo()


# ------------------------------------------------------------------ --targets
def targets(**arrays):
    ell = np.zeros((VERTICES, 3))
    ell[:10] = [1.0, 0.0, 0.0]
    mask = np.zeros(VERTICES, bool)
    mask[:10] = True
    return {"ell": ell, "mask": mask} | arrays


def test_a_npy_for_targets_is_one_line_naming_it(tmp_path, capsys):
    np.save(tmp_path / "t.npy", targets()["ell"])
    assert edit(tmp_path, "--targets", str(tmp_path / "t.npy")) == 2
    refused(capsys, "t.npy", "--targets", "a .npy", "'ell' (V, 3) and 'mask' (V,)")
    assert not (tmp_path / "out.npz").exists()


@pytest.mark.parametrize("value", [np.nan, np.inf, 1e300, 1j])
def test_non_finite_huge_or_complex_targets_are_refused(tmp_path, capsys, value):
    ell = targets()["ell"].astype(type(value))
    ell[3, 1] = value
    np.savez(tmp_path / "t.npz", **targets(ell=ell))
    assert edit(tmp_path, "--targets", str(tmp_path / "t.npz")) == 2
    refused(capsys, "t.npz", "--targets", "complex" if isinstance(value, complex) else "row 3 is not finite")


@pytest.mark.parametrize(
    ("arrays", "words"),
    [
        ({"mask": np.zeros(VERTICES, bool)}, "selects no vertex"),
        ({"ell": np.zeros((VERTICES, 3))}, r"zero \(a norm ≤ 1e-12\) on every vertex"),
        ({"mask": np.ones(VERTICES, np.int64)}, "expected bool"),
        ({"ell": np.zeros((3, 3))}, "one row per vertex"),
        ({"ell": np.array([None, None], object)}, "Object arrays cannot be loaded"),  # no pickles
    ],
)
def test_bad_target_arrays_are_one_line(tmp_path, arrays, words):
    np.savez(tmp_path / "t.npz", **targets(**arrays))
    with pytest.raises(ArgumentError, match=words) as caught:
        load_targets(tmp_path / "t.npz", VERTICES)
    assert "\n" not in str(caught.value) and "t.npz: --targets:" in str(caught.value)


def test_a_small_file_cannot_unpack_a_huge_array(tmp_path):
    np.savez_compressed(tmp_path / "t.npz", ell=np.zeros((100 * VERTICES, 3)), mask=targets()["mask"])
    with pytest.raises(ArgumentError, match="'ell' unpacks to 15,746,528 bytes"):
        load_targets(tmp_path / "t.npz", VERTICES)


def test_target_rows_keep_the_solver_s_meaning():
    """Rows as given (not rescaled): one of norm ≤ NO_TARGET is no target, as the solver reads it — the degenerate
    rows `highlights` writes (zero or nearly) stay free when its ℓ is fed back as targets."""
    from reflets.editing.solver import NO_TARGET

    ell = targets()["ell"].astype(np.float64)
    ell[1] *= NO_TARGET / 2
    kept, _ = check_targets(ell, targets()["mask"], VERTICES)
    np.testing.assert_array_equal(kept, ell)
    with pytest.raises(ArgumentError, match="no target to solve for"):
        check_targets(ell * NO_TARGET / 2, targets()["mask"], VERTICES)


# ------------------------------------------------------------------ --iterations, --mesh, --light
@pytest.mark.parametrize("iterations", ["-5", "0", "1000000000"])
def test_iterations_out_of_range_are_refused_before_the_scene_is_read(tmp_path, capsys, iterations):
    strokes = write_strokes(tmp_path, [STROKE])
    assert edit(tmp_path, "--strokes", strokes, "--iterations", iterations, scene=tmp_path / "none.toml") == 2
    refused(capsys, "--iterations", iterations, f"1..{MAX_ITERATIONS}")


def test_mesh_and_light_indices_name_the_allowed_range(tmp_path, capsys, minimal_toml):
    out = str(tmp_path / "out.npz")
    assert main(["highlights", str(PLATE), "--mesh", "3", "-o", out]) == 2
    refused(capsys, "--mesh", "no mesh[3]; allowed: 0..0")
    assert main(["highlights", str(PLATE), "--mesh", "0", "--light", "4", "-o", out]) == 2
    refused(capsys, "--light", "light[4]", "allowed: 0")
    np.savez(tmp_path / "t.npz", **targets())
    assert main(["edit-highlights", str(minimal_toml), "--mesh", "0", "--targets", str(tmp_path / "t.npz"), "-o",
                 out]) == 2  # fmt: skip
    refused(capsys, "--mesh", "no orientation field to edit")
    assert not (tmp_path / "out.npz").exists()


# ------------------------------------------------------------------ fuzzing the strokes loader
hypothesis = pytest.importorskip("hypothesis")
from hypothesis import HealthCheck, given, settings  # noqa: E402
from hypothesis import strategies as st  # noqa: E402

odd_values = st.one_of(
    st.floats(allow_nan=True, allow_infinity=True),
    st.sampled_from([0.0, -1.0, 1e-300, 1e308, 1e13, 2**70, True, None, "", "0.3", "bend", [], [1, 2], {}]),
    st.lists(st.one_of(st.floats(), st.text(max_size=3), st.none()), max_size=4),
    st.text(max_size=8),
)


def _places(data, prefix=()):
    yield prefix
    children = data.items() if isinstance(data, dict) else enumerate(data) if isinstance(data, list) else ()
    for key, value in children:
        yield from _places(value, (*prefix, key))


@settings(derandomize=True, deadline=None, suppress_health_check=list(HealthCheck), database=None, max_examples=150)
@given(data=st.data())
def test_fuzzed_strokes_load_or_fail_in_one_line(tmp_path, data):
    """A valid strokes list with values replaced (NaN, inf, huge, strings, lists, nulls), keys or strokes removed
    or added: the loader returns strokes it checked, or one ArgumentError of one line naming the file."""

    def odd():  # a copy: sampled_from gives the same list or dict each time, which a later step may change
        return copy.deepcopy(data.draw(odd_values))

    strokes = copy.deepcopy([STROKE, {**STROKE, "tool": "stencil"}])
    for _ in range(data.draw(st.integers(1, 3))):
        places = list(_places(strokes))[1:]
        if not places:  # every stroke deleted
            strokes.append(odd())
            continue
        place = data.draw(st.sampled_from(places))
        parent = strokes
        for key in place[:-1]:
            parent = parent[key]
        action = data.draw(st.sampled_from(["set", "set", "delete", "add"]))
        if action == "delete":
            del parent[place[-1]]
        elif action == "add" and isinstance(parent, dict):
            parent[data.draw(st.sampled_from(["tool", "x", "Radius", ""]))] = odd()
        elif action == "add":
            parent.append(odd())
        else:
            parent[place[-1]] = odd()
    path = write_strokes(tmp_path, strokes)  # NaN and Infinity written as such: the reader refuses them
    try:
        loaded = load_strokes(path)
    except ArgumentError as exc:
        assert "\n" not in str(exc) and path in str(exc)
    else:
        for stroke in loaded:
            assert set(stroke) == {"tool", "centre", "radius", "stroke"} and stroke["radius"] > 0
            assert np.isfinite([*stroke["centre"], stroke["radius"], *stroke["stroke"]]).all()
