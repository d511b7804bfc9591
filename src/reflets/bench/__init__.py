"""Benchmark suites behind `reflets bench SUITE`; each writes SUITE.json and SUITE.md into a results folder."""

from __future__ import annotations

import importlib
import os
import platform
from collections.abc import Callable
from pathlib import Path

from .. import jsonio
from ..errors import ArgumentError, OutputError

#: suite name → "module:function"; the function(quick: bool, out_dir: Path) returns (results dict, markdown
#: text) and may write more files. The suites sit above the techniques and the references they compare (a
#: technique's package holds its model and its passes; its benchmark needs the reference too, which itself uses
#: the technique's NumPy model: one layer up keeps the imports acyclic); imported only when they run.
SUITES: dict[str, str] = {
    "reference": "reflets.bench.reference:bench_reference",
    "arealights": "reflets.bench.arealights:bench_arealights",
    "ltc-cost": "reflets.bench.arealights:bench_ltc_cost",
    "translucency": "reflets.bench.translucency:bench_translucency",
    "reflections": "reflets.bench.reflections:bench_reflections",
    "scratches": "reflets.bench.scratches:bench_scratches",
    "renderer": "reflets.bench.renderer:bench_renderer",
    "gpu": "reflets.bench.gpu:bench_gpu",
    "shadows": "reflets.bench.shadows:bench_shadows",
    "ibl": "reflets.bench.ibl:bench_ibl",
    "viewer": "reflets.bench.viewer:bench_viewer",
    "editing": "reflets.bench.editing:bench_editing",
    "gltf": "reflets.bench.gltf:bench_gltf",
    "assets": "reflets.bench.assets:bench_assets",
    "ar": "reflets.bench.ar:bench_ar",
    "ar-loop": "reflets.bench.ar:bench_ar_loop",
    "soak": "reflets.bench.soak:bench_soak",
    "threads": "reflets.bench.threads:bench_threads",
    "reference-scale": "reflets.bench.reference_scale:bench_reference_scale",
}


def suite(name: str) -> Callable[[bool, Path], tuple[dict, str]]:
    if name not in SUITES:
        raise ArgumentError(f"unknown suite '{name}'; allowed: {', '.join(sorted(SUITES))}", field="suite")
    module, function = SUITES[name].split(":")
    return getattr(importlib.import_module(module), function)


def machine() -> dict:
    """What the numbers were measured on (written into every report)."""
    info = {
        "python": platform.python_version(),
        "platform": platform.platform(),
        "cpu": platform.processor(),
        "cores": os.cpu_count(),
    }
    try:
        from ..gpu import gl_info

        info["opengl"] = gl_info()
    except Exception as exc:  # noqa: BLE001 - a CPU-only benchmark still runs without GL
        info["opengl"] = {"error": str(exc)}
    return info


def run_suite(name: str, out_dir: Path, quick: bool = False, cluster: str | None = None) -> dict:
    """Run suite ``name`` and write its results in ``out_dir``; ``cluster``: the address of a Dask scheduler whose
    workers draw the suite's references (reflets.reference.cluster), else this machine's every core."""
    run = suite(name)
    if not out_dir.parent.is_dir():  # as every command's outputs: its folder must exist (a typo creates nothing)
        raise OutputError(f"the results folder's parent {out_dir.parent} does not exist", file=out_dir)
    try:
        out_dir.mkdir(exist_ok=True)
    except OSError as exc:
        raise OutputError(f"cannot create the results folder ({exc.strerror})", file=out_dir) from None
    if not os.access(out_dir, os.W_OK | os.X_OK):  # found now, not after the suite's minutes of work
        raise OutputError("cannot write the results folder (permission denied)", file=out_dir)
    from ..reference.parallel import places, using

    place = places(None, cluster)  # connected before the suite's minutes of work: a bad address is said at once
    try:
        with using(place):
            results, markdown = run(quick, out_dir)
    finally:
        place.close()
    info = machine()
    results = {"suite": name, "quick": quick, "machine": info, **results}
    gl = info["opengl"].get("renderer", info["opengl"].get("error", "?"))
    markdown += (
        f"\nMachine: {info['cores']} cores, {info['cpu'] or info['platform']}, Python {info['python']}, "
        f"OpenGL: {gl}. Command: `reflets bench {name}{' --quick' if quick else ''}`.\n"
    )
    jsonio.write(out_dir / f"{name}.json", results, indent=2)  # strict JSON: a NaN / inf number is null
    (out_dir / f"{name}.md").write_text(markdown)
    print(markdown)
    print(f"wrote {out_dir / (name + '.json')} and {out_dir / (name + '.md')}")
    return results
