"""The potential highlight curves of a scene's mesh (001, §4.2): ℓ per vertex for the scene's camera and its
first point or directional light, on the mesh's own orientation field (its tangents: the direction of
increasing u, what anisotropic BRDFs are oriented by). Behind ``reflets highlights``."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from ..errors import ArgumentError
from .analysis import half_vectors, highlight_tangents
from .surface import SurfaceMesh


def weld(positions: np.ndarray, faces: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Vertices at the same position merged (a loader splits them at uv or normal seams, which would cut the
    1-ring): (welded positions, welded faces, the welded index of every original vertex)."""
    scale = max(float(np.abs(positions).max(initial=0.0)), 1e-30)
    keys = np.round(positions / scale * 2**30).astype(np.int64)
    _, first, inverse = np.unique(keys, axis=0, return_index=True, return_inverse=True)
    inverse = inverse.ravel()
    return positions[first], inverse[faces], inverse


def _prepared(scene, index: int, light: int | None):
    """(mesh data, welded surface, the welded index of each vertex, half vectors, the field's tangents)."""
    from ..scene.geometry import mesh_data

    if not 0 <= index < len(scene.mesh):
        raise ArgumentError(f"no mesh[{index}]: the scene has {len(scene.mesh)}", field="--mesh")
    lights = [i for i, lt in enumerate(scene.light) if lt.type in ("point", "directional")]
    if light is None:
        if not lights:
            raise ArgumentError("the scene has no point or directional light to make highlights", field="light")
        light = lights[0]
    elif light not in lights:
        raise ArgumentError(f"light[{light}] is not a point or directional light; those are: {lights}", field="--light")
    data = mesh_data(scene, index)
    positions, faces, inverse = weld(data.positions.astype(np.float64), data.indices.astype(np.int64))
    normals = np.zeros_like(positions)
    np.add.at(normals, inverse, data.normals.astype(np.float64))
    mesh = SurfaceMesh.build(positions, faces, normals)
    u = np.zeros_like(positions)
    u[inverse] = data.tangents[:, :3]  # one of a seam's tangents
    source = scene.light[light]
    h = half_vectors(
        mesh,
        scene.camera.position,
        light_position=getattr(source, "position", None),
        light_direction=getattr(source, "direction", None),
    )
    return data, mesh, inverse, h, u


def mesh_highlights(scene, index: int, light: int | None = None, k: int = 2) -> dict[str, np.ndarray]:
    """For ``scene.mesh[index]`` in its vertex order (a file's, for a mesh file): world ``positions``,
    ``normals``, the field ``u``, the half vectors ``h`` between the camera and the light (the first point or
    directional light, or ``light``), ``ell`` (zero where degenerate) and ``degenerate``. k = 2: the field is
    unoriented (every anisotropic BRDF of the library is centrally symmetric)."""
    data, mesh, inverse, h, u = _prepared(scene, index, light)
    ell, degenerate = highlight_tangents(mesh, mesh.angles(u), h, k)
    ell[degenerate] = 0.0
    return {
        "positions": data.positions.astype(np.float64),
        "normals": mesh.normals[inverse],
        "u": mesh.field(mesh.angles(u))[inverse],
        "h": h[inverse],
        "ell": ell[inverse],
        "degenerate": degenerate[inverse],
    }


def edit_highlights(
    scene, index: int, targets: np.ndarray, mask: np.ndarray, light: int | None = None, k: int = 2, iterations: int = 20
) -> dict[str, np.ndarray]:
    """Solve the orientation field of ``scene.mesh[index]`` on the ``mask`` vertices (V,) so that its highlight
    tangents match ``targets`` (V, 3, world space as ``mesh_highlights`` writes them; zero rows: no target),
    starting from the mesh's current field. Returns ``u`` (V, 3) in the mesh's own coordinates and vertex order
    (what a material's ``orientation`` file holds) and ``energy`` (the start, then each iteration)."""
    from .solver import HighlightProblem, solve

    data, mesh, inverse, h, u = _prepared(scene, index, light)
    count = data.n_vertices
    targets, mask = np.asarray(targets, np.float64), np.asarray(mask, bool)
    if targets.shape != (count, 3) or mask.shape != (count,):
        raise ArgumentError(
            f"targets need ell ({count}, 3) and mask ({count},), one row per vertex of mesh[{index}]; got "
            f"{targets.shape} and {mask.shape}",
            field="--targets",
        )
    welded_targets = np.zeros_like(mesh.positions)
    welded_targets[inverse] = targets
    free = np.zeros(len(mesh.positions), bool)
    np.logical_or.at(free, inverse, mask)
    result = solve(HighlightProblem(mesh, h, k), mesh.angles(u), welded_targets, free, iterations=iterations)
    world = mesh.field(result.phi)[inverse]
    linear = scene.mesh[index].transform.matrix()[:3, :3]
    local = world @ np.linalg.inv(linear).T  # tangents move by M: back to the mesh's own coordinates
    local /= np.maximum(np.linalg.norm(local, axis=1, keepdims=True), 1e-300)
    return {"u": local, "energy": np.asarray(result.energy)}


def write_highlights(path: str | Path, result: dict[str, np.ndarray]) -> Path:
    from ..imageio import atomic_write

    path = Path(path)
    if path.suffix.lower() != ".npz":
        raise ArgumentError(f"the output is an .npz file, got '{path.name}'", file=path)
    import io

    buffer = io.BytesIO()
    np.savez(buffer, **result)
    atomic_write(path, buffer.getvalue())
    return path
