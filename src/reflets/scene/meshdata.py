"""Triangle mesh arrays shared by procedural shapes, file loaders, the GPU renderer and references."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np


@dataclass(frozen=True)
class MeshData:
    """An indexed triangle mesh with a full shading frame per vertex.

    Attributes
    ----------
    positions : (N, 3) float32
    normals : (N, 3) float32, unit length
    tangents : (N, 4) float32; xyz is a unit tangent along increasing u, orthogonal to the normal;
        w = ±1 is the handedness, so that the bitangent is ``w * cross(normal, tangent)`` (glTF convention).
        Anisotropic BRDFs are oriented by this frame.
    uvs : (N, 2) float32 texture coordinates
    indices : (M, 3) uint32, counter-clockwise seen from the side the normals point to
    uvs1 : (N, 2) float32, a second uv set (glTF's TEXCOORD_1), or None (textures on set 1 read ``uvs``)
    """

    positions: np.ndarray
    normals: np.ndarray
    tangents: np.ndarray
    uvs: np.ndarray
    indices: np.ndarray
    uvs1: np.ndarray | None = None

    @property
    def n_vertices(self) -> int:
        return int(self.positions.shape[0])

    @property
    def n_triangles(self) -> int:
        return int(self.indices.shape[0])

    def transformed(self, matrix: np.ndarray) -> MeshData:
        """Apply a 4×4 affine matrix: positions by M, normals by the inverse transpose, tangents by M."""
        m = np.asarray(matrix, dtype=np.float64)
        lin = m[:3, :3]
        pos = self.positions.astype(np.float64) @ lin.T + m[:3, 3]
        nrm = self.normals.astype(np.float64) @ np.linalg.inv(lin)  # == (inv(lin).T @ n.T).T
        nrm /= np.linalg.norm(nrm, axis=1, keepdims=True)
        tan = self.tangents[:, :3].astype(np.float64) @ lin.T
        # Re-orthogonalise against the new normal (non-uniform scale shears the frame).
        tan -= nrm * np.sum(tan * nrm, axis=1, keepdims=True)
        tan /= np.maximum(np.linalg.norm(tan, axis=1, keepdims=True), 1e-20)
        w = self.tangents[:, 3:4].astype(np.float64) * np.sign(np.linalg.det(lin))
        indices = self.indices if np.linalg.det(lin) > 0 else self.indices[:, ::-1].copy()
        return MeshData(
            positions=pos.astype(np.float32),
            normals=nrm.astype(np.float32),
            tangents=np.concatenate([tan, w], axis=1).astype(np.float32),
            uvs=self.uvs,
            indices=np.ascontiguousarray(indices, dtype=np.uint32),
            uvs1=self.uvs1,
        )

    def subdivided(self, k: int) -> MeshData:
        """Every triangle split into k² congruent triangles, attributes interpolated linearly (normals and
        tangents renormalised). Vertices on shared edges are duplicated per triangle: identical inputs, so a
        per-vertex transform (the Fermat reflection) gives identical outputs and leaves no cracks."""
        if k <= 1:
            return self
        i, j = np.meshgrid(np.arange(k + 1), np.arange(k + 1), indexing="ij")
        keep = (i + j) <= k
        i, j = i[keep], j[keep]
        w = np.stack([k - i - j, i, j], axis=1) / k  # (P, 3) barycentrics of the grid points
        slot = -np.ones((k + 1, k + 1), dtype=np.int64)
        slot[i, j] = np.arange(len(i))
        a, b = np.meshgrid(np.arange(k), np.arange(k), indexing="ij")
        up = (a + b) <= k - 1
        down = (a + b) <= k - 2
        local = np.concatenate(
            [
                np.stack([slot[a[up], b[up]], slot[a[up] + 1, b[up]], slot[a[up], b[up] + 1]], axis=1),
                np.stack([slot[a[down] + 1, b[down]], slot[a[down] + 1, b[down] + 1], slot[a[down], b[down] + 1]], 1),
            ]
        )
        corners = self.indices.astype(np.int64)  # (T, 3)

        def lerp(attr: np.ndarray) -> np.ndarray:
            return np.einsum("pc,tcd->tpd", w, attr.astype(np.float64)[corners]).reshape(-1, attr.shape[1])

        pos, nrm, tan, uv = lerp(self.positions), lerp(self.normals), lerp(self.tangents[:, :3]), lerp(self.uvs)
        nrm /= np.maximum(np.linalg.norm(nrm, axis=1, keepdims=True), 1e-20)
        tan /= np.maximum(np.linalg.norm(tan, axis=1, keepdims=True), 1e-20)
        hand = np.repeat(self.tangents[corners[:, 0], 3], len(w))[:, None]
        indices = (np.arange(len(corners))[:, None, None] * len(w) + local[None]).reshape(-1, 3)
        return MeshData(
            positions=pos.astype(np.float32),
            normals=nrm.astype(np.float32),
            tangents=np.concatenate([tan, hand], axis=1).astype(np.float32),
            uvs=uv.astype(np.float32),
            indices=np.ascontiguousarray(indices, dtype=np.uint32),
            uvs1=None if self.uvs1 is None else lerp(self.uvs1).astype(np.float32),
        )

    @property
    def uv_sets(self) -> np.ndarray:
        """(N, 4): both uv sets side by side (the first twice when there is no second)."""
        return np.concatenate([self.uvs, self.uvs if self.uvs1 is None else self.uvs1], axis=1)

    def interleaved(self) -> np.ndarray:
        """Vertex buffer layout for the GPU: position 3f, normal 3f, tangent 4f, uv 2f, uv1 2f (56 bytes)."""
        return np.ascontiguousarray(
            np.concatenate([self.positions, self.normals, self.tangents, self.uv_sets], axis=1), dtype=np.float32
        )


def merged(parts: list[MeshData]) -> MeshData:
    """Meshes as one, each part's indices offset; a second uv set where any part has one (a part without it gives
    its first set twice, as :attr:`MeshData.uv_sets` does)."""
    offsets = np.cumsum([0] + [p.n_vertices for p in parts[:-1]])
    return MeshData(
        positions=np.concatenate([p.positions for p in parts]),
        normals=np.concatenate([p.normals for p in parts]),
        tangents=np.concatenate([p.tangents for p in parts]),
        uvs=np.concatenate([p.uvs for p in parts]),
        indices=np.concatenate([p.indices + np.uint32(o) for p, o in zip(parts, offsets, strict=True)]),
        uvs1=np.concatenate([p.uv_sets[:, 2:] for p in parts]) if any(p.uvs1 is not None for p in parts) else None,
    )
