"""A Wavefront OBJ file as a scene: one part per material of its faces, its MTL materials as ``type = "gltf"``.

trimesh parses the geometry (split by ``usemtl``; quads and polygons triangulated); the MTL files named by the
OBJ's ``mtllib`` lines are read here, because trimesh keeps only the diffuse colour and map. What becomes what
(docs/assets.md has the table):

- ``Kd`` → base colour (linear, as Blender's importer reads it), ``map_Kd`` → base colour texture (sRGB);
- ``d`` (else ``1 − Tr``) → coverage: below 1 the material is ``alpha_mode = "blend"``; ``map_d`` → coverage from
  that image (``mask``, cut-outs): its alpha when it is the ``map_Kd`` file, else its first channel;
- ``Pr`` / ``Pm`` (the PBR extension) → roughness / metallic, ``map_Pr`` / ``map_Pm`` → the metallic-roughness
  slot's G / B channels (``-imfchan`` picks the image channel, default its first);
- without ``Pr``: roughness from the Phong exponent ``Ns`` by the Phong ↔ Beckmann correspondence
  α = √(2 / (Ns + 2)) (Walter et al. 2007), roughness = √α; a specular colour ``Ks`` of luminance under 0.1 makes
  it rougher by that much (obj2gltf's rule) — Appendix B's dielectric has a fixed 4 % specular reflectance, so
  ``Ks`` cannot scale it;
- ``Ke`` / ``map_Ke`` → emission; ``norm``, ``map_Bump``, ``bump`` → a tangent-space normal map scaled by ``-bm``
  (Blender's reading); a grey image there is a height map: left out with a warning;
- ``-s`` / ``-o`` (uv scale and offset) → the texture transform, ``-clamp on`` → clamped wrap;
- ``Ka`` and ``illum`` have no meaning in a physically based material and are ignored; every other statement
  (``map_Ks``, ``Ni``, ``Tf``, ``Pc``, ``Ps``, ``disp``…) → one warning line naming it.

OBJ has no cameras or lights (the scene gets a framing camera and the environment) and no face culling
(materials are double-sided).
"""

from __future__ import annotations

import functools
import io
import math
import re
from pathlib import Path

import numpy as np

from ..errors import SceneError
from ..quantities import MAX_MAGNITUDE
from .meshdata import MeshData

#: ``-option`` of a map statement → how many numbers / words follow it (``-o``, ``-s``, ``-t``: one to three)
_MAP_OPTIONS = {"-blendu": 1, "-blendv": 1, "-bm": 1, "-boost": 1, "-cc": 1, "-clamp": 1, "-imfchan": 1,
                "-mm": 2, "-texres": 1, "-type": 1, "-o": 3, "-s": 3, "-t": 3}  # fmt: skip
#: statements a physically based material has no use for (read silently)
_IGNORED = {"ka", "illum", "map_ka"}
_USEMTL = re.compile(r"^[ \t]*usemtl[ \t]+(\S.*?)[ \t]*$", re.MULTILINE)
_CHANNELS = {"r": "r", "g": "g", "b": "b", "m": "r", "l": "r", "z": "r"}  # -imfchan m/l/z: grey images → r


@functools.lru_cache(maxsize=8)
def _read(path: Path, size: int, mtime: int) -> tuple[tuple[str, ...], tuple]:
    """The file's ``mtllib`` names, and (MTL material name, positions, file normals or None, uv or None, faces)
    per material of the file: read and parsed once while the file is unchanged."""
    import trimesh

    from .meshfile import decode_text, trimesh_log_as_warnings

    text = decode_text(path.read_bytes())
    libraries = tuple(name for line in text.splitlines() if line.split()[:1] == ["mtllib"] for name in line.split()[1:])
    # trimesh keeps a material's name only if it can build it from the first library alone (a grey "Kd 0.8" or a
    # second mtllib loses them all): it is handed a library of bare names, the materials are read by parse_mtl
    order = list(dict.fromkeys(_USEMTL.findall(text)))
    names = "".join(f"newmtl {n}\n" for n in order).encode()

    class NamesOnly(trimesh.resolvers.FilePathResolver):
        def get(self, name: str) -> bytes:
            return names

    try:
        with trimesh_log_as_warnings(path):
            loaded = trimesh.load(io.BytesIO(text.encode("utf-8")), file_type="obj", resolver=NamesOnly(str(path)),
                                  process=False)  # fmt: skip
    except Exception as exc:  # trimesh raises many types for corrupt files
        reason = (str(exc).strip().splitlines() or [type(exc).__name__])[0][:200]
        raise SceneError(f"cannot read the OBJ file: {reason}", file=path) from exc
    geometries = loaded.geometry.values() if isinstance(loaded, trimesh.Scene) else [loaded]
    out = []
    for geom in geometries:
        if not isinstance(geom, trimesh.Trimesh) or len(geom.faces) == 0:
            continue
        pos = np.asarray(geom.vertices, dtype=np.float64)
        normals = np.asarray(geom.vertex_normals, dtype=np.float64) if "vertex_normals" in geom._cache else None
        uv = getattr(geom.visual, "uv", None)
        uv = np.asarray(uv, dtype=np.float64) if uv is not None and len(uv) == len(pos) else None
        material = getattr(getattr(geom.visual, "material", None), "name", None)
        out.append((material, pos, normals, uv, np.asarray(geom.faces, dtype=np.int64)))
    parts = tuple(sorted(out, key=lambda part: order.index(part[0]) + 1 if part[0] in order else 0))  # file order
    return libraries, parts


def _read_file(path: Path):
    stat = path.stat()
    return _read(path.absolute(), stat.st_size, stat.st_mtime_ns)


def obj_parts(path: Path):
    return _read_file(path)[1]


def load_obj_asset(path: Path) -> tuple[list[dict], dict[str, dict], list[str]]:
    """The OBJ file's parts (FileMesh dicts), MTL materials (module docstring) and warnings (each line once)."""
    warnings: list[str] = []
    libraries: dict[str, dict] = {}
    names, obj = _read_file(path)
    for name in names:
        mtl = path.parent / name
        if not mtl.is_file():
            why = "is not a file" if mtl.exists() else "not found"
            warnings.append(f"{path.name}: material library {name} {why}: its materials are the default")
            continue
        for key, value in parse_mtl(mtl, warnings).items():
            libraries.setdefault(key, value)
    parts, materials = [], {}
    for index, (material, *_rest) in enumerate(obj):
        name = f"{path.stem}/{material or 'default'}"
        if material not in libraries and material is not None and libraries:
            warnings.append(f"{path.name}: usemtl {material}: no such material in its libraries: the default")
        materials.setdefault(name, libraries.get(material, {"type": "gltf", "double_sided": True}))
        parts.append({"file": path, "part": index, "name": f"{path.stem}/{material or 'default'}",
                      "material": name})  # fmt: skip
    return parts, materials, list(dict.fromkeys(warnings))


def parse_mtl(path: Path, warnings: list[str]) -> dict[str, dict]:
    """The materials of an MTL file, as ``gltf`` material dicts (module docstring), by name."""
    from .meshfile import decode_text

    out: dict[str, dict] = {}
    statements: dict[str, tuple[str, list[str], int]] = {}
    name = None

    def finish():
        if name is not None:
            out[name] = _material(path, name, statements, warnings)

    for number, line in enumerate(decode_text(path.read_bytes()).splitlines(), start=1):
        words = line.split("#", 1)[0].split()
        if not words:
            continue
        key = words[0].lower()
        if key == "newmtl":
            finish()
            name, statements = " ".join(words[1:]) or f"line {number}", {}
            continue
        if name is None:
            raise SceneError(f"line {number}: {words[0]} before any newmtl", file=path)
        statements[key] = (words[0], words[1:], number)
    finish()
    return out


def _numbers(path: Path, statement: tuple[str, list[str], int], count: int, unit: bool = False) -> list[float]:
    """A statement's ``count`` numbers (finite, at most 1e6; ``unit``: in [0, 1]); "Kd 0.5" is grey."""
    word, args, number = statement
    try:
        values = [float(a) for a in args[:count]]
    except ValueError:
        values = []
    if not values or not all(math.isfinite(v) and abs(v) <= 1e6 for v in values):
        raise SceneError(f"line {number}: {word} needs {count} finite number(s), got {' '.join(args)!r}", file=path)
    if unit and not all(0.0 <= v <= 1.0 for v in values):
        raise SceneError(f"line {number}: {word} must be in [0, 1], got {' '.join(args)!r}", file=path)
    return values + [values[-1]] * (count - len(values))


def _map(path: Path, statement: tuple[str, list[str], int]) -> tuple[dict, dict[str, list[str]]]:
    """A map statement's TextureRef dict (file, transform, wrap, channel) and its options."""
    word, args, number = statement
    options: dict[str, list[str]] = {}
    i = 0
    while i < len(args) and args[i].lower() in _MAP_OPTIONS:
        option, i = args[i].lower(), i + 1
        taken = []
        while i < len(args) and len(taken) < _MAP_OPTIONS[option]:
            if option in ("-o", "-s", "-t", "-mm", "-bm", "-boost", "-texres") and not _is_number(args[i]):
                break
            taken.append(args[i])
            i += 1
        options[option] = taken
    if i >= len(args):
        raise SceneError(f"line {number}: {word} names no image file", file=path)
    channel = (options.get("-imfchan") or ["r"])[0].lower()
    if channel not in _CHANNELS:
        raise SceneError(f"line {number}: {word} -imfchan {channel}: allowed r, g, b, m, l, z", file=path)
    ref: dict = {"texture": path.parent / " ".join(args[i:])}
    try:
        scale = [float(v) for v in options.get("-s", [])] + [1.0, 1.0]
        offset = [float(v) for v in options.get("-o", [])] + [0.0, 0.0]
    except ValueError:
        raise SceneError(f"line {number}: {word}: -s / -o need numbers", file=path) from None
    if options.get("-s") or options.get("-o"):  # MTL's uv' = s·uv + o in v-up uv → the image's v-down transform
        ref["transform"] = {"scale": (scale[0], scale[1]), "offset": (offset[0], 1.0 - scale[1] - offset[1])}
    if [v.lower() for v in options.get("-clamp", [])] == ["on"]:
        ref["wrap"] = ("clamp", "clamp")
    return ref, options


def _is_number(word: str) -> bool:
    try:
        float(word)
    except ValueError:
        return False
    return True


def _channel(options: dict[str, list[str]]) -> str:
    return _CHANNELS[(options.get("-imfchan") or ["r"])[0].lower()]  # checked by _map


def _material(path: Path, name: str, statements: dict, warnings: list[str]) -> dict:
    where = f"{path.name}: material '{name}'"
    out: dict = {"type": "gltf", "double_sided": True, "metallic": 0.0}

    def take(key: str):
        return statements.pop(key, None)

    kd, d, tr = take("kd"), take("d"), take("tr")
    coverage = 1.0
    if d is not None:
        coverage = _numbers(path, d, 1, unit=True)[0]
    elif tr is not None:
        transparency = _numbers(path, tr, 1, unit=True)[0]
        if transparency >= 1.0:  # by the letter invisible; MeshLab and others write "Tr 1" for opaque
            warnings.append(f"{where}: Tr {transparency:g} (fully transparent by the format) read as opaque")
        else:
            coverage = 1.0 - transparency
    color = _numbers(path, kd, 3) if kd is not None else [1.0, 1.0, 1.0]
    out["base_color"] = tuple(float(np.clip(c, 0.0, 1.0)) for c in color) + (coverage,)
    if coverage < 1.0:
        out["alpha_mode"] = "blend"

    base_map, alpha_map = take("map_kd"), take("map_d")
    if base_map is not None:
        out["base_color_texture"], options = _map(path, base_map)
    if alpha_map is not None:
        ref, options = _map(path, alpha_map)
        out["alpha_mode"], out["alpha_cutoff"] = "mask", 0.5
        if base_map is None:
            out["base_color_texture"] = {**ref, "channels": "111" + _channel(options)}
        elif Path(ref["texture"]) != Path(out["base_color_texture"]["texture"]):
            out.pop("alpha_mode")
            warnings.append(f"{where}: map_d is another image than map_Kd: left out (one base colour slot)")

    pr, pm, ns, ks = take("pr"), take("pm"), take("ns"), take("ks")
    if pr is not None:
        out["roughness"] = _numbers(path, pr, 1, unit=True)[0]
    else:
        exponent = float(np.clip(_numbers(path, ns, 1)[0], 0.0, 1e4)) if ns is not None else 0.0
        roughness = (2.0 / (exponent + 2.0)) ** 0.25
        if ks is not None:
            r, g, b = _numbers(path, ks, 3)
            luminance = 0.2126 * r + 0.7152 * g + 0.0722 * b
            if luminance < 0.1:
                roughness += (1.0 - roughness) * (1.0 - max(luminance, 0.0) / 0.1)
        out["roughness"] = float(np.clip(roughness, 0.0, 1.0))
    if pm is not None:
        out["metallic"] = _numbers(path, pm, 1, unit=True)[0]
    map_pr, map_pm = take("map_pr"), take("map_pm")
    if map_pr is not None or map_pm is not None:
        refs = [None if s is None else _map(path, s) for s in (map_pr, map_pm)]
        source = refs[0] or refs[1]
        same = refs[0] is not None and refs[1] is not None and refs[0][0]["texture"] == refs[1][0]["texture"]
        g = _channel(refs[0][1]) if refs[0] is not None else "1"
        b = _channel(refs[1][1]) if refs[1] is not None and (same or refs[0] is None) else "1"
        if refs[0] is not None and refs[1] is not None and not same:
            warnings.append(f"{where}: map_Pm is another image than map_Pr: left out (Pm {out['metallic']:g} used)")
        out["metallic_roughness_texture"] = {**source[0], "channels": f"1{g}{b}1"}
        out.setdefault("roughness", 1.0)
        if pm is None and refs[1] is not None and b != "1":
            out["metallic"] = 1.0  # the map alone decides

    ke, map_ke = take("ke"), take("map_ke")
    if ke is not None:
        out["emissive"] = tuple(max(c, 0.0) for c in _numbers(path, ke, 3))
    if map_ke is not None:
        out["emissive_texture"], _ = _map(path, map_ke)
        out.setdefault("emissive", (1.0, 1.0, 1.0))

    normal = take("norm") or take("map_bump") or take("bump")
    for duplicate in ("map_bump", "bump"):
        take(duplicate)
    if normal is not None:
        ref, options = _map(path, normal)
        if _is_height_map(ref):
            warnings.append(f"{where}: {normal[0]} {Path(ref['texture']).name} is a grey height map: left out (only "
                            "tangent-space normal maps are read)")  # fmt: skip
        else:
            scale = (options.get("-bm") or ["1"])[0]
            out["normal_texture"], out["normal_scale"] = ref, float(scale) if _is_number(scale) else 1.0
    for key in sorted(set(statements) - _IGNORED):
        word, args, number = statements[key]
        warnings.append(f"{where}: {word} (line {number}) not supported: left out")
    return out


def _is_height_map(ref: dict) -> bool:
    """A bump image whose three channels are equal is a height field, not a normal map."""
    from ..textures import TextureRef, load_texture

    codes = load_texture(TextureRef(texture=ref["texture"]), False).codes[..., :3].astype(np.int16)
    return bool(np.abs(codes[..., 0] - codes[..., 1]).max() <= 2 and np.abs(codes[..., 1] - codes[..., 2]).max() <= 2)


def obj_part_mesh(path: Path, part: int) -> MeshData:
    """One material's faces of an OBJ file, with a full shading frame (file normals, else smooth ones; tangents
    from the uv layout)."""
    from .meshfile import _unit, shaded_mesh, smooth_normals, spherical_uv

    parts = obj_parts(path)
    if not 0 <= part < len(parts):
        raise SceneError(f"part {part} does not exist: the file has {len(parts)} materials' faces", file=path)
    _, pos, normals, uv, faces = parts[part]
    used, faces = np.unique(faces, return_inverse=True)
    faces = faces.reshape(-1, 3)
    pos = pos[used]
    if not np.all(np.isfinite(pos)) or np.abs(pos).max() > MAX_MAGNITUDE:
        raise SceneError(f"vertex coordinates must be finite and at most {MAX_MAGNITUDE:.0e} in magnitude", file=path)
    smooth = smooth_normals(pos, faces)
    if normals is not None:
        normals, length = _unit(normals[used])
        bad = ~(np.isfinite(length) & (length > 0))
        normals[bad] = smooth[bad]
    else:
        normals = smooth
    return shaded_mesh(pos, normals, uv[used] if uv is not None else spherical_uv(pos), faces)
