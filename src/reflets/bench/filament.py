"""Google Filament (through ``filly``) on a glTF file, timed the way ``reflets bench assets`` times reflets; and
(``"kind": "spheres"``, :func:`spheres`) spheres under a map alone, read back as linear radiance for
``reflets bench ibl``'s errors.

Run as a separate process (Filament makes its own GL context): ``python -m reflets.bench.filament JOB.json``
prints one JSON line: ``prepare_ms`` (the renderer, the scene, the file and the environment loaded and the first
frame read back) and ``frame_ms`` (per orbit frame: camera set, frame rendered, ``finish()``, read back into
NumPy — what a reflets ``Renderer.render()`` returns). JOB.json: ``asset``, ``size`` [w, h], ``fov_y`` (degrees),
``look_at``, ``positions`` (one camera position per frame), ``environment`` (an .hdr map), ``point_light``
{position, intensity (W/sr, radiometric)}, ``shadows`` (the point light casts shadows: Filament's cube shadow map;
filly's default is none), ``image`` (a PNG of the first frame, for the eye).

Filament's point light takes luminous power: Φ = 4π · 683 lm/W · mean(intensity). For a glTF file its default
camera exposure and tone mapping are kept (images shown beside reflets', not compared numerically: ``bench
assets``' errors are reflets' against its reference).
"""

from __future__ import annotations

import json
import math
import sys
import time

import numpy as np


def ensure_filly() -> None:
    """Install filly (Google Filament for Python) for a comparison if it is missing (the benchmarks' peer)."""
    import subprocess

    try:
        import filly  # noqa: F401
    except ImportError:
        print("installing filly (Google Filament for Python) for the comparison: pip install filly", flush=True)
        subprocess.run([sys.executable, "-m", "pip", "install", "-q", "filly"], check=True)


def run(job: dict) -> dict:
    import filly

    from ..imageio import read_image

    started = time.perf_counter()
    with filly.Renderer() as renderer:
        scene = renderer.create_scene()
        scene.load(job["asset"])
        pixels = np.ascontiguousarray(read_image(job["environment"])[..., :3], dtype=np.float32)
        pixels.flags.writeable = False
        scene.environment = renderer.create_environment(pixels)
        scene.environment_visible = True  # drawn behind the asset, as reflets draws it
        light = job["point_light"]
        lumens = 4.0 * math.pi * 683.0 * float(np.mean(light["intensity"]))
        point = scene.add_point_light(position=light["position"], intensity=lumens, range=1e3)
        if job.get("shadows"):
            scene.shadows = True
            point.casts_shadows = True
        camera = renderer.create_camera()
        width, height = job["size"]
        camera.set_perspective(fov_y_deg=job["fov_y"], aspect=width / height)
        camera.position = tuple(job["positions"][0])
        camera.look_at(tuple(job["look_at"]))
        scene.camera = camera
        target = renderer.create_render_target(width=width, height=height)
        renderer.render(scene, target)
        renderer.finish()
        target.read()
        prepare_ms = 1e3 * (time.perf_counter() - started)
        frames, first = [], None
        for position in job["positions"]:
            t = time.perf_counter()
            camera.position = tuple(position)
            camera.look_at(tuple(job["look_at"]))
            renderer.render(scene, target)
            renderer.finish()
            image = target.read()
            frames.append(1e3 * (time.perf_counter() - t))
            first = image if first is None else first
    if job.get("image"):
        from PIL import Image

        Image.fromarray(np.asarray(first)[..., :3]).save(job["image"])
    return {"prepare_ms": prepare_ms, "frame_ms": frames, "filly": filly.__version__}


#: exposures of a sphere's brackets (× the radiance): filly reads back 8-bit sRGB only, so a linear image is
#: rebuilt, at each pixel, from the brightest bracket whose largest channel stays below 0.95
BRACKETS = (1.0, 1.0 / 16, 1.0 / 256, 1.0 / 4096, 1.0 / 65536)


def _linear(encoded: np.ndarray) -> np.ndarray:
    """sRGB-encoded 8-bit values → linear [0, 1]."""
    c = encoded.astype(np.float64) / 255.0
    return np.where(c <= 0.04045, c / 12.92, ((c + 0.055) / 1.055) ** 2.4)


def spheres(job: dict) -> dict:
    """Spheres under an environment map alone, each as Filament renders it: linear radiance (bracketed, see
    ``BRACKETS``) and the frame times. JOB: ``kind`` ("spheres"), ``mesh`` (an .npz of positions, indices,
    normals), ``materials`` [{base_color, metallic, roughness}], ``environment`` (.hdr), ``size`` (the images'),
    ``timing_size`` (the timed frames'), ``fov_y``, ``position``, ``look_at``, ``frames``, ``images`` (an .npz
    written with one image per material). Tone mapping linear, no anti-aliasing, dithering or post-processing;
    Filament's exposure is its camera's, 1 / (1.2 × 2^EV100), and the map's intensity is set to its inverse so
    that a pixel reads the radiance (``reflets bench ibl`` checks it: a mirror sphere under a uniform map).
    ``clipped``: per material, the pixels brighter than the dimmest bracket holds (kept at its clipped value)."""
    import filly

    from ..imageio import read_image

    filly.set_log_level("error")
    mesh = np.load(job["mesh"])
    width, height = job["size"]
    images, frame_ms, clipped = [], [], []
    with filly.Renderer() as renderer:
        scene = renderer.create_scene()
        for name in ("antialiasing", "dithering", "bloom", "ssao", "vignette", "fog", "depth_of_field"):
            if hasattr(scene, name):
                setattr(scene, name, False if name != "antialiasing" else "none")
        scene.tone_mapping = "linear"
        scene.encoding = "srgb"
        pixels = np.ascontiguousarray(read_image(job["environment"])[..., :3], dtype=np.float32)
        pixels.flags.writeable = False
        scene.environment = renderer.create_environment(pixels)
        scene.environment_visible = False
        camera = renderer.create_camera()
        camera.set_perspective(fov_y_deg=job["fov_y"], aspect=width / height)
        camera.position = tuple(job["position"])
        camera.look_at(tuple(job["look_at"]))
        scene.camera = camera
        unit = 1.2 * 2.0 ** camera.exposure  # the map's intensity that makes a pixel read its radiance
        target = renderer.create_render_target(width=width, height=height)
        timing = renderer.create_render_target(width=job["timing_size"][0], height=job["timing_size"][1])
        positions, normals = (np.ascontiguousarray(mesh[k], np.float32) for k in ("positions", "normals"))
        indices = np.ascontiguousarray(mesh["indices"], np.uint32)
        for material in job["materials"]:
            material = {**material, "base_color": [*material["base_color"][:3], 1.0]}  # filly takes RGBA
            model = scene.create_mesh(positions, indices, normals=normals, **material)
            radiance = None
            for scale in reversed(BRACKETS):  # dimmest first: each brighter bracket replaces what it holds unclipped
                scene.environment_intensity = unit * scale
                renderer.render(scene, target)
                renderer.finish()
                value = _linear(target.read()[..., :3])
                fits = np.max(value, axis=-1, keepdims=True) < 0.95
                if radiance is None:  # the dimmest: everything, a pixel clipped even there at its clipped value
                    radiance, clipped_here = value / scale, int(np.count_nonzero(~fits))
                radiance = np.where(fits, value / scale, radiance)
            images.append(radiance.astype(np.float32))
            clipped.append(clipped_here)
            scene.environment_intensity = unit
            renderer.render(scene, timing)  # the timing target's first frame (its set-up) is not timed
            renderer.finish()
            timing.read()
            times = []
            for _ in range(job["frames"]):
                t = time.perf_counter()
                renderer.render(scene, timing)
                renderer.finish()
                timing.read()
                times.append(1e3 * (time.perf_counter() - t))
            frame_ms.append(times)
            model.visible = False
    np.savez(job["images"], *images)
    return {"frame_ms": frame_ms, "clipped": clipped, "filly": filly.__version__}


def main(argv: list[str]) -> int:
    """The benchmarks' subprocess: one JOB.json, one JSON line out; a job it cannot read: one line, exit 2."""
    try:
        if len(argv) != 1:
            raise ValueError("usage: python -m reflets.bench.filament JOB.json")
        with open(argv[0], encoding="utf-8") as stream:
            job = json.load(stream)
        if not isinstance(job, dict):
            raise ValueError("a job is a JSON object")
    except (OSError, ValueError, RecursionError) as exc:
        print(f"reflets.bench.filament: {argv[0] if argv else 'JOB.json'}: {exc}", file=sys.stderr)
        return 2
    print(json.dumps(spheres(job) if job.get("kind") == "spheres" else run(job)))
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
