"""The `reflets` command: happy paths, and every bad input → one line, exit 2, no traceback, no file."""

from __future__ import annotations

import json
import os
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

import reflets
from reflets.cli import main
from reflets.imageio import read_image, write_image


def run_cli(capsys, *argv: str) -> tuple[int, str, str]:
    code = main(list(argv))
    out, err = capsys.readouterr()
    return code, out, err


def test_render_minimal_scene_to_exr_png_npy(ctx, capsys, tmp_path, minimal_toml):
    for ext in ("exr", "png", "npy"):
        out = tmp_path / f"img.{ext}"
        code, stdout, _ = run_cli(capsys, "render", str(minimal_toml), "-o", str(out))
        assert code == 0 and out.is_file() and "wrote" in stdout
    exr = read_image(tmp_path / "img.exr")
    assert exr.shape == (240, 320, 3)
    assert np.array_equal(exr, read_image(tmp_path / "img.npy"))


def test_render_size_method_and_spp_options(ctx, capsys, tmp_path, minimal_toml):
    out = tmp_path / "n.npy"
    code, _, _ = run_cli(
        capsys,
        "render",
        str(minimal_toml),
        "-o",
        str(out),
        "--size",
        "64x48",
        "--method",
        "normal",
        "--spp",
        "4",
    )
    assert code == 0
    normals = np.load(out)
    assert normals.shape == (48, 64, 3)
    assert np.allclose(normals[30, 32], [0, 1, 0], atol=1e-5)


def test_compare_identical_gives_zero_and_json_keys(ctx, capsys, tmp_path, rng):
    path = tmp_path / "x.exr"
    write_image(path, rng.random((20, 30, 3)).astype(np.float32))
    code, out, _ = run_cli(capsys, "compare", str(path), str(path), "--json")
    result = json.loads(out)
    assert code == 0
    assert set(result) == {"rmse", "relmse", "psnr", "max_abs", "flip"}
    assert result["rmse"] == 0 and result["max_abs"] == 0 and result["flip"] == 0


def test_compare_two_images_matches_numpy_and_writes_diff(capsys, tmp_path, rng):
    a = rng.random((20, 30, 3)).astype(np.float32) * 4
    b = a + rng.normal(0, 0.1, a.shape).astype(np.float32).clip(-a, None)
    write_image(tmp_path / "a.exr", a)
    write_image(tmp_path / "b.exr", b)
    code, out, _ = run_cli(
        capsys,
        "compare",
        str(tmp_path / "b.exr"),
        str(tmp_path / "a.exr"),
        "--json",
        "--diff",
        str(tmp_path / "d.png"),
    )
    result = json.loads(out)
    d = b.astype(np.float64) - a
    assert code == 0 and (tmp_path / "d.png").is_file()
    assert result["rmse"] == pytest.approx(np.sqrt(np.mean(d**2)), rel=1e-9)
    assert result["relmse"] == pytest.approx(np.mean(d**2 / (a.astype(np.float64) ** 2 + 1e-2)), rel=1e-9)
    assert result["max_abs"] == pytest.approx(np.max(np.abs(d)), rel=1e-9)
    assert result["psnr"] == pytest.approx(10 * np.log10(a.max() ** 2 / np.mean(d**2)), rel=1e-7)
    assert 0 < result["flip"] < 1


def test_schema_is_json_with_the_scene_sections(capsys):
    code, out, _ = run_cli(capsys, "schema")
    schema = json.loads(out)
    assert code == 0
    assert {"camera", "materials", "mesh", "light", "background"} <= set(schema["properties"])
    assert "base_dir" not in schema["properties"]


def test_info_names_renderer_and_methods(ctx, capsys):
    code, out, _ = run_cli(capsys, "info", "--json")
    info = json.loads(out)
    assert code == 0
    assert info["opengl"]["renderer"] and "forward" in info["methods"]
    assert info["cluster"]["engine"] == "dask.distributed" and info["cluster"]["version"]  # references on a cluster


# ---------------------------------------------------------------- bad input: exit 2, one line, no output file


def _scene(tmp_path, text: str, name: str = "s.toml"):
    path = tmp_path / name
    path.write_text(text)
    return path


BAD = {
    "missing scene file": (lambda p, t: [str(p / "nope.toml")], "nope.toml"),
    "scene is a directory": (lambda p, t: [str(p)], "directory"),
    "invalid TOML": (lambda p, t: [str(_scene(p, t + "\n[[mesh\n"))], "invalid TOML"),
    "unknown key": (lambda p, t: [str(_scene(p, t.replace("fov_y", "fovy")))], "camera.fovy"),
    "unknown material type": (lambda p, t: [str(_scene(p, t.replace('"lambert"', '"glass"')))], "glass"),
    "unknown shape": (lambda p, t: [str(_scene(p, t.replace('"plane"', '"cone"')))], "mesh[0]"),
    "wrong vector length": (
        lambda p, t: [str(_scene(p, t.replace("[0, 2, 0]", "[0, 2]")))],
        "light[0].position",
    ),
    "negative radiance": (
        lambda p, t: [str(_scene(p, t.replace("[10, 10, 10]", "[10, -10, 10]")))],
        "light[0].intensity",
    ),
    "NaN albedo": (
        lambda p, t: [str(_scene(p, t.replace("[0.8, 0.8, 0.8]", "[0.8, nan, 0.8]")))],
        "materials.floor.albedo",
    ),
    "zero image size in file": (
        lambda p, t: [str(_scene(p, t.replace("[320, 240]", "[0, 240]")))],
        "camera.size",
    ),
    "zero --size": (lambda p, t: [str(_scene(p, t)), "--size", "0x240"], "--size"),
    "absurd --size": (lambda p, t: [str(_scene(p, t)), "--size", "100000x100000"], "--size"),
    "malformed --size": (lambda p, t: [str(_scene(p, t)), "--size", "big"], "--size"),
    "missing mesh file": (
        lambda p, t: [str(_scene(p, t + '\n[[mesh]]\nfile = "gone.obj"\nmaterial = "floor"\n'))],
        "mesh[1].file",
    ),
    "unknown method": (lambda p, t: [str(_scene(p, t)), "--method", "raytrace"], "forward"),
    "bad spp": (lambda p, t: [str(_scene(p, t)), "--spp", "3"], "spp"),
    "unknown technique parameter": (lambda p, t: [str(_scene(p, t)), "--param", "samples=3"], "area_samples"),
    "negative spp": (lambda p, t: [str(_scene(p, t)), "--spp", "-3"], "1..65536"),
    "huge spp": (lambda p, t: [str(_scene(p, t)), "--spp", "1000000000000"], "1..65536"),
    "supersampling beyond the driver": (lambda p, t: [str(_scene(p, t)), "--spp", "65536"], "at most"),
    "empty environment grid": (lambda p, t: [str(_scene(p, t)), "--param", "env_grid=[0,0]"], "env_grid"),
    "misspelt method": (lambda p, t: [str(_scene(p, t)), "--method", "fowrard"], "did you mean 'forward'"),
    "misspelt key": (lambda p, t: [str(_scene(p, t.replace("fov_y", "fov")))], "did you mean 'fov_y'"),
    "misspelt shape": (lambda p, t: [str(_scene(p, t.replace('"plane"', '"plnae"')))], "did you mean 'plane'"),
    "binary scene file": (lambda p, t: [str(_binary(p))], "not a text file"),
    "no pydantic internals": (
        lambda p, t: [
            str(_scene(p, t + '\n[[mesh]]\nshape = "sphere"\nmaterial = "floor"\ntransform = { scale = -1 }\n'))
        ],
        "mesh[1].transform.scale: input should be greater than 0",
    ),
}


def _binary(tmp_path):
    path = tmp_path / "scene.toml"
    path.write_bytes(b"\x00\x01\xff\xfe not text")
    return path


@pytest.mark.parametrize("case", sorted(BAD))
def test_bad_input_exits_2_with_one_line_and_writes_nothing(ctx, capsys, tmp_path, minimal_toml, case):
    make_args, word = BAD[case]
    out = tmp_path / "out.exr"
    text = minimal_toml.read_text()
    minimal_toml.unlink()
    code, stdout, stderr = run_cli(capsys, "render", *make_args(tmp_path, text), "-o", str(out))
    assert code == 2
    lines = stderr.strip().splitlines()
    assert len(lines) == 1, stderr
    assert word in lines[0], f"{word!r} not in {lines[0]!r}"
    assert "Traceback" not in stderr
    assert not out.exists()
    assert [f.name for f in tmp_path.iterdir() if f.name.startswith(".out")] == []  # no temp file left


def test_unwritable_output_paths_fail_before_rendering(capsys, tmp_path, minimal_toml):
    for target, word in [
        (tmp_path / "no" / "dir" / "x.exr", "does not exist"),
        (tmp_path / "x.tiff", "allowed"),
        (tmp_path / "folder.exr", "directory"),
    ]:
        (tmp_path / "folder.exr").mkdir(exist_ok=True)
        code, _, err = run_cli(capsys, "render", str(minimal_toml), "-o", str(target))
        assert code == 2 and word in err and "Traceback" not in err
    assert not (tmp_path / "no").exists()


def test_existing_output_is_kept_when_the_scene_is_bad(capsys, tmp_path):
    out = tmp_path / "keep.exr"
    out.write_bytes(b"precious")
    bad = _scene(tmp_path, "[camera]\nposition = [0, 0, 1]\n")
    code, _, _ = run_cli(capsys, "render", str(bad), "-o", str(out))
    assert code == 2 and out.read_bytes() == b"precious"


def test_an_output_never_replaces_one_of_the_scene_s_own_inputs(capsys, tmp_path, monkeypatch):
    """render / reference -o naming the scene's texture, environment map or height-field file (a .png, a .hdr and
    an .npy are outputs too): one line, exit 2, the file untouched (render used to write over them)."""
    from PIL import Image

    monkeypatch.chdir(tmp_path)
    Image.fromarray(np.full((8, 8, 3), 200, np.uint8)).save("wood.png")
    write_image("sky.hdr", np.full((8, 16, 3), 0.5, np.float32))
    np.save("ground.npy", np.zeros((4, 4)))
    scene = _scene(tmp_path, '[camera]\nposition = [0, 1, 3]\nlook_at = [0, 0, 0]\nsize = [16, 12]\n'
                   '[materials.m]\ntype = "gltf"\nbase_color_texture = { texture = "wood.png" }\n'
                   '[[mesh]]\nshape = "sphere"\nmaterial = "m"\n'
                   '[[mesh]]\nshape = "heightfield"\nfile = "ground.npy"\nmaterial = "m"\n'
                   '[[light]]\ntype = "environment"\nfile = "sky.hdr"\n')  # fmt: skip
    inputs = ("wood.png", "sky.hdr", "ground.npy")
    before = {name: (tmp_path / name).read_bytes() for name in inputs}
    for argv in (["render", str(scene), "-o", "wood.png"], ["render", str(scene), "-o", str(tmp_path / "sky.hdr")],
                 ["reference", str(scene), "-o", "ground.npy", "--spp", "1"]):  # fmt: skip
        code, _, err = run_cli(capsys, *argv)
        assert code == 2 and "is one of the inputs" in err and len(err.strip().splitlines()) == 1, err
    assert all((tmp_path / name).read_bytes() == data for name, data in before.items())
    assert main(["render", str(scene), "-o", "out.png"]) == 0  # another name is fine


def test_compare_bad_inputs(capsys, tmp_path, rng):
    write_image(tmp_path / "a.exr", rng.random((4, 4, 3)).astype(np.float32))
    write_image(tmp_path / "b.exr", rng.random((5, 4, 3)).astype(np.float32))
    for argv, word in [
        (["missing.exr", str(tmp_path / "a.exr")], "missing.exr"),
        ([str(tmp_path / "a.exr"), str(tmp_path / "b.exr")], "shape"),
    ]:
        code, _, err = run_cli(capsys, "compare", *argv)
        assert code == 2 and word in err and len(err.strip().splitlines()) == 1


def test_real_process_prints_no_traceback_and_debug_shows_it(tmp_path):
    bad = _scene(tmp_path, "[camera]\nposition = [0, 0, 1]\nlook_at = [0, 0, 0]\nsize = [-1, 2]\n")
    env = {**os.environ, "PYTHONPATH": os.pathsep.join(sys.path)}

    def run(*argv):
        cmd = [sys.executable, "-m", "reflets.cli", *argv]
        return subprocess.run(cmd, capture_output=True, text=True, env=env, timeout=120)

    plain = run("render", str(bad), "-o", str(tmp_path / "x.exr"))
    assert plain.returncode == 2 and "Traceback" not in plain.stderr
    assert plain.stderr.startswith("reflets: error:") and "camera.size" in plain.stderr
    debug = run("--debug", "render", str(bad), "-o", str(tmp_path / "x.exr"))
    assert "Traceback" in debug.stderr and debug.returncode != 0


def test_minimal_scene_renders_from_a_fresh_process_in_under_five_seconds(tmp_path, minimal_toml):
    """The issue's budget, start-up included (measured median here: 0.6 s on 2 cores with llvmpipe)."""
    import time

    env = {**os.environ, "PYTHONPATH": os.pathsep.join(sys.path)}
    start = time.perf_counter()
    proc = subprocess.run(
        [sys.executable, "-m", "reflets.cli", "render", str(minimal_toml), "-o", str(tmp_path / "m.exr")],
        capture_output=True,
        text=True,
        env=env,
        timeout=60,
    )
    elapsed = time.perf_counter() - start
    assert proc.returncode == 0, proc.stderr
    assert elapsed < 5.0


def test_an_output_never_replaces_an_image_or_buffer_a_gltf_names(capsys, tmp_path):
    """A .gltf's textures live in files it names by uri: `render model.gltf -o sheen.png` used to write over one."""
    import shutil

    source = Path(__file__).parent / "data" / "gltf" / "SheenTest"
    for name in ("SheenTest.gltf", "SheenTest.bin", "sheen.png"):
        shutil.copy(source / name, tmp_path / name)
    before = (tmp_path / "sheen.png").read_bytes()
    code, _, err = run_cli(capsys, "render", str(tmp_path / "SheenTest.gltf"), "-o", str(tmp_path / "sheen.png"))
    assert code == 2 and "is one of the inputs" in err and len(err.strip().splitlines()) == 1, err
    assert (tmp_path / "sheen.png").read_bytes() == before
    assert tmp_path / "SheenTest.bin" in reflets.load_scene(tmp_path / "SheenTest.gltf").input_files()


def test_bench_refuses_a_results_folder_it_cannot_make_before_running(capsys, tmp_path):
    """A results folder under a missing one, or a file: one line naming it, exit 2, nothing made (the suite's
    minutes of work never start)."""
    target = tmp_path / "missing" / "results"
    code, _, err = run_cli(capsys, "bench", "ibl", "-o", str(target))
    assert code == 2 and str(target) in err and len(err.strip().splitlines()) == 1
    assert not (tmp_path / "missing").exists()
    existing = tmp_path / "notes.txt"
    existing.write_text("mine")
    code, _, err = run_cli(capsys, "bench", "ibl", "-o", str(existing))
    assert code == 2 and existing.read_text() == "mine"


@pytest.mark.parametrize(
    "job",
    [[], ["x"], ["[]"], ['{"scene": "nope"}'], ['{"scene": "showcase", "size": [0, 0], "frames": 1}'],
     ['{"scene": "showcase", "size": [64, 48], "frames": 1e9}'], ["[" * 100_000]],
)  # fmt: skip
def test_bench_gpu_s_subprocess_refuses_a_job_it_cannot_read(capsys, job):
    from reflets.bench.gpu import main

    assert main(job) == 2
    err = capsys.readouterr().err
    assert err.startswith("reflets.bench.gpu: ") and err.count("\n") == 1


@pytest.mark.parametrize("argv", [["edit-highlights", "s.toml", "--mesh", "0", "--iterations", "1e9", "-o", "a.npz"],
                                  ["ar", "bord"], [], ["render", "s.toml", "--spp", "many"]])  # fmt: skip
def test_argparse_errors_are_one_line_too(capsys, argv):
    with pytest.raises(SystemExit) as caught:
        main(argv)
    err = capsys.readouterr().err
    assert caught.value.code == 2 and err.count("\n") == 1 and err.startswith("reflets: error: "), err


@pytest.mark.parametrize(("variable", "value"), [("REFLETS_CACHE_MB", "nan"), ("REFLETS_CACHE_MB", "-1"),
                                                 ("REFLETS_MEMORY_LIMIT", "1e300x")])  # fmt: skip
def test_a_bad_environment_variable_is_one_line_before_any_work(capsys, monkeypatch, tmp_path, variable, value):
    """Checked as the command starts: not after the scene's warnings, at its first use deep in a render."""
    monkeypatch.setenv(variable, value)
    out = tmp_path / "x.png"
    assert main(["render", str(tmp_path / "missing.toml"), "-o", str(out)]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and variable in err and not out.exists(), err
