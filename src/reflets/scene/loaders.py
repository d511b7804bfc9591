"""Scene files (TOML) and dicts → validated :class:`Scene`, with one-line errors naming file and field."""

from __future__ import annotations

import difflib
import functools
import tomllib
from pathlib import Path
from typing import Any

from pydantic import ValidationError

from ..errors import SceneError
from .lightmask import load_mask
from .model import EnvironmentLight, FileMesh, HeightFieldMesh, Scene


def load_scene(path: str | Path, camera: int | str | None = None, environment: str | Path | None = None) -> Scene:
    """Read and validate a TOML scene file; relative paths inside it are relative to its folder.

    A glTF file (.gltf, .glb) or an OBJ file with its MTL materials is a whole scene too
    (``reflets.scene.assets``): ``camera`` picks one of its cameras (index or name; default the first, else one
    framing its bounding box), ``environment`` an HDR map lighting it (default: its own lights, else the studio
    map shipped with reflets)."""
    from .assets import is_asset

    path = Path(path)
    if is_asset(path):
        return scene_from_asset(path, camera=camera, environment=environment)
    _refuse_bare_mesh_file(path)
    if camera is not None or environment is not None:
        from ..errors import ArgumentError

        raise ArgumentError("--camera and --environment apply to a glTF or OBJ file, not to a scene file", file=path)
    try:
        text = path.read_text(encoding="utf-8")
    except FileNotFoundError:
        raise SceneError("file not found", file=path) from None
    except IsADirectoryError:
        raise SceneError("is a directory, expected a .toml scene file", file=path) from None
    except UnicodeDecodeError:
        raise SceneError("not a text file (a scene is a UTF-8 TOML file)", file=path) from None
    except OSError as exc:
        raise SceneError(f"cannot read ({exc.strerror or exc.__class__.__name__})", file=path) from None
    try:
        data = tomllib.loads(text)
    except tomllib.TOMLDecodeError as exc:
        raise SceneError(f"invalid TOML: {exc}", file=path) from None
    except RecursionError:  # the parser recurses once per nested array or inline table
        raise SceneError(f"values nested too deeply (a scene needs at most {MAX_NESTING} levels)", file=path) from None
    return load_dict(data, base_dir=path.resolve().parent, source=path)


def _refuse_bare_mesh_file(path: Path) -> None:
    """A PLY, STL or OFF file carries no materials, so it is no scene by itself: said so, rather than that it is
    not TOML."""
    from .meshfile import SUPPORTED_EXTENSIONS

    if path.suffix.lower() in SUPPORTED_EXTENSIONS:
        raise SceneError(f"a {path.suffix} mesh file has no materials, so it is no scene by itself; render a scene "
                         f"TOML with [[mesh]] file = \"{path.name}\" and a material", file=path)  # fmt: skip


#: the deepest nesting of tables and arrays a scene may have (the deepest real one: a light's polygon, 4)
MAX_NESTING = 32


def _nesting_too_deep(data) -> bool:
    """Whether tables and arrays nest deeper than MAX_NESTING (iterative: no recursion to overflow)."""
    stack = [(data, 1)]
    while stack:
        value, depth = stack.pop()
        if depth > MAX_NESTING:
            return True
        children = value.values() if isinstance(value, dict) else value if isinstance(value, list | tuple) else ()
        stack.extend((child, depth + 1) for child in children if isinstance(child, dict | list | tuple))
    return False


def load_dict(data: dict[str, Any], base_dir: str | Path | None = None, source: str | Path | None = None) -> Scene:
    """Validate a scene given as a dict (the TOML structure), like ``mitsuba.load_dict``."""
    if not isinstance(data, dict):
        raise SceneError(f"a scene must be a table/dict, got {type(data).__name__}", file=source)
    if _nesting_too_deep(data):
        raise SceneError(f"values nested too deeply (a scene needs at most {MAX_NESTING} levels)", file=source)
    try:
        scene = Scene.model_validate({**data, "base_dir": Path(base_dir) if base_dir else None})
    except ValidationError as exc:
        raise SceneError(_first_error(exc, data), file=source or "<scene>") from None
    scene = _expand_file_meshes(scene, source)
    _check_files(scene, source)
    _warn_replaced_materials(scene)  # once the files are known good: a warning never comes before an error
    return scene


def _warn(lines) -> None:
    import warnings

    from ..errors import RefletsWarning

    for line in lines:
        warnings.warn(line, RefletsWarning, stacklevel=4)


def _warn_replaced_materials(scene: Scene) -> None:
    """A scene ``material`` given for a whole glTF or OBJ file that has materials of its own replaces them: one
    warning line says so (a file expanded into its parts keeps them)."""
    from .assets import is_asset, listed, own_materials

    for i, mesh in enumerate(scene.mesh):
        if not isinstance(mesh, FileMesh) or mesh.material is None or mesh.part is not None:
            continue
        path = scene.resolve(mesh.file)
        if not (is_asset(path) and path.is_file()):
            continue
        try:
            names = own_materials(path)
        except (OSError, SceneError):
            continue  # building the mesh says what is wrong with the file
        if names:
            _warn([f"mesh[{i}]: material '{mesh.material}' replaces the materials of {path.name} "
                   f"({listed(names)}); leave material out to render the file's own"])  # fmt: skip


def _expand_file_meshes(scene: Scene, source) -> Scene:
    """Each ``[[mesh]] file = "x.glb"`` without a material → one mesh per primitive instance with the file's
    materials (named "<file stem>/<material>"; the scene's own materials of the same name win)."""
    from .assets import is_asset, load_asset

    if all(m.material is not None or not isinstance(m, FileMesh) for m in scene.mesh):
        return scene
    meshes, materials = [], dict(scene.materials)
    for i, mesh in enumerate(scene.mesh):
        if mesh.material is not None:
            meshes.append(mesh)
            continue
        path = scene.resolve(mesh.file)
        if not is_asset(path):
            raise SceneError(f"mesh[{i}].material: required for a {path.suffix or 'extensionless'} file (only glTF "
                             "and OBJ files carry their own materials)", file=source)  # fmt: skip
        try:
            asset = load_asset(path)
        except SceneError as exc:
            raise SceneError(exc.message, file=exc.file, field=f"mesh[{i}].file") from None
        _warn(asset.warnings)
        for name, material in asset.materials.items():
            materials.setdefault(name, material)
        for part in asset.parts:
            meshes.append(mesh.model_copy(update={**part, "name": mesh.name or part["name"], "file": path}))
    data = {**scene.model_dump(exclude={"base_dir", "materials", "mesh"}, exclude_none=True), "mesh": meshes,
            "materials": materials, "base_dir": scene.base_dir}  # fmt: skip
    try:
        return Scene.model_validate(data)
    except ValidationError as exc:
        raise SceneError(_first_error(exc, data), file=source or "<scene>") from None


def scene_from_asset(path: str | Path, camera: int | str | None = None, environment: str | Path | None = None,
                     ) -> Scene:  # fmt: skip
    """A whole scene from a glTF or OBJ file (see :func:`load_scene`)."""
    from ..errors import ArgumentError
    from .assets import default_environment, load_asset

    path = Path(path)
    if not path.is_file():
        raise SceneError("file not found" if not path.exists() else "is not a regular file", file=path)
    asset = load_asset(path)
    _warn(asset.warnings)
    if not asset.parts:
        raise SceneError("no triangles to render (a glTF file: none in its default scene)", file=path)
    lights: list[dict] = list(asset.lights)
    if environment is not None or not lights:
        env = Path(environment) if environment is not None else default_environment()
        if not env.is_file():
            raise ArgumentError(f"environment map not found: {env}", field="--environment")
        lights.append({"type": "environment", "file": env.absolute()})
    names = [c["name"] for c in asset.cameras]
    chosen = asset.cameras[0]["fields"] if asset.cameras else None
    if camera is not None:  # a name, else an index
        index = names.index(camera) if camera in names else int(camera) if str(camera).isdigit() else -1
        if not 0 <= index < len(names):
            listed = ", ".join(f"{k} ({n})" for k, n in enumerate(names)) or "none"
            raise ArgumentError(f"no camera {camera!r} in {path.name}; its cameras: {listed}", field="--camera")
        chosen = asset.cameras[index]["fields"]
    data = {
        "title": path.stem,
        "materials": asset.materials,
        "mesh": asset.parts,
        "light": lights,
        "background": "environment" if any(light["type"] == "environment" for light in lights) else None,
        "camera": chosen if chosen is not None else {"position": (0.0, 0.0, 1.0), "look_at": (0.0, 0.0, 0.0)},
    }
    scene = load_dict({k: v for k, v in data.items() if v is not None}, base_dir=path.absolute().parent, source=path)
    if chosen is None:
        from .geometry import framing_camera

        scene = scene.model_copy(update={"camera": framing_camera(scene)})
    return scene


def _check_files(scene: Scene, source) -> None:
    """Referenced files must exist (and measured tables load) now, not half-way through a render."""
    from ..brdf.measured import Measured
    from .shapes import load_heights

    for name, material in scene.materials.items():
        _check_textures(scene, name, material, source)
        if isinstance(material, Measured):
            material.file = scene.resolve(material.file)
            try:
                material.load()
            except SceneError as exc:
                raise SceneError(exc.message, file=exc.file, field=f"materials.{name}.file") from None
        orientation = getattr(material, "orientation", None)
        if orientation is not None and not scene.resolve(orientation).is_file():
            raise SceneError(
                f"orientation field not found: {scene.resolve(orientation)}",
                file=source,
                field=f"materials.{name}.orientation",
            )
    for i, mesh in enumerate(scene.mesh):
        if isinstance(mesh, FileMesh) and not scene.resolve(mesh.file).is_file():
            raise SceneError(f"mesh file not found: {scene.resolve(mesh.file)}", file=source, field=f"mesh[{i}].file")
        if isinstance(mesh, FileMesh) and scene.resolve(mesh.file).suffix.lower() == ".gltf":  # its .bin buffers
            from ..gltf_file import read_gltf

            for buffer in read_gltf(scene.resolve(mesh.file)).external_files(images=False):
                if not buffer.is_file():
                    raise SceneError(f"{scene.resolve(mesh.file).name} names the buffer {buffer.name}, which is not "
                                     "found", file=source, field=f"mesh[{i}].file")  # fmt: skip
        if isinstance(mesh, HeightFieldMesh) and mesh.file is not None:
            mesh.file = scene.resolve(mesh.file)  # absolute: canonical_surface(mesh) has no scene to resolve with
            try:
                load_heights(mesh.file)
            except SceneError as exc:
                raise SceneError(exc.message, file=exc.file, field=f"mesh[{i}].file") from None
    _check_uv_sets(scene)
    for i, light in enumerate(scene.light):
        load_mask(scene, i)  # a bad mask fails here, naming light[i].mask
        if isinstance(light, EnvironmentLight) and not scene.resolve(light.file).is_file():
            raise SceneError(
                f"environment image not found: {scene.resolve(light.file)}",
                file=source,
                field=f"light[{i}].file",
            )


def _check_uv_sets(scene: Scene) -> None:
    """A texture on the second uv set of a mesh that has one (a procedural shape, an OBJ or PLY file, a glTF
    primitive without TEXCOORD_1) reads the first: one warning line per mesh."""
    from ..textures import texture_refs
    from .geometry import mesh_data

    for i, mesh in enumerate(scene.mesh):
        material = scene.materials.get(mesh.material) if mesh.material else None
        source = getattr(material, "base", material)  # a scratched material's textures are its base's
        second = [key for key, ref in texture_refs(source).items() if ref.uv == 1] if source is not None else []
        if not second:
            continue
        try:
            single = mesh_data(scene, i).uvs1 is None  # cached: the renderers read the same object
        except SceneError:
            continue  # rendering names what is wrong with the mesh
        if single:
            where = f"materials.{mesh.material}.{'base.' if source is not material else ''}{second[0]}"
            _warn([f"mesh[{i}] has one uv set: {where} reads uv set 1, the first is read"])


def _check_textures(scene: Scene, name: str, material, source) -> None:
    """Texture paths made absolute (materials resolve them without the scene) and present; images of a glTF file
    must exist in it. A material's own base material (a scratched one's) likewise."""
    from ..brdf.base import Material
    from ..textures import texture_refs

    base = getattr(material, "base", None)
    if isinstance(base, Material):
        _check_textures(scene, f"{name}.base", base, source)
    for key, ref in texture_refs(material).items():
        path = scene.resolve(ref.texture)
        if not path.is_file():
            what = "is a directory" if path.is_dir() else "not found"
            raise SceneError(f"texture {what}: {path}", file=source, field=f"materials.{name}.{key}")
        if ref.image is not None:
            from ..gltf_file import read_gltf

            try:
                count = len(read_gltf(path).doc.images or [])
            except SceneError as exc:
                raise SceneError(exc.message, file=exc.file, field=f"materials.{name}.{key}") from None
            if ref.image >= count:
                raise SceneError(f"image {ref.image} does not exist: {path.name} has {count} images", file=source,
                                 field=f"materials.{name}.{key}.image")  # fmt: skip
        field = key.removeprefix("maps.")
        if path != ref.texture:
            ref = ref.model_copy(update={"texture": path})
            if field == key:
                setattr(material, key, ref)
            else:
                material.maps[field] = ref
        try:  # decoded now (and cached for the renderers), so that a damaged image fails here, not mid-render
            material.texture_data(field)
        except SceneError as exc:
            raise SceneError(exc.message, file=exc.file, field=f"materials.{name}.{key}") from None


def did_you_mean(word: str, choices) -> str:
    """`` (did you mean 'x'?)`` for the closest choice, or nothing."""
    close = difflib.get_close_matches(word, list(choices), n=1, cutoff=0.6)
    return f" (did you mean {close[0]!r}?)" if close else ""


@functools.cache
def _field_names() -> frozenset[str]:
    """Every key a scene file can hold, at any depth (for "did you mean")."""
    names: set[str] = set()

    def walk(node):
        if isinstance(node, dict):
            names.update(node.get("properties", {}))
            for value in node.values():
                walk(value)
        elif isinstance(node, list):
            for value in node:
                walk(value)

    from ..brdf import MATERIALS

    walk(Scene.model_json_schema())
    for material in MATERIALS.values():
        walk(material.model_json_schema())
    return frozenset(names)


def _walk(loc: tuple, data: Any) -> tuple[str, Any]:
    """Follow a pydantic location through the user's input, dropping union tags:
    ``('mesh', 0, 'plane', 'size')`` → (``"mesh[0].size"``, the value the user wrote there, or None)."""
    parts: list[str] = []
    node = data
    skipped = False
    for item in loc:
        if isinstance(item, str) and ("-" in item or "[" in item):
            continue  # a pydantic-internal union branch ("constrained-float", "function-after[…]"), not a key
        if isinstance(item, int):
            parts.append(f"[{item}]")
            node = node[item] if isinstance(node, list) and item < len(node) else None
            skipped = False
        elif not skipped and _is_tag(item, node):
            skipped = True  # a discriminator tag inserted by pydantic, not a key the user wrote
            continue
        else:
            parts.append(("." if parts else "") + str(item))
            node = node.get(item) if isinstance(node, dict) else None
            skipped = False
    return "".join(parts) or "<scene>", node


def _field_path(loc: tuple, data: Any) -> str:
    return _walk(loc, data)[0]


def _is_tag(item: Any, node: Any) -> bool:
    """Is ``item`` the union tag pydantic put in the location (the value of ``type``/``shape``, or "file")?"""
    if not isinstance(node, dict):
        return False
    if node.get("type") == item or node.get("shape") == item:
        return True
    return item == "file" and "file" in node and "shape" not in node and "type" not in node


def _first_error(exc: ValidationError, data: dict) -> str:
    """One line for the first validation error, phrased for a scene author."""
    err = exc.errors(include_url=False)[0]
    loc, kind, msg = err["loc"], err["type"], err["msg"]
    field = _field_path(loc, data)
    if kind == "extra_forbidden":
        key = str(loc[-1])
        return f"{field}: unknown key{did_you_mean(key, _field_names())}; check the spelling against `reflets schema`"
    if kind == "mesh_kind":
        from .model import SHAPE_MODELS

        shape = err.get("input", {}).get("shape") if isinstance(err.get("input"), dict) else None
        hint = did_you_mean(str(shape), SHAPE_MODELS) if shape is not None else ""
        return f"{field}: unknown or missing shape{hint}; allowed: {msg.split('allowed: ', 1)[-1]}"
    if kind == "missing" and loc and isinstance(loc[-1], int):
        vector, got = _walk(loc[:-1], data)
        if isinstance(got, dict) and "factor" in got:  # a mapped colour (brdf.maps): the vector is its factor
            vector, got = f"{vector}.factor", got["factor"]
        count = len(got) if isinstance(got, list) else "?"
        return f"{vector}: wrong length: got {count} values, needs at least {loc[-1] + 1}"
    if kind == "missing":
        return f"{field}: required field is missing"
    if kind in ("too_long", "too_short"):
        expected = err.get("ctx", {}).get("max_length") or err.get("ctx", {}).get("min_length")
        return f"{field}: wrong length ({msg[0].lower() + msg[1:]}); expected {expected} values"
    if kind == "finite_number":
        return f"{field}: must be a finite number (got {err.get('input')!r})"
    if kind in ("union_tag_invalid", "union_tag_not_found"):
        ctx = err.get("ctx", {})
        tags = [t.strip().strip("'") for t in str(ctx.get("expected_tags", "")).split(",")]
        tag = str(ctx.get("tag", ""))
        return f"{field}: unknown type {tag!r}{did_you_mean(tag, tags)}; allowed: {ctx.get('expected_tags', '')}"
    if kind == "value_error":
        msg = msg.removeprefix("Value error, ")
        return msg if msg.startswith(("mesh[", "light", "background")) else f"{field}: {msg}"
    return f"{field}: {msg[0].lower() + msg[1:]} (got {err.get('input')!r})"


def scene_toml(scene: Scene) -> str:
    """The scene as TOML text that :func:`load_scene` reads back to the same scene from any folder: every file
    it names (meshes, maps, masks, measured tables, scratch profiles) made absolute."""
    import tomli_w

    def absolute(value):
        if isinstance(value, Path):
            return str(scene.resolve(value))
        if isinstance(value, str) and value.startswith("file:"):  # a scratch profile read from a file
            return "file:" + str(scene.resolve(Path(value[5:])))
        if isinstance(value, dict):
            return {key: absolute(item) for key, item in value.items()}
        if isinstance(value, list | tuple):
            return [absolute(item) for item in value]
        return value

    return tomli_w.dumps(absolute(scene.model_dump(exclude={"base_dir"}, exclude_none=True)))


def save_scene(scene: Scene, path: str | Path, overwrite: bool = False) -> Path:
    """Write the scene as a TOML file (see :func:`scene_toml`); an existing file is an error unless
    ``overwrite``: an edited scene never replaces what the user had by accident."""
    from ..outputs import atomic_write, check_output

    path = check_output(path, (".toml",), inputs=scene.input_files(), overwrite=overwrite)
    atomic_write(path, scene_toml(scene).encode("utf-8"))
    return path
