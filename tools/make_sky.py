"""Write the procedural sky environment shipped with reflets (run once by hand).

    python tools/make_sky.py src/reflets/data/environments/sky.hdr

A blue-to-white gradient sky, a warm ground and a small bright sun (elevation 35°, azimuth 60°,
angular radius 2.5°), in the Mitsuba 3 equirectangular layout used by reflets (row 0 = up).
"""

import sys

import numpy as np

from reflets.imageio import write_image
from reflets.scene.environment import equirect_direction


def sky(width: int = 256, height: int = 128) -> np.ndarray:
    u = (np.arange(width) + 0.5) / width
    v = (np.arange(height) + 0.5) / height
    d = equirect_direction(u[None, :], v[:, None])
    up = np.clip(d[..., 1:2], 0.0, 1.0)
    horizon, zenith = np.array([1.1, 1.15, 1.2]), np.array([0.25, 0.45, 0.95])
    image = horizon + (zenith - horizon) * up**0.6
    ground = np.array([0.35, 0.28, 0.2]) * 0.5
    image = np.where(d[..., 1:2] < 0, ground, image)
    elev, azim = np.radians(35.0), np.radians(60.0)
    sun = np.array([np.cos(elev) * np.sin(azim), np.sin(elev), -np.cos(elev) * np.cos(azim)])
    image = np.where((d @ sun > np.cos(np.radians(2.5)))[..., None], np.array([300.0, 270.0, 230.0]), image)
    return image.astype(np.float32)


if __name__ == "__main__":
    path = sys.argv[1] if len(sys.argv) > 1 else "src/reflets/data/environments/sky.hdr"
    write_image(path, sky())
    print(f"wrote {path}")
