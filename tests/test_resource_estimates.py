"""Work estimated before it is allocated (issue 21): every parameter that multiplies memory is checked against an
estimate (reflets.resources) and refused past the available memory — one line, exit 2, naming the field, the
estimate and the limit. REFLETS_MEMORY_LIMIT sets the limit low so that each refusal is exercised cheaply."""

from __future__ import annotations

import os
import subprocess
import sys
import time
import tracemalloc

import numpy as np
import pytest

import reflets
from reflets.cli import main
from reflets.demo import scene_path
from reflets.errors import ArgumentError, RefletsError, ResourceError
from reflets.resources import (
    ENV_VAR,
    available_memory,
    check,
    fitting_size,
    format_bytes,
    largest_fitting,
    memory_budget,
    parse_bytes,
)

TEAPOT = scene_path("40_reflect_teapot_sphere.toml")
PLANE = scene_path("01_plane_point.toml")
TRANSLUCENT_SPHERE = {
    "camera": {"position": [0, 0.5, 3], "look_at": [0, 0, 0], "fov_y": 35, "size": [48, 36]},
    "materials": {"skin": {"type": "translucent", "preset": "skin1", "eta": 1.0, "mm_per_unit": 25.0}},
    "mesh": [{"shape": "sphere", "radius": 1.0, "material": "skin"}],
    "light": [{"type": "point", "position": [2, 3, 2], "intensity": [20, 20, 20]}],
}


def _one_line(capsys, argv) -> str:
    assert main(argv) == 2, argv
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1 and "Traceback" not in err, err
    return err


def _refusal(err: str, field: str) -> None:
    """The line names the field, the estimate and the limit (and where the limit comes from)."""
    assert f"error: {field}: " in err, err
    assert "needs about" in err and "is available (" in err, err


# ------------------------------------------------------------------------------------- the acceptance
def test_subdivide_400_is_refused_in_a_fresh_process_quickly_and_small(tmp_path):
    """``reflets render <teapot> --method fermat --param subdivide=400`` grew to 23 GB and was killed: now exit 2,
    one line naming subdivide, its estimate (42 GB) and the limit, with the process's peak resident memory under
    500 MB (measured 178 MB)."""
    env = {**os.environ, "PYTHONPATH": os.pathsep.join(sys.path)}
    env.pop(ENV_VAR, None)
    if available_memory() > 40e9:  # a machine where the 42 GB would fit: refuse it against a stated limit
        env[ENV_VAR] = "16GB"
    stderr, peak = tmp_path / "stderr.txt", tmp_path / "peak.txt"
    # The child's own peak (VmHWM, written at exit): the kernel's ru_maxrss of a child counts the forking parent's
    # pages too (exec records the old address space's high-water mark), so under pytest it says gigabytes.
    launcher = (
        "import atexit, pathlib, runpy, sys\n"
        "def peak():\n"
        "    status = pathlib.Path('/proc/self/status').read_text().splitlines()\n"
        "    line = next(l for l in status if l.startswith('VmHWM:'))\n"
        f"    pathlib.Path({str(peak)!r}).write_text(line.split()[1])\n"
        "atexit.register(peak)\n"
        "sys.argv = sys.argv[1:]\n"
        "runpy.run_module('reflets.cli', run_name='__main__')\n"
    )
    cmd = [sys.executable, "-c", launcher, "reflets", "render", str(TEAPOT), "--method", "fermat"]
    cmd += ["--param", "subdivide=400", "-o", str(tmp_path / "teapot.png")]
    start = time.perf_counter()
    with open(stderr, "w") as err:
        proc = subprocess.run(cmd, stdout=subprocess.DEVNULL, stderr=err, env=env)
    elapsed = time.perf_counter() - start
    text = stderr.read_text().strip()
    assert proc.returncode == 2, text
    assert len(text.splitlines()) == 1 and "Traceback" not in text, text
    _refusal(text, "subdivide")
    assert "400 needs about" in text and "GB" in text and "fits)" in text, text
    peak_kb = int(peak.read_text())
    assert peak_kb * 1024 < 500e6, f"peak resident memory {peak_kb / 1024:.0f} MB"
    assert elapsed < 20.0  # start-up included (measured 1.2 s here; the check itself: the next test)


def test_subdivide_400_check_itself_takes_under_a_second(monkeypatch):
    """In-process, imports and the GL context aside: the scene's meshes (the teapot read from its file), the
    estimate and the refusal."""
    from reflets.gpu import get_context
    from reflets.renderer import Renderer

    monkeypatch.setenv(ENV_VAR, "16GB")
    scene = reflets.load_scene(TEAPOT)
    get_context()  # the GL context, as the CLI has it when the technique prepares
    start = time.perf_counter()
    with pytest.raises(ResourceError, match=r"subdivide: 400 needs about 4\d\.\d GB") as info:
        Renderer(scene, method="fermat", subdivide=400)
    assert time.perf_counter() - start < 1.0
    assert "(≤ " in str(info.value) and "REFLETS_MEMORY_LIMIT" in str(info.value)
    assert isinstance(info.value, ArgumentError)  # an out-of-range argument for this machine: exit 2 like the rest


def test_subdivide_that_fits_renders_and_the_hint_fits(monkeypatch):
    """The largest k the message offers is accepted under the same limit."""
    from reflets.renderer import Renderer

    monkeypatch.setenv(ENV_VAR, "300MB")
    scene = reflets.load_scene(TEAPOT)
    with pytest.raises(ResourceError) as info:
        Renderer(scene, method="fermat", subdivide=40)
    k = int(str(info.value).split("(≤ ")[1].split(" fits")[0])
    assert 20 <= k < 40
    with Renderer(scene, method="fermat", size=(16, 12), subdivide=k) as renderer:
        assert renderer._technique.subdivisions == [k, k]


def test_subdivision_estimate_bounds_the_measured_peak():
    """The formula's S term against tracemalloc's peak of MeshData.subdivided (its result included): an upper
    bound, and not a loose one (measured 206–209 B per vertex where S gives 208–231)."""
    from reflets.reflections.technique import subdivision_bytes
    from reflets.scene.geometry import mesh_data

    teapot = mesh_data(reflets.load_scene(TEAPOT), 1)
    k = 8
    tracemalloc.start()
    try:
        split = teapot.subdivided(k)
        peak = tracemalloc.get_traced_memory()[1]
    finally:
        tracemalloc.stop()
    v, f = split.n_vertices, split.n_triangles
    assert v == teapot.n_triangles * (k + 1) * (k + 2) // 2 and f == teapot.n_triangles * k * k
    s_term = max(164 * v + 24 * f, 140 * v + 36 * f) + 96 * teapot.n_triangles + 64 * (k + 1) ** 2
    assert 0.8 * s_term <= peak <= s_term
    one = subdivision_bytes([(teapot.n_triangles, teapot.n_vertices, k)], 1)
    two = subdivision_bytes([(teapot.n_triangles, teapot.n_vertices, k)], 2)
    assert one >= s_term and two - one == 16 * v  # one more reflector: its solved points (the buffers are shared)


# ------------------------------------------------------------------------------------- the other parameters
def test_image_size_is_refused_before_rendering_and_writing(capsys, monkeypatch, tmp_path):
    monkeypatch.setenv(ENV_VAR, "100MB")
    err = _one_line(capsys, ["render", str(PLANE), "--size", "2048x2048", "-o", str(tmp_path / "big.png")])
    _refusal(err, "size")
    assert "2048x2048 needs about 805 MB" in err and "writing .png" in err and "fits)" in err
    assert not (tmp_path / "big.png").exists()


def test_image_size_is_refused_by_the_technique_through_the_api(monkeypatch):
    monkeypatch.setenv(ENV_VAR, "50MB")
    with pytest.raises(ResourceError, match=r"^size: 1024x1024 needs about 83\.9 MB .*80 B.*\(≤ 790x790 fits\)"):
        reflets.render(PLANE, size=(1024, 1024))


def test_samples_per_pixel_times_size_is_refused_with_the_spp_that_fits(monkeypatch):
    monkeypatch.setenv(ENV_VAR, "100MB")
    with pytest.raises(ResourceError, match=r"^spp: 64 spp at 256x256 needs about 336 MB .*\(≤ 16 spp fits\)"):
        reflets.render(PLANE, size=(256, 256), spp=64)


def test_fermat_counts_its_g_buffer_per_sample(monkeypatch):
    monkeypatch.setenv(ENV_VAR, "100MB")
    with pytest.raises(ResourceError, match=r"^size: 1024x768 .*× 152 B"):  # 80 forward + 72 G-buffer
        reflets.render(TEAPOT, method="fermat", size=(1024, 768), subdivide=1)


def test_translucent_light_map_is_refused(capsys, monkeypatch, tmp_path):
    monkeypatch.setenv(ENV_VAR, "100MB")
    scene = tmp_path / "sphere.toml"
    import tomli_w

    scene.write_text(tomli_w.dumps(TRANSLUCENT_SPHERE))
    argv = ["render", str(scene), "--method", "translucent", "--param", "light_map=4096", "--size", "16x12"]
    err = _one_line(capsys, [*argv, "-o", str(tmp_path / "t.exr")])
    _refusal(err, "light_map")
    assert "4096 needs about 604 MB" in err and "(≤ 1666 fits)" in err


def test_numpy_reference_size_is_refused(capsys, monkeypatch, tmp_path):
    monkeypatch.setenv(ENV_VAR, "200MB")
    argv = ["reference", str(PLANE), "--size", "2048x2048", "--spp", "1", "-q", "-o", str(tmp_path / "r.exr")]
    err = _one_line(capsys, argv)
    _refusal(err, "size")
    assert "the reference: 4,194,304 pixels" in err and "(≤ 1000x1000 fits)" in err


@pytest.mark.parametrize(("eta", "per_pixel"), [(1.0, "640"), (1.3, "6,400")])
def test_volumetric_reference_size_is_refused(monkeypatch, eta, per_pixel):
    from reflets.reference import reference

    monkeypatch.setenv(ENV_VAR, "150MB")
    scene = {**TRANSLUCENT_SPHERE, "materials": {"skin": {**TRANSLUCENT_SPHERE["materials"]["skin"], "eta": eta}}}
    with pytest.raises(ResourceError, match=rf"^size: 512x384 .*volumetric reference: 196,608 pixels × {per_pixel} B"):
        reference(scene, engine="volumetric", size=(512, 384), spp=1, progress=False, workers=1)


def test_volumetric_reference_counts_its_worker_processes(monkeypatch):
    from reflets.reference.volumetric import volumetric_bytes

    scene = reflets.load_dict(TRANSLUCENT_SPHERE)
    one, three = volumetric_bytes(scene, (100, 100), workers=1), volumetric_bytes(scene, (100, 100), workers=2)
    assert three == 3 * one  # two workers and the parent, each with its job


def test_scratch_table_size_and_rays_are_refused(capsys, monkeypatch, tmp_path):
    monkeypatch.setenv(ENV_VAR, "500MB")
    out = str(tmp_path / "t.npz")
    err = _one_line(capsys, ["scratch-brdf", "--profile", "vgroove:0.5", "--size", "2048", "--rays", "200", "-o", out])
    _refusal(err, "size")
    assert "2048² bins" in err and "(≤ 1274 fits)" in err
    argv = ["scratch-brdf", "--profile", "vgroove:0.5", "--size", "64", "--rays", "1000000", "-o", out]
    err = _one_line(capsys, argv)
    _refusal(err, "rays")
    assert "64,000,000 rays" in err


def test_scratched_material_names_its_own_fields(monkeypatch, tmp_path):
    """A material's table is built on a cache miss: refused as ``table_size``; its α maps as ``alpha_size``."""
    from reflets.scratches.material import cached_alpha, cached_table

    monkeypatch.setenv("XDG_CACHE_HOME", str(tmp_path))  # a cold disk cache
    monkeypatch.setenv(ENV_VAR, "1GB")
    with pytest.raises(ResourceError, match=r"^table_size: 4096 needs about 4\.\d GB"):
        cached_table("vgroove:0.5", {"ior": None, "conductor": None, "fresnel": "auto"}, 4096, 201, "numpy")
    scene = reflets.load_dict(
        {
            "camera": {"position": [0, 1, 2], "look_at": [0, 0, 0]},
            "materials": {"s": {"type": "scratched", "preset": "3.14d", "alpha_size": 2048}},
            "mesh": [{"shape": "plane", "material": "s"}],
            "light": [{"type": "point", "position": [0, 1, 0], "intensity": [1, 1, 1]}],
        }
    )
    with pytest.raises(ResourceError, match=r"^alpha_size: 2048 needs about 3\.4 GB \(32 layers .*\(≤ 1024 fits\)"):
        cached_alpha(scene.materials["s"])


def test_ltc_fit_size_is_refused(capsys, monkeypatch, tmp_path):
    monkeypatch.setenv(ENV_VAR, "100MB")
    err = _one_line(capsys, ["fit-ltc", "--brdf", "ggx", "--size", "64", "-q", "-o", str(tmp_path / "l.npz")])
    _refusal(err, "size")
    assert "64 needs about 315 MB" in err and "(≤ 20 fits)" in err


def test_mesh_segments_are_refused_by_mesh(capsys, monkeypatch, tmp_path):
    monkeypatch.setenv(ENV_VAR, "1GB")
    text = PLANE.read_text()
    scene = tmp_path / "dense.toml"
    plane = 'shape = "plane"\nsize = [4, 4]'
    assert plane in text
    scene.write_text(text.replace(plane, plane + "\nsegments = [4096, 4096]"))
    err = _one_line(capsys, ["render", str(scene), "--size", "8x8", "-o", str(tmp_path / "d.exr")])
    _refusal(err, "mesh[0].segments")
    assert "16,785,409 vertices" in err and "(≤ [1493, 1493] fits)" in err


def test_an_allocation_no_estimate_foresaw_is_one_line(capsys, monkeypatch, tmp_path):
    import reflets.api

    def out_of_memory(*args, **kwargs):
        raise MemoryError("Unable to allocate 290. MiB for an array with shape (12692064, 3) and data type float64")

    monkeypatch.setattr(reflets.api, "render", out_of_memory)
    err = _one_line(capsys, ["render", str(PLANE), "--size", "8x8", "-o", str(tmp_path / "x.exr")])
    assert err.startswith("reflets: error: out of memory (Unable to allocate 290. MiB")


# ------------------------------------------------------------------------------------- the module itself
@pytest.mark.parametrize(
    ("text", "expected"),
    [
        ("8000000000", 8_000_000_000), ("1e9", 10**9), ("512MB", 512 * 10**6), ("512 M", 512 * 10**6),
        ("1.5GiB", 3 * 2**29), ("64kib", 65536), ("2g", 2 * 10**9), ("12B", 12), (" 3 TB ", 3 * 10**12),
    ],
)  # fmt: skip
def test_memory_limit_formats(monkeypatch, text, expected):
    assert parse_bytes(text) == expected
    monkeypatch.setenv(ENV_VAR, text)
    assert available_memory() == expected
    assert memory_budget().source == ENV_VAR


@pytest.mark.parametrize("text", ["abc", "-5", "0", "1.2.3", "5 apples", "inf", "nan", "1e999", "1e-3", "1e19", "GB"])
def test_bad_memory_limits_are_one_clear_error(capsys, monkeypatch, tmp_path, text):
    with pytest.raises(ArgumentError, match=rf"^{ENV_VAR}: .* is not a positive number of bytes \(e\.g\."):
        parse_bytes(text)
    monkeypatch.setenv(ENV_VAR, text)
    err = _one_line(capsys, ["render", str(PLANE), "--size", "8x8", "-o", str(tmp_path / "x.exr")])
    assert ENV_VAR in err


def test_available_memory_without_the_override(monkeypatch):
    monkeypatch.delenv(ENV_VAR, raising=False)
    budget = memory_budget()
    assert budget.source in ("MemAvailable", "cgroup memory.max", "cgroup memory.limit_in_bytes", "RLIMIT_AS",
                             "physical memory", "unknown")  # fmt: skip
    assert budget.bytes > 0 and available_memory() > 0
    monkeypatch.setenv(ENV_VAR, "  ")  # empty: not set
    assert memory_budget().source != ENV_VAR


def test_check_message_and_helpers(monkeypatch):
    monkeypatch.setenv(ENV_VAR, "1GB")
    check("x", 10**9, value=3)  # exactly the limit fits
    with pytest.raises(ResourceError) as info:
        check("x", 2.5e9, value=3, what="3 things", fits=lambda budget: 1, file="scene.toml")
    assert str(info.value) == (
        "scene.toml: x: 3 needs about 2.5 GB (3 things) but 1.0 GB is available (REFLETS_MEMORY_LIMIT); "
        "lower it (≤ 1 fits)"
    )
    assert isinstance(info.value, RefletsError) and info.value.field == "x"
    assert largest_fitting(lambda n: n * n, 1, 1000, 99) == 9
    assert largest_fitting(lambda n: n * n, 20, 1000, 99) is None
    assert fitting_size(400, 300, 10, 1_200_000 * 4) == "800x600"
    shown = [format_bytes(n) for n in (5, 1500, 2.5e6, 42.03e9, 619e9)]
    assert shown == ["5 B", "1.5 kB", "2.5 MB", "42.0 GB", "619 GB"]


def test_estimates_are_integers_without_overflow():
    """A huge parameter is refused by arithmetic on Python integers, not by a NumPy overflow."""
    from reflets.reflections.technique import subdivision_bytes

    assert subdivision_bytes([(2976, 1521, 10**12)], 1) > 10**27
    assert np.isfinite(float(subdivision_bytes([(10, 30, 10**6)], 3)))
