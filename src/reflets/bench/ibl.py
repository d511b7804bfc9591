"""`reflets bench ibl`: environment lighting from real HDR maps against the path-traced reference, its cost against
a point light, and Filament on the same spheres.

- **Error**: a sphere alone under each map — the project's sky, Poly Haven's kloppenheim_05 (an unclipped sun)
  and brown_photostudio_02 (a studio) — for the four GGX spheres of issue 29 (α 0.05, 0.15, 0.3, 0.6; F = 0.9,
  separable Smith: ``fresnel = "none"``, ``masking = "separable"``) and one material of every analytic model of
  the BRDF library (and the glTF material): relative MSE over the sphere less a 1-pixel rim against the NumPy
  reference at ``SPP`` samples a pixel, with the noise that reference carries (the mean of its squared standard
  error over the same weights: what its own noise adds to the error). reflets renders as by default: the map's
  compact emitters as lights, the rest prefiltered (``reflets.scene.map_emitters``).
- **Cost**: ``env_ms`` (that frame) and ``point_ms`` (the same sphere under one point light, shadowed as reflets
  shadows it: a sphere alone cannot shadow itself, its lookups are compiled out for both lights), medians of
  persistent ``Renderer`` frames at ``TIMING_SIZE``, interleaved in one run, and the median ratio of frames drawn
  in the same round.
- **Filament** (filly, its own process, the same run): glTF metal spheres (base colour 0.9, roughness √α — the
  GGX spheres as Filament's material model has them: Schlick's Fresnel, height-correlated Smith) under the same
  maps, the error of Filament and of reflets against the reference of that material, and both frame times.
  filly reads 8-bit sRGB back: its linear image is rebuilt from exposure brackets (``reflets.bench.filament``),
  checked first on a mirror sphere under a uniform map (it must read the map's radiance).
"""

from __future__ import annotations

import json
import math
import statistics
import subprocess
import sys
import tempfile
import time
from importlib import resources
from pathlib import Path

import numpy as np

#: the maps: the project's sky and two of Poly Haven's (shipped at 1k, README next to them)
MAPS = {"sky": "sky.hdr", "kloppenheim_05": "kloppenheim_05_1k.hdr", "brown_photostudio_02": "studio.hdr"}
GGX = {"type": "microfacet", "fresnel": "none", "specular": [0.9, 0.9, 0.9], "masking": "separable"}
#: issue 29's spheres and their bounds (relative MSE)
SPHERES = {f"GGX α={a:g}": ({**GGX, "alpha": a}, 0.05 if a < 0.1 else 0.03) for a in (0.05, 0.15, 0.3, 0.6)}
#: one material of every analytic model of the library
LIBRARY = {
    "Lambert": {"type": "lambert", "albedo": [0.7, 0.6, 0.5]},
    "plastic (GGX α=0.2 + diffuse)": {"type": "microfacet", "alpha": 0.2, "fresnel": "dielectric", "eta": 1.5,
                                      "diffuse": [0.5, 0.1, 0.1]},
    "gold (GGX α=0.1, conductor)": {"type": "microfacet", "alpha": 0.1, "fresnel": "conductor",
                                    "eta": [0.2, 0.9, 1.1], "k": [3.9, 2.4, 2.2]},
    "Phong e=50 (normalised)": {"type": "phong", "kd": [0.3] * 3, "ks": [0.5] * 3, "exponent": 50,
                                "normalized": True},
    "Blinn-Phong e=100 (normalised)": {"type": "blinn_phong", "kd": [0.3] * 3, "ks": [0.5] * 3, "exponent": 100,
                                       "normalized": True},
    "Ward α=0.15": {"type": "ward", "kd": [0.3] * 3, "ks": [0.3] * 3, "alpha": 0.15},
    "Ashikhmin-Shirley n=100": {"type": "ashikhmin_shirley", "rd": [0.3] * 3, "rs": [0.3] * 3, "nu": 100,
                                "nv": 100},
    "Lafortune (one lobe, e=40)": {"type": "lafortune", "kd": [0.3] * 3,
                                   "lobes": [{"c": [-1.0, -1.0, 1.0], "scale": [0.5] * 3, "exponent": 40}]},
    "glTF dielectric (roughness 0.4)": {"type": "gltf", "base_color": [0.6, 0.3, 0.2, 1.0], "metallic": 0.0,
                                        "roughness": 0.4},
}  # fmt: skip
#: Filament's spheres: the GGX spheres as glTF metal
FILAMENT = {f"glTF metal α={a:g}": {"base_color": [0.9, 0.9, 0.9, 1.0], "metallic": 1.0, "roughness": math.sqrt(a)}
            for a in (0.05, 0.15, 0.3, 0.6)}  # fmt: skip
POINT = {"type": "point", "position": [2.0, 3.0, 2.0], "intensity": [10, 10, 10]}
SIZE, TIMING_SIZE, SPP, FRAMES = (96, 72), (320, 240), 4096, 15
CAMERA = {"position": [0.0, 0.3, 4.0], "look_at": [0.0, 0.0, 0.0], "fov_y": 35.0}


def map_path(name: str) -> str:
    return str(resources.files("reflets").joinpath("data", "environments", MAPS[name]))


def sphere_scene(material: dict, hdr: str | None, size, light: dict | None = None):
    """A unit sphere under the map alone (or under ``light`` on black)."""
    import reflets

    lights = [light] if light is not None else [{"type": "environment", "file": hdr}]
    return reflets.load_dict({"camera": {**CAMERA, "size": list(size)}, "materials": {"m": material},
                              "mesh": [{"shape": "sphere", "radius": 1.0, "material": "m"}], "light": lights,
                              "background": [0.0, 0.0, 0.0]})  # fmt: skip


def sphere_mask(scene) -> np.ndarray:
    """The sphere's pixels less a 1-pixel rim (the silhouette's pixels mix the sphere and the background)."""
    from scipy.ndimage import binary_erosion

    from ..api import render

    return binary_erosion(np.any(render(scene, method="position") != 0, axis=-1))


def errors(scene, images: dict[str, np.ndarray], spp: int, mask: np.ndarray) -> tuple[dict[str, float], float,
                                                                                       dict[str, float]]:
    """relMSE of each image against the scene's reference over the sphere less its rim, the reference's own noise
    (mean of stderr² / (ref² + ε), relmse's weights), and each image's median pixel over the reference's (the sum
    of its channels): how much brighter or darker it is overall."""
    from ..metrics import masked_relmse
    from ..reference import reference

    result = reference(scene, spp=spp, progress=False)
    ref = result.image[mask]
    noise = float(np.mean(np.square(result.stderr[mask]) / (np.square(ref) + 1e-2)))
    found = {name: masked_relmse(image, result.image, mask) for name, image in images.items()}
    level = {name: float(np.median(image[mask].sum(-1) / np.maximum(ref.sum(-1), 1e-12))) for name, image in
             images.items()}  # fmt: skip
    return found, noise, level


def frame_times(scenes: dict, frames: int) -> dict[str, list[float]]:
    """Frame times (ms) of each scene, one persistent ``Renderer`` each, frames interleaved (round k draws every
    scene's frame k: a ratio of the same round's frames sees the same machine)."""
    import reflets

    renderers = {}
    try:
        for name, scene in scenes.items():
            renderers[name] = reflets.Renderer(scene)
        for renderer in renderers.values():
            renderer.render()
        times: dict[str, list[float]] = {name: [] for name in renderers}
        for _ in range(frames):
            for name, renderer in renderers.items():
                start = time.perf_counter()
                renderer.render()
                times[name].append(1e3 * (time.perf_counter() - start))
    finally:
        for renderer in renderers.values():
            renderer.release()
    return times


def filament_spheres(hdr: str, materials: dict[str, dict], size, timing, frames: int) -> tuple[dict, dict]:
    """Filament's linear images (at ``size``) and median frame times (at ``timing``) of glTF spheres under the
    map (reflets.bench.filament, its own process)."""
    from ..scene.geometry import mesh_data

    mesh = mesh_data(sphere_scene({"type": "lambert"}, hdr, size), 0)
    with tempfile.TemporaryDirectory() as folder:
        folder = Path(folder)
        np.savez(folder / "mesh.npz", positions=mesh.positions, indices=mesh.indices, normals=mesh.normals)
        job = {"kind": "spheres", "mesh": str(folder / "mesh.npz"), "materials": list(materials.values()),
               "environment": hdr, "size": list(size), "timing_size": list(timing), "fov_y": CAMERA["fov_y"],
               "position": CAMERA["position"], "look_at": CAMERA["look_at"], "frames": frames,
               "images": str(folder / "images.npz")}  # fmt: skip
        (folder / "job.json").write_text(json.dumps(job), "utf-8")
        done = subprocess.run([sys.executable, "-m", "reflets.bench.filament", str(folder / "job.json")],
                              capture_output=True, text=True, timeout=1800)  # fmt: skip
        if done.returncode != 0:
            raise RuntimeError(f"Filament (filly) failed: {(done.stderr or done.stdout).strip()[-600:]}")
        out = json.loads(done.stdout.strip().splitlines()[-1])
        with np.load(folder / "images.npz") as stored:
            images = {name: stored[f"arr_{k}"] for k, name in enumerate(materials)}
    times = {name: statistics.median(t) for name, t in zip(materials, out["frame_ms"], strict=True)}
    return images, {"times": times, "clipped": dict(zip(materials, out["clipped"], strict=True)), "filly": out["filly"]}


def filament_calibration(size, mask: np.ndarray) -> float:
    """Filament's mirror sphere (white metal, roughness 0) under a uniform map of 0.5: its median pixel over 0.5
    (1: its read-back gives the radiance)."""
    from ..imageio import write_image

    with tempfile.TemporaryDirectory() as folder:
        uniform = str(Path(folder) / "uniform.hdr")
        write_image(uniform, np.full((64, 128, 3), 0.5, np.float32))
        images, _ = filament_spheres(uniform, {"mirror": {"base_color": [1.0, 1.0, 1.0, 1.0], "metallic": 1.0,
                                                          "roughness": 0.0}}, size, size, 1)  # fmt: skip
    return float(np.median(images["mirror"][mask].mean(-1)) / 0.5)


def bench_ibl(quick: bool, out_dir) -> tuple[dict, str]:
    from ..api import render
    from .filament import ensure_filly

    size, timing, spp, frames = ((48, 36), (80, 60), 16, 2) if quick else (SIZE, TIMING_SIZE, SPP, FRAMES)
    ensure_filly()
    mask = sphere_mask(sphere_scene({"type": "lambert"}, None, size, POINT))  # every row's sphere, one camera
    calibration = filament_calibration(size, mask)
    if not 0.98 < calibration < 1.02:
        raise RuntimeError(f"Filament's read-back is off: a mirror sphere under a uniform map reads {calibration:.3f}× "
                           "its radiance (1 expected)")  # fmt: skip
    rows, filament_rows, filly_version = [], [], None
    for map_name in MAPS:
        hdr = map_path(map_name)
        for name, (material, bound) in {**SPHERES, **{k: (v, None) for k, v in LIBRARY.items()}}.items():
            scene = sphere_scene(material, hdr, size)
            found, noise, _ = errors(scene, {"reflets": render(scene)}, spp, mask)
            times = frame_times({"env": sphere_scene(material, hdr, timing),
                                 "point": sphere_scene(material, hdr, timing, POINT)}, frames)  # fmt: skip
            ms = {key: statistics.median(values) for key, values in times.items()}
            ratio = statistics.median(e / p for e, p in zip(times["env"], times["point"], strict=True))
            rows.append({"map": map_name, "material": name, "relmse": found["reflets"], "bound": bound,
                         "reference_noise": noise, "env_ms": ms["env"], "point_ms": ms["point"],
                         "env_over_point": ratio})  # fmt: skip
            print(f"ibl {map_name} {name}: relMSE {found['reflets']:.2e} (noise {noise:.1e}), "
                  f"{ms['env']:.1f} / {ms['point']:.1f} ms", flush=True)  # fmt: skip
        theirs, filament = filament_spheres(hdr, FILAMENT, size, timing, frames)
        filly_version = filament["filly"]
        for name, gltf in FILAMENT.items():
            material = {"type": "gltf", **gltf}
            scene = sphere_scene(material, hdr, size)
            found, noise, level = errors(scene, {"reflets": render(scene), "filament": theirs[name]}, spp, mask)
            env_ms = statistics.median(frame_times({"env": sphere_scene(material, hdr, timing)}, frames)["env"])
            filament_rows.append({"map": map_name, "material": name, "relmse": found["reflets"],
                                  "filament_relmse": found["filament"], "reference_noise": noise,
                                  "level": level["reflets"], "filament_level": level["filament"],
                                  "filament_clipped": filament["clipped"][name],
                                  "env_ms": env_ms, "filament_ms": filament["times"][name]})  # fmt: skip
            print(f"ibl {map_name} {name}: reflets {found['reflets']:.2e}, Filament {found['filament']:.2e}, "
                  f"{env_ms:.1f} / {filament['times'][name]:.1f} ms", flush=True)  # fmt: skip
    data = {"size": list(size), "timing_size": list(timing), "reference_spp": spp, "frames": frames,
            "filly": filly_version, "filament_calibration": calibration, "rows": rows,
            "filament": filament_rows}  # fmt: skip
    return data, _markdown(data)


def _markdown(data: dict) -> str:
    size, timing = data["size"], data["timing_size"]
    lines = [
        "# Environment lighting from real HDR maps",
        "",
        f"A unit sphere alone under each map: relative MSE over the sphere less a 1-pixel rim at {size[0]}×{size[1]} "
        f"against the NumPy reference at {data['reference_spp']} spp (*noise*: what the reference's own noise adds "
        "to that error); reflets as by default (the map's compact emitters as lights, the rest prefiltered). "
        f"`env_ms` / `point_ms`: the same sphere under the map / under one point light with its shadows, medians "
        f"of {data['frames']} interleaved frames of persistent renderers at {timing[0]}×{timing[1]}, one run "
        "(*env / point*: the median of the ratios of frames drawn in the same round). "
        "Generated by `reflets bench ibl`.",
        "",
        "| map | material | relMSE | bound | noise | env_ms | point_ms | env / point |",
        "|---|---|---|---|---|---|---|---|",
        *[
            f"| {r['map']} | {r['material']} | {r['relmse']:.2e} | "
            f"{'—' if r['bound'] is None else format(r['bound'], 'g')} | {r['reference_noise']:.1e} | "
            f"{r['env_ms']:.1f} | {r['point_ms']:.1f} | {r['env_over_point']:.2f} |"
            for r in data["rows"]
        ],
        "",
        f"## Filament (filly {data['filly']}), same spheres and maps, same run",
        "",
        "glTF metal spheres (base colour 0.9, roughness √α): each renderer's relative MSE against the reference of "
        "that material, the median of its pixels' ratios to the reference's (*level*), and its frame (Filament: "
        "render, finish, read back, in its own process). Filament's linear read-back (8-bit sRGB exposure "
        f"brackets), checked on a mirror sphere under a uniform map: {data['filament_calibration']:.3f}× the "
        "radiance. The reference and reflets' glTF model scatter once between microfacets, as glTF's "
        "specification has it; Filament adds an energy compensation for multiple scattering by default, which "
        "brightens rough metals: part of its error at α 0.6 is that model difference.",
        "",
        "| map | material | reflets relMSE | Filament relMSE | noise | reflets level | Filament level | reflets ms "
        "| Filament ms |",
        "|---|---|---|---|---|---|---|---|---|",
        *[
            f"| {r['map']} | {r['material']} | {r['relmse']:.2e} | {r['filament_relmse']:.2e} | "
            f"{r['reference_noise']:.1e} | {r['level']:.2f} | {r['filament_level']:.2f} | {r['env_ms']:.1f} | "
            f"{r['filament_ms']:.1f} |"
            for r in data["filament"]
        ],
        "",
    ]
    return "\n".join(lines)
