"""The highlight-editing demo's data: the spun plate's concentric field (data/fields/spun_plate.npz) and the
field after the strokes of data/strokes/spun_plate_bend.json (data/fields/spun_plate_bent.npz), in float32.

Run: .venv/bin/python tools/make_highlight_edit.py (the tests check that the shipped files are what it makes).
"""

from __future__ import annotations

import tomllib

import numpy as np

import reflets
from reflets.demo import scene_path
from reflets.editing.strokes import apply_strokes, load_strokes
from reflets.scene.geometry import mesh_data

DATA = scene_path("53_spun_plate.toml").parent.parent


def spun_field() -> np.ndarray:
    """Concentric circles about the plate's centre (its own coordinates: the plane y = 0)."""
    path = scene_path("53_spun_plate.toml")
    data = tomllib.loads(path.read_text())
    del data["materials"]["spun"]["orientation"]  # the plate alone (the field may not exist yet)
    p = mesh_data(reflets.load_dict(data, base_dir=path.parent), 0).positions.astype(np.float64)
    u = np.stack([-p[:, 2], np.zeros(len(p)), p[:, 0]], axis=1) + [1e-3, 0.0, 0.0]  # defined at the centre too
    return (u / np.linalg.norm(u, axis=1, keepdims=True)).astype(np.float32)


def bent_field() -> np.ndarray:
    scene = reflets.load_scene(scene_path("53_spun_plate.toml"))
    strokes = load_strokes(DATA / "strokes" / "spun_plate_bend.json")
    return apply_strokes(scene, 0, strokes)["u"].astype(np.float32)


if __name__ == "__main__":
    np.savez(DATA / "fields" / "spun_plate.npz", u=spun_field())
    np.savez(DATA / "fields" / "spun_plate_bent.npz", u=bent_field())
    print(f"wrote {DATA / 'fields'}")
