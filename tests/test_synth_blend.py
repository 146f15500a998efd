"""Blend modes: feathered and blurred edges, an exact Poisson clone, and every mode keeping the visibility rule."""

from __future__ import annotations

import numpy as np
import pytest

from curate.core.boxes import mask_to_xywh
from synth.blend import ALL_MODES, BlendConfig, feather, margin, paste, poisson, sample_edge, sample_style
from synth.composite import Placement, composite
from synth.effects import Effects
from synth.method2 import visible_composite
from synth.sprites import Sprite
from synth.visibility import MIN_DELTA_E, delta_e


def _texture(h=64, w=80, seed=0):
    rng = np.random.default_rng(seed)
    base = np.linspace(40, 200, w, dtype=np.float32)[None, :, None] * np.ones((h, 1, 3), np.float32)
    return np.clip(base + rng.normal(0, 12, (h, w, 3)), 0, 255).astype(np.uint8)


def _flame(h=24, w=14):
    yy, xx = np.mgrid[0:h, 0:w]
    body = ((xx - w / 2) / (w / 2.2)) ** 2 + ((yy - h * 0.6) / (h / 2.2)) ** 2 <= 1.0
    emission = np.zeros((h, w, 3), np.uint8)
    emission[body] = (255, 170, 40)
    return Sprite(np.zeros((h, w, 4), np.uint8), emission, body)


def test_config_rejects_bad_values_and_knows_its_default():
    assert BlendConfig().default and not BlendConfig(decoys=0.1).default
    for bad in ({"modes": ("screen", "multiply")}, {"modes": ()}, {"decoys": 1.5}, {"feather_px": (3.0, 1.0)}):
        with pytest.raises(ValueError, match="blend"):
            BlendConfig(**bad)


def test_feather_ramps_from_the_edge_and_never_adds_alpha():
    alpha = np.zeros((21, 21), np.float32)
    alpha[3:18, 3:18] = 1.0
    out = feather(alpha, 3.0)
    assert out[3, 10] < 0.5 and out[10, 10] == 1.0 and (out <= alpha).all()
    assert np.array_equal(feather(alpha, 0.0), alpha)


def test_poisson_clone_of_the_image_onto_itself_is_the_image():
    """A shifted clone (OpenCV's centre convention) would move the noise; the odd-sized mask box keeps it exact."""
    img = _texture(40, 50).astype(np.float32) / 255.0
    for h0, w0 in ((10, 12), (11, 13), (9, 20)):
        alpha = np.zeros((40, 50), np.float32)
        alpha[8 : 8 + h0, 9 : 9 + w0] = 1.0
        out = poisson(img, img, alpha)
        assert np.abs(out - img).max() <= 2.5 / 255.0


def test_paste_modes_change_nothing_beyond_their_margin():
    img = _texture(50, 50).astype(np.float32) / 255.0
    rgb = np.full((50, 50, 3), (1.0, 0.6, 0.1), np.float32)
    alpha = np.zeros((50, 50), np.float32)
    alpha[20:30, 20:30] = 1.0
    for mode, edge in (("alpha", 2.0), ("blur", 2.0), ("poisson", 0.0)):
        out = paste(img, rgb, alpha, mode, edge)
        m = margin(mode, edge) + 2
        outside = np.ones((50, 50), bool)
        outside[20 - m : 30 + m, 20 - m : 30 + m] = False
        assert np.array_equal(out[outside], img[outside]) and not np.array_equal(out, img), mode
    with pytest.raises(ValueError, match="paste mode"):
        paste(img, rgb, alpha, "screen", 0.0)


def test_edges_and_styles_are_drawn_only_when_asked():
    rng = np.random.default_rng(0)
    assert sample_edge(BlendConfig(), "screen", rng) == 0.0 and sample_edge(BlendConfig(), "poisson", rng) == 0.0
    assert 1.0 <= sample_edge(BlendConfig(), "alpha", rng) <= 4.0
    before = rng.bit_generator.state
    edge, look = sample_style(BlendConfig(), "add", _texture(), (10, 10, 8, 8), _texture(8, 8), rng)
    assert edge == 0.0 and look.neutral and rng.bit_generator.state == before


@pytest.mark.parametrize("mode", ALL_MODES)
def test_every_mode_keeps_the_visibility_rule_and_exact_boxes(mode):
    """Kept flames are visible (their seen part has ΔE >= MIN_DELTA_E against the plate), boxes are the boxes of
    those parts, and with the same inputs the composite is byte-identical."""
    scene = _texture()
    cfg = BlendConfig(modes=(mode,), harmonise=True, match_noise=True)
    rng = np.random.default_rng(1)
    planned = []
    for k, (x, y) in enumerate(((5, 10), (30, 20), (60, 40))):
        edge, look = sample_style(cfg, mode, scene, (x, y, 14, 24), np.full((24, 14, 3), 200, np.uint8), rng)
        planned.append((Placement(_flame(), x, y, 14, 24, mode, 0.3, 0.9, True, edge, look), f"f/{k}"))
    image, result, shown, seen = visible_composite(scene, planned, Effects(), 4)
    assert shown, mode
    plate_delta = delta_e(image, scene)
    for v, mask in zip(seen, result.flames):
        assert v.visible and (plate_delta[v.part] >= MIN_DELTA_E).all() and not (v.part & ~mask).any()
        seen_mask = mask & (plate_delta >= MIN_DELTA_E)
        assert mask_to_xywh(v.part).tolist() == mask_to_xywh(seen_mask).tolist()
    again = composite(scene, [p for p, _ in shown]).image
    assert np.array_equal(again, result.image)
