"""GLSL programs from package files, with ``#include``, declared flags and readable compile errors.

Shader files live in the package and are named by their package path, ``"reflets/gpu/shaders/x.glsl"``.
Two include forms are understood:

- ``#include "reflets/…"`` — a package file (included once per program, like ``#pragma once``);
- ``#include NAME`` — a *slot* filled by the caller (e.g. ``BRDF`` → the material's GLSL file).

Each file's text is preceded by ``#line 1 K`` where K numbers the file, so a driver message such as
``0:12(3): error: …`` (Mesa) or ``0(12) : error C…`` (NVIDIA) is rewritten to ``forward.frag:12: error: …``.
Flags become ``#define``s right after ``#version``; a flag the program does not declare is an error.
Compiled programs are cached per context (:func:`~reflets.gpu.context.context_store`) by (stages, slots, flags).
"""

from __future__ import annotations

import re
import sys
from collections import OrderedDict
from dataclasses import dataclass, field
from functools import cache
from importlib import resources

from ..errors import ShaderError
from .context import context_store

GLSL_VERSION = "#version 430 core"
#: fine derivatives (dFdxFine: a 2×2 quad's exact neighbours; core from GLSL 4.50): enabled where the driver has
#: them, and shaders test ``GL_ARB_derivative_control`` before use
EXTENSIONS = "#extension GL_ARB_derivative_control : enable"
COMMON = "reflets/gpu/shaders/common.glsl"  # constants and frame helpers, in every stage
_INCLUDE = re.compile(r'^\s*#include\s+(?:"([^"]+)"|([A-Za-z_]\w*))\s*$', re.MULTILINE)
_MESA_LINE = re.compile(r"(?m)^(\d+):(\d+)\((\d+)\)")
_NVIDIA_LINE = re.compile(r"(?m)^(\d+)\((\d+)\)")


#: sources made at run time (a material's GLSL twin with its texture maps, ``brdf.maps``), by the name they are
#: included with; a name carries a digest of its text, so one name is always one text
GENERATED: dict[str, str] = {}


def register_source(name: str, text: str) -> str:
    """Make ``text`` includable as ``name`` (a slot value); returns the name."""
    GENERATED[name] = text
    return name


def read_source(name: str) -> str:
    """Text of a package GLSL file named ``reflets/<path inside the package>``, or of a generated one."""
    generated = GENERATED.get(name)
    return generated if generated is not None else _package_source(name)


@cache
def _package_source(name: str) -> str:
    parts = name.split("/")
    if parts[0] != "reflets" or len(parts) < 2 or ".." in parts:
        raise ShaderError(f"include name must look like \"reflets/<path>\", got '{name}'")
    resource = resources.files("reflets").joinpath(*parts[1:])
    if not resource.is_file():
        raise ShaderError(f"shader file not found: {name}")
    return resource.read_text(encoding="utf-8")


@dataclass
class _Assembler:
    slots: dict[str, str]
    files: list[str] = field(default_factory=list)
    seen: set[str] = field(default_factory=set)

    def expand(self, name: str, parent: str | None = None, line: int = 0) -> str:
        if name in self.seen:
            return ""
        self.seen.add(name)
        self.files.append(name)
        index = len(self.files) - 1
        text = read_source(name)
        out = [f"#line 1 {index}"]
        for number, raw in enumerate(text.splitlines(), start=1):
            m = _INCLUDE.match(raw)
            if not m:
                out.append(raw)
                continue
            target = m.group(1)
            if target is None:
                slot = m.group(2)
                if slot not in self.slots:
                    raise ShaderError(
                        f"{name}:{number}: include slot {slot} is not filled; filled slots: "
                        f"{', '.join(sorted(self.slots)) or 'none'}"
                    )
                target = self.slots[slot]
            try:
                out.append(self.expand(target, name, number))
            except ShaderError as exc:
                if "not found" in str(exc):
                    raise ShaderError(f"{name}:{number}: {exc}") from None
                raise
            out.append(f"#line {number + 1} {index}")
        return "\n".join(out)


def glsl_literal(value) -> str:
    """A Python number (or bool) as a GLSL literal: ints stay ints, floats always carry a point or exponent."""
    if isinstance(value, bool):
        return "1" if value else "0"
    if isinstance(value, int):
        return str(value)
    text = repr(float(value))
    return text if any(c in text for c in ".e") else text + ".0"


def shared_constants(**groups: dict[str, object]) -> tuple[tuple[str, str], ...]:
    """``#define``s from Python objects a NumPy twin also reads: ``shared_constants(SURFACE={"sphere": 1})``
    gives ``SURFACE_SPHERE 1`` — one source for both sides, so a code or a tolerance cannot drift apart."""
    return tuple(
        (f"{prefix}_{key.upper()}", glsl_literal(value))
        for prefix, mapping in groups.items()
        for key, value in mapping.items()
    )


def assemble(
    name: str,
    slots: dict[str, str] | None = None,
    flags: dict[str, object] | None = None,
    constants: tuple[tuple[str, str], ...] = (),
):
    """Full source of one stage and the list of file names indexed by the ``#line`` source numbers.

    Every stage starts with ``#version``, the program's shared constants and the flags as ``#define``s, then
    the shared constants file.
    """
    defines = [f"#define {key} {value}" for key, value in constants]
    for key, value in sorted((flags or {}).items()):
        if value is True:
            defines.append(f"#define {key} 1")
        elif value is not False and value is not None:
            defines.append(f"#define {key} {value}")
    asm = _Assembler(dict(slots or {}))
    common = asm.expand(COMMON)
    body = asm.expand(name)
    return "\n".join([GLSL_VERSION, EXTENSIONS, *defines, common, body, ""]), asm.files


def map_log(log: str, files: list[str]) -> str:
    """Rewrite driver line references (source number, line) into ``file:line``."""

    def short(k: str) -> str:
        k = int(k)
        return files[k].split("/")[-1] if 0 <= k < len(files) else f"<source {k}>"

    log = _MESA_LINE.sub(lambda m: f"{short(m.group(1))}:{m.group(2)}", log)
    log = _NVIDIA_LINE.sub(lambda m: f"{short(m.group(1))}:{m.group(2)}", log)
    return log


@dataclass(frozen=True)
class ProgramSpec:
    """A program's stage files and the flags it declares (anything else passed as a flag is an error)."""

    name: str
    vertex: str | None = None
    fragment: str | None = None
    geometry: str | None = None
    compute: str | None = None
    flags: frozenset[str] = frozenset()
    #: vertex outputs captured by transform feedback (a vertex-only program read back per vertex)
    varyings: tuple[str, ...] = ()
    #: named constants shared with a NumPy twin (``shared_constants``), emitted as ``#define``s
    constants: tuple[tuple[str, str], ...] = ()


#: compiled programs kept past this many (per context) are released, least recently used first, when nothing else
#: holds them (a program compiled for each light count or material flag combination would otherwise accumulate for
#: a whole session: ~1.7 MB of generated code each on llvmpipe)
MAX_PROGRAMS = 48


def _programs(ctx) -> OrderedDict:
    """The compiled programs of ``ctx`` (each context, one per rendering thread, has its own)."""
    return context_store(ctx, "programs", OrderedDict)


def _trim_cache(cache: OrderedDict) -> None:
    """Release least recently used programs over MAX_PROGRAMS that no technique, vertex array or caller holds
    (CPython's reference count: the cache's own reference and this loop's are the only ones)."""
    for key in list(cache):
        if len(cache) <= MAX_PROGRAMS:
            return
        program = cache[key]
        if sys.getrefcount(program) <= 3:  # the cache, ``program`` and getrefcount's argument
            del cache[key]
            program.release()
        del program


def get_program(ctx, spec: ProgramSpec, *, slots: dict[str, str] | None = None, **flags):
    """Compile (or fetch from the cache) ``spec`` with include ``slots`` and ``flags`` as ``#define``s.

    Flags must be declared by the spec, except a material's own (``BRDF_*``) where the program has a BRDF slot.
    """
    material_flags = {k for k in flags if k.startswith("BRDF_")} if "BRDF" in (slots or {}) else set()
    unknown = sorted(set(flags) - spec.flags - material_flags)
    if unknown:
        raise ShaderError(
            f"program {spec.name}: undeclared flag(s) {', '.join(unknown)}; declared: "
            f"{', '.join(sorted(spec.flags)) or 'none'}"
        )
    cache = _programs(ctx)
    key = (spec, tuple(sorted((slots or {}).items())), tuple(sorted(flags.items())))
    if key in cache:
        cache.move_to_end(key)
        return cache[key]
    stages = {}
    all_files: dict[str, list[str]] = {}
    for stage in ("vertex", "fragment", "geometry", "compute"):
        name = getattr(spec, stage)
        if name is None:
            continue
        source, files = assemble(name, slots, flags, spec.constants)
        stages[stage] = source
        all_files[stage] = files
    try:
        if "compute" in stages:
            program = ctx.compute_shader(stages["compute"])
        else:
            program = ctx.program(
                vertex_shader=stages["vertex"],
                fragment_shader=stages.get("fragment"),
                geometry_shader=stages.get("geometry"),
                varyings=spec.varyings,
            )
    except Exception as exc:  # moderngl raises plain Exceptions carrying the driver log
        text = str(exc)
        stage = next((s for s in stages if s in text.lower()), None)
        files = all_files.get(stage) if stage else next(iter(all_files.values()))
        raise ShaderError(
            f"program {spec.name} failed to build: " + map_log(text, files).strip().replace("\n", " | ")
        ) from exc
    cache[key] = program
    _trim_cache(cache)
    return program


def set_uniforms(program, values: dict) -> None:
    """Set uniforms the compiler kept; unused ones are optimised away by the driver and skipped.
    ``bytes`` values are written raw (matrices: column-major float32); for an array, only the elements the
    driver kept active (a prefix: trailing elements a shader never indexes may be trimmed)."""
    for key, value in values.items():
        uniform = program.get(key, None)  # a dict lookup (``key in program`` walks every member)
        if uniform is not None:
            if isinstance(value, bytes):
                if uniform.array_length > 1:  # float32 / int32 components
                    value = value[: 4 * uniform.dimension * uniform.array_length]
                uniform.write(value)
            else:
                uniform.value = value
