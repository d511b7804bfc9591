"""One rule for every file a command writes (reflets.outputs, issue 32): an existing file is refused unless
--overwrite, an output naming one of the inputs is refused even then, its folder must exist (nothing creates
one), and every output is checked before the first byte of any is written."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from reflets.cli import main
from reflets.imageio import write_image

SCENE = """
[camera]
position = [0, 2, 4]
look_at = [0, 0, 0]
fov_y = 40
size = [8, 6]

[materials.m]
type = "lambert"
albedo = [0.5, 0.5, 0.5]

[[mesh]]
shape = "plane"
size = [2, 2]
material = "m"

[[light]]
type = "point"
position = [0, 2, 0]
intensity = [5, 5, 5]
"""


@pytest.fixture
def files(tmp_path):
    scene = tmp_path / "scene.toml"
    scene.write_text(SCENE)
    image = tmp_path / "a.exr"
    write_image(image, np.full((6, 8, 3), 0.5, np.float32))
    png = tmp_path / "b.png"
    write_image(png, np.full((6, 8, 3), 0.25, np.float32))
    return {"scene": scene, "image": image, "png": png, "dir": tmp_path}


#: command → (arguments before the output, the output's option, its extension)
COMMANDS = {
    "render": (lambda f: ["render", str(f["scene"]), "--method", "normal"], "-o", ".exr"),
    "export-gltf": (lambda f: ["export-gltf", str(f["scene"])], "-o", ".glb"),
    "compare": (lambda f: ["compare", str(f["image"]), str(f["image"])], "--diff", ".png"),
    "reference": (lambda f: ["reference", str(f["scene"]), "--spp", "1", "--size", "4x3", "-q", "--workers", "1"],
                  "-o", ".exr"),  # fmt: skip
    "ar board": (lambda f: ["ar", "board", "--columns", "2", "--rows", "1"], "-o", ".json"),
}


def run(capsys, argv: list[str]) -> tuple[int, str]:
    code = main(argv)
    return code, capsys.readouterr().err


@pytest.mark.parametrize("command", COMMANDS)
def test_an_existing_output_is_refused_then_replaced_with_overwrite(ctx, capsys, files, command):
    args, option, ext = COMMANDS[command]
    out = files["dir"] / f"out{ext}"
    out.write_bytes(b"the user's own file")
    code, err = run(capsys, [*args(files), option, str(out)])
    assert code == 2 and err.count("\n") == 1 and str(out) in err and "--overwrite" in err, err
    assert out.read_bytes() == b"the user's own file"
    code, err = run(capsys, [*args(files), option, str(out), "--overwrite"])
    assert code == 0, err
    assert out.read_bytes() != b"the user's own file"


@pytest.mark.parametrize("command", COMMANDS)
def test_an_output_in_a_missing_folder_creates_nothing(capsys, files, command):
    args, option, ext = COMMANDS[command]
    out = files["dir"] / "missing" / f"out{ext}"
    code, err = run(capsys, [*args(files), option, str(out), "--overwrite"])
    assert code == 2 and err.count("\n") == 1 and "does not exist" in err, err
    assert not out.parent.exists()


@pytest.mark.parametrize(("argv", "named"), [
    (lambda f: ["compare", str(f["image"]), str(f["png"]), "--diff", str(f["png"]), "--overwrite"], "b.png"),
    (lambda f: ["compare", str(f["image"]), str(f["image"]), "--diff", str(f["dir"] / "a.stderr.exr")], "--diff"),
    (lambda f: ["reference", str(f["scene"]), "-o", str(f["dir"] / "scene.toml"), "--overwrite"], "scene.toml"),
])  # fmt: skip
def test_an_output_that_is_an_input_is_refused_even_with_overwrite(capsys, files, argv, named):
    before = {p: p.read_bytes() for p in files["dir"].iterdir()}
    code, err = run(capsys, argv(files))
    assert code == 2 and err.count("\n") == 1 and named in err, err
    assert {p: p.read_bytes() for p in files["dir"].iterdir()} == before


def test_an_input_named_through_a_link_is_still_an_input(capsys, files):
    link = files["dir"] / "link.png"
    link.hardlink_to(files["png"])
    code, err = run(capsys, ["compare", str(files["image"]), str(files["png"]), "--diff", str(link), "--overwrite"])
    assert code == 2 and "is one of the inputs" in err, err


def test_every_output_is_checked_before_the_first_is_written(capsys, files):
    board, image = files["dir"] / "board.json", files["dir"] / "board.png"
    image.write_bytes(b"kept")
    code, err = run(capsys, ["ar", "board", "-o", str(board), "--image", str(image)])
    assert code == 2 and "board.png" in err and not board.exists()
    code, err = run(capsys, ["ar", "board", "-o", str(board), "--image", str(board.with_suffix(".json"))])
    assert code == 2 and not board.exists()  # an image must be a .png
    code, err = run(capsys, ["scratch-brdf", "--profile", "flat", "-o", str(files["dir"] / "t.npz"),
                             "--plot", str(files["dir"] / "missing" / "t.png")])  # fmt: skip
    assert code == 2 and not (files["dir"] / "t.npz").exists(), err


def test_view_refuses_its_outputs_before_opening_a_window(capsys, files):
    saved = files["dir"] / "saved.toml"
    saved.write_text("mine")
    for option, path in (("--save-scene", saved), ("--stats", files["scene"]), ("--screenshot", files["image"])):
        code, err = run(capsys, ["view", str(files["scene"]), "--frames", "1", option, str(path)])
        assert code == 2 and err.count("\n") == 1 and option in err, err
    assert saved.read_text() == "mine"
    code, err = run(capsys, ["view", str(files["scene"]), "--screenshot", str(files["dir"] / "new.png")])
    assert code == 2 and "--frames" in err and not (files["dir"] / "new.png").exists()  # else never written


def test_the_api_export_refuses_to_replace_a_file_the_scene_reads(files, tmp_path):
    from reflets.errors import OutputError
    from reflets.gltf import export_gltf
    from reflets.scene import load_dict

    mesh = tmp_path / "m.glb"
    scene = load_dict({"camera": {"position": [0, 1, 3], "look_at": [0, 0, 0], "size": [8, 6]},
                       "materials": {"m": {"type": "lambert", "albedo": [0.5, 0.5, 0.5]}},
                       "mesh": [{"shape": "sphere", "material": "m"}]})  # fmt: skip
    export_gltf(scene, mesh)
    with_file = load_dict({"camera": {"position": [0, 1, 3], "look_at": [0, 0, 0], "size": [8, 6]},
                           "mesh": [{"file": str(mesh)}]})  # fmt: skip
    before = mesh.read_bytes()
    with pytest.raises(OutputError, match="is one of the inputs"):
        export_gltf(with_file, mesh, overwrite=True)
    assert mesh.read_bytes() == before
    assert Path(export_gltf(with_file, tmp_path / "copy.glb")[0]).is_file()


#: commands whose output is checked before their inputs are read: an existing output is refused at once (the
#: inputs named need not even exist), an input named as the output too
REFUSED_FIRST = {
    "highlights": lambda f, out: ["highlights", str(f["scene"]), "--mesh", "0", "-o", out],
    "edit-highlights": lambda f, out: ["edit-highlights", str(f["scene"]), "--mesh", "0", "--targets",
                                       str(f["dir"] / "targets.npz"), "-o", out],
    "ar track": lambda f, out: ["ar", "track", str(f["png"]), "--intrinsics", str(f["dir"] / "camera.json"),
                                "--board", str(f["dir"] / "board.json"), "-o", out],
    "ar calibrate": lambda f, out: ["ar", "calibrate", str(f["png"]), "--board", str(f["dir"] / "board.json"),
                                    "-o", out],
    "ar composite": lambda f, out: ["ar", "composite", str(f["scene"]), "--background", str(f["png"]),
                                    "--intrinsics", str(f["dir"] / "camera.json"), "--board",
                                    str(f["dir"] / "board.json"), "-o", out],
    "ar run": lambda f, out: ["ar", "run", str(f["scene"]), str(f["dir"] / "clip.mp4"), "--intrinsics",
                              str(f["dir"] / "camera.json"), "--board", str(f["dir"] / "board.json"), "-o", out],
}  # fmt: skip
#: an input of each command with its output's extension, named as its output (with --overwrite: refused all the
#: same; highlights reads no file an .npz output could name)
AN_INPUT = {"edit-highlights": "targets.npz", "ar track": "board.json",
            "ar calibrate": "board.json", "ar composite": "b.png", "ar run": "clip.mp4"}  # fmt: skip
EXTENSIONS = {"highlights": ".npz", "edit-highlights": ".npz", "ar track": ".json", "ar calibrate": ".json",
              "ar composite": ".png", "ar run": ".mp4"}  # fmt: skip


@pytest.mark.parametrize("command", REFUSED_FIRST)
def test_the_other_commands_refuse_an_existing_output_or_an_input_before_any_work(capsys, files, command):
    argv = REFUSED_FIRST[command]
    existing = files["dir"] / f"out{EXTENSIONS[command]}"
    existing.write_bytes(b"mine")
    code, err = run(capsys, argv(files, str(existing)))
    assert code == 2 and err.count("\n") == 1 and "exists already" in err, err
    assert existing.read_bytes() == b"mine"
    if command not in AN_INPUT:
        return
    named = files["dir"] / AN_INPUT[command]
    if not named.exists():
        named.write_text("{}")
    before = named.read_bytes()
    code, err = run(capsys, [*argv(files, str(named)), "--overwrite"])
    assert code == 2 and err.count("\n") == 1, err
    assert "is one of the inputs" in err, err
    assert named.read_bytes() == before


def test_a_link_that_loops_is_no_input_and_no_traceback(capsys, files):
    loop = files["dir"] / "loop.png"
    loop.symlink_to(loop)
    code, err = run(capsys, ["compare", str(files["image"]), str(files["png"]), "--diff", str(loop)])
    assert code in (0, 2) and "Traceback" not in err and err.count("\n") <= 1, err
