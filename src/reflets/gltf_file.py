"""Reading glTF 2.0 files (.gltf + buffers, .glb): the default scene's node tree, primitives, images, cameras, lights.

pygltflib parses the JSON (and a .glb's chunks); the data behind it are read here, by the specification's rules,
so that nothing a file holds is dropped without a word:

- accessors of every component type, ``normalized`` integers mapped to [0, 1] / [−1, 1] (KHR_mesh_quantization's
  positions, normals, tangents and uvs stored as bytes or shorts come out the same way), interleaved buffer views
  (``byteStride``), sparse accessors (the listed elements replaced), accessors without a buffer view (zeros);
- KHR_draco_mesh_compression through DracoPy (Google's Draco decoder);
- buffers and images embedded in a .glb, as data URIs, or as files beside the .gltf (percent-encoded names);
- node transforms as matrix or TRS, composed down the default scene's hierarchy (``scene`` or the first one);
- triangle lists, strips and fans; points and lines are skipped with a warning.

What the data mean for a renderer (materials, camera fields, light units) is the scene package's business
(``reflets.scene.assets``); this module only reads. Every problem is a :class:`~reflets.errors.SceneError`
naming the file and the glTF field (``meshes[2].primitives[0].attributes.POSITION``).
"""

from __future__ import annotations

import base64
import functools
import threading
import urllib.parse
import warnings
from collections import OrderedDict
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from .errors import SceneError

#: component types (glTF's enum) → NumPy dtype, and the divisor of a normalised integer (the spec's formulas)
COMPONENTS = {
    5120: (np.int8, 127.0),
    5121: (np.uint8, 255.0),
    5122: (np.int16, 32767.0),
    5123: (np.uint16, 65535.0),
    5125: (np.uint32, None),
    5126: (np.float32, None),
}
WIDTHS = {"SCALAR": 1, "VEC2": 2, "VEC3": 3, "VEC4": 4, "MAT2": 4, "MAT3": 9, "MAT4": 16}
#: the extensions whose data this reader decodes; the material and light extensions are read by scene.assets
DECODED = {"KHR_draco_mesh_compression", "KHR_mesh_quantization", "KHR_texture_transform"}
TRIANGLES, TRIANGLE_STRIP, TRIANGLE_FAN = 4, 5, 6
#: the largest magnitude of a node transform's number (reflets' scene numbers are bounded alike: quantities.py)
MAX_NUMBER = 1e12


@dataclass
class Primitive:
    """One primitive's vertex data in the mesh's own coordinates (float64; None where the file has none)."""

    positions: np.ndarray
    indices: np.ndarray  # (M, 3) int64 triangles
    normals: np.ndarray | None = None
    tangents: np.ndarray | None = None  # (N, 4), w the handedness
    uvs: list[np.ndarray | None] = field(default_factory=lambda: [None, None])  # TEXCOORD_0, _1 in glTF uv (v down)
    material: int | None = None


@dataclass
class Instance:
    """A primitive placed by a node: ``matrix`` maps the mesh's coordinates to the file's world."""

    node: int
    mesh: int
    primitive: int
    matrix: np.ndarray
    name: str


class GltfFile:
    """A parsed glTF file (see the module docstring); made by :func:`read_gltf`, shared read-only."""

    def __init__(self, path: Path):
        import pygltflib

        self.path = path
        self.warnings: list[str] = []
        try:
            with warnings.catch_warnings():  # its own warnings about damaged files: the error below says it
                warnings.simplefilter("ignore")
                self.doc = pygltflib.GLTF2().load(str(path))
        except Exception as exc:  # pygltflib raises JSON, struct, key and type errors for damaged files
            reason = (str(exc).strip().splitlines() or [type(exc).__name__])[0][:200]
            raise SceneError(f"cannot read glTF: {reason}", file=path) from None
        if self.doc is None:
            raise SceneError("cannot read glTF: not a glTF or GLB file", file=path)
        version = str(getattr(self.doc.asset, "version", "") or "")
        if not version.startswith("2."):
            raise SceneError(f"glTF version {version or '(none)'}; reflets reads glTF 2.x", file=path)
        required = set(self.doc.extensionsRequired or [])
        known = DECODED | {"KHR_materials_emissive_strength", "KHR_lights_punctual", "KHR_materials_unlit"}
        unknown = sorted(required - known)
        if unknown:
            raise SceneError(f"extensionsRequired: {', '.join(unknown)} not supported by reflets", file=path)
        self._buffers: dict[int, bytes] = {}
        self._lock = threading.Lock()
        self.stamp: tuple = ()  # external_stamp() when read (read_gltf)

    # ------------------------------------------------------------------------------------------ raw data

    def buffer(self, index: int) -> bytes:
        with self._lock:
            if index not in self._buffers:
                self._buffers[index] = self._read_buffer(index)
            return self._buffers[index]

    def _read_buffer(self, index: int) -> bytes:
        buffers = self.doc.buffers or []
        if not 0 <= index < len(buffers):
            raise SceneError(f"buffers[{index}] does not exist", file=self.path)
        uri = buffers[index].uri
        if uri is None:
            blob = self.doc.binary_blob()
            if blob is None:
                raise SceneError(f"buffers[{index}] has no uri and the file no binary chunk", file=self.path)
            return bytes(blob)
        return self._read_uri(uri, f"buffers[{index}].uri")

    def external_stamp(self) -> tuple:
        """(path, size, modification time) of every file the document's buffers and images name by uri (None for
        one missing): read_gltf's cache and the textures' see an edited .bin or image file by it."""
        stamp = []
        for target in self.external_files():
            try:
                stat = target.stat()
                stamp.append((str(target), stat.st_size, stat.st_mtime_ns))
            except OSError:
                stamp.append((str(target), None, None))
        return tuple(stamp)

    def external_files(self, images: bool = True) -> list[Path]:
        """The files the document's buffers (and ``images``) name by uri (not data: URIs), resolved."""
        items = (*(self.doc.buffers or []), *((self.doc.images or []) if images else ()))
        uris = [item.uri for item in items if item.uri]
        return [self._uri_path(uri) for uri in uris if not uri.startswith("data:")]

    def _uri_path(self, uri: str) -> Path:
        return self.path.parent / urllib.parse.unquote(uri)

    def _read_uri(self, uri: str, where: str) -> bytes:
        if uri.startswith("data:"):
            try:
                return base64.b64decode(uri.split(",", 1)[1], validate=True)
            except (IndexError, ValueError):
                raise SceneError(f"{where}: invalid data URI", file=self.path) from None
        target = self._uri_path(uri)
        try:
            return target.read_bytes()
        except OSError as exc:
            raise SceneError(f"{where}: cannot read {target} ({exc.strerror or type(exc).__name__})",
                             file=self.path) from None  # fmt: skip

    def buffer_view(self, index: int, where: str) -> tuple[bytes, int, int | None]:
        """(the buffer's bytes, the view's offset, its stride or None) of bufferViews[index]."""
        views = self.doc.bufferViews or []
        if not 0 <= index < len(views):
            raise SceneError(f"{where}: bufferViews[{index}] does not exist", file=self.path)
        view = views[index]
        data = self.buffer(view.buffer)
        offset = view.byteOffset or 0
        if offset + view.byteLength > len(data):
            raise SceneError(f"{where}: bufferViews[{index}] runs past the end of its buffer", file=self.path)
        return data[: offset + view.byteLength], offset, view.byteStride

    def accessor(self, index: int, where: str) -> np.ndarray:
        """accessors[index] as float64 (or int64 for unnormalised integers), shape (count, width)."""
        accessors = self.doc.accessors or []
        if not 0 <= index < len(accessors):
            raise SceneError(f"{where}: accessors[{index}] does not exist", file=self.path)
        acc = accessors[index]
        where = f"{where} (accessors[{index}])"
        if acc.componentType not in COMPONENTS or acc.type not in WIDTHS:
            raise SceneError(f"{where}: unknown componentType {acc.componentType} / type {acc.type}", file=self.path)
        dtype, divisor = COMPONENTS[acc.componentType]
        width = WIDTHS[acc.type]
        out = self._dense(acc, dtype, width, where)
        if acc.sparse is not None:
            out = out.copy()
            sparse = acc.sparse
            idx_type = COMPONENTS.get(sparse.indices.componentType, (None,))[0]
            if idx_type is None:
                raise SceneError(f"{where}: sparse indices of componentType {sparse.indices.componentType}",
                                 file=self.path)  # fmt: skip
            ids = self._read(sparse.indices.bufferView, sparse.indices.byteOffset or 0, idx_type, 1, sparse.count,
                             where + ".sparse.indices").ravel().astype(np.int64)  # fmt: skip
            values = self._read(sparse.values.bufferView, sparse.values.byteOffset or 0, dtype, width, sparse.count,
                                where + ".sparse.values")  # fmt: skip
            if ids.size and (ids.min() < 0 or ids.max() >= acc.count):
                raise SceneError(f"{where}: sparse index out of range", file=self.path)
            out[ids] = values
        if acc.normalized and divisor is not None:
            return np.maximum(out.astype(np.float64) / divisor, -1.0)
        return out.astype(np.float64) if dtype == np.float32 else out.astype(np.int64)

    def _dense(self, acc, dtype, width: int, where: str) -> np.ndarray:
        if acc.bufferView is None:
            return np.zeros((acc.count, width), dtype=dtype)
        return self._read(acc.bufferView, acc.byteOffset or 0, dtype, width, acc.count, where)

    def _read(self, view_index: int, offset: int, dtype, width: int, count: int, where: str) -> np.ndarray:
        data, view_offset, stride = self.buffer_view(view_index, where)
        item = np.dtype(dtype).itemsize * width
        stride = stride or item
        start = view_offset + offset
        if count and start + stride * (count - 1) + item > len(data):
            raise SceneError(f"{where}: {count} elements run past the end of bufferViews[{view_index}]",
                             file=self.path)  # fmt: skip
        if count == 0:
            return np.zeros((0, width), dtype=dtype)
        raw = np.ndarray((count, width), dtype=np.dtype(dtype).newbyteorder("<"), buffer=data, offset=start,
                         strides=(stride, np.dtype(dtype).itemsize))  # fmt: skip
        return np.array(raw, dtype=dtype)

    def image_bytes(self, index: int) -> bytes:
        """The encoded bytes (PNG, JPEG…) of images[index]: from a buffer view or a uri."""
        images = self.doc.images or []
        if not 0 <= index < len(images):
            raise SceneError(f"images[{index}] does not exist", file=self.path)
        image = images[index]
        if image.bufferView is not None:
            data, offset, _ = self.buffer_view(image.bufferView, f"images[{index}]")
            return data[offset:]
        if not image.uri:
            raise SceneError(f"images[{index}] has neither a bufferView nor a uri", file=self.path)
        return self._read_uri(image.uri, f"images[{index}].uri")

    # ------------------------------------------------------------------------------------------ geometry

    @functools.cache  # noqa: B019 (one GltfFile per file, kept by read_gltf)
    def primitive(self, mesh: int, index: int) -> Primitive | None:
        """A primitive's triangles in mesh coordinates, or None (points, lines: with a warning)."""
        where = f"meshes[{mesh}].primitives[{index}]"
        prim = self.doc.meshes[mesh].primitives[index]
        mode = TRIANGLES if prim.mode is None else prim.mode
        if mode not in (TRIANGLES, TRIANGLE_STRIP, TRIANGLE_FAN):
            self.warnings.append(f"{where}: mode {mode} (points or lines) skipped: reflets renders triangles")
            return None
        draco = (prim.extensions or {}).get("KHR_draco_mesh_compression")
        attributes = prim.attributes
        if draco is not None:
            values, indices = self._draco(draco, where)
        else:
            values = {}
            for name in ("POSITION", "NORMAL", "TANGENT", "TEXCOORD_0", "TEXCOORD_1"):
                accessor = getattr(attributes, name, None)
                if accessor is not None:
                    values[name] = self.accessor(accessor, f"{where}.attributes.{name}").astype(np.float64)
            indices = None
            if prim.indices is not None:
                indices = self.accessor(prim.indices, f"{where}.indices").ravel().astype(np.int64)
        if "POSITION" not in values:
            raise SceneError(f"{where}: no POSITION attribute", file=self.path)
        positions = values["POSITION"][:, :3]
        n = len(positions)
        if indices is None:
            indices = np.arange(n, dtype=np.int64)
        triangles = _triangles(indices, mode)
        if triangles.size and (triangles.min() < 0 or triangles.max() >= n):
            raise SceneError(f"{where}.indices: index out of range (the primitive has {n} vertices)", file=self.path)
        extra = [name for name in ("COLOR_0", "JOINTS_0", "WEIGHTS_0") if getattr(attributes, name, None) is not None]
        if extra:
            self.warnings.append(f"{where}: {', '.join(extra)} ignored (vertex colours and skins are not rendered)")
        if prim.targets:
            self.warnings.append(f"{where}: morph targets ignored (the rest pose is rendered)")

        def attribute(name: str, width: int):
            a = values.get(name)
            if a is None:
                return None
            if a.shape != (n, width) and a.shape[0] == n and a.shape[1] >= width:
                a = a[:, :width]
            if a.shape != (n, width):
                raise SceneError(f"{where}.attributes.{name}: {a.shape[0]} values of {a.shape[1]} components, "
                                 f"needs {n} of {width}", file=self.path)  # fmt: skip
            return a

        return Primitive(
            positions=positions,
            indices=triangles,
            normals=attribute("NORMAL", 3),
            tangents=attribute("TANGENT", 4),
            uvs=[attribute("TEXCOORD_0", 2), attribute("TEXCOORD_1", 2)],
            material=prim.material,
        )

    def _draco(self, draco: dict, where: str) -> tuple[dict[str, np.ndarray], np.ndarray]:
        try:
            import DracoPy
        except ImportError:  # a dependency of reflets (pyproject.toml), but an environment may lack it
            raise SceneError(f"{where}: KHR_draco_mesh_compression needs DracoPy, a dependency of reflets missing "
                             "here; install it (pip install DracoPy)", file=self.path) from None  # fmt: skip
        data, offset, _ = self.buffer_view(
            draco.get("bufferView", -1), where + ".extensions.KHR_draco_mesh_compression"
        )
        try:
            mesh = DracoPy.decode(data[offset:])
        except Exception as exc:  # the decoder raises its own error types
            raise SceneError(
                f"{where}: cannot decode Draco data ({type(exc).__name__}: {exc})", file=self.path
            ) from None
        values = {}
        for name, unique_id in (draco.get("attributes") or {}).items():
            attribute = mesh.get_attribute_by_unique_id(int(unique_id))
            if attribute is None:
                raise SceneError(f"{where}: Draco attribute {name} (id {unique_id}) missing", file=self.path)
            values[name] = np.asarray(attribute["data"], dtype=np.float64).reshape(len(mesh.points), -1)
        return values, np.asarray(mesh.faces, dtype=np.int64).ravel()

    def scene_nodes(self) -> list[int]:
        """The root nodes of the default scene (``scene``, else the first; none: every parentless node)."""
        scenes = self.doc.scenes or []
        if scenes:
            index = self.doc.scene if self.doc.scene is not None else 0
            if not 0 <= index < len(scenes):
                raise SceneError(f"scene: scenes[{index}] does not exist", file=self.path)
            return list(scenes[index].nodes or [])
        children = {c for node in self.doc.nodes or [] for c in node.children or []}
        return [i for i in range(len(self.doc.nodes or [])) if i not in children]

    @functools.cached_property
    def world_matrices(self) -> dict[int, np.ndarray]:
        """Node index → its world matrix, for every node of the default scene (depth first; a cycle is an error)."""
        nodes = self.doc.nodes or []
        out: dict[int, np.ndarray] = {}
        stack = [(i, np.eye(4)) for i in reversed(self.scene_nodes())]
        while stack:
            index, parent = stack.pop()
            if not 0 <= index < len(nodes):
                raise SceneError(f"nodes[{index}] does not exist", file=self.path)
            if index in out:
                raise SceneError(f"nodes[{index}] is reached twice (a node has one parent)", file=self.path)
            try:
                out[index] = parent @ node_matrix(nodes[index], f"nodes[{index}]")
            except ValueError as exc:
                raise SceneError(str(exc), file=self.path) from None
            stack.extend((child, out[index]) for child in reversed(nodes[index].children or []))
        return out

    @functools.cached_property
    def instances(self) -> list[Instance]:
        """Every primitive of every mesh node of the default scene, in node order (a node scaled to nothing — glTF's
        way of hiding it — has none)."""
        out = []
        meshes = self.doc.meshes or []
        for node_index, matrix in self.world_matrices.items():
            node = self.doc.nodes[node_index]
            if node.mesh is None:
                continue
            if not 0 <= node.mesh < len(meshes):
                raise SceneError(f"nodes[{node_index}].mesh: meshes[{node.mesh}] does not exist", file=self.path)
            if node.skin is not None:
                self.warnings.append(f"nodes[{node_index}]: skin ignored (the rest pose is rendered)")
            if abs(np.linalg.det(matrix[:3, :3])) < 1e-300:
                continue
            mesh = meshes[node.mesh]
            for p in range(len(mesh.primitives or [])):
                name = node.name or mesh.name or f"node {node_index}"
                out.append(Instance(node_index, node.mesh, p, matrix, name if len(mesh.primitives) == 1 else
                                    f"{name} #{p}"))  # fmt: skip
        return out


def node_matrix(node, where: str = "node") -> np.ndarray:
    """A node's local matrix: ``matrix`` (column-major) or T · R · S; malformed or non-finite values are errors (a
    ValueError naming ``where``'s field), a rotation is normalised (exporters write nearly-unit quaternions)."""

    def numbers(name: str, count: int) -> np.ndarray | None:
        value = getattr(node, name)
        if value is None:
            return None
        try:
            array = np.asarray(value, dtype=np.float64).ravel()
        except (TypeError, ValueError):
            array = np.zeros(0)
        if array.size != count or not np.all(np.isfinite(array)) or np.abs(array).max() > MAX_NUMBER:
            raise ValueError(f"{where}.{name}: needs {count} finite numbers of magnitude ≤ {MAX_NUMBER:g}, "
                             f"got {value!r}")  # fmt: skip
        return array

    matrix = numbers("matrix", 16)
    if matrix is not None and list(matrix) != [1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1]:
        return matrix.reshape(4, 4).T
    m = np.eye(4)
    scale = numbers("scale", 3)
    if scale is not None:
        m = np.diag([*scale, 1.0])
    rotation = numbers("rotation", 4)
    if rotation is not None:
        norm = np.linalg.norm(rotation)
        if norm < 1e-6:
            raise ValueError(f"{where}.rotation: a zero quaternion is no rotation (a unit quaternion is needed)")
        m = _quaternion_matrix(rotation / norm) @ m
    translation = numbers("translation", 3)
    if translation is not None:
        m[:3, 3] += translation
    return m


def _quaternion_matrix(q) -> np.ndarray:
    x, y, z, w = (float(c) for c in q)
    m = np.eye(4)
    m[:3, :3] = [
        [1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)],
        [2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)],
        [2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)],
    ]
    return m


def _triangles(indices: np.ndarray, mode: int) -> np.ndarray:
    if mode == TRIANGLES:
        return indices[: len(indices) - len(indices) % 3].reshape(-1, 3)
    k = np.arange(max(len(indices) - 2, 0))
    if mode == TRIANGLE_FAN:
        return np.stack([indices[k + 1], indices[k + 2], np.full_like(k, indices[0])], axis=1) if len(k) else \
            np.zeros((0, 3), np.int64)  # fmt: skip
    even = k % 2 == 0  # strips alternate orientation
    a = np.where(even, indices[k], indices[k + 1])
    b = np.where(even, indices[k + 1], indices[k])
    return np.stack([a, b, indices[k + 2]], axis=1)


#: parsed files kept (the scene expands a file into parts, each part's mesh reads it again)
FILE_CACHE_ENTRIES = 8
_FILES: OrderedDict[tuple, GltfFile] = OrderedDict()
_FILES_LOCK = threading.Lock()


def read_gltf(path: str | Path) -> GltfFile:
    """The parsed file at ``path`` (cached by path, size and modification time, and those of the files it names:
    an edited .bin is read again)."""
    path = Path(path).absolute()
    try:
        stat = path.stat()
    except OSError:
        raise SceneError("glTF file not found", file=path) from None
    if not path.is_file():
        raise SceneError("is not a regular file", file=path)
    key = (str(path), stat.st_size, stat.st_mtime_ns)
    with _FILES_LOCK:
        known = _FILES.get(key)
        if known is not None:
            _FILES.move_to_end(key)
    if known is not None and known.external_stamp() == known.stamp:
        return known
    with path.open("rb") as f:
        head = f.read(4)
    if path.suffix.lower() == ".glb" and head != b"glTF":
        raise SceneError("not a binary glTF file (no 'glTF' magic)", file=path)
    parsed = GltfFile(path)
    parsed.stamp = parsed.external_stamp()
    with _FILES_LOCK:
        _FILES[key] = parsed
        while len(_FILES) > FILE_CACHE_ENTRIES:
            _FILES.popitem(last=False)
    return parsed
