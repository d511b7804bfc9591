"""The potential highlight curves of a scene's mesh (001, §4.2): ℓ per vertex for the scene's camera and its
first point or directional light, on the mesh's own orientation field (its tangents: the direction of
increasing u, what anisotropic BRDFs are oriented by). Behind ``reflets highlights``."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from ..errors import ARRAY_READ_ERRORS, ArgumentError
from ..quantities import MAX_MAGNITUDE
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


def checked_mesh(scene, index: int, editing: bool = False):
    """``mesh_data`` of ``scene.mesh[index]``, the index in range; ``editing``: its material one with an
    orientation field (an edited field is written for it: an isotropic material has none to replace)."""
    from ..brdf.base import Oriented
    from ..scene.geometry import mesh_data

    count = len(scene.mesh)
    if isinstance(index, bool) or not isinstance(index, int | np.integer) or not 0 <= index < count:
        allowed = f"0..{count - 1}" if count else "none (the scene has no mesh)"
        raise ArgumentError(f"no mesh[{index}]; allowed: {allowed}", field="--mesh")
    material = scene.materials.get(scene.mesh[index].material)
    if editing and not isinstance(material, Oriented):
        kind = f"'{scene.mesh[index].material}' ({material.type})" if material is not None else "none"
        raise ArgumentError(
            f"mesh[{index}]'s material {kind} has no orientation field to edit; an anisotropic one (ward, "
            "ashikhmin_shirley, microfacet, scratched) has",
            field="--mesh",
        )
    return mesh_data(scene, int(index))


def _checked_light(scene, light: int | None) -> int:
    """The index of the light that makes the highlights: ``light``, or the first point or directional one."""
    lights = [i for i, lt in enumerate(scene.light) if lt.type in ("point", "directional")]
    if light is None:
        if not lights:
            raise ArgumentError("the scene has no point or directional light to make highlights", field="--light")
        return lights[0]
    if light not in lights:
        allowed = ", ".join(map(str, lights)) or "none in this scene"
        count = len(scene.light)
        why = f"it is a {scene.light[light].type} light" if 0 <= light < count else f"the scene has {count} light(s)"
        raise ArgumentError(
            f"light[{light}] is not a point or directional light ({why}); allowed: {allowed}",
            field="--light",
        )
    return light


def _prepared(scene, index: int, light: int | None, editing: bool = False):
    """(mesh data, welded surface, the welded index of each vertex, half vectors, the field's tangents)."""
    data = checked_mesh(scene, index, editing)
    light = _checked_light(scene, light)
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


#: the most bytes a --targets array may take unpacked per value it needs (complex256's 32, the widest NumPy
#: number): a small compressed file cannot unpack a huge array before its shape is checked
TARGET_BYTES_PER_VALUE = 32
#: the first bytes of a .npz (a zip archive) and of a .npy
_ZIP_MAGIC, _NPY_MAGIC = b"PK\x03\x04", b"\x93NUMPY"


def check_targets(ell, mask, count: int, *, file: str | Path | None = None, field: str = "--targets"):
    """``ell`` (count, 3) of real finite numbers (a tangent direction each; a row of norm ≤ NO_TARGET: no target,
    as the solver reads it), and ``mask`` (count,) bool that selects at least one vertex with a target — or one
    ArgumentError."""
    ell, mask = np.asarray(ell), np.asarray(mask)

    def refuse(message: str):
        return ArgumentError(message, file=file, field=field)

    if ell.shape != (count, 3) or mask.shape != (count,):
        raise refuse(
            f"'ell' must be ({count}, 3) and 'mask' ({count},), one row per vertex of the mesh; got {ell.shape} and "
            f"{mask.shape}"
        )
    if ell.dtype.kind not in "fiu":
        raise refuse(f"'ell' holds {ell.dtype} values; expected real numbers (float)")
    if mask.dtype.kind != "b":
        raise refuse(f"'mask' holds {mask.dtype} values; expected bool (True: a vertex the solve may change)")
    bad = ~(np.abs(ell) <= MAX_MAGNITUDE).all(axis=1)  # NaN too
    if bad.any():
        first, count_bad = int(np.argmax(bad)), int(bad.sum())
        raise refuse(
            f"'ell' row {first} is not finite or beyond ±{MAX_MAGNITUDE:g} ({count_bad} such row(s)); expected "
            "finite numbers (a direction each)"
        )
    if not mask.any():
        raise refuse("'mask' selects no vertex; expected at least one True (a vertex the solve may change)")
    from .solver import NO_TARGET

    ell = ell.astype(np.float64)
    if not (np.linalg.norm(ell[mask], axis=1) > NO_TARGET).any():
        raise refuse(f"'ell' is zero (a norm ≤ {NO_TARGET:g}) on every vertex 'mask' selects: no target to solve "
                     "for; give one non-zero row")  # fmt: skip
    return ell, mask


def load_targets(path: str | Path, count: int, field: str = "--targets") -> tuple[np.ndarray, np.ndarray]:
    """``ell`` and ``mask`` of an .npz (np.savez) for a mesh of ``count`` vertices, checked (:func:`check_targets`);
    no pickles, and each array's unpacked size bounded before it is read."""
    path = Path(path)
    try:
        with path.open("rb") as f:
            magic = f.read(6)
        if not magic.startswith(_ZIP_MAGIC):
            what = "a .npy (one array)" if magic == _NPY_MAGIC else "not an .npz"
            raise ArgumentError(
                f"{what}; expected an .npz (np.savez) with arrays 'ell' (V, 3) and 'mask' (V,)", file=path, field=field
            )
        with np.load(path, allow_pickle=False) as data:
            missing = [key for key in ("ell", "mask") if key not in data.files]
            if missing:
                raise ArgumentError(
                    f"no array {missing[0]!r}; the .npz holds {sorted(data.files)}, expected 'ell' and 'mask'",
                    file=path,
                    field=field,
                )
            for key, values in (("ell", 3 * count), ("mask", count)):
                size, limit = data.zip.getinfo(f"{key}.npy").file_size, TARGET_BYTES_PER_VALUE * values + 4096
                if size > limit:
                    raise ArgumentError(
                        f"'{key}' unpacks to {size:,} bytes, more than a mesh of {count} vertices needs ({limit:,})",
                        file=path,
                        field=field,
                    )
            ell, mask = data["ell"], data["mask"]
    except FileNotFoundError:
        raise ArgumentError("file not found", file=path, field=field) from None
    except (*ARRAY_READ_ERRORS, KeyError) as exc:
        raise ArgumentError(f"not a readable .npz ({exc})", file=path, field=field) from None
    return check_targets(ell, mask, count, file=path, field=field)


def edit_highlights(
    scene, index: int, targets: np.ndarray, mask: np.ndarray, light: int | None = None, k: int = 2, iterations: int = 20
) -> dict[str, np.ndarray]:
    """Solve the orientation field of ``scene.mesh[index]`` on the ``mask`` vertices (V,) so that its highlight
    tangents match ``targets`` (V, 3, world space as ``mesh_highlights`` writes them; zero rows: no target),
    starting from the mesh's current field. Returns ``u`` (V, 3) in the mesh's own coordinates and vertex order
    (what a material's ``orientation`` file holds) and ``energy`` (the start, then each iteration)."""
    from .solver import HighlightProblem, check_iterations, solve

    iterations = check_iterations(iterations)
    data, mesh, inverse, h, u = _prepared(scene, index, light, editing=True)
    targets, mask = check_targets(targets, mask, data.n_vertices)
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
    from ..outputs import atomic_write

    path = Path(path)
    if path.suffix.lower() != ".npz":
        raise ArgumentError(f"the output is an .npz file, got '{path.name}'", file=path)
    import io

    buffer = io.BytesIO()
    np.savez(buffer, **result)
    atomic_write(path, buffer.getvalue())
    return path
