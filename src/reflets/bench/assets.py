"""`reflets bench assets`: real glTF assets (the DamagedHelmet, the WaterBottle) — frame times against Google
Filament in the same run, and the error against ground truth.

- **Time**, at 640 × 480 and 1280 × 720, under the studio map (Poly Haven's brown_photostudio_02, the map reflets
  ships) plus one point light, the file's own camera framing: prepare (file decoded, textures' mips built and
  uploaded, programs compiled, first frame read back) and the median orbit frame of a persistent
  ``reflets.Renderer`` (camera set, frame rendered, read back into NumPy), textured and with every texture
  dropped (factors kept); and Filament through ``filly`` on the same file, camera path, map and light, in a
  separate process in the same run (render, ``finish()``, read back: the same work). Wall clock around a finished
  frame, medians (llvmpipe's timer queries mean nothing).
- **Error**: the GPU against the NumPy reference under a point and a directional light with shadows (no
  environment), 320 × 240, relative MSE on 4 × 4-pixel block means over the asset's pixels — the sub-pixel
  sparkle of sharp highlights on normal maps is left to the pixel filter (``asset_error``; shared by
  tests/reference/test_textured_reference.py and ``python tools/asset_accuracy.py``).
"""

from __future__ import annotations

import json
import statistics
import subprocess
import sys
import tempfile
import time
import warnings
from pathlib import Path

import numpy as np

from ..api import render
from ..reference import reference
from ..reference.montecarlo import MAX_ADAPTIVE_SPP
from ..scene.assets import asset_path
from ..scene.model import DirectionalLight, PointLight, Scene
from .filament import ensure_filly

#: the lights of the comparison (radiometric; the assets are about a unit across, the camera on +z)
LIGHTS = (
    PointLight(type="point", position=(1.5, 2.0, 3.0), intensity=(20.0, 20.0, 20.0)),
    DirectionalLight(type="directional", direction=(-0.3, -0.5, -1.0), irradiance=(3.0, 3.0, 3.0)),
)
BLOCK = 4
#: the reference refines pixels noisier than this (relative standard error): a point light's highlight in a
#: near-mirror texel is a sub-pixel spike that a fixed 16 samples hit or miss (the helmet's visor: ±55 %)
ADAPTIVE_ERROR = 0.05
#: ... with up to this many samples a pixel, the most the reference allows (a glint a millionth of a pixel wide
#: needs them)
ADAPTIVE_SPP = MAX_ADAPTIVE_SPP


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


def asset_error(scene: Scene, size: tuple[int, int], spp: int = 16, reference_spp: int = 16,
                adaptive_error: float = ADAPTIVE_ERROR) -> dict[str, float]:  # fmt: skip
    """relative MSE of the GPU image (``spp`` = s² supersampling) against the NumPy reference (``reference_spp``
    samples over the pixel box) on block means over blocks the asset covers entirely; and the images' means."""
    gpu = render(scene, size=size, spp=spp)
    ref = reference(scene, spp=reference_spp, size=size, pixel="box", progress=False, adaptive_error=adaptive_error,
                    adaptive_spp=ADAPTIVE_SPP)  # fmt: skip
    covered = np.any(render(scene, size=size, method="position") != 0, axis=2)
    inside = block_means(covered[..., None].astype(float))[..., 0] == 1
    g, r = block_means(gpu)[inside], block_means(ref.image)[inside]
    return {
        "relmse": float(np.mean((g - r) ** 2) / max(np.mean(r**2), 1e-30)),
        "blocks": int(inside.sum()),
        "gpu_mean": float(g.mean()) if g.size else 0.0,
        "reference_mean": float(r.mean()) if r.size else 0.0,
    }


#: the benchmark's assets (shipped with reflets for the gallery, with their licences)
ASSET_FILES = {
    "DamagedHelmet": asset_path("DamagedHelmet/DamagedHelmet.glb"),
    "WaterBottle": asset_path("WaterBottle/WaterBottle.gltf"),
}
#: the timing's point light, in units of the asset's bounding-sphere radius from its centre
POINT_LIGHT_OFFSET = (1.5, 2.0, 3.0)


def _timing_scene(path: Path, size: tuple[int, int]) -> Scene:
    """The file's scene under the studio map (scene_from_asset's default) plus one point light over its shoulder."""
    from ..scene import load_scene
    from ..scene.geometry import mesh_data

    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        scene = load_scene(path)
    points = np.concatenate([mesh_data(scene, i).positions for i in range(len(scene.mesh))]).astype(np.float64)
    centre, radius = points.mean(axis=0), float(np.linalg.norm(np.ptp(points, axis=0))) / 2.0
    light = PointLight(type="point", position=tuple(map(float, centre + radius * np.array(POINT_LIGHT_OFFSET))),
                       intensity=(3.0 * radius**2,) * 3)  # fmt: skip
    camera = scene.camera.model_copy(update={"size": size})
    return scene.model_copy(update={"light": [*scene.light, light], "camera": camera})


def _orbit(scene: Scene, frames: int) -> list[tuple[float, float, float]]:
    """Camera positions on an arc of ±0.5 rad about the vertical through the look-at point."""
    eye, target = np.asarray(scene.camera.position, float), np.asarray(scene.camera.look_at, float)
    offset = eye - target
    radius, start = float(np.hypot(offset[0], offset[2])), float(np.arctan2(offset[0], offset[2]))
    return [(float(target[0] + radius * np.sin(a)), float(eye[1]), float(target[2] + radius * np.cos(a)))
            for a in start + np.linspace(-0.5, 0.5, frames)]  # fmt: skip


#: reflets with the features Filament (filly's defaults) renders a glTF asset with: trilinear texture filtering
#: (no anisotropy: glTF samplers have none) and the environment map unoccluded by the scene (no shadow lookups);
#: the point light's shadows as Filament's are set (:func:`with_point_shadows`)
AS_FILAMENT = {"texture_anisotropy": 1.0, "environment_occlusion": "none"}


def with_point_shadows(scene: Scene, shadows: bool) -> Scene:
    """The scene with its point lights casting shadows or not (filly's default: no shadows at all)."""
    lights = [light.model_copy(update={"shadows": shadows}) if light.type == "point" else light
              for light in scene.light]  # fmt: skip
    return scene.model_copy(update={"light": lights})


def _reflets_times(scene: Scene, positions, **params) -> dict:
    import reflets

    started = time.perf_counter()
    with reflets.Renderer(scene, **params) as renderer:
        renderer.render()
        prepare_ms = 1e3 * (time.perf_counter() - started)
        frames, first = [], None
        for position in positions:
            t = time.perf_counter()
            renderer.set_camera(position=position)
            image = renderer.render()
            frames.append(1e3 * (time.perf_counter() - t))
            first = image if first is None else first
    return {"prepare_ms": prepare_ms, "frame_ms": frames, "image": first}


def _filament_times(scene: Scene, path: Path, positions, image: Path | None, shadows: bool) -> dict:
    """Filament on the same file, camera path, map and point light (reflets.bench.filament, its own process)."""
    ensure_filly()
    environment = next(light for light in scene.light if light.type == "environment")
    point = next(light for light in scene.light if light.type == "point")
    job = {
        "asset": str(path), "size": list(scene.camera.size), "fov_y": scene.camera.fov_y,
        "look_at": list(scene.camera.look_at), "positions": [list(p) for p in positions],
        "environment": str(environment.file), "image": str(image) if image is not None else None,
        "point_light": {"position": list(point.position), "intensity": list(point.intensity)}, "shadows": shadows,
    }  # fmt: skip
    with tempfile.TemporaryDirectory() as folder:
        job_file = Path(folder) / "job.json"
        job_file.write_text(json.dumps(job), "utf-8")
        done = subprocess.run([sys.executable, "-m", "reflets.bench.filament", str(job_file)], capture_output=True,
                              text=True, timeout=1800)  # fmt: skip
    if done.returncode != 0:
        raise RuntimeError(f"Filament (filly) failed: {(done.stderr or done.stdout).strip()[-600:]}")
    return json.loads(done.stdout.strip().splitlines()[-1])


def _cell(row: dict, label: str) -> str:
    return f"{row[label]['frame_ms_median']:.1f} ({row[label]['frame_ms_p95']:.1f}) ms"


def _ratio(row: dict, ours: str, theirs: str) -> str:
    return f"{row[ours]['frame_ms_median'] / row[theirs]['frame_ms_median']:.2f}×"


def bench_assets(quick: bool, out_dir) -> tuple[dict, str]:
    from ..imageio import write_image

    out_dir = Path(out_dir)
    sizes = [(160, 120)] if quick else [(640, 480), (1280, 720)]
    frames = 4 if quick else 30
    rows, errors = [], {}
    for name, path in ASSET_FILES.items():
        for size in sizes:
            scene = _timing_scene(path, size)
            positions = _orbit(scene, frames)
            textured = _reflets_times(scene, positions)
            matched = _reflets_times(with_point_shadows(scene, False), positions, **AS_FILAMENT)
            matched_shadows = _reflets_times(scene, positions, **AS_FILAMENT)
            untextured = _reflets_times(without_textures(scene), positions)
            stem = f"assets_{name}_{size[0]}x{size[1]}"
            shown = size == sizes[0]  # the first orbit frame of each renderer, at the first size: to look at
            images = [result.pop("image") for result in (textured, matched, matched_shadows, untextured)]
            if shown:
                write_image(out_dir / f"{stem}_reflets.png", images[0])
            filament = _filament_times(scene, path, positions, out_dir / f"{stem}_filament.png" if shown else None,
                                       shadows=False)  # fmt: skip
            filament_shadows = _filament_times(scene, path, positions, None, shadows=True)
            row = {"asset": name, "size": list(size), "frames": frames}
            results = (("reflets", textured), ("reflets_as_filament", matched),
                       ("reflets_as_filament_shadows", matched_shadows), ("reflets_untextured", untextured),
                       ("filament", filament), ("filament_shadows", filament_shadows))  # fmt: skip
            for label, result in results:
                times = result["frame_ms"]
                row[label] = {"prepare_ms": result["prepare_ms"], "frame_ms_median": statistics.median(times),
                              "frame_ms_p95": float(np.percentile(times, 95))}  # fmt: skip
            row["filly"] = filament["filly"]
            rows.append(row)
            print(f"{name} {size[0]}×{size[1]}: reflets {row['reflets']['frame_ms_median']:.1f} ms (as Filament "
                  f"{row['reflets_as_filament']['frame_ms_median']:.1f}, with shadows "
                  f"{row['reflets_as_filament_shadows']['frame_ms_median']:.1f}), Filament "
                  f"{row['filament']['frame_ms_median']:.1f} (with shadows "
                  f"{row['filament_shadows']['frame_ms_median']:.1f}) ms a frame", flush=True)  # fmt: skip
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            from ..scene import load_scene

            lit = lit_for_comparison(load_scene(path))
        errors[name] = asset_error(lit, (160, 120) if quick else (320, 240))
    lines = [
        "# Real assets: reflets against Filament, and against ground truth",
        "",
        "Orbit frames of a persistent renderer (camera set, frame rendered and read back into NumPy), median and "
        f"95th percentile of {frames}; Filament through filly {rows[0]['filly']} in its own process, same run, same "
        "file, camera path, studio map and point light. Prepare: file to first frame read back.",
        "",
        "*as Filament*: reflets with the features filly renders the asset with — trilinear texture filtering "
        f"(`texture_anisotropy = {AS_FILAMENT['texture_anisotropy']:g}`: glTF samplers have no anisotropy), the map "
        "unoccluded by the scene (`environment_occlusion = \"none\"`) and no shadows (filly's default); *with "
        "shadows*: the same, and the point light casting shadows in both renderers (Filament: `scene.shadows`, "
        "`light.casts_shadows`); *reflets*: its defaults (16× anisotropic filtering, the scene's occlusion of the "
        "map from 32 shadow views, the point light's shadows); *untextured*: the defaults, every texture dropped "
        "(factors kept).",
        "",
        "| asset | size | reflets prepare | reflets frame (p95) | untextured | as Filament (p95) | Filament (p95) | "
        "ratio | as Filament, shadows | Filament, shadows | ratio | Filament prepare |",
        "|---|---|---|---|---|---|---|---|---|---|---|---|",
    ]
    for r in rows:
        lines.append(
            f"| {r['asset']} | {r['size'][0]}×{r['size'][1]} | {r['reflets']['prepare_ms']:.0f} ms | "
            f"{_cell(r, 'reflets')} | {r['reflets_untextured']['frame_ms_median']:.1f} ms | "
            f"{_cell(r, 'reflets_as_filament')} | {_cell(r, 'filament')} | "
            f"{_ratio(r, 'reflets_as_filament', 'filament')} | {_cell(r, 'reflets_as_filament_shadows')} | "
            f"{_cell(r, 'filament_shadows')} | "
            f"{_ratio(r, 'reflets_as_filament_shadows', 'filament_shadows')} | {r['filament']['prepare_ms']:.0f} ms |"
        )
    lines += [
        "",
        "## Against ground truth",
        "",
        "Point + directional light with shadows, no environment; the GPU at 16 spp against the NumPy reference (16 "
        f"samples a pixel refined to {ADAPTIVE_ERROR:.0%} relative standard error); relative MSE on 4 × 4-pixel "
        "block means over the asset's pixels.",
        "",
        "| asset | relative MSE | blocks | GPU mean | reference mean |",
        "|---|---|---|---|---|",
        *[f"| {n} | {e['relmse']:.2g} | {e['blocks']} | {e['gpu_mean']:.4f} | {e['reference_mean']:.4f} |"
          for n, e in errors.items()],
    ]  # fmt: skip
    return {"timing": rows, "error": errors}, "\n".join(lines)
