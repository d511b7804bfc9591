"""Real assets as scenes: a glTF file's parts, materials, cameras and lights in reflets' scene model (an OBJ
file's parts and MTL materials: ``reflets.scene.obj_asset``).

``load_scene("model.glb")`` (and every command taking a scene) builds a whole scene from the file; a scene TOML's
``[[mesh]] file = "model.glb"`` without ``material`` becomes one mesh per primitive instance with the file's
materials (``expand_file_meshes``), its ``transform`` applied on top of the file's node transforms.

What becomes what (docs/assets.md has the full table):

- each primitive of each mesh node of the default scene → a ``FileMesh`` with ``part`` = its index in
  :meth:`GltfFile.instances` order, named after the node; the file's world transform is baked into the part's
  vertices (reflets' meshes are stored in world space), the parsed file and its accessors are shared;
- materials → ``type = "gltf"`` (Appendix B) with their textures (``TextureRef``: the glTF file and the image
  index, the sampler's wrap modes and filter, ``KHR_texture_transform``), ``KHR_materials_emissive_strength``,
  ``KHR_materials_clearcoat``, ``KHR_materials_sheen``, ``KHR_materials_ior``, ``KHR_materials_specular``,
  ``KHR_materials_unlit``, ``KHR_materials_anisotropy``, ``KHR_materials_transmission``, ``KHR_materials_volume``;
  any other material extension → a warning naming it (its base material is rendered);
- cameras → ``Camera`` (perspective, or orthographic with ``ortho_height`` = 2 ymag and the aspect xmag / ymag;
  ``--camera K`` picks one; default the first, else one framing the bounding box);
- ``KHR_lights_punctual`` → point / directional lights, photometric units converted to radiometric ones at
  683 lm/W (the luminous efficacy of 555 nm light, as Blender's glTF importer does): W/sr = cd / 683,
  W/m² = lx / 683; spot lights → point lights with a ``spot`` cone; ``range`` is ignored (the
  specification allows it);
- no light in the file → the environment map given, or the studio map shipped with reflets
  (``data/environments/studio.hdr``, Poly Haven's brown_photostudio_02), shown as the background.
"""

from __future__ import annotations

import math
import re
from dataclasses import dataclass, field
from importlib import resources
from pathlib import Path

import numpy as np

from ..errors import SceneError
from ..gltf_file import GltfFile, read_gltf
from .meshdata import MeshData

#: the file extensions that carry materials (and so may stand without ``material`` in a scene)
ASSET_EXTENSIONS = (".gltf", ".glb", ".obj")
#: lumens per watt of 555 nm light: photometric glTF light units → reflets' radiometric ones
LUMINOUS_EFFICACY = 683.0
#: material extensions read into the ``gltf`` material
SUPPORTED_MATERIAL_EXTENSIONS = {"KHR_materials_emissive_strength", "KHR_texture_transform", "KHR_materials_clearcoat",
                                 "KHR_materials_sheen", "KHR_materials_ior", "KHR_materials_unlit",
                                 "KHR_materials_specular", "KHR_materials_anisotropy", "KHR_materials_transmission",
                                 "KHR_materials_volume"}  # fmt: skip
WRAPS = {10497: "repeat", 33071: "clamp", 33648: "mirror"}
NEAREST_FILTERS = {9728, 9984, 9986}  # NEAREST, NEAREST_MIPMAP_NEAREST, NEAREST_MIPMAP_LINEAR (mag / min)


def default_environment() -> Path:
    """The studio map lighting a file that has no light of its own."""
    return Path(str(resources.files("reflets").joinpath("data", "environments", "studio.hdr")))


def asset_path(name: str) -> Path:
    """A real asset shipped with reflets (``data/assets``: Khronos' DamagedHelmet and WaterBottle, credited there)."""
    return Path(str(resources.files("reflets").joinpath("data", "assets", *name.split("/"))))


@dataclass
class Asset:
    """What a file holds, in scene-model terms (dicts ready for validation), and what was left out."""

    path: Path
    parts: list[dict]  # FileMesh dicts (file, part, name, material)
    materials: dict[str, dict]
    cameras: list[dict]  # Camera dicts without size / the framing default
    lights: list[dict]
    warnings: list[str] = field(default_factory=list)


def is_asset(path: str | Path) -> bool:
    return Path(path).suffix.lower() in ASSET_EXTENSIONS


#: an OBJ's ``mtllib`` and ``usemtl`` statements (the file's own materials), found without parsing its geometry
_OBJ_MATERIAL_LINES = re.compile(rb"^[ \t]*(mtllib|usemtl)[ \t]+(\S[^\r\n]*?)[ \t]*\r?$", re.MULTILINE)


def own_materials(path: str | Path) -> list[str]:
    """The names of the materials a glTF file defines, or an OBJ file takes from its MTL libraries (none without
    one): what a scene's ``material`` for the whole file replaces."""
    path = Path(path)
    if path.suffix.lower() == ".obj":
        from .meshfile import decode_text

        found = _OBJ_MATERIAL_LINES.findall(path.read_bytes())
        if not any(kind == b"mtllib" for kind, _ in found):
            return []
        return list(dict.fromkeys(decode_text(name) for kind, name in found if kind == b"usemtl"))
    return [m.name or f"material {i}" for i, m in enumerate(read_gltf(path).doc.materials or [])]


def load_asset(path: str | Path) -> Asset:
    """Read a glTF file's parts, materials, cameras and lights (see the module docstring); an OBJ file's parts and
    MTL materials (``reflets.scene.obj_asset``)."""
    path = Path(path).absolute()
    if path.suffix.lower() == ".obj":
        from .obj_asset import load_obj_asset

        parts, materials, warnings = load_obj_asset(path)
        return Asset(path, parts, materials, [], [], warnings)
    gltf = read_gltf(path)
    warnings: list[str] = []
    names = _material_names(gltf)
    left_out: dict[str, list[str]] = {}  # what a material's feature becomes instead → the materials concerned
    materials = {names[i]: _material(gltf, i, warnings, left_out) for i in range(len(gltf.doc.materials or []))}
    for what, which in left_out.items():  # one line per feature, however many materials have it
        warnings.append(f"{gltf.path.name}: {what} (material{'s' if len(which) > 1 else ''} {listed(which)})")
    parts = []
    default_material = None
    for index, instance in enumerate(gltf.instances):
        material = gltf.doc.meshes[instance.mesh].primitives[instance.primitive].material
        if material is None:
            default_material = default_material or _unique("default", names)
            materials.setdefault(default_material, {"type": "gltf"})  # the specification's default material
            name = default_material
        elif not 0 <= material < len(names):
            raise SceneError(f"meshes[{instance.mesh}].primitives[{instance.primitive}].material: materials"
                             f"[{material}] does not exist", file=path)  # fmt: skip
        else:
            name = names[material]
        parts.append({"file": path, "part": index, "name": instance.name, "material": name})
    cameras, lights = _cameras(gltf, warnings), _lights(gltf, warnings)
    warnings += gltf.warnings
    return Asset(path, parts, materials, cameras, lights, list(dict.fromkeys(warnings)))  # each line once


def listed(names: list[str], shown: int = 3) -> str:
    """``'a', 'b', 'c' and 4 more``: names in a one-line message, however many there are."""
    more = f" and {len(names) - shown} more" if len(names) > shown else ""
    return ", ".join(f"'{n}'" for n in names[:shown]) + more


def _unique(name: str, taken) -> str:
    candidate, k = name, 1
    while candidate in taken:
        k += 1
        candidate = f"{name} ({k})"
    return candidate


def _material_names(gltf: GltfFile) -> list[str]:
    """Unique names of the file's materials: their own, else ``material K``, prefixed with the file's stem."""
    out: list[str] = []
    for i, material in enumerate(gltf.doc.materials or []):
        out.append(_unique(f"{gltf.path.stem}/{material.name or f'material {i}'}", out))
    return out


def _texture(gltf: GltfFile, info, where: str, warnings: list[str]) -> dict | None:
    """A TextureRef dict for a glTF textureInfo (None when absent)."""
    if info is None:
        return None
    textures = gltf.doc.textures or []
    index = info.index
    if not isinstance(index, int) or isinstance(index, bool):
        raise SceneError(f"{where}.index: must be a texture index (an integer), got {index!r}", file=gltf.path)
    if not 0 <= index < len(textures):
        raise SceneError(f"{where}.index: textures[{index}] does not exist", file=gltf.path)
    texture = textures[index]
    source = texture.source
    if source is None:  # e.g. only an extension's image (KHR_texture_basisu, EXT_texture_webp)
        found = [key for key in (texture.extensions or {})]
        warnings.append(f"{gltf.path.name}: textures[{index}] has no PNG / JPEG source ({', '.join(found) or 'none'}"
                        f"): {where} left out")  # fmt: skip
        return None
    ref: dict = {"texture": gltf.path, "image": source, "uv": info.texCoord or 0}
    image = (gltf.doc.images or [])[source] if source < len(gltf.doc.images or []) else None
    if image is not None and image.uri and not image.uri.startswith("data:"):
        import urllib.parse

        ref = {"texture": gltf.path.parent / urllib.parse.unquote(image.uri), "uv": info.texCoord or 0}
    transform = (info.extensions or {}).get("KHR_texture_transform")
    if transform is not None:
        ref["transform"] = {
            "offset": tuple(transform.get("offset", (0.0, 0.0))),
            "rotation": float(transform.get("rotation", 0.0)),
            "scale": tuple(transform.get("scale", (1.0, 1.0))),
        }
        if "texCoord" in transform:
            ref["uv"] = int(transform["texCoord"])
    if texture.sampler is not None and 0 <= texture.sampler < len(gltf.doc.samplers or []):
        sampler = gltf.doc.samplers[texture.sampler]
        ref["wrap"] = (WRAPS.get(sampler.wrapS or 10497, "repeat"), WRAPS.get(sampler.wrapT or 10497, "repeat"))
        if sampler.magFilter in NEAREST_FILTERS:
            ref["filter"] = "nearest"
    return ref


def _material(gltf: GltfFile, index: int, warnings: list[str], left_out: dict[str, list[str]]) -> dict:
    m = gltf.doc.materials[index]
    where = f"materials[{index}]"
    pbr = m.pbrMetallicRoughness
    out: dict = {"type": "gltf", "double_sided": bool(m.doubleSided)}
    if pbr is not None:
        if pbr.baseColorFactor is not None:
            out["base_color"] = tuple(float(np.clip(c, 0.0, 1.0)) for c in pbr.baseColorFactor)
        out["metallic"] = float(np.clip(1.0 if pbr.metallicFactor is None else pbr.metallicFactor, 0.0, 1.0))
        out["roughness"] = float(np.clip(1.0 if pbr.roughnessFactor is None else pbr.roughnessFactor, 0.0, 1.0))
        slot = where + ".pbrMetallicRoughness."
        out["base_color_texture"] = _texture(gltf, pbr.baseColorTexture, slot + "baseColorTexture", warnings)
        mr = _texture(gltf, pbr.metallicRoughnessTexture, slot + "metallicRoughnessTexture", warnings)
        out["metallic_roughness_texture"] = mr
    if m.normalTexture is not None:
        out["normal_texture"] = _texture(gltf, m.normalTexture, where + ".normalTexture", warnings)
        out["normal_scale"] = float(m.normalTexture.scale if m.normalTexture.scale is not None else 1.0)
    if m.occlusionTexture is not None:
        out["occlusion_texture"] = _texture(gltf, m.occlusionTexture, where + ".occlusionTexture", warnings)
        strength = m.occlusionTexture.strength
        out["occlusion_strength"] = float(np.clip(1.0 if strength is None else strength, 0.0, 1.0))
    if m.emissiveFactor is not None:
        out["emissive"] = tuple(float(max(c, 0.0)) for c in m.emissiveFactor)
    out["emissive_texture"] = _texture(gltf, m.emissiveTexture, where + ".emissiveTexture", warnings)
    extensions = m.extensions or {}
    if "KHR_materials_emissive_strength" in extensions:
        out["emissive_strength"] = float(extensions["KHR_materials_emissive_strength"].get("emissiveStrength", 1.0))
    if "KHR_materials_clearcoat" in extensions:
        out |= _clearcoat(gltf, extensions["KHR_materials_clearcoat"], f"{where}.extensions.KHR_materials_clearcoat",
                          warnings)  # fmt: skip
    if "KHR_materials_unlit" in extensions:
        out["unlit"] = True
    if "KHR_materials_ior" in extensions:
        ior = extensions["KHR_materials_ior"]
        if not isinstance(ior, dict):
            raise SceneError(f"{where}.extensions.KHR_materials_ior: must be an object", file=gltf.path)
        out["ior"] = ior.get("ior", 1.5)
    if "KHR_materials_specular" in extensions:
        out |= _specular(gltf, extensions["KHR_materials_specular"], f"{where}.extensions.KHR_materials_specular",
                         warnings)  # fmt: skip
    if "KHR_materials_sheen" in extensions:
        out |= _sheen(gltf, extensions["KHR_materials_sheen"], f"{where}.extensions.KHR_materials_sheen", warnings)
    if "KHR_materials_anisotropy" in extensions:
        out |= _anisotropy(gltf, extensions["KHR_materials_anisotropy"],
                           f"{where}.extensions.KHR_materials_anisotropy", warnings)  # fmt: skip
    if "KHR_materials_transmission" in extensions:
        out |= _transmission(gltf, extensions["KHR_materials_transmission"],
                             f"{where}.extensions.KHR_materials_transmission", warnings)  # fmt: skip
    if "KHR_materials_volume" in extensions:
        out |= _volume(gltf, extensions["KHR_materials_volume"], f"{where}.extensions.KHR_materials_volume", warnings)
    mode = (m.alphaMode or "OPAQUE").lower()
    out["alpha_mode"] = mode if mode in ("opaque", "mask", "blend") else "opaque"
    if m.alphaCutoff is not None:
        out["alpha_cutoff"] = float(np.clip(m.alphaCutoff, 0.0, 1.0))
    name = m.name or where
    for extension in sorted(set(extensions) - SUPPORTED_MATERIAL_EXTENSIONS):
        left_out.setdefault(f"{extension} not supported, the base metallic-roughness material is rendered",
                            []).append(name)  # fmt: skip
    return {key: value for key, value in out.items() if value is not None}


def _extension_textures(gltf: GltfFile, extension, where: str):
    """A material extension's textureInfo reader (raw JSON: its textureInfo objects are dicts), once the extension
    is known to be an object."""
    from types import SimpleNamespace

    if not isinstance(extension, dict):
        raise SceneError(f"{where}: must be an object", file=gltf.path)

    def info(key: str):
        value = extension.get(key)
        if value is None:
            return None
        if not isinstance(value, dict):
            raise SceneError(f"{where}.{key}: must be a textureInfo object", file=gltf.path)
        return SimpleNamespace(index=value.get("index"), texCoord=value.get("texCoord"),
                               extensions=value.get("extensions"), scale=value.get("scale"))  # fmt: skip

    return info


def _clearcoat(gltf: GltfFile, coat, where: str, warnings: list[str]) -> dict:
    """KHR_materials_clearcoat's factors and textures."""
    info = _extension_textures(gltf, coat, where)
    out = {
        "clearcoat": coat.get("clearcoatFactor", 0.0),
        "clearcoat_roughness": coat.get("clearcoatRoughnessFactor", 0.0),
        "clearcoat_texture": _texture(gltf, info("clearcoatTexture"), where + ".clearcoatTexture", warnings),
        "clearcoat_roughness_texture": _texture(gltf, info("clearcoatRoughnessTexture"),
                                                where + ".clearcoatRoughnessTexture", warnings),  # fmt: skip
    }
    normal = info("clearcoatNormalTexture")
    if normal is not None:
        out["clearcoat_normal_texture"] = _texture(gltf, normal, where + ".clearcoatNormalTexture", warnings)
        out["clearcoat_normal_scale"] = 1.0 if normal.scale is None else normal.scale
    return out


def _sheen(gltf: GltfFile, sheen, where: str, warnings: list[str]) -> dict:
    """KHR_materials_sheen's factors and textures (colour in RGB, sRGB; roughness in A)."""
    info = _extension_textures(gltf, sheen, where)
    return {
        "sheen_color": sheen.get("sheenColorFactor", (0.0, 0.0, 0.0)),
        "sheen_roughness": sheen.get("sheenRoughnessFactor", 0.0),
        "sheen_color_texture": _texture(gltf, info("sheenColorTexture"), where + ".sheenColorTexture", warnings),
        "sheen_roughness_texture": _texture(gltf, info("sheenRoughnessTexture"), where + ".sheenRoughnessTexture",
                                            warnings),  # fmt: skip
    }


def _anisotropy(gltf: GltfFile, anisotropy, where: str, warnings: list[str]) -> dict:
    """KHR_materials_anisotropy's strength, rotation and texture (direction in RG, strength in B)."""
    info = _extension_textures(gltf, anisotropy, where)
    return {
        "anisotropy_strength": anisotropy.get("anisotropyStrength", 0.0),
        "anisotropy_rotation": anisotropy.get("anisotropyRotation", 0.0),
        "anisotropy_texture": _texture(gltf, info("anisotropyTexture"), where + ".anisotropyTexture", warnings),
    }


def _transmission(gltf: GltfFile, transmission, where: str, warnings: list[str]) -> dict:
    """KHR_materials_transmission's weight (its texture's R)."""
    info = _extension_textures(gltf, transmission, where)
    return {
        "transmission": transmission.get("transmissionFactor", 0.0),
        "transmission_texture": _texture(gltf, info("transmissionTexture"), where + ".transmissionTexture", warnings),
    }


def _volume(gltf: GltfFile, volume, where: str, warnings: list[str]) -> dict:
    """KHR_materials_volume's thickness (its texture's G) and attenuation (glTF's infinite distance: none)."""
    info = _extension_textures(gltf, volume, where)
    return {
        "thickness": volume.get("thicknessFactor", 0.0),
        "thickness_texture": _texture(gltf, info("thicknessTexture"), where + ".thicknessTexture", warnings),
        "attenuation_distance": volume.get("attenuationDistance"),
        "attenuation_color": volume.get("attenuationColor", (1.0, 1.0, 1.0)),
    }


def _specular(gltf: GltfFile, specular, where: str, warnings: list[str]) -> dict:
    """KHR_materials_specular's weight (its texture's A) and Fresnel tint (its texture's RGB, sRGB)."""
    info = _extension_textures(gltf, specular, where)
    return {
        "specular": specular.get("specularFactor", 1.0),
        "specular_color": specular.get("specularColorFactor", (1.0, 1.0, 1.0)),
        "specular_texture": _texture(gltf, info("specularTexture"), where + ".specularTexture", warnings),
        "specular_color_texture": _texture(gltf, info("specularColorTexture"), where + ".specularColorTexture",
                                           warnings),  # fmt: skip
    }


def _basis(matrix: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(position, −z, +y) of a node's world matrix (cameras and lights look along their −z)."""
    position = matrix[:3, 3]
    forward = -matrix[:3, 2] / max(np.linalg.norm(matrix[:3, 2]), 1e-30)
    up = matrix[:3, 1] / max(np.linalg.norm(matrix[:3, 1]), 1e-30)
    return position, forward, up


def _cameras(gltf: GltfFile, warnings: list[str]) -> list[dict]:
    out = []
    cameras = gltf.doc.cameras or []
    for node_index, matrix in gltf.world_matrices.items():
        node = gltf.doc.nodes[node_index]
        if node.camera is None:
            continue
        if not 0 <= node.camera < len(cameras):
            raise SceneError(f"nodes[{node_index}].camera: cameras[{node.camera}] does not exist", file=gltf.path)
        camera = cameras[node.camera]
        name = camera.name or node.name or f"camera {node.camera}"
        position, forward, up = _basis(matrix)
        where = f"cameras[{node.camera}]"
        fields = {"position": tuple(map(float, position)), "look_at": tuple(map(float, position + forward)),
                  "up": tuple(map(float, up))}  # fmt: skip
        if camera.type == "orthographic" and camera.orthographic is not None:
            o = camera.orthographic
            for key in ("xmag", "ymag"):
                value = getattr(o, key)
                if not (isinstance(value, int | float) and 0.0 < abs(value) <= 1e9 and math.isfinite(value)):
                    raise SceneError(f"{where}.orthographic.{key}: must be a non-zero finite number, got {value!r}",
                                     file=gltf.path)  # fmt: skip
            aspect = abs(o.xmag) / abs(o.ymag)
            if not 1e-3 < aspect < 1e3:
                raise SceneError(f"{where}.orthographic: xmag / ymag = {aspect:g}, outside (0.001, 1000)",
                                 file=gltf.path)  # fmt: skip
            fields |= {"projection": "orthographic", "ortho_height": 2.0 * abs(float(o.ymag)),
                       "size": (max(1, round(480 * aspect)), 480), "near": float(o.znear) if o.znear else None,
                       "far": float(o.zfar) if o.zfar else None}  # fmt: skip
        elif camera.type == "perspective" and camera.perspective is not None:
            p = camera.perspective
            where += ".perspective"
            if not (isinstance(p.yfov, int | float) and 0.0 < p.yfov < math.pi):
                raise SceneError(f"{where}.yfov: must be in (0, π) radians, got {p.yfov!r}", file=gltf.path)
            aspect = p.aspectRatio
            if aspect is not None and not (isinstance(aspect, int | float) and 1e-3 < aspect < 1e3):
                raise SceneError(f"{where}.aspectRatio: must be in (0.001, 1000), got {aspect!r}", file=gltf.path)
            fields |= {"fov_y": float(min(math.degrees(p.yfov), 179.0)), "near": float(p.znear) if p.znear else None,
                       "far": float(p.zfar) if p.zfar else None}  # fmt: skip
            if p.aspectRatio:
                fields["size"] = (max(1, round(480 * float(p.aspectRatio))), 480)
        else:
            warnings.append(f"{gltf.path.name}: camera '{name}' of type {camera.type!r} without its parameters: "
                            "skipped")  # fmt: skip
            continue
        out.append({"name": name, "fields": {k: v for k, v in fields.items() if v is not None}})
    return out


def _lights(gltf: GltfFile, warnings: list[str]) -> list[dict]:
    defined = ((gltf.doc.extensions or {}).get("KHR_lights_punctual") or {}).get("lights") or []
    out = []
    for node_index, matrix in gltf.world_matrices.items():
        ref = ((gltf.doc.nodes[node_index].extensions or {}).get("KHR_lights_punctual") or {}).get("light")
        if ref is None:
            continue
        if not isinstance(ref, int) or not 0 <= ref < len(defined):
            raise SceneError(f"nodes[{node_index}].extensions.KHR_lights_punctual.light: no light {ref!r}",
                             file=gltf.path)  # fmt: skip
        light = defined[ref]
        color = np.asarray(light.get("color", (1.0, 1.0, 1.0)), dtype=np.float64)
        power = tuple(float(c) for c in np.maximum(color * float(light.get("intensity", 1.0)), 0.0) / LUMINOUS_EFFICACY)
        position, forward, _ = _basis(matrix)
        kind = light.get("type")
        name = light.get("name") or f"light {ref}"
        if kind == "directional":
            out.append({"type": "directional", "direction": tuple(map(float, forward)), "irradiance": power})
            continue
        if kind not in ("point", "spot"):
            warnings.append(f"{gltf.path.name}: light '{name}' of type {kind!r} skipped")
            continue
        point = {"type": "point", "position": tuple(map(float, position)), "intensity": power}
        if kind == "spot":
            point["spot"] = _spot(gltf, light.get("spot") or {}, f"extensions.KHR_lights_punctual.lights[{ref}].spot",
                                  tuple(map(float, forward)))  # fmt: skip
        out.append(point)
    return out


def _spot(gltf: GltfFile, spot, where: str, forward: tuple[float, float, float]) -> dict:
    """A spot light's cone along its node's −z: glTF's angles (radians) in degrees (validated by ``SpotCone``)."""
    if not isinstance(spot, dict):
        raise SceneError(f"{where}: must be an object", file=gltf.path)

    def degrees(key: str, default: float):
        value = spot.get(key, default)
        is_number = isinstance(value, int | float) and not isinstance(value, bool)
        return math.degrees(value) if is_number and math.isfinite(value) else value  # else: the model says why

    return {"direction": forward, "inner_deg": degrees("innerConeAngle", 0.0),
            "outer_deg": degrees("outerConeAngle", math.pi / 4)}  # fmt: skip


# ---------------------------------------------------------------------------------------------- geometry


def part_mesh(path: str | Path, part: int) -> MeshData:
    """One part of a glTF or OBJ file (``FileMesh.part``) in the file's world coordinates, with a full shading frame
    (``meshfile.gltf_part_mesh``, ``obj_asset.obj_part_mesh``); a whole file in one mesh is
    ``meshfile.load_mesh_file``'s."""
    if Path(path).suffix.lower() == ".obj":
        from .obj_asset import obj_part_mesh

        return obj_part_mesh(Path(path), part)
    from .meshfile import gltf_part_mesh

    return gltf_part_mesh(path, part)
