import numpy as np
import pytest

from synth.flames import colour as C


def test_planck_hotter_is_bluer_and_whiter():
    temps = np.array([1000.0, 1500.0, 2000.0, 3000.0, 4500.0, 6500.0])
    rgb = C.blackbody_rgb(temps)
    blue_over_red = rgb[:, 2] / rgb[:, 0]
    assert np.all(np.diff(blue_over_red) >= 0) and np.all(np.diff(blue_over_red[2:]) > 0)
    assert np.all(np.diff(rgb.min(axis=1)[2:]) > 0)  # whiter: the weakest channel rises
    assert np.all(np.diff(rgb[:, 1]) > 0)  # red -> orange -> yellow -> white
    assert rgb[0, 0] == 1.0 and rgb[0, 2] < 0.01  # 1000 K: deep red
    assert np.allclose(rgb[-1], 1.0, atol=0.08)  # 6500 K ~ D65 white


def test_planck_peak_follows_wien():
    lam = np.arange(200.0, 5000.0, 1.0)
    peak = lam[np.argmax(C.planck(lam, 2000.0))]
    assert abs(peak - 2.897771955e6 / 2000.0) < 2.0


@pytest.mark.parametrize(
    "kind, dominant",
    [("copper", 1), ("boron", 1), ("methane", 2), ("lithium", 0), ("strontium", 0), ("sodium", 0)],
)
def test_chemical_colours_have_their_hue(kind, dominant):
    rgb = C.line_spectrum_rgb(C.CHEMICAL_LINES[kind])
    assert int(np.argmax(rgb)) == dominant


def test_potassium_is_violet_and_sodium_yellow_orange():
    k = C.line_spectrum_rgb(C.CHEMICAL_LINES["potassium"])
    assert k[2] > k[1] and k[0] > k[1]
    na = C.line_spectrum_rgb(C.CHEMICAL_LINES["sodium"])
    assert na[1] > 0.15 and na[2] < 0.05


def test_flame_palette_is_dark_when_cold_and_brightens():
    for kind in C.PALETTES:
        pal = C.flame_palette(kind, n=64)
        assert pal.shape == (64, 3) and pal.dtype == np.float32
        assert pal[0].max() == 0.0 and pal[-1].max() > 0.9
        assert np.all(np.diff(pal.max(axis=1)) >= 0)
    with pytest.raises(ValueError, match="unknown flame palette"):
        C.flame_palette("plasma")


def test_peak_above_one_turns_the_core_yellow_white():
    from synth.flames.colour import flame_palette

    plain, hot = flame_palette("blackbody", peak=1.0), flame_palette("blackbody", peak=3.0)
    assert plain[-1][1] < 0.85 and hot[-1][1] > 0.95  # the core: orange vs clipped yellow-white
    assert np.all(hot >= plain - 1e-6) and np.all(hot <= 1.0)
    assert hot[0].max() == 0.0  # cold stays dark


@pytest.mark.parametrize(("exposure", "peak"), [(8.0, 1.3), (10.0, 1.6), (13.0, 2.0)])
def test_sampled_exposures_saturate_the_core_and_keep_a_red_orange_edge(exposure, peak):
    """The exposure and peak range :func:`synth.flames.simulate.sample_params` draws from (8-13, 1.3-2)."""
    pal = C.flame_palette("blackbody", exposure=exposure, peak=peak)
    core = pal[-1]
    assert core[0] == 1.0 and core[1] > 0.8 and core[2] > 0.45  # saturated red channel: yellow to yellow-white
    bright = pal.max(axis=1)
    edge = pal[(bright > 0.2) & (bright < 0.6)]  # the visible but dim edge: red to orange, no blue
    assert len(edge) and np.all(edge[:, 0] == edge.max(axis=1)) and np.all(edge[:, 2] < 0.1)
    assert np.all(edge[:, 1] < 0.7 * edge[:, 0])
    yellow = np.argmax(pal[:, 1] >= 0.6)  # orange-yellow from here on: the upper third or more of the temperatures
    assert yellow < 0.67 * len(pal)


def test_the_exposed_palette_goes_red_orange_yellow_white_as_a_camera_records_fire():
    """Brightness never falls with temperature; the dimmest visible colour is red, the core white at a high gain
    and warm (not white) at a low one; a higher gain is brighter everywhere."""
    low, high = C.exposed_palette(3.0), C.exposed_palette(10.0)
    for pal in (low, high):
        assert pal.shape == (256, 3) and pal.dtype == np.float32 and 0.0 <= pal.min() and pal.max() <= 1.0
        luma = pal @ np.array([0.2126, 0.7152, 0.0722], np.float32)
        assert np.all(np.diff(luma) >= -1e-6)
        assert np.array_equal(pal[0], np.zeros(3, np.float32))
        edge = pal[int(np.argmax(pal.max(axis=1) > 0.2))]
        assert edge[1] < 0.5 * edge[0] and edge[2] < 0.1  # red, not orange or yellow
    assert high[-1].min() > 0.95 and low[-1].min() < 0.6  # white core only when pushed past the sensor's range
    assert np.all(high.sum(axis=1) >= low.sum(axis=1) - 1e-6)
    assert C.flame_palette("blackbody", exposure=9.0, peak=2.0)[-1].min() < 0.6  # the display palette: yellow core
    with pytest.raises(ValueError, match="gain"):
        C.exposed_palette(0.0)
