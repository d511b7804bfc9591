"""Mitsuba 3 as an independent reference: a reflets :class:`~reflets.scene.model.Scene` as a Mitsuba scene.

:func:`to_mitsuba_dict` turns a validated scene into the dict :func:`mitsuba.load_dict` reads, and
:func:`render_mitsuba` renders it with Mitsuba's ``direct`` integrator (multiple importance sampling of
emitter and BSDF sampling, one bounce: the same light transport as the real-time techniques, which cast
no indirect light), always with shadows (compare unshadowed techniques on scenes without occlusion).
Mitsuba runs in its ``scalar_rgb`` variant (CPU, no JIT), so the radiance it returns is linear RGB,
directly comparable with the GPU images.

Conventions (each checked by ``tests/reference/test_mitsuba_bridge.py``):

* **Camera.** ``perspective`` sensor, ``fov = fov_y`` on ``fov_axis = "y"``, ``to_world`` = Mitsuba's
  look-at (local +z forward, +x left, +y up) built from ``position``, ``look_at`` and ``up``; an orthographic
  camera as the ``orthographic`` sensor, its look-at scaled in x and y by ``ortho_height`` × aspect / 2 (Mitsuba's
  window is [−1, 1] × [−1/aspect, 1/aspect]). Row 0 of the
  image is the top; a world point lands on the pixel :func:`reflets.scene.camera.project` gives.
* **Pixels.** ``hdrfilm`` with a ``box`` reconstruction filter: each pixel is the mean radiance over the
  pixel's square (uniform jitter), not the value at its centre. Compare with references averaged over
  sub-pixel positions (e.g. ``pixel_rays(..., offsets=...)``), or on smooth regions only.
* **Meshes.** The world-space triangles of :func:`reflets.scene.geometry.mesh_data` are written to binary
  PLY files (positions, vertex normals, uv) and loaded with ``face_normals = False``, so Mitsuba shades
  with our interpolated normals. Every BSDF is wrapped in ``twosided``: surfaces are shaded on the side
  the camera sees, as in the real-time renderer.
* **Materials.** ``lambert`` → ``diffuse``; ``microfacet`` with ``fresnel`` none / dielectric / conductor,
  separable masking and no diffuse term → ``roughconductor`` (``alpha_u`` along the surface tangent
  ∂p/∂u, ``sample_visible``; fresnel none → ``material = "none"``, F = 1; dielectric → real ``eta``,
  ``k = 0``; ``specular`` above 1 goes through a 1 × 1 raw bitmap). Anything else raises
  :class:`~reflets.errors.SceneError`. Mitsuba takes the tangent from the per-triangle ∂p/∂u of the uv
  (projected onto the shading normal), not from our interpolated vertex tangents: identical on planes,
  slightly different on curved anisotropic surfaces; its Beckmann masking is Walter's rational fit (≤ 0.4 %).
  ``gltf`` → ``principled`` with bitmap textures, ``normalmap`` and an area emitter (docs/reference.md: where
  Disney's BSDF differs from Appendix B, and by how much).
* **Lights.** ``point`` → ``point`` (intensity, W/sr); ``directional`` → ``directional`` (Mitsuba's
  ``direction`` is also the way the light travels); ``quad`` → ``rectangle`` (a two-triangle mesh when
  the parallelogram is not a rectangle: Mitsuba's rectangle must not be sheared) with an ``area``
  emitter on the side of normalize((c2 − c1) × (c4 − c1)); ``polygon`` → a triangle-fan mesh with an
  ``area`` emitter. ``two_sided`` adds a flipped copy 10⁻⁴ × the light's size behind the first, so each
  copy is hit only from its emitting side (coplanar copies would hide each other at random); Mitsuba picks
  among emitters uniformly, so half the light samples of a two-sided light go to the copy facing away
  (unbiased, but several times the variance at equal spp). A quad's ``mask`` becomes the emitter's radiance
  texture: a ``bitmap`` of radiance × mask (EXR in ``workdir``, ``raw``, ``filter_type = "nearest"``, clamped),
  its v = 0 row first (Mitsuba's rectangle and PLY uv), transposed on the flipped copy whose axes are swapped.
  ``environment`` → ``envmap`` from an EXR written in ``workdir`` (the image already multiplied by
  ``scale``), ``to_world`` = rotation by ``rotate_y`` about +y. Light geometry has a black BSDF (it reflects
  nothing) but, like every surface in Mitsuba, it casts shadows: Mitsuba always traces visibility.
* **Environment texels.** Mitsuba's ``envmap`` places texel column k at u = (k + ½)/W (as we do) but row k
  at v = k/(H − 1), while we read the image like a GL texture: bilinear between texel centres
  ((k + ½)/W, (k + ½)/H), wrapping in u, clamped in v. The EXR handed to Mitsuba therefore has 2H + 1 rows
  (texel centres on odd rows, midpoints of neighbours on even rows, the edge rows repeated at the poles),
  with which Mitsuba's bilinear lookup equals ours exactly.
* **Background.** A constant ``background`` colour (not black, no environment light) is what camera rays
  that miss see; it lights nothing. :func:`render_mitsuba` reproduces that exactly: it renders an RGBA
  film and composites ``rgb + (1 − alpha) · background``. :func:`to_mitsuba_dict` can instead add a
  ``constant`` emitter (``background="emitter"``, the default, for a self-contained Mitsuba scene), which
  also *illuminates* the scene — not what the real-time renderer does. With an environment light the
  environment is always what misses see, even when ``background`` is an explicit colour (a limitation).
"""

from __future__ import annotations

import tempfile
from pathlib import Path
from typing import Any

import numpy as np

from ..brdf.gltf import SLOTS as GLTF_SLOTS
from ..errors import ArgumentError, RefletsError, SceneError
from ..scene.geometry import bounding_boxes, camera_range, clip_planes, mesh_data
from ..scene.lightmask import load_mask
from ..scene.model import (
    DirectionalLight,
    EnvironmentLight,
    PointLight,
    PolygonLight,
    QuadLight,
    Scene,
)

#: the Mitsuba variant used (the CPU scalar one runs everywhere the wheel installs)
VARIANT = "scalar_rgb"
#: reconstruction filters accepted by :func:`to_mitsuba_dict`
PIXEL_FILTERS = ("box", "tent", "gaussian")
#: relative offset of the flipped copy of a two-sided area light (times the light's largest edge)
TWO_SIDED_GAP = 1e-4

_SUPPORTED = ("supported: lambert; microfacet with fresnel none/dielectric/conductor, separable masking, diffuse 0; "
              "gltf (metallic-roughness, its textures, normal map, emission) as principled")


class MitsubaUnavailableError(RefletsError):
    """Mitsuba 3 (the optional reference renderer) is not installed or cannot be imported."""


def mitsuba_module():
    """The ``mitsuba`` module with the :data:`VARIANT` variant set (set once, only if it is not already)."""
    try:
        import mitsuba as mi
    except ImportError as exc:
        raise MitsubaUnavailableError(
            f"Mitsuba 3 is not available ({exc}); install the [reference] extra: pip install 'reflets[reference]'"
        ) from None
    if mi.variant() != VARIANT:
        mi.set_variant(VARIANT)
    return mi


# --------------------------------------------------------------------------------------------- helpers


def _rgb(value) -> dict[str, Any]:
    return {"type": "rgb", "value": [float(v) for v in np.broadcast_to(np.asarray(value, dtype=np.float64), (3,))]}


def _rgb_scale(value) -> dict[str, Any]:
    """An RGB factor that may exceed 1: Mitsuba's ``rgb`` texture rejects reflectances above 1, so those go
    through a raw 1 × 1 float bitmap (same value at every uv)."""
    rgb = np.broadcast_to(np.asarray(value, dtype=np.float64), (3,))
    if np.all(rgb <= 1.0):
        return _rgb(rgb)
    mi = mitsuba_module()
    bitmap = mi.Bitmap(np.asarray(rgb, dtype=np.float32).reshape(1, 1, 3))
    return {"type": "bitmap", "bitmap": bitmap, "raw": True, "filter_type": "nearest"}


def _transform(matrix: np.ndarray):
    mi = mitsuba_module()
    return mi.ScalarTransform4f(np.asarray(matrix, dtype=np.float64).tolist())


def look_at_matrix(position, target, up) -> np.ndarray:
    """Mitsuba's camera-to-world look-at: columns left, up, forward (local +z), origin."""
    origin = np.asarray(position, dtype=np.float64)
    forward = np.asarray(target, dtype=np.float64) - origin
    forward /= np.linalg.norm(forward)
    left = np.cross(np.asarray(up, dtype=np.float64), forward)
    left /= np.linalg.norm(left)
    new_up = np.cross(forward, left)
    m = np.eye(4)
    m[:3, 0], m[:3, 1], m[:3, 2], m[:3, 3] = left, new_up, forward, origin
    return m


def write_ply(path: Path, positions: np.ndarray, indices: np.ndarray, normals=None, uvs=None) -> Path:
    """A binary little-endian PLY triangle mesh (float32 vertices, optional normals and uv)."""
    names = (
        ["x", "y", "z"] + (["nx", "ny", "nz"] if normals is not None else []) + (["u", "v"] if uvs is not None else [])
    )
    columns = [positions] + ([normals] if normals is not None else []) + ([uvs] if uvs is not None else [])
    vertex = np.ascontiguousarray(np.concatenate(columns, axis=1), dtype="<f4")
    faces = np.zeros(len(indices), dtype=[("n", "u1"), ("i", "<u4", (3,))])
    faces["n"] = 3
    faces["i"] = indices
    header = (
        "ply\nformat binary_little_endian 1.0\n"
        f"element vertex {len(vertex)}\n"
        + "".join(f"property float {n}\n" for n in names)
        + f"element face {len(faces)}\nproperty list uchar uint vertex_indices\nend_header\n"
    )
    path.write_bytes(header.encode("ascii") + vertex.tobytes() + faces.tobytes())
    return path


def _unsupported(name: str, kind: str, why: str) -> SceneError:
    return SceneError(
        f"material '{name}' (type {kind}): {why}; the Mitsuba bridge does not support it ({_SUPPORTED})",
        field=f"materials.{name}",
    )


def material_to_mitsuba(name: str, material) -> dict[str, Any]:
    """The Mitsuba BSDF dict (wrapped in ``twosided``) of one reflets material, or :class:`SceneError`."""
    kind = getattr(material, "type", type(material).__name__)
    if getattr(material, "orientation", None) is not None:  # Mitsuba's tangents come from the uv, not ours
        raise _unsupported(name, kind, "an orientation field (per-vertex tangents)")
    maps = [*getattr(material, "surface_textures", ()), *(["emission"] if any(getattr(material, "emission", None) or ())
                                                          else [])]  # fmt: skip
    if maps:  # the bridge writes a library material's constant factors only
        raise _unsupported(name, kind, f"maps or emission on a library material ({', '.join(dict.fromkeys(maps))}; "
                           'a glTF material, type = "gltf", takes textures there)')  # fmt: skip
    if kind == "lambert":
        inner = {"type": "diffuse", "reflectance": _rgb(material.albedo)}
    elif kind == "microfacet":
        inner = _microfacet_to_mitsuba(name, material)
    elif kind == "gltf":
        inner = _gltf_to_mitsuba(name, material)
    else:
        raise _unsupported(name, kind, "no matching Mitsuba BSDF")
    return {"type": "twosided", "bsdf": inner}


def _microfacet_to_mitsuba(name: str, material) -> dict[str, Any]:
    distribution = getattr(material, "distribution", "ggx")
    fresnel = getattr(material, "fresnel", "none")
    masking = getattr(material, "masking", "separable")
    diffuse = np.asarray(getattr(material, "diffuse", (0.0, 0.0, 0.0)), dtype=np.float64)
    if distribution not in ("ggx", "beckmann"):
        raise _unsupported(name, "microfacet", f"distribution '{distribution}'")
    if masking != "separable":
        raise _unsupported(name, "microfacet", f"masking '{masking}' (Mitsuba uses the separable Smith form)")
    if np.any(diffuse > 0):
        raise _unsupported(name, "microfacet", "a diffuse term > 0")
    alpha = np.broadcast_to(np.asarray(material.alpha, dtype=np.float64), (2,))
    out: dict[str, Any] = {
        "type": "roughconductor",
        "distribution": distribution,
        "alpha_u": float(alpha[0]),
        "alpha_v": float(alpha[1]),
        "sample_visible": True,
        "specular_reflectance": _rgb_scale(getattr(material, "specular", (1.0, 1.0, 1.0))),
    }
    # ``eta_rgb`` / ``k_rgb`` resolve the class defaults (dielectric 1.5, conductor gold) when eta / k are None
    eta = getattr(material, "eta_rgb", None) or getattr(material, "eta", None)
    k = getattr(material, "k_rgb", None) or getattr(material, "k", None)
    if fresnel == "none":
        out["material"] = "none"
    elif fresnel == "conductor":
        if eta is None or k is None:
            raise _unsupported(name, "microfacet", "a conductor without eta and k")
        out["eta"] = _rgb(eta)
        out["k"] = _rgb(k)
    elif fresnel == "dielectric":
        out["eta"] = _rgb(1.5 if eta is None else eta)
        out["k"] = _rgb(0.0)
    else:
        raise _unsupported(name, "microfacet", f"fresnel '{fresnel}'")
    return out


def _gltf_to_mitsuba(name: str, m) -> dict[str, Any]:
    """glTF's metallic-roughness material as Mitsuba's ``principled`` BSDF (Disney's: its diffuse has Burley's
    retro-reflection where Appendix B has Lambert's — docs/reference.md measures the difference), each factor ×
    its texture as an in-memory bitmap of linear values (bilinear or nearest, the texture's uv transform as
    ``to_uv``), the normal map through ``normalmap``; F₀ = 0.08 × ``specular`` gives the ior's 0.04."""
    refused = [(m.clearcoat > 0, "a clear coat (Disney's coat is not KHR_materials_clearcoat's)"),
               (m.sheened, "a sheen (Disney's is not the Charlie sheen)"),
               (m.anisotropic, "anisotropy"), (m.unlit, "unlit"),
               (m.alpha_mode != "opaque", f"alphaMode {m.alpha_mode.upper()}"),
               (m.specular != 1.0 or tuple(m.specular_color) != (1.0, 1.0, 1.0) or m.specular_texture is not None
                or m.specular_color_texture is not None, "KHR_materials_specular"),
               (m.ior == 0, "ior 0"),
               (m.transmissive, "transmission (KHR_materials_transmission / volume)"),
               (any(getattr(m, f) is not None and getattr(m, f).uv for f in _GLTF_MAPS), "a second uv set"),
               (any(getattr(m, f) is not None for f in _GLTF_OTHER_MAPS), "an extension's texture")]  # fmt: skip
    for found, what in refused:
        if found:
            raise _unsupported(name, "gltf", what)
    base = np.asarray(m.base_color[:3], np.float64)
    out: dict[str, Any] = {"type": "principled", "specular": float(m.dielectric_f0 / 0.08),
                           "base_color": _gltf_map(m, "base_color_texture", base, slice(0, 3), name),
                           "metallic": _gltf_map(m, "metallic_roughness_texture", m.metallic, 2, name),
                           "roughness": _gltf_map(m, "metallic_roughness_texture", m.roughness, 1, name)}  # fmt: skip
    if m.normal_texture is None:
        return out
    data = m.texture_data("normal_texture")
    local = data.texels[..., :3].astype(np.float64) * 2.0 - 1.0
    local[..., :2] *= m.normal_scale
    local /= np.maximum(np.linalg.norm(local, axis=-1, keepdims=True), 1e-12)
    return {"type": "normalmap", "normalmap": _bitmap(m.normal_texture, local * 0.5 + 0.5, name), "bsdf": out}


#: the gltf material's texture fields the bridge reads (an occlusion map is ignored: it occludes environment light
#: only in the real-time renderer, and the references trace the occlusion itself)
_GLTF_MAPS = ("base_color_texture", "metallic_roughness_texture", "normal_texture", "emissive_texture")
#: the extensions' texture fields, refused (the specular ones with their extension, the occlusion map ignored)
_NOT_OTHER = (*_GLTF_MAPS, "occlusion_texture", "specular_texture", "specular_color_texture")
_GLTF_OTHER_MAPS = tuple(field for field, *_ in GLTF_SLOTS if field not in _NOT_OTHER)


def _gltf_map(m, field: str, factor, channel, name: str):
    """A factor × a texture's channel(s) as a Mitsuba texture (the factor alone without a texture)."""
    ref = getattr(m, field)
    if ref is None:
        return _rgb(factor) if np.ndim(factor) else float(factor)
    values = m.texture_data(field).texels[..., channel].astype(np.float64) * factor
    return _bitmap(ref, values, name)


def _bitmap(ref, values: np.ndarray, name: str) -> dict[str, Any]:
    """An in-memory float bitmap of linear values (row 0 at Mitsuba's v = 0: the image's top, as ours) read through
    ``ref``'s uv transform (mesh uv, v up → image uv) with its filter and wrap mode."""
    mi = mitsuba_module()
    if ref.wrap[0] != ref.wrap[1]:
        raise _unsupported(name, "gltf", f"wrap modes {ref.wrap[0]} / {ref.wrap[1]} (Mitsuba's bitmap has one)")
    matrix = np.eye(4)
    uv = ref.uv_matrix()
    matrix[:2, :2], matrix[:2, 3] = uv[:2, :2], uv[:2, 2]
    return {"type": "bitmap", "bitmap": mi.Bitmap(np.ascontiguousarray(values, np.float32)), "raw": True,
            "filter_type": "nearest" if ref.filter == "nearest" else "bilinear",
            "wrap_mode": {"repeat": "repeat", "clamp": "clamp", "mirror": "mirror"}[ref.wrap[0]],
            "to_uv": _transform(matrix)}  # fmt: skip


def material_emitter(name: str, material) -> dict[str, Any] | None:
    """The ``area`` emitter of a glTF material's emission (× its texture), or None. Mitsuba's area emitters emit
    on the front side only, where reflets' renderers emit on both: an open emissive surface seen from behind
    differs (closed meshes do not)."""
    if getattr(material, "type", "") != "gltf":  # (an unlit one is refused with its BSDF)
        return None
    emitted = np.asarray(material.emissive, np.float64) * material.emissive_strength
    if not np.any(emitted > 0):
        return None
    return {"type": "area", "radiance": _gltf_map(material, "emissive_texture", emitted, slice(0, 3), name)}


def _area_emitter(radiance, texture: Path | None = None) -> dict[str, Any]:
    if texture is None:
        return {"type": "area", "radiance": _rgb(radiance)}
    # A masked quad: radiance × mask as a float EXR, looked up like our masks (nearest texel, clamped).
    bitmap = {"type": "bitmap", "filename": str(texture), "raw": True, "filter_type": "nearest", "wrap_mode": "clamp"}
    return {"type": "area", "radiance": bitmap}


def _mask_texture(light: QuadLight, mask: np.ndarray | None, path: Path, transpose: bool = False) -> Path | None:
    """The EXR of radiance × mask for Mitsuba's uv (row 0 at v = 0, as ``load_mask`` stores it: Mitsuba's
    bitmaps put row 0 at uv.y = 0, so the v = 0 row goes first); ``transpose`` swaps u and v."""
    if mask is None:
        return None
    from ..imageio import write_image

    values = mask.T if transpose else mask
    return write_image(path, values[:, :, None] * np.asarray(light.radiance, dtype=np.float32))


#: light geometry reflects nothing (Mitsuba would give a shape without a BSDF a grey diffuse one)
_BLACK = {"type": "diffuse", "reflectance": {"type": "rgb", "value": [0.0, 0.0, 0.0]}}


def _is_rectangle(e1: np.ndarray, e2: np.ndarray) -> bool:
    return abs(float(e1 @ e2)) <= 1e-6 * float(np.linalg.norm(e1) * np.linalg.norm(e2))


def _quad_shapes(
    light: QuadLight, workdir: Path, stem: str, mask: np.ndarray | None = None
) -> dict[str, dict[str, Any]]:
    p = light.polygon()
    e1, e2 = p[1] - p[0], p[3] - p[0]
    normal = np.cross(e1, e2)
    normal /= np.linalg.norm(normal)
    if not _is_rectangle(e1, e2):
        texture = _mask_texture(light, mask, workdir / f"{stem}_mask.exr")
        uvs = np.array([[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0]]) if texture else None
        return _polygon_shapes(p, light.radiance, light.two_sided, workdir, stem, texture, uvs)
    centre = p[0] + 0.5 * (e1 + e2)
    gap = TWO_SIDED_GAP * max(np.linalg.norm(e1), np.linalg.norm(e2))
    shapes = {}
    sides = [(e1, e2, normal, centre)]
    if light.two_sided:  # swapped axes → normal −n, shifted behind the first copy
        sides.append((e2, e1, -normal, centre - gap * normal))
    for k, (a, b, n, c) in enumerate(sides):
        m = np.eye(4)
        m[:3, 0], m[:3, 1], m[:3, 2], m[:3, 3] = 0.5 * a, 0.5 * b, n, c
        texture = _mask_texture(light, mask, workdir / f"{stem}_{k}_mask.exr", transpose=k == 1)
        shapes[f"{stem}_{k}"] = {
            "type": "rectangle",
            "to_world": _transform(m),
            "emitter": _area_emitter(light.radiance, texture),
            "bsdf": dict(_BLACK),
        }
    return shapes


def _polygon_shapes(
    points: np.ndarray, radiance, two_sided: bool, workdir: Path, stem: str, texture: Path | None = None, uvs=None
) -> dict[str, dict]:
    points = np.asarray(points, dtype=np.float64)
    fan = np.array([[0, i, i + 1] for i in range(1, len(points) - 1)], dtype=np.uint32)
    normal = np.sum(np.cross(points, np.roll(points, -1, axis=0)), axis=0)  # Newell: CCW seen from the lit side
    normal /= np.linalg.norm(normal)
    size = float(np.max(np.linalg.norm(np.roll(points, -1, axis=0) - points, axis=1)))
    variants = [(points, fan)]
    if two_sided:
        variants.append((points - TWO_SIDED_GAP * size * normal, fan[:, ::-1]))
    shapes = {}
    for k, (pts, tri) in enumerate(variants):
        path = write_ply(workdir / f"{stem}_{k}.ply", pts.astype(np.float32), tri, uvs=uvs)
        shapes[f"{stem}_{k}"] = {
            "type": "ply",
            "filename": str(path),
            "face_normals": True,
            "emitter": _area_emitter(radiance, texture),
            "bsdf": dict(_BLACK),
        }
    return shapes


def environment_for_mitsuba(image: np.ndarray) -> np.ndarray:
    """The (2H + 1, W, 3) image whose Mitsuba ``envmap`` lookup equals a bilinear lookup of ``image`` between
    texel centres ((k + ½)/W, (k + ½)/H), wrapping in u and clamping in v (see the module docstring)."""
    image = np.asarray(image, dtype=np.float32)
    h = image.shape[0]
    out = np.empty((2 * h + 1,) + image.shape[1:], dtype=np.float32)
    out[1::2] = image
    out[2:-1:2] = 0.5 * (image[:-1] + image[1:])
    out[0], out[-1] = image[0], image[-1]
    return out


def _environment_emitter(scene: Scene, light: EnvironmentLight, workdir: Path) -> dict[str, Any]:
    from ..equirect import rotation_y
    from ..imageio import write_image
    from ..scene.environment import load_environment

    image = load_environment(scene)
    path = write_image(workdir / "environment.exr", environment_for_mitsuba(image))
    m = np.eye(4)
    m[:3, :3] = rotation_y(light.rotate_y)
    return {"type": "envmap", "filename": str(path), "scale": 1.0, "to_world": _transform(m)}


def _scene_point_sets(scene: Scene, meshes: list[np.ndarray]) -> list[np.ndarray]:
    """Each mesh's vertices, each light's position or corners."""
    pts = list(meshes)
    for light in scene.light:
        if isinstance(light, PointLight):
            pts.append(np.asarray([light.position], dtype=np.float64))
        elif isinstance(light, (QuadLight, PolygonLight)):
            pts.append(light.polygon())
    return pts


# ------------------------------------------------------------------------------------------------- API


def to_mitsuba_dict(
    scene: Scene,
    workdir: Path,
    size: tuple[int, int] | None = None,
    spp: int = 64,
    seed: int = 0,
    pixel_filter: str = "box",
    *,
    background: str = "emitter",
) -> dict[str, Any]:
    """The scene as a :func:`mitsuba.load_dict` dict; mesh and environment files are written to ``workdir``.

    Parameters
    ----------
    scene : Scene
    workdir : Path
        An existing folder for the PLY and EXR files the dict refers to (keep it until the scene is loaded).
    size : (width, height), optional
        Image size; the camera's by default.
    spp : int
        Samples per pixel (``independent`` sampler).
    seed : int
        Sampler seed.
    pixel_filter : {"box", "tent", "gaussian"}
        Mitsuba reconstruction filter; ``box`` (the default) averages radiance over each pixel's square.
    background : {"emitter", "alpha", "none"}
        How a non-black constant ``background`` colour (scenes without an environment light) is handled:
        ``"emitter"`` adds a ``constant`` emitter (it also lights the scene); ``"alpha"`` uses an RGBA film
        for compositing afterwards (what :func:`render_mitsuba` does); ``"none"`` ignores it.

    Raises
    ------
    SceneError
        A material the bridge cannot express in Mitsuba (one line naming it).
    ArgumentError
        A bad size, spp, seed, filter or background mode.
    """
    mitsuba_module()  # fail early, with the install hint, when Mitsuba is missing
    width, height = _check_size(size or scene.camera.size)
    if not (isinstance(spp, int | np.integer) and 1 <= spp <= 1 << 20):
        raise ArgumentError(f"spp must be an integer in [1, {1 << 20}], got {spp!r}")
    _check_seed(seed)
    if pixel_filter not in PIXEL_FILTERS:
        raise ArgumentError(f"pixel_filter must be one of {', '.join(PIXEL_FILTERS)}, got {pixel_filter!r}")
    if background not in ("emitter", "alpha", "none"):
        raise ArgumentError(f"background must be 'emitter', 'alpha' or 'none', got {background!r}")
    workdir = Path(workdir)

    # Materials first, so an unsupported one fails before any file is written.
    bsdfs = {
        name: material_to_mitsuba(name, scene.materials[name]) for name in sorted({m.material for m in scene.mesh})
    }
    emitters = {name: material_emitter(name, scene.materials[name]) for name in bsdfs}
    for i, light in enumerate(scene.light):  # before anything is written
        if not getattr(light, "shadows", True):
            raise SceneError(
                "Mitsuba 3 traces every light's shadows; render this scene with the NumPy reference "
                "(reflets reference --engine numpy), which honours shadows = false",
                field=f"light[{i}].shadows",
            )
        if isinstance(light, PointLight) and light.spot is not None:
            raise SceneError("Mitsuba's spot light falls off its own way (not glTF's): the bridge takes isotropic "
                             "point lights", field=f"light[{i}].spot")  # fmt: skip
    cam = scene.camera
    if cam.pixel_aspect != 1.0:
        raise SceneError("Mitsuba 3's cameras have square pixels only", field="camera.pixel_aspect")
    if cam.orthographic and any(cam.principal_offset):
        raise SceneError(
            "Mitsuba 3's orthographic camera has no principal point offset", field="camera.principal_offset"
        )
    workdir.mkdir(parents=True, exist_ok=True)

    out: dict[str, Any] = {"type": "scene", "integrator": {"type": "direct", "hide_emitters": False}}
    positions = []
    for i, mesh in enumerate(scene.mesh):
        data = mesh_data(scene, i)
        positions.append(data.positions.astype(np.float64))
        path = write_ply(workdir / f"mesh_{i}.ply", data.positions, data.indices, data.normals, data.uvs)
        out[f"mesh_{i}"] = {"type": "ply", "filename": str(path), "face_normals": False, "bsdf": bsdfs[mesh.material]}
        if emitters[mesh.material] is not None:
            out[f"mesh_{i}"]["emitter"] = emitters[mesh.material]

    for i, light in enumerate(scene.light):
        if isinstance(light, PointLight):
            out[f"light_{i}"] = {"type": "point", "position": list(light.position), "intensity": _rgb(light.intensity)}
        elif isinstance(light, DirectionalLight):
            out[f"light_{i}"] = {
                "type": "directional",
                "direction": list(light.direction),
                "irradiance": _rgb(light.irradiance),
            }
        elif isinstance(light, QuadLight):
            out.update(_quad_shapes(light, workdir, f"light_{i}", load_mask(scene, i)))
        elif isinstance(light, PolygonLight):
            out.update(_polygon_shapes(light.polygon(), light.radiance, light.two_sided, workdir, f"light_{i}"))
        elif isinstance(light, EnvironmentLight):
            out[f"light_{i}"] = _environment_emitter(scene, light, workdir)

    color = scene.background_color()
    alpha = False
    if scene.environment is None and color is not None and any(c > 0 for c in color):
        if background == "emitter":
            out["background"] = {"type": "constant", "radiance": _rgb(color)}
        alpha = background == "alpha"

    point_sets = _scene_point_sets(scene, positions)
    near, far = camera_range(cam, bounding_boxes(point_sets))  # the real-time camera's near plane (and far)
    if far is None:  # none: beyond every point
        points = np.concatenate(point_sets) if point_sets else np.zeros((0, 3))
        _, extent = clip_planes(np.asarray(cam.position, dtype=np.float64), points)
        far = max(2.0 * extent, 10.0 * near)
    to_world = look_at_matrix(cam.position, cam.look_at, cam.up)
    if cam.orthographic:
        # Mitsuba's orthographic view window is x in [-1, 1], y in [-1/aspect, 1/aspect] in camera space: scaled
        # by ortho_height * aspect / 2 it is ortho_height high, with square pixels
        scale = float(cam.ortho_height) * width / height / 2.0
        near = max(near, 1e-6 * far)  # Mitsuba asks for a positive near plane
        projection = {"type": "orthographic", "to_world": _transform(to_world @ np.diag([scale, scale, 1.0, 1.0]))}
    else:
        projection = {
            "type": "perspective",
            "fov": float(cam.fov_y),
            "fov_axis": "y",
            "to_world": _transform(to_world),
            # Mitsuba moves the principal point the other way (measured: tests/scene/test_camera_intrinsics.py)
            "principal_point_offset_x": -float(cam.principal_offset[0]),
            "principal_point_offset_y": -float(cam.principal_offset[1]),
        }
    out["sensor"] = {
        **projection,
        "near_clip": float(near),
        "far_clip": float(far),
        "film": {
            "type": "hdrfilm",
            "width": width,
            "height": height,
            "rfilter": {"type": pixel_filter},
            "pixel_format": "rgba" if alpha else "rgb",
            "component_format": "float32",
        },
        "sampler": {"type": "independent", "sample_count": int(spp), "seed": int(seed)},
    }
    return out


def _check_seed(seed) -> None:
    """Mitsuba's seeds are 32-bit unsigned integers."""
    if not (isinstance(seed, int | np.integer) and 0 <= seed < 1 << 32):
        raise ArgumentError(f"seed must be an integer in [0, 2^32), got {seed!r}")


def _check_size(size) -> tuple[int, int]:
    try:
        width, height = (int(v) for v in size)
    except (TypeError, ValueError):
        raise ArgumentError(f"size must be (width, height), got {size!r}") from None
    if not (1 <= width <= 16384 and 1 <= height <= 16384):
        raise ArgumentError(f"size must be (width, height) with each in [1, 16384], got {size!r}")
    return width, height


#: the film is rendered in crop windows of at most this many pixels a side (reflets.reference.parallel's tasks)
MITSUBA_TILE = 128


def mitsuba_tiles(width: int, height: int, seed: int) -> list[tuple[tuple[int, int, int, int], int]]:
    """The crop windows (x, y, w, h) of a film and each one's seed — from the size and the seed alone, so that the
    image does not depend on where the tiles are rendered. One tile: the seed itself (the whole-film render of
    before); several: each its own seed (SeedSequence of (seed, tile)), so that no two tiles share a pattern."""
    windows = [(x, y, min(MITSUBA_TILE, width - x), min(MITSUBA_TILE, height - y))
               for y in range(0, height, MITSUBA_TILE) for x in range(0, width, MITSUBA_TILE)]  # fmt: skip
    if len(windows) == 1:
        return [(windows[0], int(seed))]
    return [(w, int(np.random.SeedSequence([int(seed), i]).generate_state(1)[0])) for i, w in enumerate(windows)]


class MitsubaTiles:
    """A scene loaded into Mitsuba once per process; its tasks render crop windows of the film."""

    def __init__(self, scene: Scene, size, spp: int, seed: int):
        mi = mitsuba_module()
        self._files = tempfile.TemporaryDirectory(prefix="reflets-mitsuba-")  # the PLY / EXR files the scene reads
        spec = to_mitsuba_dict(scene, Path(self._files.name), size=size, spp=spp, seed=seed, background="alpha")
        self.sensor = spec["sensor"]
        self.scene = mi.load_dict(spec)
        self.spp = int(spp)
        self.background = np.asarray(scene.background_color() or (0.0, 0.0, 0.0), dtype=np.float32)

    def task(self, task, advance) -> np.ndarray:
        """One crop window ((x, y, w, h), seed) → its (h, w, 3) pixels, the background composited."""
        (x, y, w, h), seed = task
        mi = mitsuba_module()
        film = {**self.sensor["film"], "crop_offset_x": x, "crop_offset_y": y, "crop_width": w, "crop_height": h}
        sensor = mi.load_dict({**self.sensor, "film": film, "sampler": {**self.sensor["sampler"], "seed": seed}})
        image = np.array(mi.render(self.scene, sensor=sensor, spp=self.spp, seed=seed), dtype=np.float32)
        if image.shape[-1] == 4:
            image = image[..., :3] + (1.0 - image[..., 3:4]) * self.background
        advance(1)
        return np.ascontiguousarray(image[..., :3])


def render_mitsuba(scene: Scene, spp: int = 64, seed: int = 0, size: tuple[int, int] | None = None,
                   cluster=None) -> np.ndarray:  # fmt: skip
    """Render ``scene`` with Mitsuba 3 (``direct`` integrator, box pixel filter): float32 (H, W, 3), row 0 top.

    A constant background colour is composited through the film's alpha (it is seen, it does not light). The film
    is rendered in crop windows (:func:`mitsuba_tiles`) — in this process (Mitsuba's own threads take every core),
    or on the workers of the Dask cluster ``cluster`` (or of an enclosing reflets.reference.parallel.using block):
    the same image either way.
    Raises :class:`MitsubaUnavailableError` without Mitsuba, :class:`SceneError` for unsupported materials.
    """
    from .parallel import default_cluster, places

    width, height = _check_size(size or scene.camera.size)
    _check_seed(seed)
    tasks = mitsuba_tiles(width, height, seed)
    image = np.zeros((height, width, 3), np.float32)
    cluster = default_cluster() if cluster is None else cluster  # `reflets bench --cluster`: its references there
    place = places(1 if cluster is None else None, cluster)
    try:
        with place.start(MitsubaTiles, (scene, (width, height), spp, seed)) as tiles:
            for index, tile in tiles.run(tasks, [1] * len(tasks), lambda k: None):
                x, y, w, h = tasks[index][0]
                image[y : y + h, x : x + w] = tile
    finally:
        place.close()
    return image
