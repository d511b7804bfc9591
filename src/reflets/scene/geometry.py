"""Scene meshes as world-space :class:`MeshData`, and the scene's bounding sphere (for clip planes)."""

from __future__ import annotations

import threading
from collections import OrderedDict

import numpy as np

from ..errors import SceneError
from .meshdata import MeshData
from .model import FileMesh, MeshBase, Scene

#: world-space meshes kept for re-use (a persistent renderer prepares again after an edit: only the meshes
#: whose description changed are built again); bounded, least recently used first out
MESH_CACHE_ENTRIES = 64
_MESH_CACHE: OrderedDict[tuple, MeshData] = OrderedDict()
_MESH_LOCK = threading.Lock()  # renders from several threads share the cache


def mesh_data(scene: Scene, index: int) -> MeshData:
    """World-space triangles of ``scene.mesh[index]`` (procedural shape or file, transform applied); the same
    description (files by path, size and modification time) gives the same cached, read-only object."""
    key = _mesh_key(scene, index)
    if key is not None:
        with _MESH_LOCK:
            if key in _MESH_CACHE:
                _MESH_CACHE.move_to_end(key)
                return _MESH_CACHE[key]
    data = _build_mesh_data(scene, index)  # outside the lock: two threads may build the same mesh once each
    if key is not None:
        for array in (data.positions, data.normals, data.tangents, data.uvs, data.indices, data.uvs1):
            if array is not None:
                array.flags.writeable = False
        with _MESH_LOCK:
            _MESH_CACHE[key] = data
            while len(_MESH_CACHE) > MESH_CACHE_ENTRIES:
                _MESH_CACHE.popitem(last=False)
    return data


def mesh_scale(scene: Scene, index: int) -> float:
    """World units per unit of the mesh's own coordinates (the cube root of its transform's |det|, a glTF part's
    node transform included): KHR_materials_volume's thickness is given in the mesh's units."""
    mesh = scene.mesh[index]
    linear = mesh.transform.matrix()[:3, :3]
    if isinstance(mesh, FileMesh) and mesh.part is not None and mesh.file.suffix.lower() in (".gltf", ".glb"):
        from .assets import read_gltf

        linear = linear @ read_gltf(scene.resolve(mesh.file)).instances[mesh.part].matrix[:3, :3]
    return float(abs(np.linalg.det(linear)) ** (1.0 / 3.0))


def _mesh_key(scene: Scene, index: int) -> tuple | None:
    mesh = scene.mesh[index]
    files = []
    for name in ("file",):
        path = getattr(mesh, name, None)
        if path is not None:
            try:
                stat = scene.resolve(path).stat()
            except OSError:
                return None  # let the build report the missing file
            files.append((str(scene.resolve(path)), stat.st_size, stat.st_mtime_ns))
            if scene.resolve(path).suffix.lower() == ".gltf":  # and the .bin it names (an edited one: built again)
                from ..gltf_file import read_gltf

                files.append(read_gltf(scene.resolve(path)).stamp)
    orientation = getattr(scene.materials.get(mesh.material), "orientation", None)
    if orientation is not None:  # the material's field replaces the tangents
        try:
            stat = scene.resolve(orientation).stat()
        except OSError:
            return None
        files.append((str(scene.resolve(orientation)), stat.st_size, stat.st_mtime_ns))
    return (mesh.model_dump_json(exclude={"name", "material", "reflector"}), tuple(files))


def _build_mesh_data(scene: Scene, index: int) -> MeshData:
    from .meshfile import load_mesh_file
    from .shapes import SHAPES

    mesh: MeshBase = scene.mesh[index]
    try:
        if isinstance(mesh, FileMesh) and mesh.part is not None:
            from .assets import part_mesh

            local = part_mesh(scene.resolve(mesh.file), mesh.part)
        elif isinstance(mesh, FileMesh):  # glTF by reflets' reader (Draco, sparse, quantized data), others by trimesh
            local = load_mesh_file(scene.resolve(mesh.file))
        else:
            _check_segments(mesh, index)
            params = mesh.model_dump(exclude={"name", "material", "transform", "shape", "reflector"})
            if params.get("file") is not None:  # a shape reading data (heightfield): relative to the scene
                params["file"] = scene.resolve(params["file"])
            local = SHAPES[mesh.shape](**params)
    except SceneError as exc:
        raise SceneError(
            exc.message, file=exc.file, field=f"mesh[{index}]" + (f".{exc.field}" if exc.field else "")
        ) from None
    orientation = getattr(scene.materials[mesh.material], "orientation", None)
    if orientation is not None:  # in the mesh's own coordinates: the transform below moves it with the mesh
        from .orientation import apply_orientation, load_orientation

        field = f"materials.{mesh.material}.orientation (mesh[{index}])"
        local = apply_orientation(local, load_orientation(scene.resolve(orientation), local.n_vertices, field))
    return local.transformed(mesh.transform.matrix())


#: peak bytes per vertex of building a procedural mesh (float64 attributes and their temporaries, then the float32
#: mesh; tracemalloc: 413–446 for plane, sphere, torus, Bézier and height field at 1024² segments; a forward
#: render of a 4.7 M-vertex sphere peaked 407 above its baseline)
MESH_BYTES_PER_VERTEX = 448


def _check_segments(mesh, index: int) -> None:
    """Refuse ``segments`` = (n_u, n_v) whose (n_u + 1)(n_v + 1) vertices × MESH_BYTES_PER_VERTEX exceed the
    available memory (reflets.resources), before the mesh is built (a cylinder's single count stays small)."""
    from ..resources import check

    segments = getattr(mesh, "segments", None)
    if not isinstance(segments, tuple | list) or len(segments) != 2:
        return
    nu, nv = (int(n) for n in segments)
    vertices = (nu + 1) * (nv + 1)

    def fits(budget: int) -> str | None:
        scale = min(1.0, (budget / (vertices * MESH_BYTES_PER_VERTEX)) ** 0.5)
        u, v = int(nu * scale), int(nv * scale)
        return f"[{u}, {v}]" if u >= 1 and v >= 1 else None

    what = f"{vertices:,} vertices × {MESH_BYTES_PER_VERTEX} B"
    check(f"mesh[{index}].segments", vertices * MESH_BYTES_PER_VERTEX, value=f"[{nu}, {nv}]", what=what, fits=fits)


def bounding_sphere(points: np.ndarray) -> tuple[np.ndarray, float]:
    """Centre and radius of a sphere holding all points (bounding-box centre; not minimal, but cheap)."""
    lo, hi = points.min(axis=0), points.max(axis=0)
    centre = 0.5 * (lo + hi)
    return centre, float(np.sqrt(np.max(np.sum((points - centre) ** 2, axis=1))))


def self_shadowing(positions: np.ndarray, indices: np.ndarray, normals: np.ndarray | None = None) -> str:
    """Where a mesh can hide part of itself from a direction its surface faces: ``"none"`` when flat (all in one
    plane), ``"inside"`` when closed and convex with its front sides out — every triangle on its convex hull's
    boundary, wound counter-clockwise seen from outside, its vertex ``normals`` (if given) on that side: a ray
    leaving the outer side leaves the hull, only a point seen from inside can be hidden —, else ``"any"`` (a
    mesh wound inwards too: the shaders turn a back face's normal towards the camera, inwards). Exact up to
    rounding: a triangle whose centroid lies on the hull's boundary lies in the supporting plane there, a
    facet's through one of its corners (checked against the facets at each corner: linear time)."""
    from scipy.spatial import ConvexHull, QhullError

    positions = np.asarray(positions, np.float64)
    if not len(positions):
        return "any"
    grid = 1e-6 * max(float(np.ptp(positions, axis=0).max()), 1e-30)  # seams' repeated positions (and −0) as one
    _, first, inverse = np.unique(np.round(positions / grid), axis=0, return_index=True, return_inverse=True)
    points = positions[first]
    original = np.asarray(indices, np.int64)
    triangles = inverse.reshape(-1)[original]
    kept = np.all(triangles != np.roll(triangles, 1, axis=1), axis=1)  # no two corners merged
    triangles, original = triangles[kept], original[kept]
    if len(points) < 3 or not len(triangles):
        return "any"
    centred = points - points.mean(axis=0)
    size = float(np.max(np.linalg.norm(centred, axis=1)))
    if size > 0.0 and np.max(np.abs(centred @ np.linalg.svd(centred, full_matrices=False)[2][-1])) <= 1e-6 * size:
        return "none"  # every point within 10⁻⁶ of the mesh's size from one plane
    edges = np.sort(triangles[:, [0, 1, 1, 2, 2, 0]].reshape(-1, 2), axis=1)
    if np.any(np.unique(edges, axis=0, return_counts=True)[1] != 2):
        return "any"  # open (a bowl's inside can hide itself from outside its hull) or not a manifold
    try:
        hull = ConvexHull(points, qhull_options="Qc")  # Qc: the points inside a flat facet, with their facet
    except QhullError:
        return "any"
    # the facets at each point: the simplices' corners and the coplanar points
    owner = np.concatenate([hull.simplices.ravel(), hull.coplanar[:, 0]])
    facet = np.concatenate([np.repeat(np.arange(len(hull.simplices)), 3), hull.coplanar[:, 1]])
    order = np.argsort(owner, kind="stable")
    owner, facet = owner[order], facet[order]
    starts = np.searchsorted(owner, np.arange(len(points) + 1))
    corner = triangles.ravel()
    counts = starts[corner + 1] - starts[corner]
    pairs = np.repeat(np.arange(len(corner)) // 3, counts)  # (triangle, facet at one of its corners)
    offset = np.repeat(starts[corner] - (np.cumsum(counts) - counts), counts)  # pair p: facet[p + its offset]
    facets = facet[np.arange(len(pairs)) + offset]
    corners = points[triangles]
    centroids = corners.mean(axis=1)
    distance = np.einsum("ij,ij->i", centroids[pairs], hull.equations[facets, :3]) + hull.equations[facets, 3]
    nearest = np.full(len(triangles), -np.inf)
    np.maximum.at(nearest, pairs, distance)
    if np.any(nearest < -1e-6 * size):
        return "any"
    winding = np.cross(corners[:, 1] - corners[:, 0], corners[:, 2] - corners[:, 0])
    if np.any(np.einsum("ij,ij->i", winding, centroids - points[hull.vertices].mean(axis=0)) <= 0.0):
        return "any"  # a triangle wound inwards (or degenerate)
    if normals is not None and np.any(np.einsum("ijk,ik->ij", np.asarray(normals, np.float64)[original], winding) <= 0):
        return "any"  # a vertex normal facing in: that side is the one shaded
    return "inside"


def framing_camera(scene: Scene):
    """A camera looking down −z at the scene's meshes, 45° vertical field of view, the bounding sphere filling the
    view (what a glTF file without a camera is shown with)."""
    from .model import Camera

    points = np.concatenate([mesh_data(scene, i).positions for i in range(len(scene.mesh))]).astype(np.float64)
    centre, radius = bounding_sphere(points)
    fov = 45.0
    distance = max(radius, 1e-6) / np.sin(np.radians(fov / 2)) * 1.05
    return Camera(position=tuple(centre + [0.0, 0.0, distance]), look_at=tuple(centre), fov_y=fov,
                  size=scene.camera.size)  # fmt: skip


#: the automatic near plane: this fraction of the smallest object's bounding-box diagonal (reversed-Z depth keeps
#: its precision however small the near plane is: ``reflets.gpu.depth``)
NEAR_FRACTION = 1e-3


def bounding_boxes(point_sets) -> np.ndarray:
    """(N, 2, 3) lower and upper corners of each non-empty point set (a mesh's vertices, an emitter's corners)."""
    boxes = [(p.min(axis=0), p.max(axis=0)) for p in map(np.asarray, point_sets) if len(p)]
    return np.asarray(boxes, dtype=np.float64).reshape(-1, 2, 3)


def camera_range(camera, boxes: np.ndarray) -> tuple[float, float | None]:
    """(near, far) of the camera's view: ``camera.near`` / ``camera.far`` where given; else far is infinite (None)
    and near is :data:`NEAR_FRACTION` of the smallest box's diagonal, or half the distance to the nearest box
    if that is less — never derived from the scene's extent, so a 10,000 km ground plane leaves a 10 cm sphere
    0.5 m away in view. An orthographic camera's depth is linear: near defaults to 0 (its own plane) and far to
    just beyond the farthest box corner along the view."""
    far = camera.far
    near = camera.near
    if camera.orthographic:
        near = 0.0 if near is None else near
        if far is None:
            boxes = np.asarray(boxes, dtype=np.float64).reshape(-1, 2, 3)
            forward = np.subtract(camera.look_at, camera.position)
            forward = forward / np.linalg.norm(forward)
            # the farthest corner of each box: its max or min coordinate along each axis, by forward's sign
            farthest = np.where(forward > 0, boxes[:, 1], boxes[:, 0])
            depth = float(((farthest - np.asarray(camera.position, np.float64)) @ forward).max()) if len(boxes) else 1.0
            extent = float(np.ptp(boxes.reshape(-1, 3), axis=0).max()) if len(boxes) else 1.0
            far = max(depth, near) + 0.01 * max(extent, 1e-6) + 1e-6
        return float(near), float(far)
    if near is None:
        boxes = np.asarray(boxes, dtype=np.float64).reshape(-1, 2, 3)
        eye = np.asarray(camera.position, dtype=np.float64)
        sizes = np.linalg.norm(boxes[:, 1] - boxes[:, 0], axis=1)
        sizes = sizes[sizes > 0]
        near = NEAR_FRACTION * float(sizes.min()) if sizes.size else NEAR_FRACTION
        gaps = np.linalg.norm(np.maximum(np.maximum(boxes[:, 0] - eye, eye - boxes[:, 1]), 0.0), axis=1)
        gaps = gaps[gaps > 0]
        if gaps.size:
            near = min(near, 0.5 * float(gaps.min()))
        if far is not None:
            near = min(near, NEAR_FRACTION * far)
    return float(near), None if far is None else float(far)


def clip_planes(eye: np.ndarray, points: np.ndarray) -> tuple[float, float]:
    """near/far enclosing every point: far beyond the farthest, near a fixed fraction of far."""
    if len(points) == 0:
        return 0.01, 100.0
    return clip_planes_of_sphere(eye, *bounding_sphere(points))


def clip_planes_of_sphere(
    eye: np.ndarray, centre: np.ndarray | None = None, radius: float = 0.0
) -> tuple[float, float]:
    """``clip_planes`` for points held by a known bounding sphere (None: an empty scene)."""
    if centre is None:
        return 0.01, 100.0
    far = (float(np.linalg.norm(centre - eye)) + radius) * 1.01 + 1e-6
    nearest = float(np.linalg.norm(centre - eye)) - radius
    near = max(far * 1e-5, min(nearest * 0.99, far * 1e-2)) if nearest > 0 else far * 1e-5
    return near, far
