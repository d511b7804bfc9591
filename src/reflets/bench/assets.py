"""Real assets against ground truth (issue 28): the GPU renderer and the NumPy reference on the same textured
glTF file, under a point and a directional light with shadows (no environment), compared on 4×4-pixel block means
over the asset's pixels — the sub-pixel sparkle of sharp highlights on normal maps is left to the pixel filter.

Shared by tests/reference/test_textured_reference.py and ``python tools/asset_accuracy.py`` (docs/assets.md's
table); the full ``reflets bench assets`` (prepare and frame times against Filament) is not written yet."""

from __future__ import annotations

import numpy as np

from ..api import render
from ..reference import reference
from ..scene.model import DirectionalLight, PointLight, Scene

#: the lights of the comparison (radiometric; the assets are about a unit across, the camera on +z)
LIGHTS = (
    PointLight(type="point", position=(1.5, 2.0, 3.0), intensity=(20.0, 20.0, 20.0)),
    DirectionalLight(type="directional", direction=(-0.3, -0.5, -1.0), irradiance=(3.0, 3.0, 3.0)),
)
BLOCK = 4


def lit_for_comparison(scene: Scene) -> Scene:
    """The scene under :data:`LIGHTS` on a black background."""
    return scene.model_copy(update={"light": list(LIGHTS), "background": (0.0, 0.0, 0.0)})


def without_textures(scene: Scene, keep: tuple[str, ...] = ()) -> Scene:
    """The scene with every material texture dropped but those named in ``keep`` (their factors stay)."""
    materials = {
        name: m.model_copy(update={f: None for f in type(m).model_fields if f.endswith("_texture") and f not in keep})
        for name, m in scene.materials.items()
    }
    return scene.model_copy(update={"materials": materials})


def block_means(image: np.ndarray) -> np.ndarray:
    h, w = image.shape[:2]
    return image.reshape(h // BLOCK, BLOCK, w // BLOCK, BLOCK, -1).mean(axis=(1, 3))


def asset_error(scene: Scene, size: tuple[int, int], spp: int = 16, reference_spp: int = 16) -> dict[str, float]:
    """relative MSE of the GPU image (``spp`` = s² supersampling) against the NumPy reference (``reference_spp``
    samples over the pixel box) on block means over blocks the asset covers entirely; and the images' means."""
    gpu = render(scene, size=size, spp=spp)
    ref = reference(scene, spp=reference_spp, size=size, pixel="box", progress=False)
    covered = np.any(render(scene, size=size, method="position") != 0, axis=2)
    inside = block_means(covered[..., None].astype(float))[..., 0] == 1
    g, r = block_means(gpu)[inside], block_means(ref.image)[inside]
    return {
        "relmse": float(np.mean((g - r) ** 2) / max(np.mean(r**2), 1e-30)),
        "blocks": int(inside.sum()),
        "gpu_mean": float(g.mean()) if g.size else 0.0,
        "reference_mean": float(r.mean()) if r.size else 0.0,
    }
