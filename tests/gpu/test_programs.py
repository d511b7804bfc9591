"""GPU plumbing: includes, slots, flags, compile errors mapped to file:line, HDR readback, the context."""

from __future__ import annotations

import numpy as np
import pytest

from reflets.errors import GLUnavailableError, ShaderError
from reflets.gpu import HDRTarget, ProgramSpec, get_program
from reflets.gpu import programs as programs_module
from reflets.gpu.context import gl_choice
from reflets.gpu.programs import EXTENSIONS, GLSL_VERSION, assemble, map_log


@pytest.fixture
def shader_files(tmp_path, monkeypatch):
    """Serve fake package shader files from a dict, so tests can compile broken code."""
    files: dict[str, str] = {}
    real = programs_module.read_source

    def fake(name: str) -> str:
        return files[name] if name in files else real(name)

    monkeypatch.setattr(programs_module, "read_source", fake)
    return files


def test_include_inlines_once_and_numbers_files(shader_files):
    shader_files["reflets/t/a.glsl"] = '#include "reflets/t/b.glsl"\n#include "reflets/t/b.glsl"\nvoid main() {}\n'
    shader_files["reflets/t/b.glsl"] = "float twice(float x) { return 2.0 * x; }\n"
    source, files = assemble("reflets/t/a.glsl", flags={"N_LIGHTS": 4, "USE_X": True, "OFF": False})
    assert source.startswith(f"{GLSL_VERSION}\n{EXTENSIONS}\n#define N_LIGHTS 4\n#define USE_X 1\n")
    assert "OFF" not in source
    assert source.count("float twice") == 1
    assert files == ["reflets/gpu/shaders/common.glsl", "reflets/t/a.glsl", "reflets/t/b.glsl"]


def test_missing_include_names_including_file_and_line(shader_files):
    shader_files["reflets/t/a.glsl"] = 'void f() {}\n#include "reflets/t/nope.glsl"\n'
    with pytest.raises(ShaderError, match=r"a.glsl:2: .*not found: reflets/t/nope.glsl"):
        assemble("reflets/t/a.glsl")


def test_unfilled_slot_is_an_error(shader_files):
    shader_files["reflets/t/a.glsl"] = "#include BRDF\n"
    with pytest.raises(ShaderError, match="slot BRDF is not filled"):
        assemble("reflets/t/a.glsl")


def test_compile_error_reports_file_and_line(ctx, shader_files):
    shader_files["reflets/t/ok.vert"] = "void main() { gl_Position = vec4(0.0); }\n"
    shader_files["reflets/t/helper.glsl"] = "float ok() { return 1.0; }\nfloat bad() { return undefined_name; }\n"
    shader_files["reflets/t/bad.frag"] = (
        '#include "reflets/t/helper.glsl"\nout vec4 c;\nvoid main() { c = vec4(ok()); }\n'
    )
    spec = ProgramSpec("broken", vertex="reflets/t/ok.vert", fragment="reflets/t/bad.frag")
    with pytest.raises(ShaderError, match=r"helper.glsl:2"):
        get_program(ctx, spec)


def test_map_log_understands_mesa_and_nvidia_formats():
    files = ["reflets/gpu/shaders/common.glsl", "reflets/x/forward.frag"]
    assert map_log("0:12(5): error: boom", files).startswith("common.glsl:12")
    assert map_log("1(7) : error C1008: undefined", files).startswith("forward.frag:7")


def test_undeclared_flag_is_an_error(ctx):
    spec = ProgramSpec(
        "p",
        vertex="reflets/techniques/shaders/emitter.vert",
        fragment="reflets/techniques/shaders/emitter.frag",
        flags=frozenset({"A"}),
    )
    with pytest.raises(ShaderError, match="undeclared flag.*B.*declared: A"):
        get_program(ctx, spec, B=1)


def test_programs_are_cached_per_flags(ctx):
    from reflets.techniques.forward import MESH_PROGRAM

    slots = {"BRDF": "reflets/brdf/glsl/lambert.glsl"}
    a = get_program(ctx, MESH_PROGRAM, slots=slots, OUTPUT=0)
    assert get_program(ctx, MESH_PROGRAM, slots=slots, OUTPUT=0) is a
    assert get_program(ctx, MESH_PROGRAM, slots=slots, OUTPUT=1) is not a


def test_hdr_target_keeps_float_values_and_puts_row_0_on_top(ctx):
    target = HDRTarget(ctx, 8, 4)
    try:
        target.use(clear=(0.0, 0.0, 0.0, 0.0))
        ctx.scissor = (0, 3, 8, 1)  # GL's top row is y = 3
        target.fbo.clear(1234.5, 1e-6, -2.0, 1.0)
        ctx.scissor = None
        image = target.read()
    finally:
        target.release()
    assert image.dtype == np.float32 and image.shape == (4, 8, 3)
    assert np.array_equal(image[0], np.tile([1234.5, np.float32(1e-6), -2.0], (8, 1)).astype(np.float32))
    assert np.all(image[1:] == 0)


def test_reflets_gl_rejects_unknown_values(monkeypatch):
    monkeypatch.setenv("REFLETS_GL", "vulkan")
    with pytest.raises(GLUnavailableError, match="REFLETS_GL: unknown value 'vulkan'; allowed: auto, nvidia, llvmpipe"):
        gl_choice()


def test_no_gl_at_all_gives_one_line_with_install_hint(tmp_path):
    """A process whose EGL loader finds no vendor library: one line naming what to install, exit 2."""
    import os
    import subprocess
    import sys

    empty = tmp_path / "vendors"
    empty.mkdir()
    env = {
        **os.environ,
        "__EGL_VENDOR_LIBRARY_DIRS": str(empty),
        "REFLETS_GL": "auto",
        "PYTHONPATH": os.pathsep.join(sys.path),
    }
    env.pop("__EGL_VENDOR_LIBRARY_FILENAMES", None)
    proc = subprocess.run(
        [sys.executable, "-m", "reflets.cli", "info"], capture_output=True, text=True, env=env, timeout=120
    )
    assert proc.returncode == 2
    assert "unavailable" in proc.stdout and "apt-get install" in proc.stdout
    assert "Traceback" not in proc.stdout + proc.stderr


def test_the_program_cache_releases_unused_programs_past_its_bound(ctx, monkeypatch):
    """Past MAX_PROGRAMS, the least recently used programs nobody holds are released; one a caller (a
    technique, a vertex array) still holds is kept and stays usable."""
    from reflets.techniques.shadows import DEPTH_PROGRAM

    spec = ProgramSpec("soak", vertex=DEPTH_PROGRAM.vertex, fragment=DEPTH_PROGRAM.fragment,
                       flags=frozenset({"VARIANT"}))  # fmt: skip
    cache = programs_module._programs(ctx)
    monkeypatch.setattr(programs_module, "MAX_PROGRAMS", 0)
    programs_module._trim_cache(cache)  # only the programs something holds remain
    monkeypatch.setattr(programs_module, "MAX_PROGRAMS", len(cache) + 3)
    held = get_program(ctx, spec, VARIANT=0)
    keys = [k for k in cache if k[0] == spec]
    for variant in range(1, 8):
        get_program(ctx, spec, VARIANT=variant)  # nobody keeps these
    remaining = [k for k in cache if k[0] == spec]
    assert keys[0] in remaining  # held: kept, though the least recently used
    assert len(cache) <= programs_module.MAX_PROGRAMS
    assert len(remaining) <= 3
    assert get_program(ctx, spec, VARIANT=0) is held and held.glo > 0
