"""Scene meshes as world-space :class:`MeshData`, and the scene's bounding sphere (for clip planes)."""

from __future__ import annotations

import numpy as np

from ..errors import SceneError
from .meshdata import MeshData
from .model import FileMesh, MeshBase, Scene


def mesh_data(scene: Scene, index: int) -> MeshData:
    """World-space triangles of ``scene.mesh[index]`` (procedural shape or file, transform applied)."""
    from .meshfile import load_mesh_file
    from .shapes import SHAPES

    mesh: MeshBase = scene.mesh[index]
    try:
        if isinstance(mesh, FileMesh):
            local = load_mesh_file(scene.resolve(mesh.file))
        else:
            params = mesh.model_dump(exclude={"name", "material", "transform", "shape", "reflector"})
            if params.get("file") is not None:  # a shape reading data (heightfield): relative to the scene
                params["file"] = scene.resolve(params["file"])
            local = SHAPES[mesh.shape](**params)
    except SceneError as exc:
        raise SceneError(
            exc.message, file=exc.file, field=f"mesh[{index}]" + (f".{exc.field}" if exc.field else "")
        ) from None
    return local.transformed(mesh.transform.matrix())


def bounding_sphere(points: np.ndarray) -> tuple[np.ndarray, float]:
    """Centre and radius of a sphere holding all points (bounding-box centre; not minimal, but cheap)."""
    lo, hi = points.min(axis=0), points.max(axis=0)
    centre = 0.5 * (lo + hi)
    return centre, float(np.sqrt(np.max(np.sum((points - centre) ** 2, axis=1))))


def clip_planes(eye: np.ndarray, points: np.ndarray) -> tuple[float, float]:
    """near/far enclosing every point: far beyond the farthest, near a fixed fraction of far."""
    if len(points) == 0:
        return 0.01, 100.0
    centre, radius = bounding_sphere(points)
    far = (float(np.linalg.norm(centre - eye)) + radius) * 1.01 + 1e-6
    nearest = float(np.linalg.norm(centre - eye)) - radius
    near = max(far * 1e-5, min(nearest * 0.99, far * 1e-2)) if nearest > 0 else far * 1e-5
    return near, far
