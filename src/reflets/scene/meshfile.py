"""Triangle meshes from files (OBJ, PLY, glTF/GLB, STL, OFF), with a full shading frame.

glTF and GLB are read by reflets' own reader (``reflets.gltf_file``: Draco, quantized and sparse data, which
trimesh would hand over as vertices at 0 when it cannot decode them); trimesh parses the other formats, and what
it would log to stderr (with tracebacks) becomes one warning line naming the file. This module turns either
into :class:`MeshData`: scene graphs are flattened with their node transforms, missing normals and uvs are
filled in, and per-vertex tangents are built from the uv layout so anisotropic materials have an orientation
on any mesh.
"""

from __future__ import annotations

import codecs
import contextlib
import functools
import io
import logging
import re
import threading
import warnings
from dataclasses import replace
from pathlib import Path

import numpy as np

from reflets.errors import RefletsWarning, SceneError
from reflets.gltf_file import read_gltf
from reflets.quantities import MAX_MAGNITUDE
from reflets.scene.meshdata import MeshData, merged

SUPPORTED_EXTENSIONS = (".obj", ".ply", ".gltf", ".glb", ".stl", ".off")
#: the formats reflets' glTF reader takes (never trimesh: see the module docstring)
GLTF_EXTENSIONS = (".gltf", ".glb")

#: fallback order for text without a byte order mark: strict UTF-8, then Windows-1252 (a superset of Latin-1's
#: printable characters, with ’ € … in 0x80–0x9F), then Latin-1, which maps every byte and so never fails
TEXT_ENCODINGS = ("utf-8", "cp1252", "latin-1")
_UTF16_BOMS = ((codecs.BOM_UTF16_LE, "utf-16-le"), (codecs.BOM_UTF16_BE, "utf-16-be"))
#: the ``end_header`` line of a PLY file with its line break (the header is text whatever the body); anchored at a
#: line start so that a comment mentioning it does not end the header early
_PLY_END_HEADER = re.compile(rb"(?:\A|[\r\n])[ \t]*end_header[ \t]*(?:\r?\n|\r)")
_PLY_ASCII = re.compile(rb"^[ \t]*format[ \t]+ascii\b", re.MULTILINE | re.IGNORECASE)


def decode_text(data: bytes) -> str:
    """Text of a mesh or material file in any common encoding, with LF line endings.

    A UTF-8 byte order mark is dropped (so is a UTF-16 one, with the text decoded as UTF-16); otherwise the
    first of :data:`TEXT_ENCODINGS` that decodes every byte wins. CRLF and lone CR become LF.
    """
    text = None
    for bom, encoding in _UTF16_BOMS:
        if data.startswith(bom):
            try:
                text = data[len(bom) :].decode(encoding)
                break
            except UnicodeDecodeError:
                pass
    if text is None:
        data = data.removeprefix(codecs.BOM_UTF8)
        for encoding in TEXT_ENCODINGS:
            try:
                text = data.decode(encoding)
                break
            except UnicodeDecodeError:
                continue
    assert text is not None  # latin-1 decodes anything
    return text.replace("\r\n", "\n").replace("\r", "\n")


def _utf8_text(data: bytes) -> bytes:
    """A text file's bytes as UTF-8 without BOM, with LF line endings (the same object when already so)."""
    if b"\r" not in data and not data.startswith((codecs.BOM_UTF8, codecs.BOM_UTF16_LE, codecs.BOM_UTF16_BE)):
        try:
            data.decode("utf-8")
            return data
        except UnicodeDecodeError:
            pass
    return decode_text(data).encode("utf-8")


def _ply_bytes(data: bytes) -> bytes:
    """A PLY file with its header as UTF-8/LF; an ASCII body is re-encoded too, a binary one is kept byte for byte."""
    end = _PLY_END_HEADER.search(data)
    if end is None:  # not a PLY file: trimesh says so
        return _utf8_text(data)
    header = _utf8_text(data[: end.end()])
    return _utf8_text(data) if _PLY_ASCII.search(header) else header + data[end.end() :]


def _stl_bytes(data: bytes) -> bytes:
    """A binary STL (its length matches the triangle count at byte 80, as trimesh checks) as is; ASCII re-encoded."""
    if len(data) >= 84 and len(data) - 84 == 50 * int.from_bytes(data[80:84], "little"):
        return data
    return _utf8_text(data)


#: how each text-based format's bytes reach trimesh: as UTF-8 with LF line endings, so trimesh never has to guess
#: an encoding (its guess needs the optional charset_normalizer and drops what it cannot decode)
_TRANSCODE = {".obj": _utf8_text, ".off": _utf8_text, ".ply": _ply_bytes, ".stl": _stl_bytes}


@functools.cache
def _resolver_class(trimesh):
    """trimesh's file resolver, handing MTL material libraries (read by the OBJ loader) over as UTF-8/LF too."""

    class TextAssetResolver(trimesh.resolvers.FilePathResolver):
        def get(self, name: str) -> bytes:
            data = super().get(name)
            return _utf8_text(data) if name.strip().lower().endswith(".mtl") else data  # textures stay binary

    return TextAssetResolver


class _ThreadRecords(logging.Handler):
    """The log records of one thread (renders on other threads read files too)."""

    def __init__(self):
        super().__init__(logging.WARNING)
        self.thread, self.records = threading.get_ident(), []

    def emit(self, record: logging.LogRecord) -> None:
        if record.thread == self.thread:
            self.records.append(record)


@contextlib.contextmanager
def trimesh_log_as_warnings(path: Path):
    """What trimesh logs while it reads ``path`` (an image it cannot load, with its traceback, on stderr) as one
    RefletsWarning line per message, naming the file."""
    logger, handler = logging.getLogger("trimesh"), _ThreadRecords()
    logger.addHandler(handler)
    try:
        yield
    finally:
        logger.removeHandler(handler)
    said = [(r.getMessage().strip().splitlines() or [r.levelname])[0][:200] for r in handler.records]
    for line in dict.fromkeys(said):
        warnings.warn(f"{path.name}: {line} (trimesh, reading it)", RefletsWarning, stacklevel=3)


def _load_trimesh(path: Path, ext: str):
    """trimesh's object for a mesh file other than glTF; text formats are decoded here, see :data:`_TRANSCODE`."""
    import trimesh  # heavy import, only needed by scenes that use mesh files

    data = _TRANSCODE[ext](path.read_bytes())
    resolver = _resolver_class(trimesh)(str(path.absolute()))
    with trimesh_log_as_warnings(path):
        return trimesh.load(io.BytesIO(data), file_type=ext[1:], resolver=resolver, process=False)


def _unit(v: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Normalised rows and their original lengths (zero rows stay zero)."""
    length = np.linalg.norm(v, axis=1, keepdims=True)
    return np.divide(v, length, out=np.zeros_like(v), where=length > 0), length[:, 0]


def _scatter(idx: np.ndarray, values: np.ndarray, n: int) -> np.ndarray:
    """Add each triangle's ``values`` (M, 3) to its three corner vertices: an (n, 3) array of sums."""
    flat, vals = idx.ravel(), np.repeat(values, 3, axis=0)
    return np.stack([np.bincount(flat, weights=vals[:, k], minlength=n) for k in range(3)], axis=1)


def orthonormal_tangent(normals: np.ndarray) -> np.ndarray:
    """A unit vector orthogonal to each unit normal, continuous except across n.z = 0.

    Branchless construction of Duff et al. 2017, "Building an Orthonormal Basis, Revisited" (JCGT 6(1)),
    which fixes the precision loss of Frisvad's 2012 method near n = (0, 0, -1).
    """
    x, y, z = normals.T
    sign = np.copysign(1.0, z)
    a = -1.0 / (sign + z)
    return np.stack([1.0 + sign * x * x * a, sign * x * y * a, -sign * x], axis=1)


def compute_tangents(positions, normals, uvs, indices) -> np.ndarray:
    """Per-vertex tangents with handedness from a uv layout (Lengyel 2001, as in glTF/MikkTSpace).

    Each triangle's ``∂p/∂u`` and ``∂p/∂v`` are solved from its edges and uv differences, normalised and
    accumulated at its corners weighted by triangle area (so slivers with nearly singular uv do not
    dominate, as they would with Lengyel's raw 1/det weights). The sum is Gram–Schmidt orthogonalised
    against the vertex normal; ``w = sign(dot(cross(n, t), Σ∂p/∂v))`` so the bitangent ``w * cross(n, t)``
    follows increasing v even where the uv layout is mirrored.

    Where the uv gives no usable direction (collapsed uv, uv seams that cancel, ∂p/∂u parallel to the
    normal) the tangent falls back to :func:`orthonormal_tangent`, any unit vector orthogonal to the normal,
    with ``w = +1``.

    Parameters
    ----------
    positions : (N, 3), normals : (N, 3), uvs : (N, 2), indices : (M, 3)

    Returns
    -------
    (N, 4) float32
    """
    p = np.asarray(positions, dtype=np.float64)
    n, _ = _unit(np.asarray(normals, dtype=np.float64))
    uv = np.asarray(uvs, dtype=np.float64)
    idx = np.asarray(indices, dtype=np.int64).reshape(-1, 3)
    e1, e2 = p[idx[:, 1]] - p[idx[:, 0]], p[idx[:, 2]] - p[idx[:, 0]]
    d1, d2 = uv[idx[:, 1]] - uv[idx[:, 0]], uv[idx[:, 2]] - uv[idx[:, 0]]
    det = d1[:, 0] * d2[:, 1] - d2[:, 0] * d1[:, 1]
    inv = np.divide(1.0, det, out=np.zeros_like(det), where=det != 0.0)[:, None]
    dp_du, _ = _unit((e1 * d2[:, 1:] - e2 * d1[:, 1:]) * inv)
    dp_dv, _ = _unit((e2 * d1[:, :1] - e1 * d2[:, :1]) * inv)
    area = 0.5 * np.linalg.norm(np.cross(e1, e2), axis=1)[:, None]
    t_sum = _scatter(idx, dp_du * area, len(p))
    b_sum = _scatter(idx, dp_dv * area, len(p))

    t, length = _unit(t_sum - n * np.sum(t_sum * n, axis=1, keepdims=True))
    bad = length <= 1e-6 * np.linalg.norm(t_sum, axis=1) + 1e-30
    t[bad] = orthonormal_tangent(n[bad])
    w = np.where(np.sum(np.cross(n, t) * b_sum, axis=1) < 0.0, -1.0, 1.0)
    w[bad] = 1.0
    return np.concatenate([t, w[:, None]], axis=1).astype(np.float32)


def smooth_normals(positions: np.ndarray, indices: np.ndarray) -> np.ndarray:
    """Angle-weighted vertex normals (Thürmer & Wüthrich 1998); (0, 1, 0) where a vertex touches no area.

    Weighting each adjacent face normal by the triangle's angle at the vertex makes the result independent
    of how a flat region is split into triangles (a cube's corner gets exactly (±1, ±1, ±1)/√3).
    """
    p, idx = np.asarray(positions, dtype=np.float64), np.asarray(indices, dtype=np.int64)
    corners = p[idx]  # (M, 3 corners, 3)
    face, _ = _unit(np.cross(corners[:, 1] - corners[:, 0], corners[:, 2] - corners[:, 0]))
    to_next, _ = _unit((np.roll(corners, -1, axis=1) - corners).reshape(-1, 3))
    to_prev, _ = _unit((np.roll(corners, 1, axis=1) - corners).reshape(-1, 3))
    angle = np.arccos(np.clip(np.sum(to_next * to_prev, axis=1), -1.0, 1.0)).reshape(-1, 3)
    summed = np.stack(
        [np.bincount(idx.ravel(), weights=(angle * face[:, k : k + 1]).ravel(), minlength=len(p)) for k in range(3)],
        axis=1,
    )
    n, length = _unit(summed)
    n[length == 0.0] = (0.0, 1.0, 0.0)
    return n


def spherical_uv(positions: np.ndarray) -> np.ndarray:
    """uv by spherical projection about the bounding-box centre, laid out like :func:`shapes.sphere`.

    ``u = φ / 2π`` with φ the azimuth about +y from +z towards +x, ``v = θ / π`` from +y down. The seam is
    not split, so triangles straddling u = 0 get a wrapped texture and fall back to a generic tangent.
    """
    d = positions - 0.5 * (positions.min(axis=0) + positions.max(axis=0))
    r = np.linalg.norm(d, axis=1)
    u = (np.arctan2(d[:, 0], d[:, 2]) / (2.0 * np.pi)) % 1.0
    cos_theta = np.divide(d[:, 1], r, out=np.zeros_like(r), where=r > 0)
    return np.stack([u, np.arccos(np.clip(cos_theta, -1.0, 1.0)) / np.pi], axis=1)


def _parts(loaded, trimesh) -> list[tuple[np.ndarray, np.ndarray | None, np.ndarray | None, np.ndarray]]:
    """(world positions, file normals or None, uv or None, faces) for each triangle mesh in the file."""
    if isinstance(loaded, trimesh.Scene):
        items = [(loaded.geometry[g], m) for m, g in (loaded.graph[node] for node in loaded.graph.nodes_geometry)]
    else:
        items = [(loaded, np.eye(4))]
    out = []
    for geom, matrix in items:
        if not isinstance(geom, trimesh.Trimesh) or len(geom.faces) == 0:
            continue  # point clouds, polylines
        v, faces = np.asarray(geom.vertices, dtype=np.float64), np.asarray(geom.faces, dtype=np.int64)
        lin = np.asarray(matrix, dtype=np.float64)[:3, :3]
        # trimesh keeps normals read from the file in its cache and computes them on demand otherwise.
        nrm = (
            np.asarray(geom.vertex_normals, dtype=np.float64)
            if "vertex_normals" in getattr(geom, "_cache", ())
            else None
        )
        nrm = nrm @ np.linalg.inv(lin) if nrm is not None and nrm.shape == v.shape else None
        uv = getattr(geom.visual, "uv", None)
        uv = np.asarray(uv, dtype=np.float64) if uv is not None and len(uv) == len(v) else None
        faces = faces if np.linalg.det(lin) > 0 else faces[:, ::-1]
        out.append((v @ lin.T + matrix[:3, 3], nrm, uv, faces))
    return out


def load_mesh_file(path: str | Path) -> MeshData:
    """Load a triangle mesh file into a :class:`MeshData`.

    Parameters
    ----------
    path : str or Path
        An ``.obj``, ``.ply``, ``.gltf``, ``.glb``, ``.stl`` or ``.off`` file. A glTF scene is flattened
        into one mesh with its node transforms applied (:func:`gltf_mesh`, reflets' reader: Draco decoded, or
        refused in one line); quads and polygons are triangulated by trimesh.
        Text formats (OBJ and its MTL, ASCII PLY, OFF, ASCII STL) may be UTF-8 (with or without BOM),
        Windows-1252 or Latin-1 with LF, CRLF or CR line endings: see :func:`decode_text`.

    Returns
    -------
    MeshData
        Normals are the file's vertex normals (renormalised) when it has them, else angle-weighted smooth
        normals from :func:`smooth_normals` (so unmerged STL triangles stay flat; glTF: flat normals, as its
        specification requires). uv is the file's texture coordinates (with v up, the OpenGL convention) or,
        when a part has none, a spherical projection about the bounding-box centre (:func:`spherical_uv`).
        Tangents come from :func:`compute_tangents` (glTF: the file's, when it has them). Vertices no
        triangle uses are dropped (trimesh's formats).

    Raises
    ------
    SceneError
        Missing file, unsupported extension, unreadable or corrupt file, or no triangles in it.
    """
    path = Path(path)
    ext = path.suffix.lower()
    if ext not in SUPPORTED_EXTENSIONS:
        raise SceneError(
            f"unsupported mesh extension {ext or '(none)'!r}; allowed: {', '.join(SUPPORTED_EXTENSIONS)}",
            file=path,
        )
    if not path.is_file():
        raise SceneError("mesh file not found" if not path.exists() else "is not a regular file", file=path)
    if ext in GLTF_EXTENSIONS:
        return gltf_mesh(path)

    import trimesh  # heavy import, only needed by scenes that use mesh files

    try:
        parts = _parts(_load_trimesh(path, ext), trimesh)
    except Exception as exc:  # trimesh raises many types for corrupt files
        reason = (str(exc).strip().splitlines() or [type(exc).__name__])[0][:200]
        raise SceneError(f"cannot read mesh file: {reason}", file=path) from exc
    if not parts:
        raise SceneError("contains no triangles (only points, lines or nothing)", file=path)

    offsets = np.cumsum([0] + [len(part[0]) for part in parts[:-1]])
    pos = np.concatenate([part[0] for part in parts])
    faces = np.concatenate([part[3] + o for part, o in zip(parts, offsets, strict=True)])
    if not np.all(np.isfinite(pos)) or faces.min() < 0 or faces.max() >= len(pos):
        raise SceneError("corrupt mesh: non-finite vertex coordinates or face indices out of range", file=path)
    if np.abs(pos).max() > MAX_MAGNITUDE:
        raise SceneError(f"vertex coordinates up to {np.abs(pos).max():.3g}, over {MAX_MAGNITUDE:.0e}: scale the mesh "
                         "in its file (the transform's scale applies after)", file=path)  # fmt: skip

    nrm = smooth_normals(pos, faces)
    has_uv = np.concatenate([np.full(len(part[0]), part[2] is not None) for part in parts])
    uv = spherical_uv(pos) if not has_uv.all() else np.empty((len(pos), 2))
    for (_, file_nrm, file_uv, _), o in zip(parts, offsets, strict=True):  # a few parts, not vertices
        if file_nrm is not None:
            unit, length = _unit(file_nrm)
            ok = np.isfinite(length) & (length > 0)
            nrm[o : o + len(unit)][ok] = unit[ok]
        if file_uv is not None:
            uv[o : o + len(file_uv)] = file_uv

    used, faces = np.unique(faces, return_inverse=True)
    return shaded_mesh(pos[used], nrm[used], uv[used], faces.reshape(-1, 3))


def shaded_mesh(positions, normals, uvs, faces, tangents=None) -> MeshData:
    """A float32 :class:`MeshData` of float64 arrays, its tangents built from the uv layout unless given."""
    if tangents is None:
        tangents = compute_tangents(positions, normals, uvs, faces)
    return MeshData(
        positions=np.asarray(positions, np.float32),
        normals=np.asarray(normals, np.float32),
        tangents=np.asarray(tangents, np.float32),
        uvs=np.asarray(uvs, np.float32),
        indices=np.asarray(faces, np.uint32),
    )


def gltf_part_mesh(path: str | Path, part: int) -> MeshData:
    """One primitive instance of a glTF file in the file's world coordinates, with a full shading frame: the
    file's normals (flat normals when it has none, as the specification requires), its tangents (else built from
    the uv layout: ``compute_tangents``), its TEXCOORD_0 and TEXCOORD_1 (v flipped to reflets' v up)."""
    gltf = read_gltf(path)
    instances = gltf.instances
    if not 0 <= part < len(instances):
        raise SceneError(f"part {part} does not exist: the file has {len(instances)} primitive instances", file=path)
    instance = instances[part]
    prim = gltf.primitive(instance.mesh, instance.primitive)
    where = f"meshes[{instance.mesh}].primitives[{instance.primitive}]"
    if prim is None or len(prim.indices) == 0:
        raise SceneError(f"{where}: no triangles", file=path)
    pos, faces = prim.positions, prim.indices
    normals, tangents, (uv, uv1) = prim.normals, prim.tangents, prim.uvs
    if normals is None:  # flat: every triangle its own three vertices
        corners = faces.ravel()
        pos, faces = pos[corners], np.arange(len(corners)).reshape(-1, 3)
        uv = uv[corners] if uv is not None else None
        uv1 = uv1[corners] if uv1 is not None else None
        tangents = None
        face = np.cross(pos[faces[:, 1]] - pos[faces[:, 0]], pos[faces[:, 2]] - pos[faces[:, 0]])
        normals = np.repeat(_unit(face)[0], 3, axis=0)
    if not (np.all(np.isfinite(pos)) and np.all(np.isfinite(normals))):
        raise SceneError(f"{where}: non-finite vertex data", file=path)
    mesh_uv = np.stack([uv[:, 0], 1.0 - uv[:, 1]], axis=1) if uv is not None else spherical_uv(pos)
    normals, length = _unit(normals)
    normals[length == 0] = (0.0, 1.0, 0.0)
    if tangents is not None and not np.all(np.isfinite(tangents)):
        tangents = None  # built from the uv layout
    local = shaded_mesh(pos, normals, mesh_uv, faces, tangents)
    if uv1 is not None:
        local = replace(local, uvs1=np.stack([uv1[:, 0], 1.0 - uv1[:, 1]], axis=1).astype(np.float32))
    world = local.transformed(instance.matrix)
    extent = np.abs(world.positions).max()
    if not np.isfinite(extent) or extent > MAX_MAGNITUDE:
        raise SceneError(f"{where} placed by nodes[{instance.node}]: vertex coordinates up to {extent:.3g}, over "
                         f"{MAX_MAGNITUDE:.0e}", file=path)  # fmt: skip
    return world


def gltf_mesh(path: Path) -> MeshData:
    """Every primitive instance of a glTF file's default scene in one mesh (a material given in the scene)."""
    count = len(read_gltf(path).instances)
    parts = [gltf_part_mesh(path, k) for k in range(count)]
    if not parts:
        raise SceneError("contains no triangles (only points, lines or nothing)", file=path)
    return merged(parts)
