"""``reflets export-gltf``: a scene as a binary glTF 2.0 file (.glb) that any glTF viewer opens — so that an
edited orientation field (highlight editing) is seen outside reflets.

- meshes: world-space positions, normals, **tangents** (xyz + handedness: the mesh's own, or its material's
  orientation field — what a glTF renderer orients anisotropy by), both uv sets, indices; one node each;
- materials: a ``gltf`` material (what a glTF / OBJ asset is read as) as it is — every factor, texture (its image
  bytes as read, unless re-encoded: a channel swizzle or an explicit ``srgb`` against the slot's role), sampler,
  uv set, KHR_texture_transform, alpha mode and extension (emissive_strength, ior, specular, clearcoat, sheen,
  anisotropy, unlit): a glTF file read, exported and read again gives the same materials and textures;
  other models through glTF's metallic-roughness model, which is GGX: a reflets material maps exactly when it is a GGX
  microfacet (roughness = √α; a conductor's base colour is its normal-incidence Fresnel reflectance), and
  approximately otherwise (roughness from the lobe's GGX-equivalent α, as the prefiltered environment uses it;
  a Lambertian part as base colour, a coloured specular through ``KHR_materials_specular``); anisotropic α
  through ``KHR_materials_anisotropy`` (α_t = mix(α_b, 1, strength²) along the tangent, turned by 90° when the
  rougher direction is the bitangent); each approximation is reported;
- lights: point, spot and directional lights through ``KHR_lights_punctual``, in its photometric units (× 683 lm/W:
  the inverse of what reading does, ``reflets.scene.assets``); area lights as emissive geometry
  (``KHR_materials_emissive_strength``); the environment is left out (reported);
- the camera: perspective (field of view, aspect ratio) or orthographic.
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np

ANISOTROPY = "KHR_materials_anisotropy"
SPECULAR = "KHR_materials_specular"
LIGHTS = "KHR_lights_punctual"
EMISSIVE = "KHR_materials_emissive_strength"
TRANSMISSION = "KHR_materials_transmission"
VOLUME = "KHR_materials_volume"
TRANSFORM = "KHR_texture_transform"
#: glTF sampler wrap codes
WRAP_CODES = {"repeat": 10497, "clamp": 33071, "mirror": 33648}
PNG_MAGIC, JPEG_MAGIC = b"\x89PNG\r\n\x1a\n", b"\xff\xd8\xff"


class _Textures:
    """The exported file's images, samplers and textures, each written once: images by content, samplers by
    settings, textures by (image, sampler)."""

    def __init__(self, add_view):
        self.add_view = add_view  # bytes → bufferView index
        self.images: list[dict] = []
        self.samplers: list[dict] = []
        self.textures: list[dict] = []
        self._image_index: dict[bytes, int] = {}
        self.used: set[str] = set()

    def info(self, ref, role_srgb: bool, where: str, notes: list[str]) -> dict:
        """A textureInfo dict for ``ref`` read as ``role_srgb`` (the slot's colour encoding)."""
        import hashlib

        data, mime = self._encoded(ref, role_srgb, where, notes)
        digest = hashlib.sha1(data).digest()
        if digest not in self._image_index:
            self._image_index[digest] = len(self.images)
            self.images.append({"bufferView": self.add_view(data), "mimeType": mime})
        sampler = {"wrapS": WRAP_CODES[ref.wrap[0]], "wrapT": WRAP_CODES[ref.wrap[1]]}
        if ref.filter == "nearest":
            sampler |= {"magFilter": 9728, "minFilter": 9984}  # NEAREST, NEAREST_MIPMAP_NEAREST
        if sampler not in self.samplers:
            self.samplers.append(sampler)
        texture = {"source": self._image_index[digest], "sampler": self.samplers.index(sampler)}
        if texture not in self.textures:
            self.textures.append(texture)
        info: dict = {"index": self.textures.index(texture)}
        if ref.uv:
            info["texCoord"] = ref.uv
        if ref.transform is not None:
            t = ref.transform
            info["extensions"] = {TRANSFORM: {"offset": list(t.offset), "rotation": t.rotation, "scale": list(t.scale)}}
            self.used.add(TRANSFORM)
        return info

    @staticmethod
    def _encoded(ref, role_srgb: bool, where: str, notes: list[str]) -> tuple[bytes, str]:
        """The image's own bytes when glTF can hold them as they are (PNG / JPEG, no swizzle, the slot's
        encoding), else its decoded texels as a PNG in the slot's encoding."""
        from .imageio import _encode_png, linear_to_srgb
        from .textures import load_texture, texture_bytes

        data, _ = texture_bytes(ref)
        mime = "image/png" if data.startswith(PNG_MAGIC) else "image/jpeg" if data.startswith(JPEG_MAGIC) else None
        srgb = role_srgb if ref.srgb is None else ref.srgb
        if mime is not None and ref.channels in (None, "rgba") and srgb == role_srgb:
            return data, mime
        decoded = load_texture(ref, srgb)
        codes = decoded.codes
        if srgb != role_srgb:  # re-encoded for the slot: its linear values in the slot's encoding, 8 bits
            values = decoded.texels.copy()
            if role_srgb:
                values[..., :3] = linear_to_srgb(np.clip(values[..., :3], 0.0, 1.0))
            codes = np.clip(np.rint(values * 255.0), 0, 255).astype(np.uint8)
            notes.append(f"{where}: re-encoded {'as sRGB' if role_srgb else 'linear'} (glTF fixes each slot's "
                         f"encoding; 8-bit rounding)")  # fmt: skip
        return _encode_png(np.ascontiguousarray(codes)), "image/png"


def _gltf_material(name: str, m, textures: _Textures) -> tuple[dict, list[str]]:
    """A ``gltf`` material written back as it is (the inverse of ``reflets.scene.assets``' reading)."""
    from .brdf.gltf import SLOTS

    notes: list[str] = []
    role = {field: srgb for field, _, srgb, _ in SLOTS}

    def info(field: str, **extra) -> dict | None:
        ref = getattr(m, field)
        return None if ref is None else textures.info(ref, role[field], f"{name}.{field}", notes) | extra

    pbr = {"baseColorFactor": list(m.base_color), "metallicFactor": m.metallic, "roughnessFactor": m.roughness,
           "baseColorTexture": info("base_color_texture"),
           "metallicRoughnessTexture": info("metallic_roughness_texture")}  # fmt: skip
    emissive = np.asarray(m.emissive, float)
    strength = m.emissive_strength * max(1.0, float(emissive.max()))  # glTF's factor is at most 1 per channel
    out = {
        "name": name,
        "pbrMetallicRoughness": pbr,
        "normalTexture": info("normal_texture", scale=m.normal_scale),
        "occlusionTexture": info("occlusion_texture", strength=m.occlusion_strength),
        "emissiveFactor": (emissive * m.emissive_strength / strength).tolist() if strength > 0 else [0.0, 0.0, 0.0],
        "emissiveTexture": info("emissive_texture"),
        "alphaMode": m.alpha_mode.upper(),
        "alphaCutoff": m.alpha_cutoff if m.alpha_mode == "mask" else None,
        "doubleSided": m.double_sided,
    }
    extensions: dict = {}
    if strength != 1.0 and strength > 0:
        extensions[EMISSIVE] = {"emissiveStrength": strength}
    if m.unlit:
        extensions["KHR_materials_unlit"] = {}
    if m.ior != 1.5:
        extensions["KHR_materials_ior"] = {"ior": m.ior}
    tinted = tuple(m.specular_color) != (1.0, 1.0, 1.0)
    if m.specular != 1.0 or tinted or m.specular_texture or m.specular_color_texture:
        extensions[SPECULAR] = {"specularFactor": m.specular, "specularColorFactor": list(m.specular_color),
                                "specularTexture": info("specular_texture"),
                                "specularColorTexture": info("specular_color_texture")}  # fmt: skip
    if m.clearcoat > 0 or m.clearcoat_texture is not None:
        extensions["KHR_materials_clearcoat"] = {
            "clearcoatFactor": m.clearcoat, "clearcoatRoughnessFactor": m.clearcoat_roughness,
            "clearcoatTexture": info("clearcoat_texture"),
            "clearcoatRoughnessTexture": info("clearcoat_roughness_texture"),
            "clearcoatNormalTexture": info("clearcoat_normal_texture", scale=m.clearcoat_normal_scale),
        }  # fmt: skip
    if max(m.sheen_color) > 0 or m.sheen_color_texture is not None:
        extensions["KHR_materials_sheen"] = {
            "sheenColorFactor": list(m.sheen_color), "sheenRoughnessFactor": m.sheen_roughness,
            "sheenColorTexture": info("sheen_color_texture"),
            "sheenRoughnessTexture": info("sheen_roughness_texture"),
        }  # fmt: skip
    if m.anisotropic or m.anisotropy_texture is not None:
        extensions[ANISOTROPY] = {"anisotropyStrength": m.anisotropy_strength,
                                  "anisotropyRotation": m.anisotropy_rotation,
                                  "anisotropyTexture": info("anisotropy_texture")}  # fmt: skip
    if m.transmission > 0 or m.transmission_texture is not None:
        extensions[TRANSMISSION] = {"transmissionFactor": m.transmission,
                                    "transmissionTexture": info("transmission_texture")}  # fmt: skip
    if m.thickness > 0 or m.thickness_texture is not None or m.attenuation_distance is not None:
        extensions[VOLUME] = {"thicknessFactor": m.thickness, "thicknessTexture": info("thickness_texture"),
                              "attenuationDistance": m.attenuation_distance,
                              "attenuationColor": list(m.attenuation_color)}  # fmt: skip
    if extensions:
        out["extensions"] = extensions
    return _without_none(out), notes


def _reads_second_set(material) -> bool:
    """A texture of this material (a scratched one's base) reads the second uv set."""
    from .textures import texture_refs

    source = material.base if material.type == "scratched" else material
    return any(ref.uv == 1 for ref in texture_refs(source).values())


def _without_none(d: dict) -> dict:
    return {key: _without_none(value) if isinstance(value, dict) else value for key, value in d.items()
            if value is not None}  # fmt: skip


def _alphas(material) -> tuple[float, float] | None:
    """The (along the tangent, along the bitangent) GGX α of an anisotropic material, or None (isotropic)."""
    kind = material.type
    if kind == "scratched":
        return _alphas(material.base)
    if kind in ("microfacet", "ward") and isinstance(material.alpha, tuple | list):
        return float(material.alpha[0]), float(material.alpha[1])
    if kind == "ashikhmin_shirley" and material.nu != material.nv:  # Walter et al.'s exponent ↔ α
        return math.sqrt(2.0 / (material.nu + 2.0)), math.sqrt(2.0 / (material.nv + 2.0))
    return None


def _specular_tint_field(source) -> str | None:
    """The colour of a library model written as KHR_materials_specular's tint (a Phong ks, an Ashikhmin-Shirley rs, a
    microfacet specular), if it has one."""
    return next((f for f in ("ks", "rs", "specular") if f in type(source).model_fields), None)


def material_to_gltf(name: str, material) -> tuple[dict, list[str]]:
    """A glTF material dict (pbrMetallicRoughness and extensions) and the approximations it makes."""
    from .fresnel import fresnel_conductor
    from .techniques.ibl import equivalent_alpha

    kind = material.type
    notes: list[str] = []
    base, metallic, roughness = [0.8, 0.8, 0.8], 0.0, 1.0
    extensions: dict = {}
    source = material.base if kind == "scratched" else material
    if kind == "scratched":
        notes.append(f"{name}: scratched, exported by its base BRDF (the scratch lobes have no glTF form)")
    if source.type == "lambert":
        base = list(source.albedo)
    elif source.type == "microfacet":
        alpha = source.alpha if not isinstance(source.alpha, tuple | list) else min(source.alpha)
        roughness = math.sqrt(float(alpha))
        if source.distribution != "ggx":
            notes.append(f"{name}: {source.distribution} distribution exported as GGX")
        if source.fresnel == "conductor":
            eta = np.broadcast_to(np.asarray(source.eta if source.eta is not None else (0.2, 0.9, 1.1), float), 3)
            k = np.broadcast_to(np.asarray(source.k if source.k is not None else (3.9, 2.4, 2.2), float), 3)
            f0 = [float(fresnel_conductor(1.0, eta[c], k[c])) for c in range(3)]
            base, metallic = list(np.asarray(f0) * np.asarray(source.specular)), 1.0
        else:
            base = list(source.diffuse)
            extensions[SPECULAR] = {"specularFactor": 1.0, "specularColorFactor": [float(c) for c in source.specular]}
    elif source.type == "mirror":
        base, metallic, roughness = list(getattr(source, "reflectance", (1.0, 1.0, 1.0))), 1.0, 0.0
    else:
        lambert, _ = source.lambertian_split()
        base = list(lambert)
        roughness = math.sqrt(equivalent_alpha(source))
        tint = _specular_tint_field(source)
        specular = getattr(source, tint) if tint is not None else None
        if specular is not None:
            extensions[SPECULAR] = {"specularFactor": 1.0, "specularColorFactor": [float(c) for c in specular]}
        if _alphas(source) is None:
            notes.append(f"{name}: {source.type} exported as GGX of roughness {roughness:.3f} (its lobe's equivalent)")
        else:
            notes.append(f"{name}: {source.type} exported as anisotropic GGX (its exponents' equivalent α)")
    alphas = _alphas(material)
    if alphas is not None:
        along, across = alphas
        rough, smooth = max(along, across), min(along, across)
        roughness = math.sqrt(smooth)
        strength = math.sqrt(max(0.0, (rough - smooth) / max(1.0 - smooth, 1e-9)))
        extensions[ANISOTROPY] = {
            "anisotropyStrength": min(strength, 1.0),
            "anisotropyRotation": 0.0 if along >= across else math.pi / 2,  # the rougher direction
        }
    gltf = {
        "name": name,
        "pbrMetallicRoughness": {
            "baseColorFactor": [*[float(min(max(c, 0.0), 1.0)) for c in base], 1.0],
            "metallicFactor": metallic,
            "roughnessFactor": float(min(max(roughness, 0.0), 1.0)),
        },
        "doubleSided": True,
    }
    if extensions:
        gltf["extensions"] = extensions
    return gltf, notes


def _mapped_colours(name: str, source, exported: dict, textures: _Textures) -> list[str]:
    """A library material's maps (``brdf.maps``) in glTF's slots: the mapped colour that became the base colour
    (the Lambertian albedo; a conductor's specular tint, a mirror's reflectance) its baseColorTexture, the one that
    became KHR_materials_specular's tint its specularColorTexture (both sRGB, as glTF defines them); the normal and
    occlusion maps, the emission (its factor over 1 by KHR_materials_emissive_strength) and its map in theirs; a
    texture with no slot (a translucent albedo map) noted."""
    from .textures import texture_refs

    notes: list[str] = []
    conductor = source.type == "microfacet" and source.fresnel == "conductor"
    base = "specular" if conductor else "reflectance" if source.type == "mirror" else source.lambertian_field
    specular = exported.get("extensions", {}).get(SPECULAR)
    tint = _specular_tint_field(source)
    emission = getattr(source, "emission", None)
    if emission is not None:
        strength = max(1.0, float(max(emission)))
        exported["emissiveFactor"] = [float(c) / strength for c in emission]
        if strength > 1.0:
            exported.setdefault("extensions", {})[EMISSIVE] = {"emissiveStrength": strength}
    for key, ref in texture_refs(source).items():  # a translucent albedo map too (no slot: noted)
        mapped, field, where = key.startswith("maps."), key.removeprefix("maps."), f"{name}.{key}"
        if key == "normal_map":
            exported["normalTexture"] = textures.info(ref, False, where, notes) | {"scale": ref.scale}
        elif key == "occlusion":
            exported["occlusionTexture"] = textures.info(ref, False, where, notes) | {"strength": ref.strength}
        elif mapped and field == "emission":
            exported["emissiveTexture"] = textures.info(ref, True, where, notes)
        elif mapped and field == base:
            exported["pbrMetallicRoughness"]["baseColorTexture"] = textures.info(ref, True, where, notes)
        elif mapped and field == tint and specular is not None and not conductor:
            specular["specularColorTexture"] = textures.info(ref, True, where, notes)
        else:
            notes.append(f"{where}: its texture has no glTF slot in this export (not written)")
    return notes


def _gltf_camera(g, cam, boxes: np.ndarray):
    """The scene camera as a glTF camera (orthographic: xmag / ymag are half the view window's width / height, its
    required zfar the renderer's own: ``camera_range`` of the meshes' and emitters' boxes — a far plane beyond them
    would spend the linear depth's float32 precision on empty space)."""
    from .scene.geometry import camera_range

    if cam.orthographic:
        ymag = cam.ortho_height / 2.0
        xmag = ymag * cam.size[0] / cam.size[1] / cam.pixel_aspect
        znear, zfar = camera_range(cam, boxes)
        return g.Camera(type="orthographic", orthographic=g.Orthographic(xmag=xmag, ymag=ymag, znear=znear,
                                                                          zfar=zfar))  # fmt: skip
    perspective = g.Perspective(yfov=math.radians(cam.fov_y), aspectRatio=cam.size[0] / cam.size[1], znear=0.01)
    return g.Camera(type="perspective", perspective=perspective)


def export_gltf(scene, path: str | Path, overwrite: bool = False) -> tuple[Path, list[str]]:
    """Write ``scene`` as a .glb (atomically; an existing file is refused unless ``overwrite``, one of the scene's
    own input files always); returns the path and the approximations made (one line each)."""
    import pygltflib as g

    from .outputs import atomic_write, check_output
    from .scene.assets import LUMINOUS_EFFICACY
    from .scene.geometry import bounding_boxes, mesh_data, mesh_scale

    path = check_output(path, (".glb",), inputs=scene.input_files(), overwrite=overwrite)
    notes: list[str] = []
    blob = bytearray()
    views, accessors = [], []

    def add_view(data: bytes, target: int | None = None) -> int:
        while len(blob) % 4:
            blob.append(0)
        views.append(g.BufferView(buffer=0, byteOffset=len(blob), byteLength=len(data), target=target))
        blob.extend(data)
        return len(views) - 1

    def add(array: np.ndarray, target: int | None, kind: str, component: int, bounds: bool = False) -> int:
        data = np.ascontiguousarray(array)
        add_view(data.tobytes(), target)
        accessor = g.Accessor(bufferView=len(views) - 1, componentType=component, count=len(data), type=kind)
        if bounds:
            accessor.min, accessor.max = data.min(axis=0).tolist(), data.max(axis=0).tolist()
        accessors.append(accessor)
        return len(accessors) - 1

    names = list(scene.materials)
    materials = []
    textures = _Textures(add_view)
    for name in names:
        material = scene.materials[name]
        source = material.base if material.type == "scratched" else material
        if source.type == "gltf":  # a real asset's material (a scratched one's base), as it is
            exported, found = _gltf_material(name, source, textures)
            if source is not material:
                found.insert(0, f"{name}: scratched, exported by its base BRDF (the scratch lobes have no glTF form)")
        else:
            exported, found = material_to_gltf(name, material)
            found += _mapped_colours(name, source, exported, textures)
        materials.append(exported)
        notes += found
    meshes, nodes, points = [], [], []  # points: every exported vertex, for an orthographic camera's far plane
    for index, mesh in enumerate(scene.mesh):
        data = mesh_data(scene, index)
        points.append(data.positions)
        # a volume's thickness is in its mesh's units: such a mesh keeps its scale on its node (world = s × local)
        scale = mesh_scale(scene, index) if getattr(scene.materials[mesh.material], "volumetric", False) else 1.0
        attributes = g.Attributes(
            POSITION=add((data.positions / scale).astype(np.float32), g.ARRAY_BUFFER, g.VEC3, g.FLOAT, bounds=True),
            NORMAL=add(data.normals.astype(np.float32), g.ARRAY_BUFFER, g.VEC3, g.FLOAT),
            TANGENT=add(data.tangents.astype(np.float32), g.ARRAY_BUFFER, g.VEC4, g.FLOAT),
            TEXCOORD_0=add(
                np.stack([data.uvs[:, 0], 1.0 - data.uvs[:, 1]], 1).astype(np.float32), g.ARRAY_BUFFER, g.VEC2, g.FLOAT
            ),
        )
        if data.uvs1 is not None or _reads_second_set(scene.materials[mesh.material]):  # what reflets renders
            second = data.uv_sets[:, 2:]
            attributes.TEXCOORD_1 = add(np.stack([second[:, 0], 1.0 - second[:, 1]], 1).astype(np.float32),
                                        g.ARRAY_BUFFER, g.VEC2, g.FLOAT)  # fmt: skip
        indices = add(data.indices.astype(np.uint32).ravel(), g.ELEMENT_ARRAY_BUFFER, g.SCALAR, g.UNSIGNED_INT)
        primitive = g.Primitive(attributes=attributes, indices=indices, material=names.index(mesh.material))
        meshes.append(g.Mesh(name=mesh.name or f"mesh[{index}]", primitives=[primitive]))
        nodes.append(g.Node(name=mesh.name or f"mesh[{index}]", mesh=len(meshes) - 1,
                            scale=[scale] * 3 if scale != 1.0 else None))  # fmt: skip
    lights = []
    for index, light in enumerate(scene.light):
        if light.type in ("point", "directional"):
            power = light.intensity if light.type == "point" else light.irradiance  # W/sr, W/m²
            peak = max(float(max(power)), 1e-30)
            spot = light.spot if light.type == "point" else None
            lights.append({"type": "spot" if spot else light.type, "color": [float(c) / peak for c in power],
                           "intensity": peak * LUMINOUS_EFFICACY, "name": f"light[{index}]"})  # cd, lx; fmt: skip
            if spot is not None:
                lights[-1]["spot"] = {"innerConeAngle": float(np.radians(spot.inner_deg)),
                                      "outerConeAngle": float(np.radians(spot.outer_deg))}  # fmt: skip
            node = g.Node(name=f"light[{index}]", extensions={LIGHTS: {"light": len(lights) - 1}})
            if light.type == "point":
                node.translation = [float(c) for c in light.position]
            if light.type == "directional" or spot is not None:  # glTF's lights shine along their node's −z
                axis = light.direction if spot is None else spot.direction
                node.rotation = _rotation_to(np.asarray(axis, float))
            nodes.append(node)
        elif light.type in ("quad", "polygon"):
            poly = np.asarray(light.polygon(), np.float32)
            points.append(poly)
            fan = np.array([[0, k, k + 1] for k in range(1, len(poly) - 1)], np.uint32).ravel()
            peak = max(float(max(light.radiance)), 1e-30)
            materials.append({"name": f"light[{index}]", "emissiveFactor": [float(c) / peak for c in light.radiance],
                              "extensions": {EMISSIVE: {"emissiveStrength": peak}},
                              "pbrMetallicRoughness": {"baseColorFactor": [0, 0, 0, 1]},
                              "doubleSided": bool(light.two_sided)})  # fmt: skip
            attributes = g.Attributes(POSITION=add(poly, g.ARRAY_BUFFER, g.VEC3, g.FLOAT, bounds=True))
            fan_indices = add(fan, g.ELEMENT_ARRAY_BUFFER, g.SCALAR, g.UNSIGNED_INT)
            primitive = g.Primitive(attributes=attributes, indices=fan_indices, material=len(materials) - 1)
            meshes.append(g.Mesh(name=f"light[{index}]", primitives=[primitive]))
            nodes.append(g.Node(name=f"light[{index}]", mesh=len(meshes) - 1))
            notes.append(
                f"light[{index}]: a {light.type} light exported as emissive geometry (it lights nothing in glTF)"
            )
        else:
            notes.append(f"light[{index}]: the environment map is not exported")
    cam = scene.camera
    eye, target = np.asarray(cam.position, float), np.asarray(cam.look_at, float)
    nodes.append(
        g.Node(
            name="camera", camera=0, translation=eye.tolist(), rotation=_rotation_to(target - eye, np.asarray(cam.up))
        )
    )
    used = {ext for m in materials for ext in m.get("extensions", {})} | ({LIGHTS} if lights else set())
    used = sorted(used | textures.used)
    document = g.GLTF2(
        scene=0,
        scenes=[g.Scene(nodes=list(range(len(nodes))))],
        nodes=nodes,
        meshes=meshes,
        materials=[g.Material.from_dict(m) for m in materials],
        accessors=accessors,
        images=[g.Image(**image) for image in textures.images],
        samplers=[g.Sampler(**sampler) for sampler in textures.samplers],
        textures=[g.Texture(**texture) for texture in textures.textures],
        bufferViews=views,
        buffers=[g.Buffer(byteLength=len(blob))],
        cameras=[_gltf_camera(g, cam, bounding_boxes(points))],
        extensionsUsed=used,
        extensions={LIGHTS: {"lights": lights}} if lights else {},
    )
    document.set_binary_blob(bytes(blob))
    atomic_write(path, b"".join(document.save_to_bytes()))
    return path, notes


def _rotation_to(forward: np.ndarray, up: np.ndarray | None = None) -> list[float]:
    """The quaternion (x, y, z, w) turning −z onto ``forward`` (and +y towards ``up``): glTF cameras and
    directional lights look along their −z."""
    f = forward / np.linalg.norm(forward)
    up = np.array([0.0, 1.0, 0.0]) if up is None or abs(np.dot(up, f)) > 0.999 * np.linalg.norm(up) else up
    if abs(np.dot(up / np.linalg.norm(up), f)) > 0.999:
        up = np.array([1.0, 0.0, 0.0])
    right = np.cross(f, up)
    right /= np.linalg.norm(right)
    true_up = np.cross(right, f)
    m = np.stack([right, true_up, -f], axis=1)  # columns: the node's x, y, z in the world
    w = math.sqrt(max(0.0, 1.0 + m[0, 0] + m[1, 1] + m[2, 2])) / 2.0
    x = math.copysign(math.sqrt(max(0.0, 1.0 + m[0, 0] - m[1, 1] - m[2, 2])) / 2.0, m[2, 1] - m[1, 2])
    y = math.copysign(math.sqrt(max(0.0, 1.0 - m[0, 0] + m[1, 1] - m[2, 2])) / 2.0, m[0, 2] - m[2, 0])
    z = math.copysign(math.sqrt(max(0.0, 1.0 - m[0, 0] - m[1, 1] + m[2, 2])) / 2.0, m[1, 0] - m[0, 1])
    return [x, y, z, w]
