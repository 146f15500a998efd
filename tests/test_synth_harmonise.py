"""Background estimators (noise sigma, edge blur, light tint) recover what was put in; looks are deterministic."""

from __future__ import annotations

import cv2
import numpy as np

from synth.harmonise import Look, apply_look, edge_blur, light_tint, noise_sigma, sample_look


def _steps(sigma: float, h=96, w=96) -> np.ndarray:
    """Vertical bars 12 px wide (50 / 200 grey) blurred by ``sigma`` px."""
    grey = np.where((np.arange(w) // 12) % 2 == 0, 50.0, 200.0)[None, :] * np.ones((h, 1))
    if sigma > 0:
        grey = cv2.GaussianBlur(grey, (0, 0), sigmaX=sigma)
    return np.repeat(np.round(grey).astype(np.uint8)[..., None], 3, axis=-1)


def test_noise_sigma_recovers_added_noise():
    rng = np.random.default_rng(0)
    for sigma in (3.0, 8.0):
        noisy = np.clip(128 + rng.normal(0, sigma, (80, 80, 1)) * np.ones(3), 0, 255).astype(np.uint8)
        assert abs(noise_sigma(noisy) - sigma) < 0.2 * sigma
    assert noise_sigma(np.full((80, 80, 3), 90, np.uint8)) == 0.0


def test_edge_blur_recovers_the_blur_of_edges():
    assert edge_blur(_steps(0.0)) < 0.3
    for sigma in (1.0, 2.0, 3.0):
        assert abs(edge_blur(_steps(sigma)) - sigma) < 0.15 * sigma
    assert edge_blur(np.full((40, 40, 3), 100, np.uint8)) == 0.0  # no edges


def test_light_tint_follows_the_cast():
    assert np.allclose(light_tint(np.full((8, 8, 3), 120, np.uint8), 0.5), 1.0)
    r, g, b = light_tint(np.full((8, 8, 3), (200, 120, 60), np.uint8), 0.5)
    assert r > 1.0 > b and light_tint(np.full((8, 8, 3), (200, 120, 60), np.uint8), 0.0) == (1.0, 1.0, 1.0)


def test_looks_are_neutral_unless_asked_and_deterministic():
    layer = np.random.default_rng(1).random((20, 20, 3)).astype(np.float32)
    weight = np.ones((20, 20), np.float32)
    assert np.array_equal(apply_look(layer, weight, Look()), layer)
    look = Look((1.1, 1.0, 0.9), 1.0, 5.0, 7)
    assert np.array_equal(apply_look(layer, weight, look), apply_look(layer, weight, look))
    background = _steps(2.0, 60, 60)
    rng = np.random.default_rng(0)
    assert sample_look(background, (20, 20, 10, 10), _steps(0.0, 10, 10), False, False, rng).neutral
    matched = sample_look(background, (20, 20, 10, 10), _steps(0.0, 10, 10), True, True, rng)
    assert matched.soften > 1.0 and matched.tint == (1.0, 1.0, 1.0)  # a grey background has no cast
