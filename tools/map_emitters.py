"""A map's compact emitters split off as lights (``emitters = "extract"``, reflets/scene/map_emitters.py) against
the whole map prefiltered: what the rule finds in the shipped maps, then GGX spheres (F = 0.9, separable masking,
96 × 72) under kloppenheim_05, the sky and the studio map, and a sphere on a floor under kloppenheim_05 (128 × 96),
each against the NumPy reference (256 spp, the whole map, with visibility); relative MSE over the sphere's (the
floor's) pixels; the frame's cost under the sky; synthetic maps of small lamps — a night of 30 (against a
1,024-spp reference, and its frame's cost), an interior of 6 with a window —, the culling's and the prefiltering's
cost: the numbers of docs/techniques/environment-lighting.md.

    python tools/map_emitters.py
"""

from __future__ import annotations

import tempfile
import time
from importlib import resources
from pathlib import Path

import numpy as np

import reflets
from reflets.bench.ibl import CAMERA, GGX
from reflets.equirect import row_solid_angles
from reflets.imageio import read_image
from reflets.metrics import masked_relmse
from reflets.scene.lightmask import LUMINANCE
from reflets.scene.map_emitters import find_emitters

MAPS = {name: str(resources.files("reflets").joinpath("data", "environments", f"{name}.hdr"))
        for name in ("kloppenheim_05_1k", "sky", "studio")}  # fmt: skip


def sphere_scene(hdr: str, alpha: float, emitters: str):
    """``reflets bench ibl``'s GGX sphere (its camera, F = 0.9, separable masking) at 96 × 72 under the map, its
    emitters extracted or kept."""
    return reflets.load_dict({
        "camera": {**CAMERA, "size": [96, 72]},
        "materials": {"m": {**GGX, "alpha": alpha}},
        "mesh": [{"shape": "sphere", "radius": 1, "material": "m"}],
        "light": [{"type": "environment", "file": hdr, "emitters": emitters}],
    })  # fmt: skip


def floor_scene(hdr: str, emitters: str):
    return reflets.load_dict({
        "camera": {"position": [0, 2.5, 5], "look_at": [0, 0.3, 0], "fov_y": 40, "size": [128, 96]},
        "materials": {"m": {**GGX, "alpha": 0.3}, "floor": {"type": "lambert", "albedo": [0.6, 0.6, 0.6]}},
        "mesh": [{"shape": "sphere", "radius": 1, "material": "m", "transform": {"translate": [0, 1, 0]}},
                 {"shape": "plane", "size": [12, 12], "material": "floor"}],
        "light": [{"type": "environment", "file": hdr, "emitters": emitters}],
    })  # fmt: skip


def frame_costs(frames: int = 20) -> str:
    """Median frame times of persistent renderers drawn in turn (one run: their ratios hold on a shared machine):
    the sphere on the floor under the sky, whole map / its sun as a light (and the residual map unoccluded: what
    the occlusion's lookups cost), and under one point light."""
    def floor_under(lights):
        return floor_scene(MAPS["sky"], "keep").model_copy(update={"light": lights})

    sky = floor_scene(MAPS["sky"], "keep").light[0]
    point = reflets.load_dict({"camera": {"position": [0, 0, 1], "look_at": [0, 0, 0]},
                               "light": [{"type": "point", "position": [2, 3, 4], "intensity": [20, 20, 20]}]}).light
    split = floor_under([sky.model_copy(update={"emitters": "extract"})])
    scenes = {"whole map": (floor_under([sky]), {}), "sun as a light": (split, {}), "every lookup at every pixel": (
              split, {"environment_occlusion": "every-pixel"}), "the residual unoccluded": (
              split, {"environment_occlusion": "none"}), "one point light": (floor_under(point), {})}  # fmt: skip
    renderers = {name: reflets.Renderer(scene, size=(320, 240), **params) for name, (scene, params) in scenes.items()}
    times = {name: [] for name in renderers}
    for renderer in renderers.values():
        renderer.render()
    for i in range(frames):
        for name, renderer in renderers.items():
            renderer.set_camera(position=[0.01 * i, 2.5, 5])
            start = time.perf_counter()
            renderer.render()
            times[name].append(1e3 * (time.perf_counter() - start))
    for renderer in renderers.values():
        renderer.release()
    return ", ".join(f"{name} {np.median(t):.1f} ms" for name, t in times.items())


def prefilter_cost() -> str:
    """The GPU's prefiltering of a map (ibl.PrefilteredEnvironment: the GGX mips and the irradiance map), median of
    three, for the sky (256 × 128) and kloppenheim_05 (1k)."""
    from reflets.gpu import get_context
    from reflets.scene.environment import load_environment
    from reflets.techniques.ibl import PrefilteredEnvironment

    ctx, found = get_context(), []
    for name in ("sky", "kloppenheim_05_1k"):
        scene = sphere_scene(MAPS[name], 0.3, "extract")
        image = load_environment(scene)
        times = []
        for _ in range(3):
            source = ctx.texture((image.shape[1], image.shape[0]), 3, image.tobytes(), dtype="f4")
            ctx.finish()
            start = time.perf_counter()
            maps = PrefilteredEnvironment(source, image, scene.environment)
            ctx.finish()
            times.append(1e3 * (time.perf_counter() - start))
            maps.release()
            source.release()
        found.append(f"{name} ({image.shape[1]} × {image.shape[0]}) {np.median(times):.0f} ms")
    return ", ".join(found)


def culling_costs(frames: int = 15) -> str:
    """A GGX sphere (α 0.15) alone under kloppenheim_05 at 320 × 240, its shadow lookups compiled out (the default:
    nothing can shadow it) and kept (shadows.CULL_MESHES = 0 while its renderer prepares): median frames, drawn in
    turn."""
    from reflets.techniques import shadows

    scene = sphere_scene(MAPS["kloppenheim_05_1k"], 0.15, "extract")
    culled = reflets.Renderer(scene, size=(320, 240))
    default, shadows.CULL_MESHES = shadows.CULL_MESHES, 0
    try:
        kept = reflets.Renderer(scene, size=(320, 240))
    finally:
        shadows.CULL_MESHES = default
    times = {"compiled out": [], "kept": []}
    for renderer in (culled, kept):
        renderer.render()
    for _ in range(frames):
        for name, renderer in (("compiled out", culled), ("kept", kept)):
            start = time.perf_counter()
            renderer.render()
            times[name].append(1e3 * (time.perf_counter() - start))
    culled.release()
    kept.release()
    return ", ".join(f"lookups {name} {np.median(t):.1f} ms" for name, t in times.items())


def showcase_costs(frames: int = 5) -> str:
    """The gallery's showcase (60_showcase.toml, under the sky) at 320 × 240, whole map / its sun as a light:
    median frame times of two persistent renderers drawn in turn."""
    from reflets.demo import scene_path

    base = reflets.load_scene(scene_path("60_showcase.toml"))
    renderers = {}
    for mode in ("keep", "extract"):
        lights = [light.model_copy(update={"emitters": mode}) if light.type == "environment" else light
                  for light in base.light]  # fmt: skip
        renderers[mode] = reflets.Renderer(base.model_copy(update={"light": lights}), size=(320, 240))
        renderers[mode].render()
    times = {mode: [] for mode in renderers}
    for _ in range(frames):
        for mode, renderer in renderers.items():
            start = time.perf_counter()
            renderer.render()
            times[mode].append(1e3 * (time.perf_counter() - start))
    for renderer in renderers.values():
        renderer.release()
    return f"whole map {np.median(times['keep']):.0f} ms, sun as a light {np.median(times['extract']):.0f} ms"


def night_map(path: Path) -> str:
    """A synthetic night map at 1k: a dark sky (0.02) over darker ground, 30 lamps of 3 × 3 texels (200–2,000, warm)
    at random positions above the horizon (seed 3); saved as .npy."""
    rng = np.random.default_rng(3)
    h, w = 512, 1024
    sky = np.full((h, w, 3), 0.02, np.float32)
    sky[h // 2 :] = 0.005
    for _ in range(30):
        row, col = rng.integers(40, h // 2 - 5), rng.integers(0, w)
        sky[row - 1 : row + 2, np.arange(col - 1, col + 2) % w] = np.array([1.0, 0.8, 0.5]) * rng.uniform(200, 2000)
    np.save(path, sky)
    return str(path)


def interior_map(path: Path) -> str:
    """A synthetic interior at 1k: walls (0.2–0.6, a warm floor below the horizon), a window (a 20° × 15° pane of
    8, too wide to be compact) and 6 small ceiling lamps of 3 × 3 texels (300–900); saved as .npy."""
    rng = np.random.default_rng(5)
    h, w = 512, 1024
    room = np.empty((h, w, 3), np.float32)
    room[...] = np.linspace(0.2, 0.6, w)[None, :, None] * np.array([1.0, 0.95, 0.9])
    room[h // 2 :] = (0.25, 0.18, 0.12)
    room[150:193, 300:357] = (8.0, 8.5, 9.0)  # the window
    for _ in range(6):
        row, col = rng.integers(20, 80), rng.integers(0, w)
        room[row - 1 : row + 2, np.arange(col - 1, col + 2) % w] = np.array([1.0, 0.9, 0.7]) * rng.uniform(300, 900)
    np.save(path, room)
    return str(path)


def small_lamps(directory: Path) -> None:
    """The interior's lamps: GGX spheres against a 1,024-spp reference, the whole map and the rule's emitters."""
    hdr = interior_map(directory / "interior.npy")
    print(f"interior map: the rule finds {len(find_emitters(np.load(hdr))[0])} emitter(s) (6 lamps, a window)")
    lamp_errors("interior map", hdr)


def lamp_errors(label: str, hdr: str) -> None:
    """GGX spheres (α 0.05, 0.3) under a map against a 1,024-spp reference: the whole map, the rule's emitters."""
    for alpha in (0.05, 0.3):
        scene = sphere_scene(hdr, alpha, "keep")
        sphere = np.any(reflets.render(scene, method="position") != 0, axis=-1)
        ref = reflets.reference(scene, spp=1024, progress=False).image
        images = {"whole map": reflets.render(scene), "the rule's emitters": reflets.render(sphere_scene(
            hdr, alpha, "extract"))}  # fmt: skip
        found = ", ".join(f"{name} {masked_relmse(image, ref, sphere):.2e}"
                          for name, image in images.items())
        print(f"{label}, GGX α {alpha}: {found}")


def night(directory: Path) -> None:
    """Many small lamps: GGX spheres under the night map against a 1,024-spp reference — the whole map and the
    rule's emitters (each a light) —, and the frame's cost at 320 × 240 both ways."""
    hdr = night_map(directory / "night.npy")
    print(f"night map: the rule finds {len(find_emitters(np.load(hdr))[0])} of its 30 lamps")
    lamp_errors("night map (30 lamps)", hdr)
    costs = {}
    for mode in ("keep", "extract"):
        renderer = reflets.Renderer(sphere_scene(hdr, 0.05, mode), size=(320, 240))
        renderer.render()
        times = []
        for _ in range(9):
            start = time.perf_counter()
            renderer.render()
            times.append(1e3 * (time.perf_counter() - start))
        renderer.release()
        costs[mode] = np.median(times)
    print(f"night map, the sphere at 320 × 240, median frame: whole map {costs['keep']:.1f} ms, "
          f"its lamps as lights {costs['extract']:.1f} ms")


def errors(make, masks) -> list[str]:
    """Relative MSE of the GPU image with the whole map and with its emitters split off, over each mask."""
    ref = reflets.reference(make("keep"), spp=256, progress=False).image
    out = []
    for mode in ("keep", "extract"):
        image = reflets.render(make(mode))
        out.append(" / ".join(f"{masked_relmse(image, ref, m):.2e}" for m in masks))
    return out


def main() -> None:
    find_emitters(read_image(MAPS["sky"]))  # (the first call imports scipy.ndimage)
    for name, hdr in MAPS.items():
        image = read_image(hdr)
        start = time.perf_counter()
        emitters, _ = find_emitters(image)
        ms = 1e3 * (time.perf_counter() - start)
        total = float(np.sum((image.astype(np.float64) @ LUMINANCE) * row_solid_angles(*image.shape[:2])[:, None]))
        found = ", ".join(f"{e.texels} texels, {e.solid_angle:.1e} sr, r = {np.degrees(e.radius):.1f}°, "
                          f"{np.dot(e.power, LUMINANCE) / total:.0%} of the power" for e in emitters)
        print(f"{name} ({image.shape[1]} × {image.shape[0]}, found in {ms:.1f} ms): {len(emitters)} emitter(s) {found}")
    for name, hdr in MAPS.items():
        for alpha in (0.05, 0.15, 0.3, 0.6):
            sphere = np.any(reflets.render(sphere_scene(hdr, alpha, "keep"), method="position") != 0, axis=-1)
            keep, extract = errors(lambda mode, h=hdr, a=alpha: sphere_scene(h, a, mode), [sphere])
            print(f"{name}, GGX α {alpha}: whole map {keep}, emitters as lights {extract}")
    hdr = MAPS["kloppenheim_05_1k"]
    position = reflets.render(floor_scene(hdr, "keep"), method="position")
    floor = (np.abs(position[..., 1]) < 1e-3) & np.any(position != 0, axis=-1)
    sphere = np.any(position != 0, axis=-1) & ~floor
    keep, extract = errors(lambda mode: floor_scene(hdr, mode), [sphere, floor])
    print(f"kloppenheim_05, sphere / floor: whole map {keep}, emitters as lights {extract}")
    print(f"the sphere on the floor under the sky, 320 × 240, median frame: {frame_costs()}")
    print(f"the showcase, 320 × 240, median frame: {showcase_costs()}")
    print(f"a GGX sphere alone under kloppenheim_05, 320 × 240, median frame: {culling_costs()}")
    print(f"prefiltering a map on the GPU: {prefilter_cost()}")
    with tempfile.TemporaryDirectory() as directory:
        night(Path(directory))
        small_lamps(Path(directory))


if __name__ == "__main__":
    main()
