"""The fuzzing pass's findings (issue 19) as regression tests: each ends in one line naming the field or file,
exit 2 — never a traceback, an abort or an overflow blamed on the output image."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from reflets.cli import main
from reflets.demo import scene_path

PLANE = scene_path("01_plane_point.toml").read_text()


def _run(capsys, argv) -> str:
    assert main(argv) == 2, argv
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1 and "Traceback" not in err, err
    return err


def _render(capsys, tmp_path: Path, text: str, *extra: str) -> str:
    scene = tmp_path / "scene.toml"
    scene.write_text(text)
    return _run(capsys, ["render", str(scene), "-o", str(tmp_path / "out.png"), "--size", "32x24", *extra])


@pytest.mark.parametrize("spp", ["1000000000000", "66049", "-1", "0"])
def test_samples_per_pixel_out_of_range(capsys, tmp_path, spp):
    assert "spp" in _render(capsys, tmp_path, PLANE, "--spp", spp)


@pytest.mark.parametrize("grid", ["[0,0]", "[-1,4]", "[100000,100000]"])
def test_environment_grid_out_of_range(capsys, tmp_path, grid):
    assert "env_grid" in _render(capsys, tmp_path, PLANE, "--param", f"env_grid={grid}")


@pytest.mark.parametrize(
    "value",
    ["x = " + "[" * 1000 + "]" * 1000, "x = " + "{a = " * 1000 + "1" + "}" * 1000,
     "[camera.up2]\nv = " + "[" * 500 + "1" + "]" * 500],
)  # fmt: skip
def test_values_nested_too_deeply(capsys, tmp_path, value):
    assert "nested too deeply" in _render(capsys, tmp_path, PLANE + "\n" + value + "\n")


def test_a_dict_nested_too_deeply_is_a_scene_error():
    import reflets
    from reflets.errors import SceneError

    deep = 1
    for _ in range(5000):
        deep = [deep]
    with pytest.raises(SceneError, match="nested too deeply"):
        reflets.render({"camera": {"position": [0, 1, 1], "look_at": [0, 0, 0]}, "mesh": deep})


def test_empty_npy_height_field_and_profile(capsys, tmp_path):
    (tmp_path / "empty.npy").write_bytes(b"")
    head = '[camera]\nposition = [0, 2, 2]\nlook_at = [0, 0, 0]\n[materials.m]\n'
    err = _render(capsys, tmp_path, head + 'type = "lambert"\n[[mesh]]\nshape = "heightfield"\nfile = "empty.npy"\n'
                  'material = "m"\n')  # fmt: skip
    assert "empty.npy" in err and "mesh[0].file" in err
    profile = tmp_path / "empty.npy"  # a profile path is taken as given (docs/techniques/scratches.md)
    err = _render(capsys, tmp_path, head + f'type = "scratched"\nprofile = "file:{profile}"\n[[mesh]]\n'
                  'shape = "plane"\nmaterial = "m"\n')  # fmt: skip
    assert "empty.npy" in err and "profile" in err


@pytest.mark.parametrize(
    ("old", "new", "field"),
    [
        ("intensity = [10, 10, 10]", "intensity = [1e308, 10, 10]", "light[0].intensity"),
        ("size = [4, 4]", "size = [1e30, 4]", "mesh[0].size"),
        ("position = [0, 3, 4]", "position = [0, 3e300, 4]", "camera.position"),
        ("albedo = [0.8, 0.8, 0.8]", "albedo = [0.8, 0.8, 1e40]", "albedo"),
    ],
)
def test_magnitudes_are_refused_by_field(capsys, tmp_path, old, new, field):
    assert old in PLANE
    assert field in _render(capsys, tmp_path, PLANE.replace(old, new))


def test_a_mesh_file_whose_coordinates_overflow(capsys, tmp_path):
    (tmp_path / "big.obj").write_text("v 0 0 0\nv 1e30 0 0\nv 0 1 0\nf 1 2 3\n")
    text = PLANE.replace('[[mesh]]\nshape = "plane"\nsize = [4, 4]', '[[mesh]]\nfile = "big.obj"')
    err = _render(capsys, tmp_path, text)
    assert "big.obj" in err and "coordinates" in err


def test_an_environment_only_large_names_its_scale(capsys, tmp_path):
    np.save(tmp_path / "sky.npy", np.full((8, 16, 3), 1e6, np.float32))
    text = PLANE + '\n[[light]]\ntype = "environment"\nfile = "sky.npy"\nscale = 1e7\n'
    err = _render(capsys, tmp_path, text)
    assert "sky.npy" in err and "scale" in err
