"""Line integral convolution (Cabral & Leedom 1993) of a sign-free direction field in an image: white noise
averaged along the field's streamlines, so that the image shows the curves the field is tangent to — here the
potential highlight curves of an orientation field (ℓ), drawn over the viewer's frame."""

from __future__ import annotations

import numpy as np


def line_integral_convolution(directions: np.ndarray, mask: np.ndarray, length: int = 12, seed: int = 0) -> np.ndarray:
    """(H, W) in [0, 1]: noise averaged over ``length`` one-pixel steps each way along ``directions`` (H, W, 2:
    x right, y down; a direction and its opposite alike) where ``mask`` is set; 0 elsewhere."""
    h, w = mask.shape
    noise = np.random.default_rng(seed).random((h, w))
    size = np.linalg.norm(directions, axis=-1, keepdims=True)
    unit = np.where(size > 1e-12, directions / np.maximum(size, 1e-300), 0.0)
    rows, cols = np.nonzero(mask)
    total = noise[rows, cols].copy()
    count = np.ones(len(rows))
    for sign in (1.0, -1.0):
        y, x = rows.astype(np.float64), cols.astype(np.float64)
        previous = unit[rows, cols] * sign
        alive = np.ones(len(rows), bool)
        for _ in range(length):
            x, y = x + previous[:, 0], y + previous[:, 1]
            ix, iy = np.round(x).astype(int), np.round(y).astype(int)
            alive &= (ix >= 0) & (ix < w) & (iy >= 0) & (iy < h)
            ix, iy = np.clip(ix, 0, w - 1), np.clip(iy, 0, h - 1)
            alive &= mask[iy, ix]
            step = unit[iy, ix]
            flip = np.einsum("ij,ij->i", step, previous) < 0  # keep going the same way (the field has no sign)
            step = np.where(flip[:, None], -step, step)
            previous = np.where(alive[:, None], step, previous)
            total += np.where(alive, noise[iy, ix], 0.0)
            count += alive
    out = np.zeros((h, w))
    out[rows, cols] = total / count
    # stretch the averaged noise's narrow spread to [0, 1] (its mean stays ½)
    values = out[rows, cols]
    spread = max(float(values.std()), 1e-6)
    out[rows, cols] = np.clip(0.5 + (values - values.mean()) / (4.0 * spread), 0.0, 1.0)
    return out
