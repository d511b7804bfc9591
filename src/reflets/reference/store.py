"""Stored reference images: a slow ground truth (an hour of CPU for the volumetric bunny at 1024×768) computed
once, kept next to the benchmark results, and used again only while everything that determines it matches —
the scene (mesh files by content, not by path), the sample count, the seed and the reference code's version (not
the number of worker processes: another split of the same samples is an equally good reference).

A stored file holds the masked pixels only, as float16 (relative rounding 5·10⁻⁴, far below any reference's
Monte Carlo noise), with the fingerprint's inputs written out so that a reader can see what it is."""

from __future__ import annotations

import io
import json
import time
from collections.abc import Callable
from pathlib import Path

import numpy as np

from ..cache import content_key, file_digest

#: bump when the volumetric reference's algorithm changes what it converges to (a stored reference stays a valid
#: estimate when only its random streams change — a checkpoint's key adds those: volumetric.SAMPLING_VERSION)
REFERENCE_VERSION = "volumetric-1"


def fingerprint(scene, **params) -> tuple[str, dict]:
    """A digest of the scene and the reference's parameters, and the description it was made from."""
    description = scene.model_dump(mode="json")
    for mesh in description.get("mesh", []):
        if mesh.get("file"):
            mesh["file"] = {"name": Path(mesh["file"]).name, "sha256": file_digest(mesh["file"])}
    for material in description.get("materials", {}).values():
        _textures_by_content(material)
    description = {"scene": description, "version": REFERENCE_VERSION, **params}
    return _digest(description), description


def _textures_by_content(node: dict) -> None:
    """Every texture a material dict names — its own, its ``maps``', a nested material's (a scratched one's base) —
    keyed by its content, like meshes: an image edited in place makes a new reference."""
    for value in node.values():
        if isinstance(value, dict) and value.get("texture") and not isinstance(value["texture"], dict):
            value["texture"] = {"name": Path(value["texture"]).name, "sha256": file_digest(value["texture"])}
        elif isinstance(value, dict):
            _textures_by_content(value)


#: scene keys that do not change the image (the gallery's caption)
PRESENTATION_KEYS = ("title", "description")


def _digest(description: dict) -> str:
    """The digest of what determines the image: the description without its presentation keys, and without
    keys at the default that reproduces how older references were made (a light's ``shadows = true``: traced; a
    point light without a ``spot`` cone; a centred camera with square pixels), so that editing a caption or adding
    such a field keeps stored references valid (one of them took 38 minutes)."""
    scene = {k: v for k, v in description["scene"].items() if k not in PRESENTATION_KEYS}
    scene["mesh"] = [  # a mesh's glTF part: None (added later) for every file mesh made before
        {k: v for k, v in mesh.items() if not (k == "part" and v is None)} for mesh in scene.get("mesh", [])
    ]
    scene["light"] = [  # and a point light's spot cone: None (added later) for every light made before; an
        # environment's ``emitters``: how the GPU renders the map, never what the references see
        {k: v for k, v in light.items()
         if not (k == "shadows" and v is True) and not (k == "spot" and v is None) and k != "emitters"}
        for light in scene.get("light", [])
    ]
    if "camera" in scene:  # a calibrated or orthographic camera's fields, at the pinhole older references had
        scene["camera"] = {k: v for k, v in scene["camera"].items() if (k, v) not in _CENTRED_CAMERA}
    scene["materials"] = {name: _volumetric_material(m) for name, m in scene.get("materials", {}).items()}
    return content_key({**description, "scene": scene}, length=16)


def _volumetric_material(material: dict) -> dict:
    """A material as the volumetric reference sees it: fields left unset (None: added later, optional) dropped,
    in nested materials too (a scratched material's base), and a translucent material's real-time model (its
    diffusion ``profile``, ``single_scattering``) — the path tracer simulates the medium itself."""
    real_time = ("profile", "single_scattering") if material.get("type") == "translucent" else ()
    return {k: _volumetric_material(v) if isinstance(v, dict) and "type" in v else v
            for k, v in material.items() if v is not None and k not in real_time}  # fmt: skip


#: camera fields at their defaults (added after references were stored: the same image)
_CENTRED_CAMERA = (("principal_offset", [0.0, 0.0]), ("pixel_aspect", 1.0), ("near", None), ("far", None),
                   ("projection", "perspective"), ("ortho_height", None))  # fmt: skip


def save(path: Path, image, digest: str, description: dict, seconds: float) -> None:
    from ..outputs import atomic_write

    m = image.mask
    payload = {
        "mask": np.packbits(m.ravel()),
        "shape": np.array(m.shape),
        "image": image.image[m].astype(np.float16),
        "stderr": image.stderr[m].astype(np.float16),
        "spp": np.array(image.spp),
        "fingerprint": np.array(digest),
        "description": np.array(json.dumps(description)),
        "seconds": np.array(seconds),
    }
    buffer = io.BytesIO()
    path.parent.mkdir(parents=True, exist_ok=True)
    np.savez_compressed(buffer, **payload)
    atomic_write(path, buffer.getvalue())


def load(path: Path, digest: str):
    """The stored image and its compute time, or None when the file is missing or made for something else."""
    if not path.exists():
        return None
    with np.load(path) as data:
        if str(data["fingerprint"]) != digest and _digest(json.loads(str(data["description"]))) != digest:
            return None
    return read(path)


def read(path: Path):
    """The stored image and its compute time, whatever it was made for (``load`` checks the fingerprint first)."""
    from .results import VolumetricImage

    with np.load(path) as data:
        shape = tuple(int(v) for v in data["shape"])
        mask = np.unpackbits(data["mask"])[: shape[0] * shape[1]].astype(bool).reshape(shape)
        image = np.zeros((*shape, 3), np.float32)
        stderr = np.zeros((*shape, 3), np.float32)
        image[mask] = data["image"].astype(np.float32)
        stderr[mask] = data["stderr"].astype(np.float32)
        return VolumetricImage(image, stderr, mask, int(data["spp"])), float(data["seconds"])


def stored_or_rendered(path: Path, scene, render: Callable[[], object], **params) -> tuple[object, dict]:
    """The reference stored at ``path`` when its fingerprint matches (scene + ``params``), otherwise
    ``render()``'s, stored there. Returns the image and {"stored": bool, "seconds": compute time,
    "fingerprint": digest, "file": path}."""
    digest, description = fingerprint(scene, **params)
    found = load(path, digest)
    if found is not None:
        image, seconds = found
        return image, {"stored": True, "seconds": seconds, "fingerprint": digest, "file": str(path)}
    print(f"computing the reference stored as {path} (fingerprint {digest}); this is slow, it is kept for next time")
    start = time.perf_counter()
    image = render()
    seconds = time.perf_counter() - start
    save(path, image, digest, description, seconds)
    return image, {"stored": False, "seconds": seconds, "fingerprint": digest, "file": str(path)}
