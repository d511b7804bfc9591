"""The document's face-constant diffuse weights and its sphere decomposition (004 §4.2, §5.2)."""

from __future__ import annotations

import numpy as np
import trimesh

from reflets.ar.lighting import face_weights_exact, face_weights_fit, face_weights_normalised
from reflets.ar.spheres import decompose, surface_samples


def random_normals(count: int = 200, seed: int = 0) -> np.ndarray:
    n = np.random.default_rng(seed).normal(size=(count, 3))
    return n / np.linalg.norm(n, axis=1, keepdims=True)


def test_exact_face_weights_sum_to_pi_and_match_a_monte_carlo_integral():
    n = random_normals()
    w = face_weights_exact(n)
    np.testing.assert_allclose(w.sum(axis=1), np.pi, rtol=1e-12)
    # Monte Carlo of ∫_F max(0, n·ω) dω for one normal
    rng = np.random.default_rng(1)
    d = rng.normal(size=(400_000, 3))
    d /= np.linalg.norm(d, axis=1, keepdims=True)
    face = np.argmax(np.abs(d), axis=1) * 2 + (np.take_along_axis(d, np.argmax(np.abs(d), 1)[:, None], 1)[:, 0] < 0)
    cos = np.maximum(d @ n[0], 0.0) * 4 * np.pi
    mc = np.array([cos[face == f].sum() / len(d) for f in range(6)])
    np.testing.assert_allclose(w[0], mc, atol=0.02)


def test_the_document_s_fit_does_not_sum_to_pi_and_the_normalised_one_does():
    n = random_normals()
    total = face_weights_fit(n).sum(axis=1)
    assert np.abs(total / np.pi - 1).max() > 0.01  # the erratum: a constant sky comes out a few % off
    np.testing.assert_allclose(face_weights_normalised(n).sum(axis=1), np.pi)
    error = np.abs(face_weights_fit(n) - face_weights_exact(n)).max()
    assert error < 0.3  # a fit, of the right shape


def test_k_means_recovers_known_spheres():
    centres = np.array([[0.0, 0.0, 0.0], [3.0, 0.5, 0.0], [0.0, 3.0, 1.0]])
    radii = np.array([1.0, 0.6, 0.8])
    parts = []
    for c, r in zip(centres, radii, strict=True):
        ball = trimesh.creation.icosphere(subdivisions=3, radius=r)
        parts.append(surface_samples(np.asarray(ball.vertices) + c, np.asarray(ball.faces), 3000, seed=len(parts)))
    found_c, found_r = decompose(np.concatenate(parts), 3)
    order = [int(np.argmin(np.linalg.norm(found_c - c, axis=1))) for c in centres]
    np.testing.assert_allclose(found_c[order], centres, atol=0.05)
    np.testing.assert_allclose(found_r[order], radii, rtol=0.03)
