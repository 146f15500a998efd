"""Smoke mattes: the soft opacity of made smoke is recovered from the image alone, no side of the box shows, the
background behind the smoke is not carried along, and what cannot be matted (dark soot, no smoke, the sky around
dark smoke, flames) is not."""

from __future__ import annotations

import numpy as np

from synth.compose.ramps import window
from synth.smoke.matte import MIN_OPACITY, WINDOW_INNER, dark_channel, matte

BOX = (40, 30, 100, 80)


def _scene(smoke_rgb=(235, 235, 235), density: float = 0.85) -> tuple[np.ndarray, np.ndarray]:
    """(H, W, 3) uint8 a textured, saturated scene with a made smoke blob laid over it in BOX, and the blob's true
    opacity (h, w) in BOX."""
    rng = np.random.default_rng(0)
    h, w = 160, 200
    yy, xx = np.mgrid[0:h, 0:w]
    scene = np.stack([60 + 40 * np.sin(xx / 7.0), 90 + 50 * np.cos(yy / 5.0), 30 + 20 * rng.random((h, w))], -1)
    x, y, bw, bh = BOX
    v, u = np.mgrid[0:bh, 0:bw]
    alpha = density * np.exp(-(((u - bw / 2) / (bw / 4)) ** 2 + ((v - bh / 2) / (bh / 4)) ** 2))
    part = scene[y : y + bh, x : x + bw]
    scene[y : y + bh, x : x + bw] = part * (1 - alpha[..., None]) + np.array(smoke_rgb) * alpha[..., None]
    return np.clip(scene, 0, 255).astype(np.uint8), alpha


def test_a_matte_recovers_the_smokes_opacity_and_colour_without_its_background() -> None:
    image, truth = _scene()
    rgba, opacity = matte(image, BOX)
    alpha = rgba[..., 3] / 255.0
    assert rgba.shape == (80, 100, 4) and opacity >= MIN_OPACITY
    assert np.corrcoef(alpha.ravel(), (truth * window(80, 100, WINDOW_INNER)).ravel())[0, 1] > 0.85
    rgb = rgba[..., :3].astype(int)
    thick, thin = alpha > 0.5, (alpha > 0.02) & (alpha < 0.3)
    assert thick.any() and thin.any() and rgb[thick].mean() > 180  # the light smoke ...
    spread = rgb.max(axis=-1) - rgb.min(axis=-1)
    x, y, w, h = BOX
    behind = image[y : y + h, x : x + w].astype(int)
    assert spread[thin].mean() < 15 < (behind.max(-1) - behind.min(-1))[thin].mean()  # ... grey where thin, not the
    # colourful scene behind it


def test_no_side_of_the_box_shows() -> None:
    rgba, _ = matte(*_scene(density=1.0)[:1], BOX)
    a = rgba[..., 3]
    assert max(a[0].max(), a[-1].max(), a[:, 0].max(), a[:, -1].max(), a[:8, :8].max()) == 0


def test_dark_soot_and_a_box_without_smoke_are_not_matted() -> None:
    assert matte(_scene(smoke_rgb=(20, 20, 20))[0], BOX) is None  # the dark channel prior needs light smoke
    flat = np.full((160, 200, 3), (30, 80, 40), np.uint8)
    assert matte(flat, BOX) is None  # nothing hazy: mean opacity below MIN_OPACITY


def test_the_sky_around_dark_smoke_is_not_matted_as_smoke(monkeypatch) -> None:
    import synth.smoke.matte as m

    x, y, w, h = BOX
    v, u = np.mgrid[0:h, 0:w]
    soot = 0.9 * np.exp(-(((u - w / 2) / (w / 4)) ** 2 + ((v - h / 2) / (h / 4)) ** 2))[..., None]
    sky = np.full((160, 200, 3), (200, 212, 236), np.float64)
    sky[y : y + h, x : x + w] = sky[y : y + h, x : x + w] * (1 - soot) + 70 * soot  # dark grey smoke on a bright sky
    image = sky.astype(np.uint8)
    assert matte(image, BOX) is None  # the prior's haze is the sky around it, with a hole where the smoke is
    monkeypatch.setattr(m, "CENTRE_HAZE", 0.0)
    assert matte(image, BOX) is not None  # without the rule, the sky would be pasted as smoke
    assert m.centred(np.ones((9, 9), np.float32))  # a fog as dense at the sides as at the centre is smoke


def test_a_fire_inside_the_smoke_is_kept_out_of_the_matte() -> None:
    image, _ = _scene()
    fire = (80, 60, 20, 20)  # the blob's centre
    rgba, _ = matte(image, BOX, [fire])
    assert rgba[30:50, 40:60, 3].max() == 0 and matte(image, BOX)[0][30:50, 40:60, 3].min() > 100


def test_the_dark_channel_is_the_minimum_over_channels_and_the_patch() -> None:
    img = np.ones((5, 5, 3), np.float32)
    img[2, 2, 1] = 0.0
    assert dark_channel(img, 3)[1:4, 1:4].max() == 0.0 and dark_channel(img, 3)[0, 4] == 1.0
