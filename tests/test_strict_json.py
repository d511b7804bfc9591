"""Every `--json` output and every results file is strict JSON: a number with no finite value is null (issue 21).

Python's json writes NaN / Infinity by default, which jq, JSON.parse and strict parsers reject; the parse below
raises on those tokens, as they do.
"""

from __future__ import annotations

import json
import math
from pathlib import Path

import numpy as np
import pytest

from reflets import jsonio
from reflets.cli import main
from reflets.imageio import write_image

ROOT = Path(__file__).resolve().parents[1]


def _reject(token: str):
    raise ValueError(f"non-strict JSON token {token}")


def strict_loads(text: str):
    """``json.loads`` that fails on NaN, Infinity and -Infinity, like jq or JSON.parse."""
    return json.loads(text, parse_constant=_reject)


def run_cli(capsys, *argv: str) -> tuple[int, str]:
    code = main(list(argv))
    out, _ = capsys.readouterr()
    return code, out


# ---------------------------------------------------------------- the helper


def test_strict_loads_rejects_the_non_finite_tokens():
    for text in ("NaN", "[Infinity]", '{"a": -Infinity}'):
        with pytest.raises(ValueError, match="non-strict"):
            strict_loads(text)


def test_dumps_writes_every_non_finite_number_as_null():
    nan, inf = float("nan"), float("inf")
    data = {
        "python": [nan, inf, -inf, 1.5],
        "numpy": (np.float64(np.nan), np.float32(np.inf), np.float16(-np.inf), np.float32(0.25)),
        "nested": {"deeper": [{"x": (nan, [inf])}], "fine": 2},
        "array": np.array([[1.0, np.nan], [-np.inf, 3.0]]),
        "scalars": [np.int64(7), np.bool_(True), None, "NaN"],
        np.int32(4): -inf,
    }
    text = jsonio.dumps(data)
    assert strict_loads(text) == {
        "python": [None, None, None, 1.5],
        "numpy": [None, None, None, 0.25],
        "nested": {"deeper": [{"x": [None, [None]]}], "fine": 2},
        "array": [[1.0, None], [None, 3.0]],
        "scalars": [7, True, None, "NaN"],
        "4": None,
    }
    assert strict_loads(jsonio.dumps(nan)) is None and strict_loads(jsonio.dumps(np.float32(-np.inf))) is None


def test_dumps_keeps_the_formatting_arguments_and_finite_values():
    data = {"b": [1, 2.5, {"z": None, "a": True}], "a": "é"}
    for kw in ({}, {"indent": 2}, {"indent": 1, "sort_keys": True}):
        assert jsonio.dumps(data, **kw) == json.dumps(data, **kw)
    assert jsonio.dumps([0.1, 1e300, -0.0, 5e-324]) == json.dumps([0.1, 1e300, -0.0, 5e-324])


def test_dumps_is_strict_even_when_asked_otherwise_and_through_default():
    class Odd:
        pass

    assert jsonio.dumps([math.inf], allow_nan=True) == "[null]"
    assert strict_loads(jsonio.dumps({"o": Odd()}, default=lambda o: [math.nan, 1.0])) == {"o": [None, 1.0]}


def test_write_writes_strict_utf8(tmp_path):
    path = jsonio.write(tmp_path / "r.json", {"psnr": math.inf, "name": "réf"}, indent=2)
    assert strict_loads(path.read_text(encoding="utf-8")) == {"psnr": None, "name": "réf"}


# ---------------------------------------------------------------- the CLI's --json outputs and JSON files


@pytest.mark.parametrize(("content", "said"), [
    ('{"a": 1, "a": 2}', "key 'a' is given twice"),
    ('{"markers": {"0": [], "0": []}}', "key '0' is given twice"),
    ('{"a": NaN}', "NaN is not JSON"),
    ('[-Infinity]', "-Infinity is not JSON"),
    ("[" * 100_000 + "]" * 100_000, "nested too deeply"),
    (b"\xff\xfe{", "not a text file"),
    ('{"a": 1', "not a board"),
    (None, "is a directory"),
])  # fmt: skip
def test_json_inputs_are_read_strictly_and_refused_in_one_line(tmp_path, content, said):
    """What every JSON input of a command goes through (a board, intrinsics, strokes, an event script)."""
    from reflets.errors import ArgumentError

    path = tmp_path / "in.json"
    if content is None:
        path.mkdir()
    elif isinstance(content, bytes):
        path.write_bytes(content)
    else:
        path.write_text(content)
    with pytest.raises(ArgumentError) as caught:
        jsonio.read(path, field="--board", what="a board")
    assert said in str(caught.value) and "\n" not in str(caught.value) and "--board" in str(caught.value)


def test_a_device_is_not_read_as_a_json_input():
    """/dev/zero has no size to check and no end: refused before it is read."""
    from reflets.errors import ArgumentError

    with pytest.raises(ArgumentError, match="is not a regular file"):
        jsonio.read("/dev/zero", field="--board", what="a board")


def test_a_json_input_past_the_size_bound_is_refused_before_it_is_read(tmp_path, monkeypatch):
    from reflets.errors import ArgumentError

    path = tmp_path / "big.json"
    path.write_text("[" + "0," * 1000 + "0]")
    monkeypatch.setattr(jsonio, "MAX_JSON_BYTES", 1000)
    with pytest.raises(ArgumentError, match="is 2,003 bytes; a script is at most 1,000"):
        jsonio.read(path, what="a script")
    small = tmp_path / "ok.json"
    small.write_text('{"a": [1, 2.5]}')
    assert jsonio.read(small) == {"a": [1, 2.5]}


def test_compare_identical_images_gives_strict_json_with_psnr_null(capsys, tmp_path, rng):
    path = tmp_path / "x.exr"
    write_image(path, rng.random((12, 16, 3)).astype(np.float32))
    code, out = run_cli(capsys, "compare", str(path), str(path), "--json")
    result = strict_loads(out)
    assert code == 0
    assert result["psnr"] is None
    assert result["rmse"] == 0 and result["max_abs"] == 0 and result["flip"] == 0


def test_compare_with_a_black_reference_and_a_zero_stderr_gives_nulls(capsys, tmp_path, rng):
    test, ref = tmp_path / "t.exr", tmp_path / "r.exr"
    write_image(test, rng.random((12, 16, 3)).astype(np.float32) + 0.1)
    write_image(ref, np.zeros((12, 16, 3), np.float32))
    write_image(tmp_path / "r.stderr.exr", np.zeros((12, 16, 3), np.float32))  # no Monte Carlo noise: z is NaN
    code, out = run_cli(capsys, "compare", str(test), str(ref), "--json")
    result = strict_loads(out)
    assert code == 0
    assert result["psnr"] is None  # -inf: the default peak (the reference's maximum) is 0
    assert result["mean_z"] is None and result["mean_abs_z"] is None and result["within_3_stderr"] is None
    assert result["rmse"] > 0 and math.isfinite(result["relmse"])


def test_info_json_is_strict(capsys):
    code, out = run_cli(capsys, "info", "--json")  # exit 2 without OpenGL, and still one JSON object
    info = strict_loads(out)
    assert code in (0, 2) and "methods" in info and "opengl" in info


def test_schema_is_strict(capsys):
    code, out = run_cli(capsys, "schema")
    assert code == 0 and "properties" in strict_loads(out)


def test_ar_board_file_is_strict_and_ar_files_write_null(capsys, tmp_path):
    from reflets.ar import write_json

    assert run_cli(capsys, "ar", "board", "-o", str(tmp_path / "board.json"))[0] == 0
    assert strict_loads((tmp_path / "board.json").read_text(encoding="utf-8"))["markers"]
    write_json(tmp_path / "camera.json", {"K": np.eye(3).tolist(), "dist": [math.nan] * 5})
    assert strict_loads((tmp_path / "camera.json").read_text(encoding="utf-8"))["dist"] == [None] * 5


def test_bench_results_file_is_strict(monkeypatch, tmp_path, capsys):
    import reflets.bench as bench

    def fake_suite(quick: bool, out_dir: Path) -> tuple[dict, str]:
        return {"rows": [{"prepare_ms": math.nan, "speedup": np.float64(np.inf), "frame_ms": 1.5}]}, "# fake\n"

    monkeypatch.setattr(bench, "suite", lambda name: fake_suite)
    machine = {"python": "3", "platform": "p", "cpu": "c", "cores": 1, "opengl": {}}
    monkeypatch.setattr(bench, "machine", lambda: machine)
    bench.run_suite("fake", tmp_path, quick=True)
    capsys.readouterr()
    results = strict_loads((tmp_path / "fake.json").read_text(encoding="utf-8"))
    assert results["rows"] == [{"prepare_ms": None, "speedup": None, "frame_ms": 1.5}]


# ---------------------------------------------------------------- committed JSON files


def _committed_json() -> list[Path]:
    return sorted([*(ROOT / "benchmarks" / "results").rglob("*.json"), *(ROOT / "src" / "reflets").rglob("*.json")])


def test_committed_json_files_parse_strictly():
    files = _committed_json()
    assert any(p.name == "shadows.json" for p in files), f"benchmarks/results not found under {ROOT}"
    bad = []
    for path in files:
        try:
            strict_loads(path.read_text(encoding="utf-8"))
        except ValueError as exc:
            bad.append(f"{path.relative_to(ROOT)}: {exc}")
    assert not bad, "\n".join(bad)
