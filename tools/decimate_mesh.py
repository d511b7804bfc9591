"""Decimate a mesh for the package data (run once by hand; not a runtime dependency).

    pip install fast-simplification trimesh
    python tools/decimate_mesh.py ../shared/data/stanford-bunny.obj src/reflets/data/meshes/bunny.ply --faces 8000

Normalises the mesh to unit height, resting on y = 0 and centred in x and z, so scenes can place it
with a plain transform.
"""

import argparse

import fast_simplification
import numpy as np
import trimesh


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("source")
    parser.add_argument("output")
    parser.add_argument("--faces", type=int, default=8000)
    args = parser.parse_args()
    mesh = trimesh.load(args.source, force="mesh", process=True)
    ratio = 1.0 - min(1.0, args.faces / len(mesh.faces))
    points, faces = fast_simplification.simplify(mesh.vertices, mesh.faces, target_reduction=ratio)
    lo, hi = points.min(axis=0), points.max(axis=0)
    points = (points - [(lo[0] + hi[0]) / 2, lo[1], (lo[2] + hi[2]) / 2]) / (hi[1] - lo[1])
    out = trimesh.Trimesh(points.astype(np.float32), faces, process=True)
    trimesh.repair.fix_normals(out)
    out.export(args.output)
    print(f"{args.output}: {len(out.vertices)} vertices, {len(out.faces)} triangles")


if __name__ == "__main__":
    main()
