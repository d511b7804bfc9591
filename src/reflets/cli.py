"""The ``reflets`` command: parses arguments, calls the Python API, prints. No rendering logic lives here.

User mistakes (reflets.errors.RefletsError) print one line and exit with status 2; ``--debug`` shows the
traceback instead.
"""

from __future__ import annotations

import argparse
import re
import sys
import time
from pathlib import Path

import numpy as np

from . import jsonio
from .errors import ArgumentError, OutputError, RefletsError

EXIT_USER_ERROR = 2


def _size(text: str) -> tuple[int, int]:
    m = re.fullmatch(r"\s*(\d+)\s*[xX×]\s*(\d+)\s*", text)
    if not m:
        raise ArgumentError(f"'{text}' is not WIDTHxHEIGHT (e.g. 640x480)", field="--size")
    from .arguments import check_size

    try:
        return check_size((int(m.group(1)), int(m.group(2))))
    except ArgumentError as exc:
        raise ArgumentError(exc.message, field="--size") from None


def _params(items: list[str]) -> dict[str, object]:
    """``--param key=value`` pairs; values parsed as TOML literals (numbers, booleans, arrays, strings)."""
    import tomllib

    out: dict[str, object] = {}
    for item in items:
        key, sep, value = item.partition("=")
        if not sep or not key.strip():
            raise ArgumentError(f"'{item}' is not KEY=VALUE", field="--param")
        try:
            out[key.strip()] = tomllib.loads(f"v = {value}")["v"]
        except tomllib.TOMLDecodeError:
            out[key.strip()] = value
    return out


def _check_render_memory(out: Path, size: tuple[int, int]) -> None:
    """Refuse, before rendering, an image whose render and write would not fit in memory (reflets.resources):
    width · height · (a frame's bytes per sample at 1 spp + the format's writing bytes per pixel). Memory the
    render frees is not all returned before the write (a 4096² PNG: measured 155 B per pixel at the peak, this
    says 192); a larger spp is checked by the technique, before its target is made."""
    from .imageio import WRITE_BYTES_PER_PIXEL
    from .resources import check, fitting_size
    from .techniques.base import FRAME_BYTES_PER_SAMPLE

    width, height = size
    per_pixel = FRAME_BYTES_PER_SAMPLE + WRITE_BYTES_PER_PIXEL.get(out.suffix.lower(), 112)
    check(
        "size",
        width * height * per_pixel,
        value=f"{width}x{height}",
        what=f"{width * height:,} pixels × {per_pixel} B: rendering, then writing {out.suffix.lower()}",
        fits=lambda budget: fitting_size(width, height, per_pixel, budget),
    )


def _scene_argument(args):
    """The scene of a command: a TOML file, or a glTF file with its --camera / --environment choices."""
    from .scene import load_scene

    return load_scene(args.scene, camera=args.camera, environment=args.environment)


def _overwrite_option(p) -> None:
    """Every command that writes files refuses to replace one unless told (reflets.outputs)."""
    p.add_argument("--overwrite", action="store_true", help="replace output files that exist (refused otherwise)")


def _asset_options(p) -> None:
    p.add_argument("--camera", help="a glTF file's camera (index or name; default its first, else one framing it)")
    p.add_argument(
        "--environment", help="an HDR map lighting a glTF / OBJ file (default: its lights, else a studio map)"
    )


def cmd_render(args) -> int:
    from .api import render
    from .imageio import IMAGE_WRITE_EXTENSIONS, write_image
    from .outputs import check_output, check_output_path

    out = check_output_path(args.output or Path(args.scene).stem + ".exr", IMAGE_WRITE_EXTENSIONS)  # a typo: at once
    size = _size(args.size) if args.size else None
    scene = _scene_argument(args)
    check_output(out, IMAGE_WRITE_EXTENSIONS, inputs=scene.input_files() | {Path(args.scene)},
                 overwrite=args.overwrite)  # fmt: skip
    _check_render_memory(out, size or tuple(scene.camera.size))
    image = render(scene, method=args.method, size=size, seed=args.seed, spp=args.spp, **_params(args.param))
    write_image(out, image, exposure=args.exposure, tonemap=args.tonemap, bit_depth=args.bit_depth)
    print(f"wrote {out} ({image.shape[1]}x{image.shape[0]})")
    return 0


def cmd_view(args) -> int:
    from .imageio import IMAGE_WRITE_EXTENSIONS
    from .outputs import check_output
    from .viewer.events import check_frames, parse_event
    from .viewer.window import ViewerWindow, load_script

    script = load_script(args.script) if args.script else None
    outputs = {"--screenshot": (args.screenshot, IMAGE_WRITE_EXTENSIONS), "--save-scene": (args.save_scene, (".toml",)),
               "--stats": (args.stats, (".json",))}  # fmt: skip

    def check_outputs(inputs) -> None:  # before the first frame; again once the scene's own files are known
        for option, (path, allowed) in outputs.items():
            if path is not None:
                check_output(path, allowed, inputs=inputs, overwrite=args.overwrite, field=option)

    check_outputs([args.scene, args.script])
    check_frames(args.frames)
    if args.screenshot and args.frames is None:
        raise ArgumentError("is written after the frames --frames N asks for; give --frames (an interactive "
                            "window saves screenshots with its panel)", field="--screenshot")  # fmt: skip
    try:  # before the window opens
        parse_event({"type": "exposure", "stops": args.exposure})
    except ArgumentError as exc:
        raise ArgumentError(exc.message, field="--exposure") from None
    size = _size(args.size) if args.size else None
    window = ViewerWindow(args.scene, method=args.method, size=size, **_params(args.param))
    try:
        check_outputs(window.controller.scene.input_files())
    except OutputError:
        window.close()
        raise
    window.controller.handle({"type": "exposure", "stops": args.exposure})
    window.controller.handle({"type": "tonemap", "mode": args.tonemap})
    status = window.run(frames=args.frames, screenshot=args.screenshot, script=script, save_scene=args.save_scene,
                        overwrite=args.overwrite)  # fmt: skip
    if args.screenshot:
        print(f"wrote {args.screenshot}")
    if args.save_scene:
        print(f"wrote {args.save_scene}")
    if args.stats:
        jsonio.write(args.stats, status, indent=1)
    times = status["window_frame_ms"][1:] or status["window_frame_ms"]
    frames = len(status["window_frame_ms"])
    print(
        f"{frames} frames, median {np.median(times):.1f} ms, the last image of {status['spp']} spp "
        f"({status['method']}, {status['renderer']})"
    )
    return 0


def cmd_highlights(args) -> int:
    from .arguments import as_scene
    from .editing.highlights import mesh_highlights, write_highlights
    from .outputs import check_output

    check_output(args.output, (".npz",), inputs=[args.scene], overwrite=args.overwrite)
    scene = as_scene(args.scene)
    check_output(args.output, (".npz",), inputs=scene.input_files(), overwrite=args.overwrite)
    result = mesh_highlights(scene, args.mesh, light=args.light)
    out = write_highlights(args.output, result)
    n, bad = len(result["ell"]), int(result["degenerate"].sum())
    print(f"wrote {out}: ℓ at {n} vertices of mesh[{args.mesh}] ({bad} degenerate: critical points or regions)")
    return 0


def cmd_edit_highlights(args) -> int:
    from .arguments import as_scene
    from .editing.highlights import checked_mesh, edit_highlights, load_targets, write_highlights
    from .editing.solver import check_iterations
    from .editing.strokes import apply_strokes, load_strokes
    from .outputs import check_output

    if (args.targets is None) == (args.strokes is None):
        raise ArgumentError("give --targets (ℓ* and a mask) or --strokes (a scripted session), one of them")
    inputs = [args.scene, args.targets, args.strokes]
    check_output(args.output, (".npz",), inputs=inputs, overwrite=args.overwrite)
    check_iterations(args.iterations, field="--iterations")
    strokes = None if args.strokes is None else load_strokes(args.strokes)  # before the scene: cheap checks first
    scene = as_scene(args.scene)
    check_output(args.output, (".npz",), inputs=scene.input_files(), overwrite=args.overwrite)
    if strokes is not None:
        result = apply_strokes(
            scene, args.mesh, strokes, light=args.light, iterations=args.iterations, file=args.strokes
        )
        out = write_highlights(args.output, result)
        energies = ", ".join(f"{a:.2e} → {b:.2e}" for a, b in result["energy"])
        print(f"wrote {out}: {len(result['energy'])} stroke(s), tensor energy {energies}")
        return 0
    targets, mask = load_targets(args.targets, checked_mesh(scene, args.mesh, editing=True).n_vertices)
    result = edit_highlights(scene, args.mesh, targets, mask, light=args.light, iterations=args.iterations)
    out = write_highlights(args.output, result)
    energy = result["energy"]
    print(f"wrote {out}: {len(energy) - 1} iterations, tensor energy {energy[0]:.3e} → {energy[-1]:.3e}")
    return 0


def cmd_export_gltf(args) -> int:
    from .arguments import as_scene
    from .gltf import export_gltf
    from .outputs import check_output

    check_output(args.output, (".glb",), inputs=[args.scene], overwrite=args.overwrite)
    path, notes = export_gltf(as_scene(args.scene), args.output, overwrite=args.overwrite)
    for note in notes:
        print(f"approximated: {note}")
    print(f"wrote {path}")
    return 0


def cmd_ar_board(args) -> int:
    from .ar.board import Board
    from .imageio import write_png8
    from .outputs import check_output

    out = check_output(args.output, (".json",), overwrite=args.overwrite)
    if args.image:
        check_output(args.image, (".png",), overwrite=args.overwrite, field="--image")
    board = Board.grid(args.columns, args.rows, args.size, args.gap, args.dictionary)
    board.cv_dictionary()  # an unknown dictionary fails before anything is written
    image = board.image()[0] if args.image else None  # made before the first file is written
    print(f"wrote {board.save(out)} ({len(board.markers)} markers)")
    if image is not None:
        print(f"wrote {write_png8(args.image, np.repeat(image[..., None], 3, axis=2))}")
    return 0


def _ar_files(args) -> tuple:
    """The board and the intrinsics of an ``ar`` command (read first: small files, checked whole)."""
    from .ar.board import Board
    from .ar.camera import Intrinsics

    return Board.load(args.board), Intrinsics.load(args.intrinsics)


def cmd_ar_track(args) -> int:
    from .ar.images import read_frames
    from .ar.tracking import track
    from .outputs import check_output

    out = check_output(args.output, (".json",), inputs=[*args.images, args.board, args.intrinsics],
                       overwrite=args.overwrite)  # fmt: skip
    board, intrinsics = _ar_files(args)
    poses = track(read_frames(args.images, size=intrinsics.size), board, intrinsics, names=args.images)
    views = [
        {"image": str(name), "R_world_to_cam": p.R.tolist(), "t_world_to_cam": p.t.tolist(), "markers": p.markers}
        if p is not None
        else {"image": str(name), "R_world_to_cam": None, "t_world_to_cam": None, "markers": 0}
        for name, p in zip(args.images, poses, strict=True)
    ]
    jsonio.write(out, {"views": views}, indent=1)
    found = sum(p is not None for p in poses)
    print(f"wrote {out}: a pose for {found} of {len(poses)} images")
    return 0


def cmd_ar_calibrate(args) -> int:
    from .ar.board import Board
    from .ar.calibration import MIN_MARKERS, calibrate
    from .ar.images import read_frames
    from .outputs import check_output

    out = check_output(args.output, (".json",), inputs=[*args.images, args.board], overwrite=args.overwrite)
    board = Board.load(args.board)
    result = calibrate(read_frames(args.images), board, names=args.images)
    K, dist = result.intrinsics.K, result.intrinsics.dist
    print(f"fx {K[0, 0]:.2f}  fy {K[1, 1]:.2f}  cx {K[0, 2]:.2f}  cy {K[1, 2]:.2f}")
    print("dist (k1 k2 p1 p2 k3) " + " ".join(f"{d:.5f}" for d in dist))
    print(f"RMS reprojection error {result.rms:.3f} px over {result.views_used} of {len(result.markers)} images "
          f"(those with {MIN_MARKERS} markers or more)")  # fmt: skip
    print(f"wrote {result.intrinsics.save(out)}")
    return 0


def _ar_inputs(args, *more) -> list:
    """Every file ``ar composite`` / ``ar run`` reads that an output could name (the scene's own files: later)."""
    return [args.scene, args.board, args.intrinsics, args.environment, *more]


def _ar_session(args, board, intrinsics, objects):
    """A Session for ``reflets ar composite`` / ``ar run``."""
    from .ar.capture import CubeMap
    from .ar.session import CUBE_SIZE, Session
    from .imageio import read_image
    from .quantities import MAX_MAGNITUDE

    cube = None
    if args.environment:  # a light probe instead of the capture
        cube = CubeMap.from_equirect(read_image(args.environment), CUBE_SIZE)
    if args.radius is not None and not 0 < args.radius <= MAX_MAGNITUDE:
        raise ArgumentError(f"must be a positive number of board units (at most {MAX_MAGNITUDE:g}), got "
                            f"{args.radius}", field="--radius")  # fmt: skip
    try:
        return Session(objects, board, intrinsics, mode=args.mode, radius=args.radius, cube=cube,
                       supersample=args.supersample, method=args.method)  # fmt: skip
    except ArgumentError as exc:
        if exc.field == "supersample":  # the option that gave it
            raise ArgumentError(exc.message, field="--supersample") from None
        raise


def _print_timings(timings: list[dict[str, float]]) -> None:
    stages = sorted({k for t in timings for k in t}, key=lambda k: (k == "frame_ms", k))
    cells = [f"{k[:-3]} {np.median([t[k] for t in timings if k in t]):.1f}" for k in stages]
    print("median ms per stage: " + ", ".join(cells))


def cmd_ar_composite(args) -> int:
    from .ar.images import read_frames
    from .arguments import as_scene
    from .imageio import write_png8
    from .outputs import check_output

    inputs = _ar_inputs(args, args.background, *(args.capture or []))
    out = check_output(args.output, (".png",), inputs=inputs, overwrite=args.overwrite)
    if args.capture and args.environment:
        raise ArgumentError("give --capture frames or an --environment light probe, not both", field="--environment")
    board, intrinsics = _ar_files(args)
    (background,) = read_frames([args.background], "RGB", size=intrinsics.size)
    captures = read_frames(args.capture or [], "RGB", size=intrinsics.size)
    objects = as_scene(args.scene)
    check_output(out, (".png",), inputs=objects.input_files(), overwrite=args.overwrite)
    session = _ar_session(args, board, intrinsics, objects)
    pose = session.track(background)  # its own markers: never a pose kept from another frame
    if pose is None:
        raise ArgumentError("the board's markers are not found in the background frame", file=args.background)
    tracked = sum(session.process(frame, composite=False).pose is not None for frame in captures)
    result = session.process(background, pose=pose)
    if captures:
        print(f"captured {tracked} of {len(captures)} frames (the others: no board found)")
    _print_timings([result.timings])
    changed = result.composite.changed.mean()
    print(f"{changed:.1%} of the pixels changed; wrote {write_png8(out, result.composite.image)}")
    return 0


#: the most frames ``ar run --frames`` asks for (a day of video at 30 frames a second; without it a video runs to
#: its end and a camera until interrupted)
MAX_RUN_FRAMES = 30 * 86_400


def cmd_ar_run(args) -> int:
    from .ar.images import check_intrinsics_size
    from .ar.video import FrameSink, FrameSource
    from .arguments import as_scene
    from .outputs import check_not_input

    if args.frames is not None and not 1 <= args.frames <= MAX_RUN_FRAMES:
        raise ArgumentError(f"{args.frames:,} is out of range; a run stops after 1..{MAX_RUN_FRAMES:,} frames",
                            field="--frames")  # fmt: skip
    sink = FrameSink.open(args.output, overwrite=args.overwrite, inputs=_ar_inputs(args, *args.inputs))
    board, intrinsics = _ar_files(args)
    source = FrameSource.open(args.inputs, args.webcam, size=intrinsics.size)
    objects = as_scene(args.scene)
    check_not_input(sink.path, objects.input_files())
    session = _ar_session(args, board, intrinsics, objects)
    timings, shown, posed = [], 0, 0
    try:
        for frame in source.frames(limit=args.frames):
            check_intrinsics_size(frame.shape[1], frame.shape[0], intrinsics.size, field=f"input frame {shown}")
            result = session.process(frame)
            sink.write(result.composite.image if result.composite is not None else frame)
            timings.append(result.timings)
            shown += 1
            posed += result.pose is not None
        if shown == 0:
            raise ArgumentError("no frame could be read", field="input")
    except KeyboardInterrupt:
        if args.webcam is None or shown == 0:  # a video or images cut short: as a failed run
            sink.discard()
            raise
        print(f"stopped by an interrupt after {shown} frames")  # how a camera's run ends: its recording kept
    except BaseException:
        sink.discard()  # nothing of a run that failed half-way (an output there before: untouched)
        raise
    sink.commit()
    print(f"{shown} frames, a pose in {posed}")
    _print_timings(timings)
    print(f"wrote {sink.describe()}")
    return 0


def cmd_reference(args) -> int:
    from .reference import reference
    from .reference.batch import make, plan
    from .reference.parallel import places, using
    from .scene import load_scene

    size = _size(args.size) if args.size else None
    if args.engine != "volumetric" and args.target_error is not None:
        raise ArgumentError("--target-error is the volumetric engine's (--engine volumetric)", field="--target-error")
    if args.workers is not None and args.workers < 1:
        raise ArgumentError(f"workers must be at least 1 (got {args.workers})", field="--workers")
    if args.cluster is not None:
        from .reference.cluster import check_address

        if args.workers is not None:
            raise ArgumentError("give either --workers (this machine's processes) or --cluster, not both",
                                field="--workers")  # fmt: skip
        check_address(args.cluster)
    params = {"spp": args.spp, "seed": args.seed, "visibility": args.visibility, "pixel": args.pixel,
              "heuristic": args.mis, "size": size, "target_error": args.target_error}  # fmt: skip
    planned = plan(args.scene, args.output, lambda path: load_scene(path, camera=args.camera,
                   environment=args.environment), engine=args.engine, resume=args.resume, params=params,
                   overwrite=args.overwrite)  # fmt: skip
    if all(item.up_to_date for item in planned):
        place = None  # nothing to render: no cluster to reach
    elif args.engine == "mitsuba" and args.cluster is None:
        place = places(1)  # Mitsuba's own threads take every core
    else:
        place = places(None, args.cluster)  # every core (fitted to the memory), or one cluster connection
    # the Mitsuba bridge's crop windows go to a cluster named, never to this machine's processes; a count of
    # processes given is the reference's own (checked against the memory as given)
    where = {"cluster": place} if args.engine == "mitsuba" and args.cluster is not None else {}
    if args.workers is not None and args.engine != "mitsuba":
        where = {"workers": args.workers}

    def render(item):
        return reference(item.scene, spp=args.spp, seed=args.seed, engine=args.engine,
                         visibility=args.visibility == "on", size=size, pixel=args.pixel, heuristic=args.mis,
                         progress=not args.quiet, checkpoint=item.checkpoint, keep_checkpoint=True,
                         target_error=args.target_error, **where)  # fmt: skip

    try:
        with using(place):  # the batch's references share it
            make(planned, render)
    finally:
        if place is not None:
            place.close()
    return 0


def cmd_bench(args) -> int:
    from .bench import run_suite

    run_suite(args.suite, Path(args.output), quick=args.quick, cluster=args.cluster)
    return 0


def cmd_compare(args) -> int:
    from .api import compare
    from .imageio import read_image
    from .outputs import check_output

    ref = Path(args.reference)
    stderr_path = Path(args.stderr) if args.stderr else ref.with_name(ref.stem + ".stderr" + ref.suffix)
    if args.diff:
        check_output(args.diff, (".png",), inputs=[args.test, ref, stderr_path], overwrite=args.overwrite,
                     field="--diff")  # fmt: skip
    a, b = read_image(args.test), read_image(args.reference)
    result = compare(a, b)
    if args.stderr or stderr_path.is_file():
        from .metrics import zscores

        result.update(zscores(a, b, read_image(stderr_path)))
    if args.diff:
        from .imageio import write_png8
        from .metrics import difference_image

        write_png8(Path(args.diff), difference_image(a, b))
    if args.json:
        print(jsonio.dumps(result))
    else:
        for key, value in result.items():
            print(f"{key:>7}  {value:.6g}")
    return 0


def cmd_info(args) -> int:
    from importlib import metadata

    from .techniques import TECHNIQUES

    packages = [
        "reflets",
        "numpy",
        "scipy",
        "moderngl",
        "glcontext",
        "pydantic",
        "trimesh",
        "OpenEXR",
        "flip-evaluator",
        "mitsuba",
        "opencv-python-headless",
        "distributed",
    ]
    versions = {}
    for name in packages:
        try:
            versions[name] = metadata.version(name)
        except metadata.PackageNotFoundError:
            versions[name] = None
    from .renderer.compose import evaluation_table

    info = {"packages": versions, "methods": sorted(TECHNIQUES)}
    # the engine behind `reflets reference --cluster` (reflets.reference.cluster)
    info["cluster"] = {"engine": "dask.distributed", "version": versions["distributed"]}
    info["auto"] = [{"material": m, "light": light, "evaluation": how} for m, light, how in evaluation_table()]
    status = 0
    try:
        from .gpu import gl_info

        info["opengl"] = gl_info()
    except RefletsError as exc:
        info["opengl"] = {"error": str(exc)}
        status = EXIT_USER_ERROR
    if args.json:
        print(jsonio.dumps(info, indent=2))
    else:
        gl = info["opengl"]
        if "error" in gl:
            print(f"OpenGL    unavailable: {gl['error']}")
        else:
            print(f"OpenGL    {gl['version']} — {gl['renderer']} ({gl['vendor']}), REFLETS_GL={gl['driver_choice']}")
        print("methods   " + ", ".join(info["methods"]))
        print(f"cluster   references on a cluster through {info['cluster']['engine']} "
              f"{info['cluster']['version'] or '(not installed)'}: reflets reference SCENE --cluster tcp://HOST:8786")
        print("auto      how the default method evaluates each material under each light:")
        for row in info["auto"]:
            print(f"          {row['material']:<17}{row['light']:<12}{row['evaluation']}")
        for name, version in versions.items():
            print(f"{name:<24}{version or '-'}")
    return status


def cmd_schema(args) -> int:
    from .scene.schema import scene_json_schema

    print(jsonio.dumps(scene_json_schema(), indent=2))
    return 0


def cmd_demo(args) -> int:
    from .demo import run_demo

    run_demo(Path(args.output), size=_size(args.size) if args.size else None)
    return 0


def cmd_fit_ltc(args) -> int:
    from .arealights.ltc_fit import fit_ltc
    from .outputs import check_output

    params = _params(args.param)
    measured = [str(params["file"])] if "file" in params else []  # a measured BRDF's table
    out = check_output(args.output, (".npz",), inputs=measured, overwrite=args.overwrite)
    progress = None if args.quiet else (lambda i, n: print(f"\r  view angle {i}/{n}", end="", file=sys.stderr))
    table = fit_ltc(args.brdf, params, args.size, progress=progress)
    if progress is not None:
        print(file=sys.stderr)
    options = [f"--param {p}" for p in args.param] + ([f"--size {args.size}"] if args.size else [])
    table.meta["command"] = " ".join(["reflets fit-ltc --brdf", args.brdf, *options, "-o", out.name])
    table.save(out)
    e = table.meta["error_summary"]
    print(
        f"wrote {out} ({table.meta['brdf']}, {table.size[0]}x{table.size[1]}, {table.meta['fit_seconds']:.1f} s); "
        f"L1 fit error per cell: median {e['l1_median']:.4f}, mean {e['l1_mean']:.4f}, "
        f"95th percentile {e['l1_p95']:.4f}, max {e['l1_max']:.4f}"
    )
    return 0


def cmd_scratch_brdf(args) -> int:
    from .outputs import check_output
    from .scratches import build_table, plot_table

    profile = [args.profile[5:]] if args.profile.startswith("file:") else []
    out = check_output(args.output, (".npz",), inputs=profile, overwrite=args.overwrite)
    plot = Path(args.plot) if args.plot else out.with_suffix(".png")
    check_output(plot, (".png",), inputs=profile, overwrite=args.overwrite, field="--plot")
    conductor = None
    if args.conductor:
        eta, k = args.conductor[: len(args.conductor) // 2], args.conductor[len(args.conductor) // 2 :]
        if len(args.conductor) not in (2, 6):
            raise ArgumentError("give ETA K (2 numbers) or ETA_R ETA_G ETA_B K_R K_G K_B (6)", field="--conductor")
        conductor = (eta[0], k[0]) if len(eta) == 1 else (tuple(eta), tuple(k))
    started = time.perf_counter()
    table = build_table(
        args.profile,
        ior=None if args.ior is None and conductor is None else args.ior,
        conductor=conductor,
        fresnel=args.fresnel,
        size=args.size,
        rays=args.rays,
        seed=args.seed,
        backend=args.backend,
    )
    seconds = time.perf_counter() - started
    table.save(out)
    plot_table(table, plot)
    print(
        f"wrote {out} and {plot} ({args.profile}, {args.size}x{args.size}, {args.rays} rays per column, "
        f"{args.backend}, {seconds:.2f} s); max |energy - 1| over columns {np.max(np.abs(table.energy - 1.0)):.2e}"
    )
    return 0


class _Parser(argparse.ArgumentParser):
    """argparse's own errors (an unknown option, ``--iterations 1e9`` not a whole number) as one line, exit 2,
    like every other error: the usage is what ``--help`` prints."""

    def error(self, message: str):
        self.exit(EXIT_USER_ERROR, f"reflets: error: {message} (see: {self.prog} --help)\n")


def build_parser() -> argparse.ArgumentParser:
    parser = _Parser(prog="reflets", description=__doc__.splitlines()[0])
    parser.add_argument("--debug", action="store_true", help="show tracebacks of errors")
    sub = parser.add_subparsers(dest="command", required=True, metavar="COMMAND")

    p = sub.add_parser("render", help="render a scene file to EXR / PNG / NPY / HDR")
    p.add_argument("scene", help="scene file (.toml), or a glTF (.gltf, .glb) or OBJ (.obj + .mtl) file")
    _asset_options(p)
    p.add_argument("-o", "--output", help="output image (.exr, .png, .npy, .hdr); default SCENE_STEM.exr")
    p.add_argument("--size", help="WIDTHxHEIGHT, overrides the camera's size")
    p.add_argument("--method", help="technique name (see `reflets info`); default: the scene's, or auto")
    p.add_argument(
        "--spp",
        type=int,
        default=None,
        help="samples per pixel (default: the method's own, 1 for deterministic methods)",
    )
    p.add_argument("--seed", type=int, default=0, help="random seed (default 0)")
    p.add_argument(
        "--param",
        action="append",
        default=[],
        metavar="KEY=VALUE",
        help="technique parameter, repeatable (e.g. --param area_samples=16)",
    )
    p.add_argument("--exposure", type=float, default=0.0, help="PNG only: exposure in stops (default 0)")
    p.add_argument("--tonemap", choices=["srgb", "aces"], default="srgb", help="PNG only: tone curve")
    p.add_argument("--bit-depth", type=int, choices=[8, 16], default=8, help="PNG only: bits per channel (default 8)")
    _overwrite_option(p)
    p.set_defaults(func=cmd_render)

    p = sub.add_parser("view", help="interactive window over the persistent renderer (orbit, pick, edit, compare)")
    p.add_argument("scene", help="scene file (.toml), or a glTF (.gltf, .glb) or OBJ (.obj + .mtl) file")
    p.add_argument("--size", help="WIDTHxHEIGHT of the window, overrides the camera's size")
    p.add_argument("--method", help="technique name (see `reflets info`); default: the scene's, or auto")
    p.add_argument("--param", action="append", default=[], metavar="KEY=VALUE", help="technique parameter, repeatable")
    p.add_argument("--frames", type=int, help="draw N frames (after the script), write --screenshot, and exit")
    p.add_argument("--screenshot", help="with --frames: the last frame (.png: the window's pixels; .exr: HDR)")
    p.add_argument("--script", help="JSON list of events to replay, one per frame (docs/viewer.md)")
    p.add_argument("--save-scene", help="write the scene, edits included, as TOML when the viewer exits")
    p.add_argument("--stats", help="write the frame times, event latencies and status as JSON when the viewer exits")
    p.add_argument("--exposure", type=float, default=0.0, help="exposure in stops (default 0)")
    p.add_argument("--tonemap", choices=["srgb", "aces"], default="srgb", help="tone curve (default srgb)")
    _overwrite_option(p)
    p.set_defaults(func=cmd_view)

    p = sub.add_parser("highlights", help="potential highlight curves of a mesh's orientation field (ℓ per vertex)")
    p.add_argument("scene", help="scene file (.toml)")
    p.add_argument("--mesh", type=int, required=True, help="index of the mesh in the scene")
    p.add_argument("--light", type=int, help="index of the point or directional light (default: the first)")
    p.add_argument("-o", "--output", required=True, help="output .npz: positions, normals, u, h, ell, degenerate")
    _overwrite_option(p)
    p.set_defaults(func=cmd_highlights)

    p = sub.add_parser("edit-highlights", help="solve a mesh's orientation field for target highlight tangents")
    p.add_argument("scene", help="scene file (.toml)")
    p.add_argument("--mesh", type=int, required=True, help="index of the mesh in the scene")
    p.add_argument("--targets", help=".npz: ell (V, 3; zero rows: no target) and mask (V,) bool")
    p.add_argument(
        "--strokes",
        help="JSON list of up to 256 strokes (tool bend | expand | stencil, centre, radius, stroke) applied in turn",
    )
    p.add_argument("--light", type=int, help="index of the point or directional light (default: the first)")
    p.add_argument("--iterations", type=int, default=20, help="Levenberg–Marquardt iterations at most (20; 1..1000)")
    p.add_argument("-o", "--output", required=True, help="output .npz: u (V, 3, the mesh's coordinates), energy")
    _overwrite_option(p)
    p.set_defaults(func=cmd_edit_highlights)

    p = sub.add_parser("export-gltf", help="the scene as binary glTF (.glb): meshes with tangents, materials, lights")
    p.add_argument("scene", help="scene file (.toml)")
    p.add_argument("-o", "--output", required=True, help="output .glb")
    _overwrite_option(p)
    p.set_defaults(func=cmd_export_gltf)

    p = sub.add_parser("ar", help="augmented reality: marker boards and tracking (the 'ar' extra)")
    ar = p.add_subparsers(dest="ar_command", required=True, metavar="AR_COMMAND")
    q = ar.add_parser("board", help="a grid board of ArUco markers: board.json (and its printable image)")
    q.add_argument("-o", "--output", required=True, help="board.json")
    q.add_argument("--image", help="the board as a PNG to print")
    q.add_argument("--columns", type=int, default=5)
    q.add_argument("--rows", type=int, default=4)
    q.add_argument("--size", type=float, default=0.05, help="marker side in board units (default 0.05: metres)")
    q.add_argument("--gap", type=float, default=0.0125, help="space between markers")
    q.add_argument("--dictionary", default="DICT_6X6_250", help="OpenCV ArUco dictionary")
    _overwrite_option(q)
    q.set_defaults(func=cmd_ar_board)
    q = ar.add_parser("track", help="camera poses of images of a board: poses.json")
    q.add_argument("images", nargs="+", help="images (in order: a pose is kept a few frames when the board is lost)")
    q.add_argument("--intrinsics", required=True, help="camera.json: K, dist, size")
    q.add_argument("--board", required=True, help="board.json")
    q.add_argument("-o", "--output", required=True, help="poses.json")
    _overwrite_option(q)
    q.set_defaults(func=cmd_ar_track)
    q = ar.add_parser("calibrate", help="camera intrinsics from images of a board: camera.json (K, dist, size)")
    q.add_argument("images", nargs="+", help="images of the board, one size, from varied and tilted viewpoints")
    q.add_argument("--board", required=True, help="board.json")
    q.add_argument("-o", "--output", required=True, help="camera.json")
    _overwrite_option(q)
    q.set_defaults(func=cmd_ar_calibrate)
    for name, helptext in (
        ("composite", "virtual objects lit by the captured environment, composited into a photograph: out.png"),
        ("run", "the live loop (detect, pose, capture, shade, composite) on a video, a camera or images"),
    ):
        q = ar.add_parser(name, help=helptext)
        q.add_argument("scene", help="the virtual objects (.toml; board units, board frame: y up, the board at y = 0)")
        if name == "composite":
            q.add_argument("--background", required=True, help="the photograph to composite into (shows the board)")
            q.add_argument("--capture", nargs="+", help="frames (showing the board) captured into the environment")
            q.add_argument("-o", "--output", required=True, help="out.png")
            q.set_defaults(func=cmd_ar_composite)
        else:
            q.add_argument("inputs", nargs="*", help="a video file or images (or --webcam N)")
            q.add_argument("--webcam", type=int, help="a camera index (OpenCV's VideoCapture)")
            q.add_argument("--frames", type=int, help="stop after this many frames")
            q.add_argument("-o", "--output", required=True, help="a video (.mp4, .avi) or a folder of PNG frames")
            q.set_defaults(func=cmd_ar_run)
        q.add_argument("--intrinsics", required=True, help="camera.json")
        q.add_argument("--board", required=True, help="board.json")
        q.add_argument(
            "--mode",
            choices=("differential", "document"),
            default="differential",
            help="differential rendering over reflets' IBL (default), or the document's lighting",
        )
        q.add_argument("--radius", type=float, help="scene radius for the capture's parallax correction (board units)")
        q.add_argument("--environment", help="an HDR equirect light probe instead of the capture")
        q.add_argument("--supersample", type=int, default=2, help="s × s subpixels per pixel (1-4, default 2)")
        q.add_argument("--method", help="the renderer's method in the differential mode (default auto)")
        _overwrite_option(q)

    p = sub.add_parser("reference", help="ground-truth Monte Carlo render (NumPy or Mitsuba 3)")
    p.add_argument("scene", nargs="+", help="scene file (.toml), or a glTF (.gltf, .glb) or OBJ (.obj + .mtl) file; "
                   "several: a batch written into the folder -o names")  # fmt: skip
    _asset_options(p)
    p.add_argument("-o", "--output", help="output image (.exr or .npy; the standard error goes to NAME.stderr.exr), "
                   "or an existing folder: STEM.exr per scene and references.json, the content key of each (a "
                   "scene run again whose key has not changed is kept)")  # fmt: skip
    p.add_argument("--overwrite", action="store_true", help="replace an existing output image; a batch: the images "
                   "in the folder that its references.json does not say were made from these scenes and parameters")
    p.add_argument("--spp", type=int, default=64, help="samples per pixel (default 64)")
    p.add_argument("--seed", type=int, default=0, help="random seed (default 0)")
    p.add_argument(
        "--engine",
        choices=["numpy", "mitsuba", "volumetric"],
        default="numpy",
        help="numpy (direct lighting, default), mitsuba, or volumetric (translucent media, all scattering orders)",
    )
    p.add_argument("--workers", type=int, default=None, help="processes sharing the work (the same image for any "
                   "number; default: every core)")  # fmt: skip
    p.add_argument("--cluster", metavar="ADDRESS", help="tcp://HOST:PORT of a Dask scheduler: its workers share the "
                   "work (README, References on a cluster; the same image)")  # fmt: skip
    p.add_argument("--resume", action="store_true", help="volumetric engine: go on from OUTPUT.partial.npz, the "
                   "partial sums a killed run left (the image of an uninterrupted run)")  # fmt: skip
    p.add_argument("--target-error", type=float, default=None, help="volumetric engine: stop when the mean relative "
                   "standard error is at most this (0 < E < 1)")  # fmt: skip
    p.add_argument("--visibility", choices=["on", "off"], default="on", help="shadows (default on)")
    p.add_argument(
        "--pixel",
        choices=["center", "box"],
        default="center",
        help="sample pixel centres like the GPU (default) or average over the pixel",
    )
    p.add_argument("--mis", choices=["power", "balance"], default="power", help="MIS heuristic (default power)")
    p.add_argument("--size", help="WIDTHxHEIGHT, overrides the camera's size")
    p.add_argument("-q", "--quiet", action="store_true", help="no progress bar")
    p.set_defaults(func=cmd_reference)

    p = sub.add_parser("bench", help="run a benchmark suite and write benchmarks/results/SUITE.{json,md}")
    p.add_argument("suite", help="suite name: reference, arealights, ltc-cost, translucency, reflections, scratches")
    p.add_argument("-o", "--output", default="benchmarks/results", help="results folder (default benchmarks/results)")
    p.add_argument("--quick", action="store_true", help="smaller sizes, for a smoke test")
    p.add_argument("--cluster", metavar="ADDRESS", help="tcp://HOST:PORT of a Dask scheduler: its workers draw the "
                   "suite's references (default: this machine's every core)")  # fmt: skip
    p.set_defaults(func=cmd_bench)

    p = sub.add_parser("compare", help="error metrics of TEST against REFERENCE")
    p.add_argument("test")
    p.add_argument("reference")
    p.add_argument("--json", action="store_true", help="print one JSON object")
    p.add_argument("--diff", metavar="DIFF.png", help="write a false-colour relative-difference image")
    p.add_argument(
        "--stderr",
        metavar="STDERR.exr",
        help="reference's per-pixel standard error (default: REFERENCE.stderr.exr if it exists); "
        "adds mean_z, mean_abs_z, within_3_stderr",
    )
    _overwrite_option(p)
    p.set_defaults(func=cmd_compare)

    p = sub.add_parser("fit-ltc", help="fit a linearly-transformed-cosine table to a BRDF (for --method ltc)")
    p.add_argument(
        "--brdf",
        required=True,
        help="a family (ggx, beckmann, phong, blinn_phong, ward: a table over view angle x roughness) or any "
        "material type (lambert, microfacet, lafortune, ashikhmin_shirley, measured, ...: one material)",
    )
    p.add_argument(
        "--param",
        action="append",
        default=[],
        metavar="KEY=VALUE",
        help="material parameter, repeatable (e.g. --param alpha=0.3 fixes a family's roughness: one material; "
        "--param file=PATH for measured)",
    )
    p.add_argument("--size", type=int, help="entries per axis (default 64 for a family, 32 for one material)")
    p.add_argument("-o", "--output", required=True, help="output table (.npz)")
    p.add_argument("-q", "--quiet", action="store_true", help="no progress")
    _overwrite_option(p)
    p.set_defaults(func=cmd_fit_ltc)

    p = sub.add_parser("scratch-brdf", help="precompute the BRDF table of a scratch profile (2D ray tracing)")
    p.add_argument("--profile", required=True, help="vgroove:D | quartic:D | flat | file:PATH (x,h CSV or .npy)")
    p.add_argument("--ior", type=float, help="real index of the walls (Schlick); none and no --conductor: F = 1")
    p.add_argument("--conductor", type=float, nargs="+", metavar="X", help="ETA K, or 3 ETA then 3 K (RGB)")
    p.add_argument("--fresnel", choices=["auto", "exact"], default="auto", help="auto: Schlick / Lazányi")
    p.add_argument("--size", type=int, default=256, help="bins per axis (default 256)")
    p.add_argument("--rays", type=int, default=10000, help="rays per φ_in column (default 10000)")
    p.add_argument("--seed", type=int, default=0)
    p.add_argument("--backend", choices=["numpy", "gpu"], default="numpy", help="gpu: the compute shader")
    p.add_argument("-o", "--output", required=True, help="output table (.npz)")
    p.add_argument("--plot", help="plot of the table (default: the output with .png)")
    _overwrite_option(p)
    p.set_defaults(func=cmd_scratch_brdf)

    p = sub.add_parser("info", help="OpenGL driver, methods and package versions")
    p.add_argument("--json", action="store_true")
    p.set_defaults(func=cmd_info)

    p = sub.add_parser("schema", help="print the JSON schema of scene files")
    p.set_defaults(func=cmd_schema)

    p = sub.add_parser("demo", help="render the built-in scenes into an HTML gallery")
    p.add_argument("-o", "--output", default="out/demo", help="output folder (default out/demo)")
    p.add_argument("--size", help="WIDTHxHEIGHT for every scene (default: each scene's own)")
    p.set_defaults(func=cmd_demo)
    return parser


def _one_line_warnings() -> None:
    """reflets' warnings as one line on stderr, like its errors (no source line under them)."""
    import warnings

    from .diagnostics import RefletsWarning

    default = warnings.showwarning

    def show(message, category, filename, lineno, file=None, line=None):
        if issubclass(category, RefletsWarning):
            print(f"reflets: warning: {message}", file=sys.stderr)
        else:
            default(message, category, filename, lineno, file, line)

    warnings.showwarning = show


def _check_environment() -> None:
    """The environment variables reflets reads, checked as a command starts — a bad one is one line before any
    work or warning, not an error at its first use deep in a render."""
    import os

    from .cache import cache_budget
    from .resources import ENV_VAR, parse_bytes

    cache_budget()
    if os.environ.get(ENV_VAR, "").strip():
        parse_bytes(os.environ[ENV_VAR])


def main(argv: list[str] | None = None) -> int:
    parser = build_parser()
    args = parser.parse_args(argv)
    _one_line_warnings()
    try:
        _check_environment()
        return args.func(args)
    except RefletsError as exc:
        if args.debug:
            raise
        print(f"reflets: error: {exc}", file=sys.stderr)
        return EXIT_USER_ERROR
    except MemoryError as exc:  # what no estimate foresaw (reflets.resources checks the parameters that multiply)
        if args.debug:
            raise
        print(
            f"reflets: error: out of memory ({exc or 'an allocation failed'}); lower the size, spp or parameters",
            file=sys.stderr,
        )
        return EXIT_USER_ERROR
    except KeyboardInterrupt:
        print("reflets: interrupted", file=sys.stderr)
        return 130


if __name__ == "__main__":
    sys.exit(main())
