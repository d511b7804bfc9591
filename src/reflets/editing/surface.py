"""A triangle mesh as the highlight-editing chapter (001, §4.2.3) discretises a surface: welded vertices with
normals, a tangent frame (t, b, n) each, the 1-ring and 2-ring neighbourhoods, barycentric vertex areas, and
the discrete Levi-Civita connection — the angle ρ_ij that parallel-transports a tangent angle measured in
vertex j's frame into vertex i's (the minimal rotation taking n_j to n_i, as Knöppel et al. 2013)."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import scipy.sparse as sp


@dataclass
class SurfaceMesh:
    """positions (V, 3), faces (F, 3), unit normals (V, 3), frames t, b (V, 3) with b = n × t; ``edges`` (E, 2)
    every directed 1-ring pair (i, j), ``transport`` (E,) the connection angle ρ_ij; ``ring2`` (E2, 2) directed
    pairs within two rings; ``areas`` (V,) one third of the adjacent triangles' areas."""

    positions: np.ndarray
    faces: np.ndarray
    normals: np.ndarray
    t: np.ndarray
    b: np.ndarray
    edges: np.ndarray
    transport: np.ndarray
    ring2: np.ndarray
    areas: np.ndarray

    @classmethod
    def build(cls, positions: np.ndarray, faces: np.ndarray, normals: np.ndarray | None = None) -> SurfaceMesh:
        positions = np.asarray(positions, np.float64)
        faces = np.asarray(faces, np.int64)
        e1 = positions[faces[:, 1]] - positions[faces[:, 0]]
        e2 = positions[faces[:, 2]] - positions[faces[:, 0]]
        cross = np.cross(e1, e2)
        if normals is None:  # area-weighted face normals
            normals = np.zeros_like(positions)
            for corner in range(3):
                np.add.at(normals, faces[:, corner], cross)
        normals = _unit(np.asarray(normals, np.float64))
        t = tangent_frames(normals)
        b = np.cross(normals, t)
        n = len(positions)
        pairs = np.concatenate([faces[:, [0, 1]], faces[:, [1, 2]], faces[:, [2, 0]]])
        adjacency = sp.coo_matrix((np.ones(len(pairs)), (pairs[:, 0], pairs[:, 1])), shape=(n, n)).tocsr()
        adjacency = ((adjacency + adjacency.T) > 0).astype(np.int32)
        rows, cols = adjacency.nonzero()
        edges = np.stack([rows, cols], axis=1)
        two = ((adjacency @ adjacency + adjacency) > 0).tolil()
        two.setdiag(0)
        rows2, cols2 = two.tocsr().nonzero()
        areas = np.zeros(n)
        for corner in range(3):
            np.add.at(areas, faces[:, corner], np.linalg.norm(cross, axis=1) / 6.0)
        mesh = cls(positions, faces, normals, t, b, edges, np.zeros(len(edges)), np.stack([rows2, cols2], 1), areas)
        mesh.transport = mesh._transport_angles()
        return mesh

    def local(self, pairs: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Neighbour j of each pair (i, j) in i's frame: tangent coordinates (P, 2) and elevation along n_i (P,)."""
        i, j = pairs[:, 0], pairs[:, 1]
        d = self.positions[j] - self.positions[i]
        return np.stack([_dot(d, self.t[i]), _dot(d, self.b[i])], axis=1), _dot(d, self.normals[i])

    def _transport_angles(self) -> np.ndarray:
        i, j = self.edges[:, 0], self.edges[:, 1]
        moved = rotate_onto(self.t[j], self.normals[j], self.normals[i])
        return np.arctan2(_dot(moved, self.b[i]), _dot(moved, self.t[i]))

    # ------------------------------------------------------------------ fields
    def angles(self, u: np.ndarray) -> np.ndarray:
        """The angle φ of each vertex's tangent u in its frame (u projected on the tangent plane)."""
        return np.arctan2(_dot(u, self.b), _dot(u, self.t))

    def field(self, phi: np.ndarray) -> np.ndarray:
        """The unit tangents u = cos φ t + sin φ b."""
        return np.cos(phi)[:, None] * self.t + np.sin(phi)[:, None] * self.b


def tangent_frames(normals: np.ndarray) -> np.ndarray:
    """A unit tangent per normal: the world axis least aligned with n, made orthogonal to it (deterministic)."""
    axes = np.eye(3)[np.argmin(np.abs(normals), axis=1)]
    return _unit(axes - _dot(axes, normals)[:, None] * normals)


def rotate_onto(v: np.ndarray, a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Vectors v rotated by the minimal rotation taking unit a to unit b (Rodrigues; identity where a ∥ b)."""
    axis = np.cross(a, b)
    sin = np.linalg.norm(axis, axis=1)
    cos = _dot(a, b)
    k = axis / np.maximum(sin, 1e-300)[:, None]
    rotated = v * cos[:, None] + np.cross(k, v) * sin[:, None] + k * (_dot(k, v) * (1.0 - cos))[:, None]
    return np.where((sin > 1e-12)[:, None], rotated, v)


def _dot(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    return np.einsum("ij,ij->i", a, b)


def _unit(v: np.ndarray) -> np.ndarray:
    return v / np.maximum(np.linalg.norm(v, axis=-1, keepdims=True), 1e-300)
