"""Long references a person can live with (the volumetric engine): a run killed half-way and resumed from its
checkpoint ends in the uninterrupted image bit for bit, in one process or several; a target error stops it early,
at the same block for any number of processes; the checkpoint of another reference is refused; the CLI keeps an
interrupted run's partial sums and never overwrites them."""

from __future__ import annotations

import numpy as np
import pytest

import reflets
from reflets.errors import ArgumentError
from reflets.reference import volumetric
from reflets.reference.volumetric import render_volumetric

SCENE = {
    "camera": {"position": [0, 0.5, 3], "look_at": [0, 0, 0], "fov_y": 35, "size": [16, 12]},
    "materials": {"skin": {"type": "translucent", "preset": "skin1", "eta": 1.0, "mm_per_unit": 25.0}},
    "mesh": [{"shape": "sphere", "radius": 1.0, "material": "skin"}],
    "light": [{"type": "point", "position": [2, 3, 2], "intensity": [20, 20, 20]}],
}


def _crash_after(monkeypatch, blocks: int, error=KeyboardInterrupt) -> None:
    """Make each process's walk fail after ``blocks`` blocks (Ctrl-C, or an error, half-way; forked workers
    inherit it)."""
    original, calls = volumetric._VolumetricJob.sums, []

    def sums(self, *args):
        if len(calls) == blocks:
            raise error("stopped half-way")
        calls.append(1)
        return original(self, *args)

    monkeypatch.setattr(volumetric._VolumetricJob, "sums", sums)


@pytest.mark.parametrize("workers", [1, 2, "cluster"])
def test_a_killed_run_resumed_gives_the_uninterrupted_image(tmp_path, monkeypatch, workers, request):
    """Ctrl-C after three blocks in one process (its sums written at once, not after SAVE_EVERY_S), then the run
    resumed in one or two processes, or on a cluster of two workers (tests/reference/conftest.py)."""
    scene = reflets.load_dict(SCENE)
    whole = render_volumetric(scene, spp=8, seed=2, progress=False)
    saved = tmp_path / "ref.partial.npz"
    with monkeypatch.context() as crashing:
        _crash_after(crashing, 3)
        with pytest.raises(KeyboardInterrupt):
            render_volumetric(scene, spp=8, seed=2, progress=False, checkpoint=saved)
    with np.load(saved) as data:
        assert int(data["next_block"]) == 3  # the blocks done before the interruption
    place = {"cluster": request.getfixturevalue("cluster").scheduler_address} if workers == "cluster" else {}
    resumed = render_volumetric(scene, spp=8, seed=2, progress=False, checkpoint=saved,
                                workers=None if place else workers, **place)  # fmt: skip
    np.testing.assert_array_equal(resumed.image, whole.image)
    np.testing.assert_array_equal(resumed.stderr, whole.stderr)
    assert resumed.spp == 8 and not saved.exists()  # the finished run's partial sums are gone


def test_an_error_in_a_worker_process_stops_the_run_and_keeps_its_sums(tmp_path, monkeypatch):
    """Two processes, each failing on its third block: the run stops at once (the other blocks dropped), the
    blocks added in order are written, and the run resumed gives the uninterrupted image."""
    scene = reflets.load_dict(SCENE)
    whole = render_volumetric(scene, spp=16, seed=2, progress=False)
    saved = tmp_path / "ref.partial.npz"
    with monkeypatch.context() as crashing:
        _crash_after(crashing, 2, error=RuntimeError)
        with pytest.raises(RuntimeError, match="half-way"):
            render_volumetric(scene, spp=16, seed=2, progress=False, checkpoint=saved, workers=2)
    with np.load(saved) as data:
        assert 0 < int(data["next_block"]) < len(volumetric.sample_blocks(16, int(whole.mask.sum())))
    resumed = render_volumetric(scene, spp=16, seed=2, progress=False, checkpoint=saved, workers=2)
    np.testing.assert_array_equal(resumed.image, whole.image)
    np.testing.assert_array_equal(resumed.stderr, whole.stderr)


def test_a_target_error_stops_at_the_same_block_in_any_number_of_processes():
    scene = reflets.load_dict(SCENE)
    full = render_volumetric(scene, spp=64, seed=1, progress=False)
    m = full.mask
    full_error = float(np.mean(full.stderr[m].mean(axis=1) / full.image[m].mean(axis=1)))
    target = 2.0 * full_error  # reached after about a quarter of the samples
    one = render_volumetric(scene, spp=64, seed=1, progress=False, target_error=target)
    two = render_volumetric(scene, spp=64, seed=1, progress=False, target_error=target, workers=2)
    assert 1 < one.spp < 64 and one.spp == two.spp
    np.testing.assert_array_equal(one.image, two.image)
    with pytest.raises(ArgumentError, match="in \\(0, 1\\)"):
        render_volumetric(scene, spp=8, progress=False, target_error=0.0)


def test_the_checkpoint_of_another_reference_is_refused(tmp_path, monkeypatch):
    scene = reflets.load_dict(SCENE)
    saved = tmp_path / "ref.partial.npz"
    with monkeypatch.context() as crashing:
        _crash_after(crashing, 2)
        with pytest.raises(KeyboardInterrupt):
            render_volumetric(scene, spp=8, seed=2, progress=False, checkpoint=saved)
    before = saved.read_bytes()
    with pytest.raises(ArgumentError, match="another reference"):
        render_volumetric(scene, spp=8, seed=3, progress=False, checkpoint=saved)  # another seed
    for junk in ("not numpy", ""):  # a file of something else; an empty one (a power cut mid-write)
        (tmp_path / "junk.npz").write_text(junk)
        with pytest.raises(ArgumentError, match="not a reflets checkpoint"):
            render_volumetric(scene, spp=8, seed=2, progress=False, checkpoint=tmp_path / "junk.npz")
    assert saved.read_bytes() == before


def test_the_cli_keeps_an_interrupted_run_s_partial_sums(tmp_path, capsys):
    from reflets.cli import main

    scene = tmp_path / "sphere.toml"
    scene.write_text(
        "[camera]\nposition = [0, 0.5, 3]\nlook_at = [0, 0, 0]\nfov_y = 35\nsize = [16, 12]\n"
        '[materials.skin]\ntype = "translucent"\npreset = "skin1"\neta = 1.0\nmm_per_unit = 25.0\n'
        '[[mesh]]\nshape = "sphere"\nradius = 1.0\nmaterial = "skin"\n'
        '[[light]]\ntype = "point"\nposition = [2, 3, 2]\nintensity = [20, 20, 20]\n'
    )
    out = tmp_path / "ref.exr"
    partial = tmp_path / "ref.exr.partial.npz"
    partial.write_bytes(b"someone's partial sums")
    args = ["reference", str(scene), "-o", str(out), "--engine", "volumetric", "--spp", "2", "-q"]
    assert main(args) == 2 and "--resume" in capsys.readouterr().err
    assert partial.read_bytes() == b"someone's partial sums" and not out.exists()
    partial.unlink()
    assert main([*args, "--resume"]) == 2 and "nothing to resume" in capsys.readouterr().err
    assert main([*args, "--target-error", "2"]) == 2 and "(0, 1)" in capsys.readouterr().err
    assert main([*args[:-3], "--spp", "1000000000", "-q"]) == 2 and "1..65536" in capsys.readouterr().err
    assert not out.exists()
    numpy_args = ["reference", str(scene), "-o", str(out), "--spp", "2", "-q", "--target-error", "0.1"]
    assert main(numpy_args) == 2 and "volumetric engine" in capsys.readouterr().err
    assert main([*args, "--target-error", "0.5"]) == 0 and out.exists() and not partial.exists()


def test_every_core_by_default(monkeypatch):
    """``reflets.reference`` without ``workers`` shares the work among every core (its engines get no count: the
    place is chosen by reflets.reference.parallel.places), or the place of an enclosing ``using`` block."""
    from reflets.reference import parallel

    seen = {}

    def fake(scene, **kwargs):
        seen.update(kwargs)
        raise StopIteration

    monkeypatch.setattr(volumetric, "render_volumetric", fake)
    monkeypatch.setattr(parallel, "cores", lambda: 7)
    with pytest.raises(StopIteration):
        reflets.reference(reflets.load_dict(SCENE), engine="volumetric", spp=2, progress=False)
    assert seen["workers"] is None and seen["cluster"] is None
    assert parallel.places().processes == 7 and isinstance(parallel.places(1), parallel.InProcess)
    with parallel.using(parallel.LocalProcesses(3)):
        assert parallel.places().processes == 3
    with pytest.raises(ArgumentError, match="not both"):
        parallel.places(2, "tcp://127.0.0.1:8786")
    for bad in (0, -3, 2.5, True):
        with pytest.raises(ArgumentError, match="at least 1"):
            parallel.places(bad)
    with pytest.raises(ArgumentError, match=r"^workers: 1000000000 needs about .* fits\)$"):  # a count given
        reflets.reference(reflets.load_dict({**SCENE, "materials": {"skin": {"type": "lambert"}}}), workers=10**9)
    with pytest.raises(ArgumentError, match="at least 1"):
        reflets.reference(reflets.load_dict(SCENE), engine="volumetric", workers=0)


def test_a_batch_of_scenes_into_a_folder_kept_by_content(tmp_path, capsys):
    """``reflets reference a.toml b.toml -o refs/``: one image per scene and an index of what each was made from;
    run again, the images whose scene and parameters did not change are kept; another image there is refused
    unless --overwrite; every argument is checked before the first image."""
    import json

    from reflets.cli import main

    scenes = []
    for name, intensity in (("a", 10), ("b", 20)):
        scene = tmp_path / f"{name}.toml"
        scene.write_text("[camera]\nposition = [0, 0, 3]\nlook_at = [0, 0, 0]\nsize = [8, 6]\n[materials.m]\n"
                         'type = "lambert"\n[[mesh]]\nshape = "sphere"\nmaterial = "m"\n[[light]]\ntype = "point"\n'
                         f"position = [1, 2, 3]\nintensity = [{intensity}, {intensity}, {intensity}]\n")  # fmt: skip
        scenes.append(str(scene))
    refs = tmp_path / "refs"
    refs.mkdir()
    base = ["reference", *scenes, "-o", str(refs), "-q", "--workers", "1"]
    args = [*base, "--spp", "2"]
    assert main(args) == 0
    index = json.loads((refs / "references.json").read_text())
    assert sorted(index) == ["a.exr", "b.exr"] and (refs / "b.stderr.exr").exists()
    before = (refs / "a.exr").stat().st_mtime_ns
    capsys.readouterr()
    assert main(args) == 0 and (refs / "a.exr").stat().st_mtime_ns == before
    assert capsys.readouterr().out.count("up to date") == 2
    assert main([*base, "--spp", "4"]) == 2  # other parameters: the images there are refused
    assert "--overwrite" in capsys.readouterr().err and (refs / "a.exr").stat().st_mtime_ns == before
    assert main([*base, "--spp", "4", "--overwrite"]) == 0
    assert json.loads((refs / "references.json").read_text())["a.exr"]["spp"] == 4
    (tmp_path / "other").mkdir()
    (tmp_path / "other" / "a.toml").write_text(open(scenes[0]).read())
    for bad in (["reference", scenes[0], str(tmp_path / "other" / "a.toml"), "-o", str(refs), "--overwrite"],
                ["reference", *scenes, "-o", str(tmp_path / "missing")],
                ["reference", *scenes]):  # fmt: skip
        assert main(bad) == 2
    err = capsys.readouterr().err
    assert "would both be written" in err and "must exist" in err and "-o FOLDER" in err
