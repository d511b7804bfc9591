"""Google Filament (through ``filly``) on a glTF file, timed the way ``reflets bench assets`` times reflets.

Run as a separate process (Filament makes its own GL context): ``python -m reflets.bench.filament JOB.json``
prints one JSON line: ``prepare_ms`` (the renderer, the scene, the file and the environment loaded and the first
frame read back) and ``frame_ms`` (per orbit frame: camera set, frame rendered, ``finish()``, read back into
NumPy — what a reflets ``Renderer.render()`` returns). JOB.json: ``asset``, ``size`` [w, h], ``fov_y`` (degrees),
``look_at``, ``positions`` (one camera position per frame), ``environment`` (an .hdr map), ``point_light``
{position, intensity (W/sr, radiometric)}, ``shadows`` (the point light casts shadows: Filament's cube shadow map;
filly's default is none), ``image`` (a PNG of the first frame, for the eye).

Filament's point light takes luminous power: Φ = 4π · 683 lm/W · mean(intensity). Its default camera exposure and
tone mapping are kept (images are shown beside reflets', not compared numerically: the benchmark's errors are
reflets' against its reference).
"""

from __future__ import annotations

import json
import math
import sys
import time


def run(job: dict) -> dict:
    import filly
    import numpy as np

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


if __name__ == "__main__":
    with open(sys.argv[1], encoding="utf-8") as stream:
        print(json.dumps(run(json.load(stream))))
