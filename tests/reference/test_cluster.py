"""References on a Dask cluster (reflets.reference.cluster): the image and its standard error equal one
process's bit for bit (numpy and volumetric engines), the scene's files travel by content, a worker killed during
the run has its tasks run again (the same results), and bad addresses, unreachable schedulers and version
mismatches are one line, exit 2. The resumed run on a cluster: tests/reference/test_reference_runs.py."""

from __future__ import annotations

import hashlib
import os
import signal

import numpy as np
import pytest

import reflets
from reflets.cli import main
from reflets.errors import ArgumentError
from reflets.reference import cluster as clusters
from reflets.reference.montecarlo import MonteCarloReference
from reflets.reference.parallel import InProcess

TRANSLUCENT = {
    "camera": {"position": [0, 0.5, 3], "look_at": [0, 0, 0], "fov_y": 35, "size": [16, 12]},
    "materials": {"skin": {"type": "translucent", "preset": "skin1", "eta": 1.0, "mm_per_unit": 25.0}},
    "mesh": [{"shape": "sphere", "radius": 1.0, "material": "skin"}],
    "light": [{"type": "point", "position": [2, 3, 2], "intensity": [20, 20, 20]}],
}


def _mesh_scene(tmp_path):
    """A scene that reads a file (an OBJ mesh next to it), to be shipped."""
    (tmp_path / "tri.obj").write_text("v -1 -1 0\nv 1 -1 0\nv 0 1 0\nf 1 2 3\n")
    return reflets.load_dict({
        "camera": {"position": [0, 0, 3], "look_at": [0, 0, 0], "fov_y": 50, "size": [24, 16]},
        "materials": {"m": {"type": "microfacet", "distribution": "ggx", "alpha": 0.3}},
        "mesh": [{"file": "tri.obj", "material": "m"}],
        "light": [{"type": "quad", "corners": [[-0.5, 1, 1], [0.5, 1, 1], [-0.5, 1.5, 2]], "radiance": [5, 5, 5]}],
    }, base_dir=tmp_path)  # fmt: skip


def test_references_on_a_cluster_equal_one_process_bit_for_bit(cluster, tmp_path):
    address = cluster.scheduler_address
    scene = _mesh_scene(tmp_path)
    one = reflets.reference(scene, spp=64, workers=1, progress=False)
    remote = reflets.reference(scene, spp=64, cluster=address, progress=False)
    np.testing.assert_array_equal(remote.image, one.image)
    np.testing.assert_array_equal(remote.stderr, one.stderr)
    assert one.image.max() > 0
    digest = hashlib.sha256((tmp_path / "tri.obj").read_bytes()).hexdigest()
    assert (cluster.cache / "reflets" / "cluster" / "files" / digest).is_file()  # fetched by its content
    # adaptive rounds: a session's second run of tasks (new task keys), the refined pixels the same
    one = reflets.reference(scene, spp=16, workers=1, progress=False, adaptive_error=0.05, adaptive_spp=64)
    remote = reflets.reference(scene, spp=16, cluster=address, progress=False, adaptive_error=0.05, adaptive_spp=64)
    assert one.pixel_spp.max() == 64
    np.testing.assert_array_equal(remote.image, one.image)
    np.testing.assert_array_equal(remote.pixel_spp, one.pixel_spp)

    translucent = reflets.load_dict(TRANSLUCENT)
    one = reflets.reference(translucent, spp=16, seed=3, engine="volumetric", workers=1, progress=False)
    remote = reflets.reference(translucent, spp=16, seed=3, engine="volumetric", cluster=address, progress=False)
    np.testing.assert_array_equal(remote.image, one.image)
    np.testing.assert_array_equal(remote.stderr, one.stderr)


def test_a_translucent_reference_in_tiles_of_pixels(cluster, monkeypatch):
    """The volumetric engine's blocks of samples split into tiles of the object's pixels (a large image: many
    tasks for a cluster): 1 process, 2 processes and the cluster give one image bit for bit; a single tile is the
    untiled image of before, several another estimate of it (other streams, within the standard errors)."""
    from reflets.reference import volumetric

    translucent = reflets.load_dict(TRANSLUCENT)
    untiled = volumetric.render_volumetric(translucent, spp=8, seed=3, progress=False)
    monkeypatch.setattr(volumetric, "VOLUMETRIC_TILE_PIXELS", 40)  # the tiles are made here, sent with the tasks
    assert len(volumetric.pixel_tiles(int(untiled.mask.sum()))) >= 3
    one = volumetric.render_volumetric(translucent, spp=8, seed=3, progress=False)
    for where in ({"workers": 2}, {"cluster": cluster.scheduler_address}):
        other = volumetric.render_volumetric(translucent, spp=8, seed=3, progress=False, **where)
        np.testing.assert_array_equal(other.image, one.image)
        np.testing.assert_array_equal(other.stderr, one.stderr)
    m = one.mask
    assert not np.array_equal(one.image, untiled.image)
    z = (one.image[m] - untiled.image[m]) / np.sqrt(one.stderr[m] ** 2 + untiled.stderr[m] ** 2 + 1e-30)
    assert abs(float(np.mean(z))) < 0.2 and float(np.mean(np.abs(z))) < 1.2


def test_a_worker_killed_during_the_run_has_its_tasks_run_again(cluster, tmp_path):
    """Twelve tiles; one worker process killed (SIGKILL) as the first tile comes back: Dask's nanny starts a new
    one, the lost tiles run again, and every tile equals the one drawn in this process."""
    scene = _mesh_scene(tmp_path)
    pixels = np.arange(24 * 16)
    tasks = [(pixels[i * 32 : (i + 1) * 32], 1024, (5, i), (24, 16, "center")) for i in range(12)]
    here = dict(InProcess().start(MonteCarloReference, (scene,)).run(tasks, [1] * 12, lambda k: None))
    place = clusters.connect(cluster.scheduler_address)
    try:
        pids = place.client.run(os.getpid)
        results, killed = {}, False
        with place.start(MonteCarloReference, (scene,)) as session:
            for index, result in session.run(tasks, [1] * 12, lambda k: None):
                if not killed:
                    os.kill(next(iter(pids.values())), signal.SIGKILL)
                    killed = True
                results[index] = result
        assert sorted(results) == list(range(12))
        for index, (mean, err) in results.items():
            np.testing.assert_array_equal(mean, here[index][0])
            np.testing.assert_array_equal(err, here[index][1])
        assert place.client.run(os.getpid) != pids  # a new worker process took the killed one's place
    finally:
        place.close()


@pytest.mark.parametrize("address, says", [
    ("nonsense", "not a scheduler address"),
    ("http://127.0.0.1:8786", "not a scheduler address"),
    ("tcp://127.0.0.1:99999", "not a scheduler address"),
    ("", "an address is needed"),
])  # fmt: skip
def test_a_bad_address_is_one_line(address, says):
    with pytest.raises(ArgumentError, match=says):
        clusters.connect(address)


def test_an_unreachable_scheduler_is_one_line_exit_2(tmp_path, monkeypatch, capsys):
    monkeypatch.setattr(clusters, "CONNECT_TIMEOUT_S", 1.0)
    scene = tmp_path / "s.toml"
    scene.write_text('[camera]\nposition = [0, 0, 3]\nlook_at = [0, 0, 0]\nsize = [8, 8]\n')
    code = main(["reference", str(scene), "-o", str(tmp_path / "r.exr"), "--cluster", "tcp://127.0.0.1:9", "-q"])
    err = capsys.readouterr().err.strip()
    assert code == 2 and len(err.splitlines()) == 1 and "no Dask scheduler answered" in err
    assert not (tmp_path / "r.exr").exists()


def test_a_version_mismatch_names_the_worker_and_the_versions():
    here = {"python": "3.11", "reflets": "0.5.0", "numpy": "2.1.0", "distributed": "2026.8.0", "cloudpickle": "3.1"}
    workers = {"tcp://10.0.0.2:4000": dict(here), "tcp://10.0.0.3:4000": {**here, "numpy": "1.26.4"}}
    clusters.check_versions("tcp://10.0.0.1:8786", here, {"tcp://10.0.0.2:4000": dict(here)})  # all match
    with pytest.raises(ArgumentError, match=r"worker tcp://10.0.0.3:4000 runs numpy 1.26.4 \(here 2.1.0\)"):
        clusters.check_versions("tcp://10.0.0.1:8786", here, workers)


def test_a_shipped_scene_is_laid_out_from_its_files_contents(tmp_path, monkeypatch):
    """What a worker sees: the scene's paths under a folder of its content key, the files as they were."""
    scene = _mesh_scene(tmp_path)
    shipped, contents = clusters.ShippedScene.packed(scene)
    monkeypatch.setenv("XDG_CACHE_HOME", str(tmp_path / "worker"))
    with pytest.raises(reflets.errors.RefletsError, match="was not sent to this worker"):
        shipped.scene()
    clusters._keep_files(contents)  # as a task keeps them
    there = shipped.scene()
    (mesh,) = there.input_files()
    assert str(mesh).startswith(str(tmp_path / "worker")) and mesh.read_bytes() == (tmp_path / "tri.obj").read_bytes()
    assert there.model_copy(update={"mesh": scene.mesh}) == scene.model_copy(update={"base_dir": None})


def test_the_mitsuba_bridge_split_into_crop_windows_on_a_cluster(cluster, tmp_path):
    """Mitsuba 3 renders the film in crop windows (each its own seed, from the size and seed alone): on the
    cluster's workers the same image as in this process; a film of one window is the whole-film render of before."""
    pytest.importorskip("mitsuba")
    from reflets.reference.mitsuba_bridge import MITSUBA_TILE, mitsuba_tiles, render_mitsuba

    scene = _mesh_scene(tmp_path)
    size = (MITSUBA_TILE * 2 + 10, MITSUBA_TILE + 5)  # six windows, the last ones partial
    assert len(mitsuba_tiles(*size, 3)) == 6 and mitsuba_tiles(16, 12, 3) == [((0, 0, 16, 12), 3)]
    here = render_mitsuba(scene, spp=4, seed=3, size=size)
    there = reflets.reference(scene, spp=4, seed=3, size=size, engine="mitsuba", cluster=cluster.scheduler_address,
                              progress=False).image  # fmt: skip
    np.testing.assert_array_equal(there, here)
    assert here.max() > 0
