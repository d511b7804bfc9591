"""Write tests/data/gltf/SheenTest: a glTF 2.0 file of KHR_materials_sheen materials (no Khronos sample with a sheen
is in the project's shared assets; reflets' tests need one): three spheres on a felt floor — a red velvet (factors
only), a sheen whose colour and roughness come from textures (an RGBA PNG: stripes of colour in RGB, a roughness
ramp in A, read by both textures, as the extension allows), a sheen under a clear coat — and a camera.

Run from the repository root: ``python tools/make_sheen_test.py`` (deterministic: the same bytes every run).
"""

from __future__ import annotations

import io
import json
from pathlib import Path

import numpy as np
from PIL import Image

OUT = Path(__file__).resolve().parents[1] / "tests" / "data" / "gltf" / "SheenTest"


def sphere(radius: float, centre, rings: int = 24, segments: int = 48):
    """Positions, normals, uvs and triangle indices of a uv sphere (u around, v from the north pole)."""
    v, u = np.meshgrid(np.linspace(0, 1, rings + 1), np.linspace(0, 1, segments + 1), indexing="ij")
    theta, phi = v * np.pi, u * 2 * np.pi
    normal = np.stack([np.sin(theta) * np.sin(phi), np.cos(theta), np.sin(theta) * np.cos(phi)], -1).reshape(-1, 3)
    uv = np.stack([u, v], -1).reshape(-1, 2)
    k = np.arange(rings * segments)
    i, j = k // segments, k % segments
    a, b = i * (segments + 1) + j, (i + 1) * (segments + 1) + j
    faces = np.concatenate([np.stack([a, b, a + 1], -1), np.stack([a + 1, b, b + 1], -1)])
    return normal * radius + np.asarray(centre), normal, uv, faces


def floor(size: float, height: float):
    h = size / 2
    positions = np.array([[-h, height, -h], [h, height, -h], [h, height, h], [-h, height, h]])
    normals = np.tile([0.0, 1.0, 0.0], (4, 1))
    uv = np.array([[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0]])
    return positions, normals, uv, np.array([[0, 2, 1], [0, 3, 2]])


def camera_matrix(eye) -> list[float]:
    """The column-major world matrix of a camera at ``eye`` looking at the origin (glTF cameras look along −z)."""
    z = np.asarray(eye, float) / np.linalg.norm(eye)
    x = np.cross([0.0, 1.0, 0.0], z)
    x /= np.linalg.norm(x)
    m = np.eye(4)
    m[:3, 0], m[:3, 1], m[:3, 2], m[:3, 3] = x, np.cross(z, x), z, eye
    return [round(float(v), 12) for v in m.T.ravel()]


def texture_png() -> bytes:
    """64 × 64 RGBA: four vertical stripes of sheen colour (sRGB), alpha a roughness ramp 0.25 … 1 down the image."""
    colours = np.array([[255, 90, 90], [90, 255, 120], [110, 140, 255], [255, 230, 120]], np.uint8)
    rgb = np.repeat(colours, 16, axis=0)[None].repeat(64, axis=0)
    alpha = np.linspace(64, 255, 64).round().astype(np.uint8)[:, None].repeat(64, axis=1)
    stream = io.BytesIO()
    Image.fromarray(np.dstack([rgb, alpha]), "RGBA").save(stream, "PNG", optimize=False)
    return stream.getvalue()


def main() -> None:
    parts = [sphere(0.25, (-0.6, 0.0, 0.0)), sphere(0.25, (0.0, 0.0, 0.0)), sphere(0.25, (0.6, 0.0, 0.0)),
             floor(2.0, -0.25)]  # fmt: skip
    blob, views, accessors, meshes = bytearray(), [], [], []

    def add(array: np.ndarray, kind: str, target: int, minmax: bool = False) -> int:
        data = np.ascontiguousarray(array, np.uint32 if kind == "SCALAR" else np.float32)
        views.append({"buffer": 0, "byteOffset": len(blob), "byteLength": data.nbytes, "target": target})
        blob.extend(data.tobytes())
        accessor = {"bufferView": len(views) - 1, "componentType": 5125 if kind == "SCALAR" else 5126,
                    "count": len(data) if kind != "SCALAR" else data.size, "type": kind}  # fmt: skip
        if minmax:
            accessor |= {"min": data.min(axis=0).tolist(), "max": data.max(axis=0).tolist()}
        accessors.append(accessor)
        return len(accessors) - 1

    for material, (positions, normals, uv, faces) in enumerate(parts):
        attributes = {"POSITION": add(positions, "VEC3", 34962, minmax=True), "NORMAL": add(normals, "VEC3", 34962),
                      "TEXCOORD_0": add(uv, "VEC2", 34962)}  # fmt: skip
        indices = add(faces.ravel(), "SCALAR", 34963)
        meshes.append({"primitives": [{"attributes": attributes, "indices": indices, "material": material}]})
    sheen_texture = {"index": 0}
    materials = [
        {"name": "velvet", "pbrMetallicRoughness": {"baseColorFactor": [0.3, 0.02, 0.05, 1], "metallicFactor": 0,
                                                    "roughnessFactor": 0.8},
         "extensions": {"KHR_materials_sheen": {"sheenColorFactor": [1.0, 0.3, 0.4], "sheenRoughnessFactor": 0.3}}},
        {"name": "textured sheen", "pbrMetallicRoughness": {"baseColorFactor": [0.1, 0.1, 0.1, 1],
                                                            "metallicFactor": 0, "roughnessFactor": 0.7},
         "extensions": {"KHR_materials_sheen": {"sheenColorFactor": [1, 1, 1], "sheenColorTexture": sheen_texture,
                                                "sheenRoughnessFactor": 1.0,
                                                "sheenRoughnessTexture": sheen_texture}}},
        {"name": "coated sheen", "pbrMetallicRoughness": {"baseColorFactor": [0.6, 0.6, 0.1, 1],
                                                          "metallicFactor": 0, "roughnessFactor": 0.5},
         "extensions": {"KHR_materials_sheen": {"sheenColorFactor": [0.5, 0.5, 1.0], "sheenRoughnessFactor": 0.6},
                        "KHR_materials_clearcoat": {"clearcoatFactor": 0.5, "clearcoatRoughnessFactor": 0.1}}},
        {"name": "felt", "pbrMetallicRoughness": {"baseColorFactor": [0.2, 0.2, 0.2, 1], "metallicFactor": 0,
                                                  "roughnessFactor": 1.0},
         "extensions": {"KHR_materials_sheen": {"sheenColorFactor": [0.8, 0.8, 0.8], "sheenRoughnessFactor": 0.5}}},
    ]  # fmt: skip
    OUT.mkdir(parents=True, exist_ok=True)
    (OUT / "sheen.png").write_bytes(texture_png())
    (OUT / "SheenTest.bin").write_bytes(bytes(blob))
    document = {
        "asset": {"version": "2.0", "generator": "reflets tools/make_sheen_test.py"},
        "extensionsUsed": ["KHR_materials_sheen", "KHR_materials_clearcoat"],
        "scene": 0,
        "scenes": [{"nodes": [0, 1, 2, 3, 4]}],
        "nodes": [*({"mesh": k, "name": materials[k]["name"]} for k in range(4)),
                  {"camera": 0, "name": "camera", "matrix": camera_matrix((0.0, 0.6, 2.0))}],
        "cameras": [{"type": "perspective", "perspective": {"yfov": 0.7, "znear": 0.05, "aspectRatio": 4 / 3}}],
        "meshes": meshes,
        "materials": materials,
        "textures": [{"source": 0, "sampler": 0}],
        "samplers": [{"magFilter": 9729, "minFilter": 9987, "wrapS": 10497, "wrapT": 10497}],
        "images": [{"uri": "sheen.png"}],
        "buffers": [{"byteLength": len(blob), "uri": "SheenTest.bin"}],
        "bufferViews": views,
        "accessors": accessors,
    }  # fmt: skip
    (OUT / "SheenTest.gltf").write_text(json.dumps(document, indent=1) + "\n", "utf-8")
    print(f"wrote {OUT} ({len(blob)} bytes of geometry)")


if __name__ == "__main__":
    main()
