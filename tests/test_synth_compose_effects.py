"""Camera effects: old draws kept, probabilities obeyed, content never moved, low light spares the flames."""

from __future__ import annotations

import numpy as np
import pytest

from synth.compose.effects import CameraConfig, Effects, apply_effects, expose, sample_effects


def test_the_mild_draws_are_those_of_images_made_before_camera_effects() -> None:
    old = sample_effects(np.random.default_rng(5))
    new = sample_effects(np.random.default_rng(5), CameraConfig())
    fields = ("wb_gains", "blur_sigma", "noise_seed")
    assert all(getattr(old, f) == getattr(new, f) for f in fields)
    assert (old.exposure, old.defocus_px, old.motion_px, old.vignette, old.downscale) == (1.0, 0.0, 0, 0.0, 1.0)


def test_probabilities_are_obeyed() -> None:
    always = [sample_effects(np.random.default_rng(k), CameraConfig(1, 1, 1, 1, 1)) for k in range(20)]
    assert all(e.exposure < 0.5 and e.defocus_px > 0 and e.motion_px >= 5 and e.vignette > 0 for e in always)
    assert all(e.downscale < 1 and 25 <= e.jpeg_quality < 55 for e in always)
    never = [sample_effects(np.random.default_rng(k), CameraConfig(0, 0, 0, 0, 0)) for k in range(20)]
    assert all((e.exposure, e.defocus_px, e.motion_px, e.vignette, e.downscale) == (1, 0, 0, 0, 1) for e in never)
    with pytest.raises(ValueError, match="camera.cctv"):
        CameraConfig(cctv=1.5)


def test_no_effect_is_the_identity_and_blurs_keep_brightness() -> None:
    img = np.random.default_rng(0).integers(0, 256, (40, 60, 3), dtype=np.uint8)
    assert np.array_equal(apply_effects(img, Effects()), img)
    flat = np.full((40, 60, 3), 120, np.uint8)
    for e in (Effects(defocus_px=3.0), Effects(motion_px=9, motion_deg=30.0), Effects(downscale=0.4)):
        assert np.abs(apply_effects(flat, e).astype(int) - 120).max() <= 1


def test_vignette_darkens_the_corners_only() -> None:
    out = apply_effects(np.full((41, 61, 3), 200, np.uint8), Effects(vignette=0.4))
    assert out[20, 30, 0] == 200 and out[0, 0, 0] == 120  # corner: 1 - 0.4 * min(2 / 2, 1)


def test_low_light_darkens_the_scene_but_not_the_flames() -> None:
    img = np.full((10, 10, 3), 180, np.uint8)
    keep = np.zeros((10, 10), bool)
    keep[2:5, 2:5] = True
    dark = expose(img, Effects(exposure=0.25), keep)
    assert (dark[keep] == 180).all() and (dark[~keep] < 110).all()
    assert expose(img, Effects()) is img
