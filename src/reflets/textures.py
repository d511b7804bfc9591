"""Textures of materials: the scene-file reference, decoding by role, mip chains, GPU upload, NumPy lookups.

A material parameter read from an image (a glTF texture, an MTL map, ``{ texture = "wood.png" }`` in a scene)
is a :class:`TextureRef`. What the pixels mean decides how they are decoded, not the file: colour (base colour,
emission) is sRGB-encoded and linearised, data (metallic-roughness, normals, occlusion) is used as stored.

Both renderers read the same decoded texels:

- the GPU gets ``SRGB8_ALPHA8`` for colour (the sampler linearises before filtering), float16 for normal maps
  (8-bit mips and filtering would tilt a normal by up to 1/255 and blur the Toksvig lengths) and 8-bit codes for
  other data (roughness, metalness, occlusion: their files' own precision; float16 cost the helmet 7 % of its
  frame on llvmpipe, measured by hand with ``reflets bench assets`` before the change), with a full mip chain built
  here in linear float (a box filter; the driver's own mipmap generation is not guaranteed gamma-correct for sRGB
  formats), trilinear and 16× anisotropic filtering, and
  the wrap modes of the file's sampler; one texture per content and role, shared by every object and renderer
  of a GL context (``texture_for``);
- the NumPy reference samples level 0 bilinearly with the same wrap modes (``TextureData.sample``): a
  supersampled reference pixel averages such lookups over the pixel's footprint, which is what the GPU's mip
  filtering approximates.

uv convention: a mesh's uv has v up (OpenGL, OBJ); image row 0 is the top. A lookup at mesh uv ``(u, v)`` reads
the image at ``(u, 1 − v)`` from its top-left corner — glTF's uv, where KHR_texture_transform applies.
"""

from __future__ import annotations

import hashlib
import io
import math
import threading
from collections import OrderedDict
from dataclasses import dataclass
from pathlib import Path
from typing import Annotated, Literal

import numpy as np
from pydantic import BaseModel, ConfigDict, Field

from .errors import SceneError
from .imageio import linear_to_srgb, srgb_to_linear

Wrap = Literal["repeat", "clamp", "mirror"]
FiniteFloat = Annotated[float, Field(allow_inf_nan=False, ge=-1e6, le=1e6)]


class TextureTransform(BaseModel):
    """KHR_texture_transform: uv' = T(offset) · R(rotation) · S(scale) · uv, in the image's uv (origin top-left,
    v down); ``rotation`` in radians, counter-clockwise in that space as the extension defines it."""

    model_config = ConfigDict(extra="forbid")
    offset: tuple[FiniteFloat, FiniteFloat] = (0.0, 0.0)
    rotation: FiniteFloat = 0.0
    scale: tuple[FiniteFloat, FiniteFloat] = (1.0, 1.0)

    def matrix(self) -> np.ndarray:
        """3×3 matrix acting on (u, v, 1) in image uv (the extension's own formula)."""
        c, s = math.cos(self.rotation), math.sin(self.rotation)
        translation = np.array([[1, 0, self.offset[0]], [0, 1, self.offset[1]], [0, 0, 1]], float)
        rotation = np.array([[c, s, 0], [-s, c, 0], [0, 0, 1]], float)
        scale = np.diag([self.scale[0], self.scale[1], 1.0])
        return translation @ rotation @ scale


class TextureRef(BaseModel):
    """An image read by a material parameter.

    ``texture``: an image file (PNG, JPEG…; relative to the scene file), or a glTF file with ``image`` = the index
    of one of its images (embedded or not); ``uv``: the uv set; ``srgb``: how colour is encoded (None: by the
    parameter's role — colour sRGB, data linear); ``transform``: KHR_texture_transform; ``wrap``: (s, t) wrap
    modes; ``filter``: "linear" (trilinear mips, anisotropic) or "nearest"; ``channels``: a swizzle applied when
    decoding (an MTL map's ``-imfchan``: one grey map feeding one channel of a packed slot)."""

    model_config = ConfigDict(extra="forbid")
    texture: Path
    image: int | None = Field(None, ge=0, description="the image index inside a glTF file")
    uv: int = Field(0, ge=0, le=1, description="the uv set (TEXCOORD_n)")
    srgb: bool | None = Field(None, description="sRGB-encoded colour (None: by the parameter's role)")
    transform: TextureTransform | None = None
    wrap: tuple[Wrap, Wrap] = ("repeat", "repeat")
    filter: Literal["linear", "nearest"] = "linear"
    channels: str | None = Field(
        None,
        pattern="^[rgba01]{4}$",
        description="which image channel (r, g, b, a) or constant (0, 1) each of the parameter's R, G, B, A reads, "
        'e.g. "1r11" puts a grey roughness map where metallic-roughness reads roughness (G); None: as stored',
    )

    def uv_matrix(self) -> np.ndarray:
        """3×3 matrix from mesh uv (v up) to image uv (v down, transform applied)."""
        flip = np.array([[1.0, 0.0, 0.0], [0.0, -1.0, 1.0], [0.0, 0.0, 1.0]])
        return (self.transform.matrix() if self.transform is not None else np.eye(3)) @ flip

    def uv_uniform(self) -> bytes:
        """:meth:`uv_matrix` as a GLSL mat3 uniform's bytes (float32, column-major)."""
        return self.uv_matrix().T.astype(np.float32).tobytes()


#: bytes of decoded textures kept in memory (a 2048² map holds 16 MB of codes and 64 MB of float texels), least
#: recently used out
TEXTURE_CACHE_BYTES = 512 * 2**20
_DECODED: OrderedDict[str, TextureData] = OrderedDict()
_LOCK = threading.Lock()


@dataclass
class TextureData:
    """A decoded texture: ``codes`` (H, W, 4) uint8 as stored (row 0 = top), ``srgb`` whether colour is
    sRGB-encoded, ``key`` its content hash; ``texels`` the linear float32 values both renderers read."""

    codes: np.ndarray
    srgb: bool
    key: str
    wrap: tuple[str, str] = ("repeat", "repeat")
    nearest: bool = False

    def __post_init__(self):
        values = self.codes.astype(np.float32) / 255.0
        if self.srgb:
            values[..., :3] = srgb_to_linear(values[..., :3])
        self.texels = values

    @property
    def nbytes(self) -> int:
        return int(self.codes.nbytes + self.texels.nbytes)

    @property
    def size(self) -> tuple[int, int]:
        return self.codes.shape[1], self.codes.shape[0]

    def sample(self, uv: np.ndarray) -> np.ndarray:
        """Bilinear (or nearest) lookups at image uv (N, 2) (origin top-left), with the wrap modes: (N, 4)."""
        h, w = self.codes.shape[:2]
        x = np.asarray(uv[:, 0], np.float64) * w - 0.5
        y = np.asarray(uv[:, 1], np.float64) * h - 0.5
        if self.nearest:
            xi = _wrap(np.floor(x + 0.5).astype(np.int64), w, self.wrap[0])
            yi = _wrap(np.floor(y + 0.5).astype(np.int64), h, self.wrap[1])
            return self.texels[yi, xi].astype(np.float64)
        x0, y0 = np.floor(x), np.floor(y)
        fx, fy = (x - x0)[:, None], (y - y0)[:, None]
        x0, y0 = x0.astype(np.int64), y0.astype(np.int64)
        xa, xb = _wrap(x0, w, self.wrap[0]), _wrap(x0 + 1, w, self.wrap[0])
        ya, yb = _wrap(y0, h, self.wrap[1]), _wrap(y0 + 1, h, self.wrap[1])
        t = self.texels
        top = t[ya, xa] * (1 - fx) + t[ya, xb] * fx
        bottom = t[yb, xa] * (1 - fx) + t[yb, xb] * fx
        return (top * (1 - fy) + bottom * fy).astype(np.float64)

    def mip_chain(self, normal_map: bool = False) -> list[np.ndarray]:
        """The GPU's levels down to 1×1, each the box mean of the one above in linear values (2×2 texels; an odd
        side's last three rows / columns merge into one): colour re-encoded as sRGB uint8 (h, w, 4), other data
        as uint8 codes, a normal map as float16 (neither the mips nor the sampler's bilinear weights quantise a
        normal to 8 bits).

        ``normal_map``: the level-0 vectors (2 c − 1) are made unit first, so that a level's mean vector is
        shorter than 1 by how much the normals under it vary (Toksvig 2005: the GLSL widens the lobe by it)."""
        linear = self.texels
        if normal_map:
            vectors = linear[..., :3] * 2.0 - 1.0
            length = np.linalg.norm(vectors, axis=-1, keepdims=True)
            flat = np.array([0.0, 0.0, 1.0], np.float32)
            unit = np.where(length > 1e-6, vectors / np.maximum(length, 1e-6), flat)
            linear = np.concatenate([unit * 0.5 + 0.5, linear[..., 3:]], axis=-1)
        levels = [linear.astype(np.float16) if normal_map else self.codes]
        while linear.shape[0] > 1 or linear.shape[1] > 1:
            linear = _halve(_halve(linear, 0), 1)
            if normal_map:
                levels.append(linear.astype(np.float16))
                continue
            encoded = linear.copy()
            if self.srgb:
                encoded[..., :3] = linear_to_srgb(np.clip(encoded[..., :3], 0.0, 1.0))
            levels.append(np.clip(np.rint(encoded * 255.0), 0, 255).astype(np.uint8))
        return levels

    def gpu_bytes(self, normal_map: bool = False) -> int:
        """Bytes of the GPU texture with its mips (4 bytes a texel, 8 for a float16 normal map; 4/3 for the
        chain)."""
        return int(self.codes.shape[0] * self.codes.shape[1] * (8 if normal_map else 4) * 4 / 3)


def _wrap(i: np.ndarray, n: int, mode: str) -> np.ndarray:
    if mode == "clamp":
        return np.clip(i, 0, n - 1)
    if mode == "mirror":
        period = np.mod(i, 2 * n)
        return np.where(period < n, period, 2 * n - 1 - period)
    return np.mod(i, n)


def _halve(a: np.ndarray, axis: int) -> np.ndarray:
    """Half as many rows (axis 0) or columns (axis 1), each the mean of two; an odd count's last three merge into
    one (weights ⅓); a single one stays."""
    n = a.shape[axis]
    if n == 1:
        return a
    a = np.moveaxis(a, axis, 0)
    out = a[0 : n - 1 : 2] * 0.5 + a[1:n:2] * 0.5
    if n % 2:
        out[-1] = (a[n - 3] + a[n - 2] + a[n - 1]) / 3.0
    return np.moveaxis(out, 0, axis)


#: how many pixels an image may have (Pillow's own bomb limit is 89 M; a material map is rarely over 8192²)
MAX_TEXTURE_PIXELS = 8192 * 8192


def decode_image_bytes(data: bytes, what: str) -> np.ndarray:
    """(H, W, 4) uint8 RGBA of an image file's bytes (grey, grey + alpha, palette, RGB and RGBA widened; 16-bit
    channels rounded to 8), or a SceneError naming ``what``."""
    from PIL import Image

    try:
        with Image.open(io.BytesIO(data)) as image:
            if image.width * image.height > MAX_TEXTURE_PIXELS:
                raise SceneError(f"{what}: {image.width}x{image.height} texture, over {MAX_TEXTURE_PIXELS:,} pixels")
            if image.mode in ("I;16", "I;16B", "I", "F"):
                grey = np.asarray(image, dtype=np.float64)
                scale = 65535.0 if grey.max() > 255 else 255.0
                codes = np.clip(np.rint(grey / scale * 255.0), 0, 255).astype(np.uint8)
                return np.dstack([codes, codes, codes, np.full_like(codes, 255)])
            return np.asarray(image.convert("RGBA"), dtype=np.uint8).copy()
    except SceneError:
        raise
    except Image.UnidentifiedImageError:
        raise SceneError(f"{what}: not an image Pillow reads (PNG, JPEG, WebP…)") from None
    except Exception as exc:  # Pillow raises many types for damaged data
        raise SceneError(f"{what}: cannot decode the image ({type(exc).__name__}: {exc})") from None


def swizzled(codes: np.ndarray, channels: str | None) -> np.ndarray:
    """(H, W, 4) codes rearranged by a ``TextureRef.channels`` string (the same array when None)."""
    if channels is None or channels == "rgba":
        return codes
    constants = {"0": 0, "1": 255}
    planes = [codes[..., "rgba".index(c)] if c in "rgba" else np.full(codes.shape[:2], constants[c], np.uint8)
              for c in channels]  # fmt: skip
    return np.ascontiguousarray(np.stack(planes, axis=-1))


def texture_data(codes_source, key_source: bytes, srgb: bool, wrap=("repeat", "repeat"), nearest=False,
                 channels: str | None = None) -> TextureData:  # fmt: skip
    """The decoded texture of some image bytes (``codes_source()`` decodes them), cached by content and role."""
    key = hashlib.sha1(key_source + repr((srgb, tuple(wrap), nearest, channels)).encode()).hexdigest()
    with _LOCK:
        if key in _DECODED:
            _DECODED.move_to_end(key)
            return _DECODED[key]
    data = TextureData(swizzled(codes_source(), channels), srgb, key, tuple(wrap), nearest)
    data.codes.flags.writeable = False
    data.texels.flags.writeable = False
    with _LOCK:
        _DECODED[key] = data
        while sum(d.nbytes for d in _DECODED.values()) > TEXTURE_CACHE_BYTES and len(_DECODED) > 1:
            _DECODED.popitem(last=False)
    return data


#: (file, image, size, mtime, decoding) → its decoded texture: a file loaded again (every scene validation: a
#: viewer's camera move) is neither read nor hashed again while it is unchanged on disk
_BY_FILE: dict[tuple, TextureData] = {}


def load_texture(ref: TextureRef, role_srgb: bool) -> TextureData:
    """The texels of ``ref`` (its path absolute: the scene loader makes it so), decoded for its role."""
    srgb = role_srgb if ref.srgb is None else ref.srgb
    path = Path(ref.texture)
    try:
        stat = path.stat()
    except OSError as exc:
        raise SceneError(f"cannot read the texture ({exc.strerror or type(exc).__name__})", file=path) from None
    file_key = (str(path), ref.image, stat.st_size, stat.st_mtime_ns, srgb, tuple(ref.wrap), ref.filter, ref.channels)
    if ref.image is not None:  # inside a glTF file, maybe in a .bin or image file it names: their stamps too
        from .gltf_file import read_gltf

        file_key += read_gltf(path).stamp
    with _LOCK:
        known = _BY_FILE.get(file_key)
        if known is not None and known.key in _DECODED:
            _DECODED.move_to_end(known.key)
            return known
    data, what = texture_bytes(ref)
    decode = lambda: decode_image_bytes(data, what)  # noqa: E731
    decoded = texture_data(decode, data, srgb, ref.wrap, ref.filter == "nearest", ref.channels)
    with _LOCK:
        _BY_FILE[file_key] = decoded
        for key in [k for k, v in _BY_FILE.items() if v.key not in _DECODED]:  # evicted: forget its file too
            del _BY_FILE[key]
    return decoded


def texture_refs(material) -> dict[str, TextureRef]:
    """A material's textures by field: its ``*_texture`` fields (glTF's, a translucent albedo map) and its mapped
    colours (``maps.albedo``: ``brdf.maps``)."""
    refs = {key: getattr(material, key) for key in type(material).model_fields}
    refs = {key: ref for key, ref in refs.items() if isinstance(ref, TextureRef)}
    return {**refs, **{f"maps.{key}": ref for key, ref in (getattr(material, "maps", None) or {}).items()}}


def lookup(ref: TextureRef, data: TextureData, uv: np.ndarray, field: str) -> np.ndarray:
    """(N, 4) texels of ``data`` (``ref`` decoded) at mesh uv: (N, 4) both uv sets (``MeshData.uv_sets``), or (N, 2)
    the first alone; ``field`` names the parameter in the error for a missing second set."""
    if uv.shape[-1] == 2 and ref.uv:
        raise ValueError(f"{field} reads uv set {ref.uv}: pass both uv sets, (N, 4)")
    uv = uv[:, 2 * ref.uv : 2 * ref.uv + 2]
    m = ref.uv_matrix()
    return data.sample(uv @ m[:2, :2].T + m[:2, 2])


def texture_bytes(ref: TextureRef) -> tuple[bytes, str]:
    """The encoded image (PNG, JPEG…) ``ref`` names — a file, or an image inside a glTF file — and how to name it
    in a message; a SceneError when it cannot be read."""
    path = Path(ref.texture)
    if ref.image is not None:
        from .gltf_file import read_gltf  # an image inside a glTF file

        return read_gltf(path).image_bytes(ref.image), f"{path}: images[{ref.image}]"
    try:
        return path.read_bytes(), str(path)
    except OSError as exc:
        raise SceneError(f"cannot read the texture ({exc.strerror or type(exc).__name__})", file=path) from None


SRGB8_ALPHA8 = 0x8C43


def texture_for(ctx, data: TextureData, normal_map: bool = False):
    """The GL texture of ``data`` in ``ctx`` (uploaded once per context; its memory checked first); a normal map's
    mips from unit vectors (:meth:`TextureData.mip_chain`)."""
    import moderngl

    from .gpu import depth
    from .gpu.context import context_store
    from .resources import check

    store = context_store(ctx, "material_textures")
    key = data.key + (":normal" if normal_map else "")
    texture = store.get(key)
    if texture is not None:
        return texture
    kind = "float16 normal" if normal_map else "sRGB8 colour" if data.srgb else "8-bit data"
    check("texture", data.gpu_bytes(normal_map), value=f"{data.size[0]}x{data.size[1]}",
          what=f"{kind} texels and their mips")  # fmt: skip
    levels = data.mip_chain(normal_map)
    w, h = data.size
    if normal_map:
        texture = ctx.texture((w, h), 4, levels[0].tobytes(), dtype="f2")
    elif data.srgb:
        texture = ctx.texture((w, h), 4, levels[0].tobytes(), internal_format=SRGB8_ALPHA8)
    else:
        texture = ctx.texture((w, h), 4, levels[0].tobytes())
    texture.build_mipmaps(0, len(levels) - 1)  # allocates the chain; the levels are written next
    for level, codes in enumerate(levels[1:], start=1):
        texture.write(codes.tobytes(), level=level)
    if data.nearest:
        texture.filter = (moderngl.NEAREST_MIPMAP_NEAREST, moderngl.NEAREST)
    else:
        texture.filter = (moderngl.LINEAR_MIPMAP_LINEAR, moderngl.LINEAR)
        texture.anisotropy = 16.0  # the renderer's texture_anisotropy sets it when it draws
    depth.texture_wrap(ctx, texture, data.wrap)
    store[key] = texture
    return texture
