"""Orientation fields (001, chapter 4): a tangent per vertex that orients an anisotropic material, read from the
material's ``orientation`` file and put in place of the mesh's own tangents (``geometry.mesh_data``), so that
every technique and the references render it alike."""

from __future__ import annotations

from dataclasses import replace
from pathlib import Path

import numpy as np
import scipy.sparse as sp
from scipy.sparse.csgraph import breadth_first_order

from ..errors import ARRAY_READ_ERRORS, SceneError
from .meshdata import MeshData

#: a field whose edges disagree in sign (t_i·t_j < 0) on at most this fraction is kept as given
CONSISTENT_FRACTION = 0.02


def load_orientation(path: Path, n_vertices: int, field: str) -> np.ndarray:
    """``u`` (V, 3) of an orientation file, checked: a readable .npz, key u, one finite row per vertex."""
    try:
        with np.load(path) as data:
            if "u" not in data.files:
                raise SceneError(f"no array 'u' (it has: {', '.join(data.files) or 'none'})", file=path, field=field)
            u = np.asarray(data["u"], np.float64)
    except ARRAY_READ_ERRORS as exc:
        raise SceneError(f"not a readable .npz orientation field ({exc})", file=path, field=field) from None
    if u.shape != (n_vertices, 3):
        raise SceneError(
            f"u has shape {u.shape}; the mesh has {n_vertices} vertices: expected ({n_vertices}, 3), one tangent "
            "per vertex in the mesh's order",
            file=path,
            field=field,
        )
    if not np.all(np.isfinite(u)):
        raise SceneError("u has NaN or infinite values", file=path, field=field)
    return u


def apply_orientation(data: MeshData, u: np.ndarray) -> MeshData:
    """The mesh with ``u`` as its tangents: projected on each tangent plane (a vertex where u is along the
    normal keeps its own tangent), and their signs made consistent along the mesh's edges by a breadth-first
    walk (the BRDFs are centrally symmetric: u and −u orient them alike, but interpolating opposite tangents
    across a triangle would not), so that only triangles around a half-integer singularity mix opposite ones."""
    n = data.normals.astype(np.float64)
    t = u - np.sum(u * n, axis=1, keepdims=True) * n
    size = np.linalg.norm(t, axis=1, keepdims=True)
    t = np.where(size > 1e-6, t / np.maximum(size, 1e-300), data.tangents[:, :3])
    t = _consistent_signs(t, data.indices)
    tangents = np.concatenate([t, data.tangents[:, 3:4]], axis=1).astype(np.float32)
    return replace(data, tangents=tangents)  # the rest as it is (both uv sets)


def _consistent_signs(t: np.ndarray, faces: np.ndarray) -> np.ndarray:
    """Signs flipped so that neighbours agree: a field that mostly does already (a vector field, whose
    singularities alone have disagreeing edges) is kept as it is; otherwise each vertex, in breadth-first
    order, takes the sign its already-signed neighbours vote for (Σ s_j t_i·t_j)."""
    count = len(t)
    pairs = np.concatenate([faces[:, [0, 1]], faces[:, [1, 2]], faces[:, [2, 0]]]).astype(np.int64)
    if np.mean(np.einsum("ij,ij->i", t[pairs[:, 0]], t[pairs[:, 1]]) < 0) <= CONSISTENT_FRACTION:
        return t
    graph = sp.coo_matrix((np.ones(len(pairs)), (pairs[:, 0], pairs[:, 1])), shape=(count, count)).tocsr()
    graph = (graph + graph.T).tocsr()
    sign = np.zeros(count)
    for start in range(count):
        if sign[start]:
            continue
        order = breadth_first_order(graph, start, directed=False, return_predecessors=False)
        for v in order:
            near = graph.indices[graph.indptr[v] : graph.indptr[v + 1]]
            vote = float(np.dot(sign[near], t[near] @ t[v]))
            sign[v] = 1.0 if vote >= 0 else -1.0
    return t * sign[:, None]
