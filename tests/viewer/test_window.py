"""``reflets view`` in a real window under Xvfb (installed by the project's set-up, tools/install-system-packages):
the window's pixels against ``reflets render``, a replayed event script against a one-shot render of the
scene the viewer saves, and clear errors. Each test runs the command in its own process (the window's GLX
context becomes that process's reflets context)."""

from __future__ import annotations

import json
import os
import re
import shutil
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

import reflets
from reflets.demo import scene_path
from reflets.metrics import relmse

SHOWCASE = scene_path("60_showcase.toml")
SIZE = "160x120"


def reflets_cmd(*args: str, display: bool = True, timeout: float = 300) -> subprocess.CompletedProcess:
    xvfb = shutil.which("xvfb-run")
    if display and xvfb is None:
        pytest.fail("xvfb-run is missing: `make test` installs it (tools/install-system-packages)")
    base = [xvfb, "-a", "-s", "-screen 0 1024x768x24"] if display else []
    env = None if display else {k: v for k, v in os.environ.items() if k != "DISPLAY"}
    return subprocess.run(
        [*base, sys.executable, "-m", "reflets.cli", *args], capture_output=True, text=True, timeout=timeout, env=env
    )


def psnr(a: np.ndarray, b: np.ndarray) -> float:
    mse = np.mean((a.astype(np.float64) - b.astype(np.float64)) ** 2)
    return float("inf") if mse == 0 else 10 * np.log10(255.0**2 / mse)


@pytest.mark.slow
def test_the_window_shows_what_render_writes(tmp_path):
    """`reflets view SCENE --frames 30 --screenshot shot.png` (the window's pixels) against `reflets render SCENE
    -o x.png`: PSNR ≥ 40 dB (the showcase's scratch lobes accumulate 30 frames in the window, one in render)."""
    shot, rendered = tmp_path / "shot.png", tmp_path / "x.png"
    done = reflets_cmd("view", str(SHOWCASE), "--size", SIZE, "--frames", "30", "--screenshot", str(shot))
    assert done.returncode == 0, done.stderr
    assert "30 frames" in done.stdout
    done = reflets_cmd("render", str(SHOWCASE), "--size", SIZE, "-o", str(rendered), display=False)
    assert done.returncode == 0, done.stderr
    from PIL import Image

    a, b = np.asarray(Image.open(shot)), np.asarray(Image.open(rendered))
    assert a.shape == b.shape == (120, 160, 3)
    assert psnr(a, b) >= 40.0


@pytest.mark.slow
def test_a_replayed_script_ends_in_the_saved_scene_s_image(tmp_path, ctx):
    """Orbit, select the statue (a click on the bunny), set its roughness, drag the quad light (shift + drag):
    the last frame (EXR) equals a one-shot render of the scene the viewer saves, with the samples the viewer
    accumulated (relative MSE < 1e-4)."""
    from reflets.scene.camera import project

    scene = reflets.load_scene(SHOWCASE)
    bunny = np.asarray(scene.mesh[1].transform.translate) + [0.0, 0.35, 0.0]
    script = [
        {"type": "orbit", "dx": 12, "dy": 4},
        {"type": "wait", "frames": 2},
    ]
    # the bunny's pixel after the orbit: the viewer's camera, orbited the same way (no window needed)
    from reflets.viewer import OrbitCamera

    camera = OrbitCamera.from_camera(scene.camera)
    camera.orbit(script[0]["dx"], script[0]["dy"])
    x, y = project(scene.camera.model_copy(update=camera.fields()), bunny, (160, 120))
    script += [
        {"type": "pointer", "action": "down", "x": float(x), "y": float(y)},
        {"type": "pointer", "action": "up", "x": float(x), "y": float(y)},
        {"type": "material", "fields": {"alpha": 0.12}},
        {"type": "select", "light": 0},
        {"type": "pointer", "action": "down", "x": 80, "y": 40, "shift": True},
        {"type": "pointer", "action": "move", "x": 95, "y": 40, "shift": True},
        {"type": "pointer", "action": "up", "x": 95, "y": 40, "shift": True},
    ]
    (tmp_path / "script.json").write_text(json.dumps(script))
    shot, saved = tmp_path / "last.exr", tmp_path / "edited.toml"
    done = reflets_cmd(
        "view", str(SHOWCASE), "--size", SIZE, "--script", str(tmp_path / "script.json"),
        "--frames", "3", "--screenshot", str(shot), "--save-scene", str(saved),
    )  # fmt: skip
    assert done.returncode == 0, done.stderr
    spp = int(re.search(r"of (\d+) spp", done.stdout).group(1))
    edited = reflets.load_scene(saved)
    assert edited.materials["glaze"].alpha == pytest.approx(0.12)  # the statue's material, picked by the click
    assert not np.allclose(edited.light[0].corners, scene.light[0].corners)
    assert edited.camera.position != scene.camera.position
    expected = reflets.render(edited, size=(160, 120), spp=spp)
    assert relmse(reflets.imageio.read_image(shot), expected) < 1e-4


def test_without_a_display_the_viewer_says_so(tmp_path):
    done = reflets_cmd("view", str(SHOWCASE), "--frames", "1", display=False, timeout=60)
    assert done.returncode == 2
    assert "cannot open a window" in done.stderr and "xvfb-run" in done.stderr
    assert "Traceback" not in done.stderr


@pytest.mark.parametrize(
    "args, message",
    [
        (["--script", "missing.json"], "missing.json: --script: file not found"),
        (["--frames", "0"], "--frames"),
        (["--screenshot", "shot.bmp", "--frames", "1"], "shot.bmp"),
    ],
)
def test_bad_view_arguments_are_one_line_errors(tmp_path, args, message):
    args = [str(tmp_path / a) if a.endswith((".json", ".bmp")) else a for a in args]
    done = reflets_cmd("view", str(SHOWCASE), *args, display=False, timeout=60)
    assert done.returncode == 2
    assert message in done.stderr and "Traceback" not in done.stderr


def test_a_script_with_a_bad_event_is_refused_before_the_scene_changes(tmp_path):
    (tmp_path / "bad.json").write_text(json.dumps([{"type": "teleport"}]))
    saved = tmp_path / "edited.toml"
    done = reflets_cmd(
        "view", str(scene_path("02_sphere_directional.toml")), "--script", str(tmp_path / "bad.json"),
        "--frames", "1", "--save-scene", str(saved),
    )  # fmt: skip
    assert done.returncode == 2
    assert "unknown event type 'teleport'" in done.stderr and "Traceback" not in done.stderr
    assert not Path(saved).exists()


PANEL_SCRIPT = """
import sys
import numpy as np
from PIL import Image
import reflets
from reflets.viewer.window import ViewerWindow

Image.fromarray(np.full((16, 16, 4), (255, 0, 255, 255), np.uint8)).save(sys.argv[1] + "/magenta.png")
scene = reflets.load_dict({
    "camera": {"position": [0, 0, 3], "look_at": [0, 0, 6], "size": [640, 480]},  # looking away from the mesh
    "materials": {"card": {"type": "gltf", "base_color": [1, 1, 1, 0.5], "metallic": 0.0,
                           "base_color_texture": {"texture": sys.argv[1] + "/magenta.png"}}},
    "mesh": [{"shape": "plane", "size": [1, 1], "material": "card"}],
    "light": [{"type": "point", "position": [0, 2, 0], "intensity": [1, 1, 1]}],
})
window = ViewerWindow(scene, size=(640, 480))
counts = []
for select in (False, True):
    if select:
        window.controller.handle({"type": "select", "mesh": 0})
    for _ in range(3):  # the panels settle
        window.draw()
        window.draw_panels()
        window.wnd.swap_buffers()
    window.draw()
    window.draw_panels()
    pixels = np.frombuffer(window.wnd.fbo.read(components=3), np.uint8).reshape(480, 640, 3)
    counts.append(int(np.sum(np.all(pixels == (255, 0, 255), axis=-1))))
print("magenta", *counts, len(window.panels._thumbnails))
window.close()
"""


@pytest.mark.slow
def test_the_selection_panel_shows_a_gltf_material_s_textures(tmp_path):
    """A selected mesh's glTF textures are pictured in the Selection panel (the view itself looks away: the
    magenta pixels are the picture's, 16 x 16 texels shown at their size)."""
    script = tmp_path / "panel.py"
    script.write_text(PANEL_SCRIPT, "utf-8")
    xvfb = shutil.which("xvfb-run")
    if xvfb is None:
        pytest.fail("xvfb-run is missing: `make test` installs it (tools/install-system-packages)")
    done = subprocess.run([xvfb, "-a", "-s", "-screen 0 1024x768x24", sys.executable, str(script), str(tmp_path)],
                          capture_output=True, text=True, timeout=300)  # fmt: skip
    assert done.returncode == 0, done.stderr
    before, after, pictures = (int(k) for k in done.stdout.split()[-3:])
    assert before == 0 and after >= 16 * 16 and pictures == 1
