from dataclasses import replace

import cv2
import numpy as np
import pytest

from synth.flames import simulate as F

SMALL = dict(rows=48, cols=32, frames=60, keep_every=20, warmup=30)


def test_projection_removes_divergence():
    rng = np.random.default_rng(0)
    u = F._noise(rng, (40, 40), 4)
    v = F._noise(rng, (40, 40), 4)

    def div(a, b):
        return 0.5 * (a[1:-1, 2:] - a[1:-1, :-2] + b[2:, 1:-1] - b[:-2, 1:-1])[4:-4, 4:-4]

    pu, pv, _ = F.project(u, v, np.zeros_like(u), iters=400)
    assert np.abs(div(pu, pv)).mean() < 0.2 * np.abs(div(u, v)).mean()


def test_advection_moves_a_blob_along_the_velocity():
    field = np.zeros((20, 20), np.float32)
    field[10, 5] = 1.0
    gy, gx = np.mgrid[0:20, 0:20].astype(np.float32)
    u = np.full_like(field, 3.0)
    out = F.advect(field, u, np.zeros_like(field), (gx, gy))
    assert np.unravel_index(np.argmax(out), out.shape) == (10, 8)


@pytest.mark.parametrize("shape", F.SHAPES)
def test_fluid_flames_rise_and_have_masks(shape):
    seq = F.generate_sequence("t", F.FlameParams(shape=shape, **SMALL), np.random.default_rng(1))
    assert len(seq.sprites) == 3
    for sp in seq.sprites:
        assert sp.mask.any()
        rows = np.nonzero(sp.mask.any(axis=1))[0]
        assert rows[-1] >= sp.mask.shape[0] - 10  # flames stand on their source at the bottom
        emission_rows = np.nonzero(sp.emission.max(axis=(1, 2)) > 2)[0]
        assert emission_rows[0] <= rows[0]  # the crop keeps all the light


def test_noise_generator_and_determinism():
    p = F.FlameParams(generator="noise", **SMALL)
    a = F.generate_sequence("a", p, np.random.default_rng(5))
    b = F.generate_sequence("a", p, np.random.default_rng(5))
    assert len(a.sprites) == 3
    for x, y in zip(a.sprites, b.sprites):
        assert np.array_equal(x.over, y.over) and np.array_equal(x.emission, y.emission)


def test_fluid_determinism_and_seed_sensitivity():
    p = F.FlameParams(**SMALL)
    a = F.generate_sequence("a", p, np.random.default_rng(3)).sprites[-1]
    b = F.generate_sequence("a", p, np.random.default_rng(3)).sprites[-1]
    c = F.generate_sequence("a", p, np.random.default_rng(4)).sprites[-1]
    assert np.array_equal(a.emission, b.emission)
    assert a.emission.shape != c.emission.shape or not np.array_equal(a.emission, c.emission)


def test_rare_palettes_and_validation():
    p = F.sample_params(np.random.default_rng(0), rare=True, **SMALL)
    assert p.palette != "blackbody"
    sp = F.generate_sequence("r", p, np.random.default_rng(0)).sprites[-1]
    assert sp.mask.any()
    with pytest.raises(ValueError, match="unknown flame shape"):
        F.FlameParams(shape="cube")
    with pytest.raises(ValueError, match="unknown flame generator"):
        F.FlameParams(generator="embergen")


def test_flame_base_is_irregular_not_a_straight_cut():
    p = F.FlameParams(shape="pool", base_fade=3.0, **SMALL)
    att = F.base_attenuation(p, p.rows - 3, np.random.default_rng(0))
    assert att.shape == (p.rows, p.cols) and att.min() == 0.0 and att.max() == 1.0
    first_lit = (att > 0.5).argmin(axis=0)  # per column: first row (from the top) that is faded out
    assert len(set(first_lit.tolist())) > 1
    flat = F.base_attenuation(F.FlameParams(base_fade=0.0, **SMALL), 45, np.random.default_rng(0))
    assert np.all(flat == 1.0)


def test_sampled_aspect_ratios_lie_in_the_real_range():
    rng = np.random.default_rng(0)
    aspects = np.array([F.sample_aspect(rng) for _ in range(4000)])
    assert aspects.min() >= F.ASPECT_RANGE[0] and aspects.max() <= F.ASPECT_RANGE[1]
    low, median, high = np.percentile(aspects, [10, 50, 90])
    assert 0.5 < median < 0.65  # fire-cctv-416 train boxes: median 0.57
    assert 0.22 < low < 0.36 and 1.0 < high < 1.45  # ... 10-90 %: 0.29-1.33


def test_a_sequence_is_stretched_to_its_aspect():
    for aspect in (0.35, 1.1):
        p = F.FlameParams(aspect=aspect, **SMALL)
        seq = F.generate_sequence("a", p, np.random.default_rng(2))
        got = float(np.median([F.mask_aspect(s) for s in seq.sprites]))
        assert abs(got - aspect) < 0.08 or seq.meta["stretch"] in (1 / F.MAX_STRETCH, F.MAX_STRETCH)
        assert all(s.mask.shape == s.emission.shape[:2] == s.over.shape[:2] for s in seq.sprites)


def test_sampled_flames_have_a_saturated_yellow_core_and_are_mostly_bright():
    bright = []
    for k in range(4):
        rng = np.random.default_rng([7, k])
        p = F.sample_params(rng, frames=30, keep_every=15)  # the shipped grid and warmup
        sprites = F.generate_sequence("c", p, rng).sprites
        e = np.concatenate([s.emission[s.mask] for s in sprites]).astype(int)
        core = e[e.max(axis=1) >= np.percentile(e.max(axis=1), 90)]
        assert np.median(core[:, 0]) >= 250 and np.median(core[:, 1]) >= 180  # saturated: yellow to yellow-white
        assert np.median(core[:, 2]) >= 40  # not a pure orange
        bright.append((e[:, 1] >= 140).mean())  # orange-yellow or brighter
        assert np.all(e[:, 0] >= e[:, 1]) and np.all(e[:, 1] >= e[:, 2] - 1)  # black-body order: red >= green >= blue
    assert min(bright) > 0.3 and np.median(bright) > 0.5  # mostly bright, not a dim red ribbon (a jet is thinnest)


def test_rare_flames_are_tinted_plausibly():
    rng = np.random.default_rng(0)
    drawn = {F.sample_params(rng, rare=True).palette for _ in range(200)}
    assert drawn == set(F.RARE_PALETTES)  # no lilac, crimson or red clouds
    p = F.FlameParams(palette="methane", **SMALL)
    w = F.tint_weight(p, p.rows - 3)
    assert w[p.rows - 3, 0] == 1.0 and w[0, 0] == 0.0  # blue at the base, black-body above
    sp = F.generate_sequence("m", p, np.random.default_rng(1)).sprites[-1]
    e, rows = sp.emission.astype(int), np.nonzero(sp.mask.any(axis=1))[0]
    base, top = slice(rows[-1] - 8, rows[-1] + 1), slice(rows[0], (rows[0] + rows[-1]) // 2)
    blueness = lambda cut: float((e[cut][:, :, 2] - e[cut][:, :, 0])[sp.mask[cut]].mean())  # noqa: E731
    assert blueness(base) > blueness(top) + 60 and blueness(top) < -60  # blue base, a yellow-orange flame above
    assert F.tint_weight(F.FlameParams(**SMALL), 45) is None


def test_texture_streaks_the_body_and_texture_0_changes_nothing():
    """Inner streaks: the flame's own colours vary more inside its mask (orange tongues in the yellow); at 0 the
    sprites are those of a config without the key, byte for byte."""
    for generator in ("fluid", "noise"):
        flat = F.generate_sequence("a", F.FlameParams(generator=generator, **SMALL), np.random.default_rng(3))
        zero = F.generate_sequence(
            "a", F.FlameParams(generator=generator, texture=0.0, **SMALL), np.random.default_rng(3)
        )
        assert all(np.array_equal(a.emission, b.emission) for a, b in zip(flat.sprites, zero.sprites))
    gains = []
    for k in range(3):  # the interior (mask eroded 3 px): more spread, more orange
        inner = {}
        for texture in (0.0, 0.5):
            rng = np.random.default_rng([7, k])
            sprites = F.generate_sequence(
                "c", F.sample_params(rng, frames=60, keep_every=30, texture=texture), rng
            ).sprites
            green = np.concatenate(
                [s.emission[cv2.erode(s.mask.astype(np.uint8), np.ones((7, 7), np.uint8)) > 0][:, 1] for s in sprites]
            ).astype(float)
            inner[texture] = (green.std(), (green < 200).mean())
        assert inner[0.5][0] > 1.1 * inner[0.0][0] and inner[0.5][1] > inner[0.0][1]
        gains.append(inner[0.5][1] - inner[0.0][1])
    assert np.mean(gains) > 0.2
    field = F.streaks(F.FlameParams(texture=0.5, **SMALL), np.random.default_rng(0))
    assert field.shape == (48 * 2 * 4, 32 * 2) and 0.0 <= field.min() and field.max() <= 1.0
    rows_var, cols_var = np.diff(field, axis=0).std(), np.diff(field, axis=1).std()
    assert cols_var > 2 * rows_var  # vertical streaks: they change faster across than up
    with pytest.raises(ValueError, match="texture"):
        F.FlameParams(texture=1.0)


def _fields(p: F.FlameParams) -> tuple[np.ndarray, np.ndarray]:
    """(temperature, soot) fields of ``p``'s grid: a hot tongue in the lower middle, soot everywhere."""
    y, x = np.mgrid[0 : p.rows, 0 : p.cols].astype(np.float32)
    hot = np.clip(1.0 - np.hypot((x - p.cols / 2) / (0.15 * p.cols), (y - 0.7 * p.rows) / (0.2 * p.rows)), 0, 1)
    return hot.astype(np.float32), np.full((p.rows, p.cols), 0.8, np.float32)


def test_exposed_flames_differ_from_the_display_ones_only_in_colour_white_cored_and_red_edged():
    """With ``exposed`` a black-body flame's parameters are the same draws but a gain in EXPOSED_GAIN (a chemical
    one has none); rendered from the same fields its mask covers the display one's, a share of it near-white (the
    display flame has none) and its colourful pixels more orange (a lower green over red)."""
    chemical = F.sample_params(np.random.default_rng(0), rare=True, exposed=True)
    assert chemical.palette != "blackbody" and chemical.gain == 0.0
    for k in range(3):
        plain = F.sample_params(np.random.default_rng([5, k]), frames=120, keep_every=40)
        exposed = F.sample_params(np.random.default_rng([5, k]), frames=120, keep_every=40, exposed=True)
        assert F.EXPOSED_GAIN[0] <= exposed.gain <= F.EXPOSED_GAIN[1] and replace(exposed, gain=0.0) == plain
        sprites = [F.render_fields(*_fields(p), p, F.palettes(p)[0]) for p in (plain, exposed)]
        assert np.all(sprites[1].mask[sprites[0].mask])
        white = [(s.emission[s.mask].min(axis=1) > 230).mean() for s in sprites]
        assert white[0] == 0.0 and white[1] > 0.05
        green_over_red = [
            np.median(s.emission[s.mask][:, 1] / np.maximum(s.emission[s.mask][:, 0], 1)) for s in sprites
        ]
        assert green_over_red[1] < green_over_red[0]
    with pytest.raises(ValueError, match="gain"):
        F.FlameParams(gain=-1.0)
