"""Re-lit own smoke: the frame changes only inside the smoke's box and off its fires, softly (no side of the box
shows), recomposing with the smoke's own colour and density gives the frame back, what cannot be matted, would
not be seen or does not fade before the box's sides is left as it was, and the same rng gives the same frame."""

from __future__ import annotations

import numpy as np

from synth.smoke import relight as R
from synth.smoke.matte import Haze

BOX = (40, 30, 100, 80)


def _scene(smoke_rgb=(235, 235, 235), density: float = 0.6) -> np.ndarray:
    """(160, 200, 3) uint8 a textured, saturated scene with a made smoke blob laid over it in BOX."""
    rng = np.random.default_rng(0)
    h, w = 160, 200
    yy, xx = np.mgrid[0:h, 0:w]
    scene = np.stack([60 + 40 * np.sin(xx / 7.0), 90 + 50 * np.cos(yy / 5.0), 30 + 20 * rng.random((h, w))], -1)
    x, y, bw, bh = BOX
    v, u = np.mgrid[0:bh, 0:bw]
    alpha = density * np.exp(-(((u - bw / 2) / (bw / 4)) ** 2 + ((v - bh / 2) / (bh / 4)) ** 2))
    part = scene[y : y + bh, x : x + bw]
    scene[y : y + bh, x : x + bw] = part * (1 - alpha[..., None]) + np.array(smoke_rgb) * alpha[..., None]
    return np.clip(scene, 0, 255).astype(np.uint8)


def test_a_relit_frame_changes_only_within_the_boxs_reach_and_keeps_its_closed_sides() -> None:
    image = _scene()
    out, records = R.relight_frame(image, [BOX], [], np.random.default_rng(1))
    (x, y, w, h), _ = R.reach(BOX, 200, 160)
    assert (x, y, w, h) == (15, 10, 150, 120)  # a quarter of the box's size on each side, within the frame
    inside = np.zeros(image.shape[:2], bool)
    inside[y : y + h, x : x + w] = True
    assert records[0] is not None and records[0]["colour"] in R.COLOURS
    assert np.array_equal(out[~inside], image[~inside])  # nothing beyond the reach
    crop, orig = out[y : y + h, x : x + w].astype(int), image[y : y + h, x : x + w].astype(int)
    assert np.abs(crop - orig).max() > 20  # the smoke did change ...
    edge = np.concatenate([(crop - orig)[0], (crop - orig)[-1], (crop - orig)[:, 0], (crop - orig)[:, -1]])
    assert np.abs(edge).max() <= 1  # ... but not on the reach's sides: no rectangle shows
    assert image is not out


def test_the_reach_stays_in_the_frame_and_its_window_is_open_on_the_frames_sides() -> None:
    (x, y, w, h), shape = R.reach((0, 40, 100, 80), 200, 160)
    assert (x, y, w, h) == (0, 20, 125, 120) and shape.shape == (120, 125)
    assert shape[60, 0] == 1.0 and shape[60, -1] == 0.0 and shape[0, 60] == 0.0  # open on the left only
    whole, full = R.reach((0, 0, 200, 160), 200, 160)
    assert whole == (0, 0, 200, 160) and (full == 1.0).all()  # a box filling its frame: re-lit whole


def test_recomposing_with_the_smokes_own_colour_and_density_gives_the_frame_back(monkeypatch) -> None:
    image = _scene()
    region, shape = R.reach(BOX, 200, 160)
    own = R.haze(image, BOX)
    grey = np.full(3, float(own.airlight @ R.REC601), np.float32)
    got = R.haze(image, region, shape=shape, airlight=grey)
    monkeypatch.setattr(R, "DENSITY", (1.0, 1.0))
    monkeypatch.setattr(R, "TINT", 0.0)
    monkeypatch.setattr(R, "COLOURS", {"white": (1.0, 1.0)})
    monkeypatch.setattr(R, "haze", lambda *a, **k: Haze(got.opacity, grey, got.mean))
    where, relit, record = R.relight_box(image, BOX, [], np.random.default_rng(0))
    assert where == region and record["density"] == 1.0 and record["ratio"] == 1.0
    x, y, w, h = region
    crop = image[y : y + h, x : x + w].astype(np.float32) / 255.0
    a = got.opacity[..., None]
    behind = (crop - grey * a) / np.maximum(1.0 - a, R.CLEAR_FLOOR)
    thin = (got.opacity < 1.0 - R.CLEAR_FLOOR) & (behind >= 0).all(-1) & (behind <= 1).all(-1)  # recovered exactly
    assert thin.mean() > 0.5
    assert np.abs(relit.astype(int) - np.round(crop * 255).astype(int))[thin].max() <= 1


def test_smoke_too_faint_to_see_after_relighting_is_left_as_it_was(monkeypatch) -> None:
    image = _scene()
    monkeypatch.setattr(R, "DENSITY", (0.05, 0.05))  # a' = 0.05 a: no pixel reaches SEEN_OPACITY
    out, records = R.relight_frame(image, [BOX], [], np.random.default_rng(0))
    assert records == [None] and np.array_equal(out, image)


def test_haze_that_does_not_fade_before_the_reachs_closed_sides_is_left_as_it_was() -> None:
    image = _scene()
    region, shape = R.reach(BOX, 200, 160)
    x, y, w, h = region
    fog = image.copy()
    fog[y : y + h, x : x + w] = (0.3 * fog[y : y + h, x : x + w] + 0.7 * 235).astype(np.uint8)  # haze to the sides
    assert R.fades_out(image, region, R.haze(image, BOX).airlight, shape)
    assert not R.fades_out(fog, region, R.haze(fog, BOX).airlight, shape)  # the window would cut an ellipse out
    out, records = R.relight_frame(fog, [BOX], [], np.random.default_rng(0))
    assert records == [None] and np.array_equal(out, fog)
    bars = fog.copy()
    bars[:, :20] = 0  # black bars are neither haze nor what it hides: still a haze to the sides
    assert not R.fades_out(bars, region, R.haze(bars, BOX).airlight, shape)
    frame = (0, 0, 200, 160)
    whole, open_window = R.reach(frame, 200, 160)
    assert R.fades_out(fog, whole, R.haze(fog, BOX).airlight, open_window)  # no closed side: nothing to cut


def test_dark_soot_and_a_clear_box_are_left_as_they_were() -> None:
    soot = _scene(smoke_rgb=(20, 20, 20))
    out, records = R.relight_frame(soot, [BOX, (0, 0, 2, 2), (300, 200, 40, 40)], [], np.random.default_rng(0))
    assert records == [None, None, None] and np.array_equal(out, soot)  # too dark to matte; too small; off the frame


def test_the_fire_inside_the_smoke_is_untouched_and_the_same_rng_gives_the_same_frame() -> None:
    image = _scene()
    fire = (80, 55, 20, 20)
    a, rec_a = R.relight_frame(image, [BOX], [fire], np.random.default_rng(5))
    b, rec_b = R.relight_frame(image, [BOX], [fire], np.random.default_rng(5))
    assert np.array_equal(a, b) and rec_a == rec_b
    fx, fy, fw, fh = fire
    assert np.array_equal(a[fy : fy + fh, fx : fx + fw], image[fy : fy + fh, fx : fx + fw])
