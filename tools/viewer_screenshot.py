"""docs/images/viewer.png: the viewer's window with its panels, the statue selected.

Run without a display as: xvfb-run -a -s "-screen 0 1024x768x24" .venv/bin/python tools/viewer_screenshot.py
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
from PIL import Image

from reflets.demo import scene_path
from reflets.viewer.window import ViewerWindow

OUT = Path(__file__).resolve().parents[1] / "docs" / "images" / "viewer.png"

window = ViewerWindow(scene_path("60_showcase.toml"), size=(800, 600))
window.controller.handle({"type": "select", "mesh": 1})
for frame in range(4):  # a few frames: the scratch lobes accumulate, the panels settle
    window.draw()
    window.draw_panels()
    if frame == 3:
        width, height = window.wnd.buffer_size
        pixels = np.frombuffer(window.wnd.fbo.read(viewport=(0, 0, width, height), components=3), np.uint8)
        OUT.parent.mkdir(parents=True, exist_ok=True)
        Image.fromarray(pixels.reshape(height, width, 3)[::-1]).save(OUT)
    window.wnd.swap_buffers()
window.close()
print(f"wrote {OUT}")
