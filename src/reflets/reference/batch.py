"""``reflets reference``: one scene into one image, or a batch of scenes into a folder kept by content.

    reflets reference scene.toml -o scene.ref.exr            # and scene.ref.stderr.exr
    reflets reference scenes/*.toml -o refs/ [--cluster tcp://HOST:8786]

Everything is checked before the first reference starts (each scene read and validated, each output's folder,
name and extension, no output equal to an input, no two outputs with one name), so a typo fails in seconds, not
after an hour of work. A batch writes ``refs/STEM.exr`` and ``refs/STEM.stderr.exr`` per scene and an index,
``refs/references.json``: the content key of what each image was made from (the scene, its files' contents and
the reference's parameters: reflets.reference.store.fingerprint). Run again, a batch keeps the images whose key
has not changed and renders the others; an image there that the index does not vouch for is refused (replaced
with ``--overwrite``). The references of a batch share one place (reflets.reference.parallel: every core, or one cluster
connection).
"""

from __future__ import annotations

import json
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path

from ..errors import ArgumentError, OutputError
from .checkpoint import PartialSums

INDEX = "references.json"


@dataclass
class Planned:
    """One reference to make: its scene, its outputs and, in a batch, its content key."""

    source: Path
    scene: object
    out: Path
    stderr: Path
    checkpoint: Path | None
    key: str | None = None  # a batch's content key (None: a single output, not indexed)
    up_to_date: bool = False


def plan(sources: list[str], output: str | None, load: Callable, *, engine: str, resume: bool, params: dict,
         overwrite: bool = False) -> list[Planned]:  # fmt: skip
    """The references to make, every argument checked (module docstring); ``params`` the reference's
    parameters that make its content key (spp, seed, size, ...); ``overwrite``: one scene's output replaces the
    image there, a batch the images its index does not vouch for (both refused otherwise)."""
    from ..outputs import check_not_input, check_output, check_output_path

    folder = Path(output) if output else None
    batch = len(sources) > 1 or (folder is not None and folder.is_dir())
    if batch and folder is None:
        raise ArgumentError("several scenes need -o FOLDER (an existing folder)", field="-o")
    if batch and not folder.is_dir():
        raise OutputError("several scenes are written into a folder: "
                          + ("this is a file" if folder.exists() else "it must exist"), file=folder)  # fmt: skip
    index = _read_index(folder / INDEX) if batch else {}
    planned: list[Planned] = []
    for source in sources:
        scene = load(source)
        if engine == "volumetric":  # what the engine cannot render, said before any image is written
            from .volumetric import _check_volumetric_scene

            _check_volumetric_scene(scene)
        out = folder / (Path(source).stem + ".exr") if batch else folder or Path(Path(source).stem + ".ref.exr")
        check_output_path(out, (".exr", ".npy"))
        item = Planned(Path(source), scene, out, out.with_name(out.stem + ".stderr" + out.suffix),
                       _checkpoint(out, engine, resume, batch))  # fmt: skip
        for other in planned:
            if {item.out.resolve(), item.stderr.resolve()} & {other.out.resolve(), other.stderr.resolve()}:
                raise ArgumentError(f"{other.source} and {source} would both be written to {out.parent} as "
                                    f"{out.name} or {item.stderr.name}: give the scenes different names",
                                    field="scene")  # fmt: skip
        if batch:
            item.key = _content_key(scene, engine, params)
            entry = index.get(out.name, {})
            made = out.exists() and (engine == "mitsuba" or item.stderr.exists())
            item.up_to_date = made and entry.get("key") == item.key
            if not item.up_to_date and not overwrite:
                for path in (out, item.stderr):
                    if path.exists():
                        raise OutputError(f"exists and {folder / INDEX} does not say it was made from this scene "
                                          "and these parameters: --overwrite to replace it, or write elsewhere",
                                          file=path)  # fmt: skip
        planned.append(item)
    inputs = set().union(*(item.scene.input_files() | {item.source} for item in planned))
    for item in planned:  # no output replaces a file that any of the scenes reads
        for path in (item.out, item.stderr):
            check_not_input(path, inputs)
    if not batch:  # one scene's output: the rule of every command (reflets.outputs)
        item = planned[0]
        for path in (item.out, item.stderr) if engine != "mitsuba" else (item.out,):  # Mitsuba: no error image
            check_output(path, (".exr", ".npy"), overwrite=overwrite)
    return planned


def _content_key(scene, engine: str, params: dict) -> str:
    """What a batch's image was made from: the reference store's fingerprint (the scene, its meshes' and textures'
    contents, the parameters) and the contents of every other file the scene reads (maps, masks, measured BRDFs)."""
    from ..cache import file_digest
    from .store import fingerprint

    files = {str(path): file_digest(path) for path in sorted(scene.input_files())}
    return fingerprint(scene, engine=engine, files=sorted(files.values()), **params)[0]


def _checkpoint(out: Path, engine: str, resume: bool, batch: bool) -> Path | None:
    """A volumetric reference keeps its partial sums next to its output (OUTPUT.partial.npz): there, they are gone
    on from with ``--resume`` only; ``--resume`` with none there is an error for one scene (nothing to resume), a
    fresh start for a batch's scene."""
    if engine != "volumetric":
        if resume:
            raise ArgumentError("--resume is the volumetric engine's (--engine volumetric)", field="--resume")
        return None
    checkpoint = out.with_name(out.name + ".partial.npz")
    if checkpoint.exists() and not resume:
        raise OutputError("partial sums of an interrupted reference are there: --resume to go on from them, or "
                          "delete them", file=checkpoint)  # fmt: skip
    if resume and not batch and not checkpoint.exists():
        raise ArgumentError(f"nothing to resume: {checkpoint} does not exist", field="--resume")
    return checkpoint


def _read_index(path: Path) -> dict:
    if not path.exists():
        return {}
    try:
        index = json.loads(path.read_text())
    except (OSError, UnicodeDecodeError, json.JSONDecodeError) as exc:
        raise OutputError(f"not a reflets index of references ({exc}): move it away", file=path) from None
    if not isinstance(index, dict) or not all(isinstance(v, dict) for v in index.values()):
        raise OutputError("not a reflets index of references: move it away", file=path)
    return index


def make(planned: list[Planned], render: Callable[[Planned], object], say: Callable[[str], None] = print) -> None:
    """Render each planned reference (``render(item)`` → a ReferenceResult) and write its images; a batch's index
    is written after each one, so that a batch stopped half-way keeps what it finished."""
    from ..imageio import write_image
    from ..jsonio import write

    for item in planned:
        if item.up_to_date:
            say(f"kept {item.out}: up to date (same scene, files and parameters)")
            continue
        index_path = item.out.parent / INDEX
        if item.key is not None and item.out.name in (index := _read_index(index_path)):
            del index[item.out.name]  # replaced: the entry goes first, so that a kill never leaves it vouching
            write(index_path, index, indent=2)
        result = render(item)
        write_image(item.out, result.image)
        if result.engine != "mitsuba":
            write_image(item.stderr, result.stderr)
        if item.checkpoint is not None:  # the images are safe: the partial sums go
            PartialSums(item.checkpoint, "").remove()
        if item.key is not None:
            index = _read_index(index_path)
            index[item.out.name] = {"key": item.key, "scene": str(item.source), "engine": result.engine,
                                    "spp": result.spp, "seconds": round(result.seconds, 3)}  # fmt: skip
            write(index_path, index, indent=2)
        say(
            f"wrote {item.out}"
            + (f" and {item.stderr}" if result.engine != "mitsuba" else "")
            + f" ({result.spp} spp, {result.seconds:.1f} s, {result.samples_per_second / 1e6:.2f} M samples/s)"
        )
