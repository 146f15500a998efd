"""Flame colour figures: near-white, saturation, hue and red share of flame pixels, and the command."""

from __future__ import annotations

import json
from pathlib import Path

import cv2
import numpy as np
import pytest

from fuzzyfire.cli import main
from ground.data.formats.registry import read_dataset
from synth.flames.cutouts import CutoutConfig
from synth.flames.measure import colour_of, flame_colour

WHITE, RED, ORANGE, YELLOW, BLUE = (255, 255, 250), (230, 20, 10), (255, 128, 0), (250, 230, 40), (30, 60, 200)


def test_the_figures_of_known_colours() -> None:
    pixels = np.array([WHITE] * 2 + [RED] + [ORANGE] * 3 + [YELLOW] * 2, np.uint8)
    c = colour_of(pixels, boxes=1)
    assert (c.boxes, c.pixels) == (1, 8) and c.white == pytest.approx(2 / 8)
    assert c.red == pytest.approx(1 / 6)  # of the six colourful pixels (white is not colourful)
    assert 25 <= c.hue <= 35  # the median colourful pixel is orange
    assert colour_of(np.array([ORANGE], np.uint8), 1).hue == pytest.approx(30, abs=1.5)
    assert colour_of(np.array([RED], np.uint8), 1).red == 1.0 and colour_of(np.array([YELLOW], np.uint8), 1).red == 0
    grey = colour_of(np.array([(128, 128, 128)], np.uint8), 1)
    assert np.isnan(grey.hue) and np.isnan(grey.red) and grey.white == 0.0 and grey.saturation == 0.0
    with pytest.raises(ValueError, match="no flame pixels"):
        colour_of(np.zeros((0, 3), np.uint8), 0)


def _flames(root: Path, core: tuple[int, int, int], edge: tuple[int, int, int]) -> Path:
    """A YOLO set of two 160x120 images on blue, each a flame (an ``edge`` disc with a ``core`` centre) boxed."""
    (root / "images").mkdir(parents=True)
    (root / "labels").mkdir()
    for k, (cx, cy) in enumerate([(60, 50), (100, 70)]):
        img = np.zeros((120, 160, 3), np.uint8)
        img[:] = BLUE
        cv2.circle(img, (cx, cy), 22, edge, -1)
        cv2.circle(img, (cx, cy), 12, core, -1)
        cv2.imwrite(str(root / "images" / f"f{k}.png"), cv2.cvtColor(img, cv2.COLOR_RGB2BGR))
        (root / "labels" / f"f{k}.txt").write_text(f"0 {cx / 160} {cy / 120} {50 / 160} {50 / 120}\n")
    (root / "data.yaml").write_text("names: [fire]\nnc: 1\n")
    return root


def test_white_cored_red_edged_flames_read_so_and_yellow_ones_do_not(tmp_path: Path) -> None:
    photo = flame_colour(read_dataset(_flames(tmp_path / "a", WHITE, RED)).dataset, CutoutConfig())
    sticker = flame_colour(read_dataset(_flames(tmp_path / "b", YELLOW, ORANGE)).dataset, CutoutConfig())
    assert photo.boxes == sticker.boxes == 2 and photo.pixels > 2 * np.pi * 15**2
    assert photo.white > 0.2 and sticker.white == 0.0
    assert photo.red > 0.5 > sticker.red and photo.hue < 12 < 25 <= sticker.hue
    blank = tmp_path / "c"
    _flames(blank, BLUE, BLUE)
    with pytest.raises(ValueError, match="no 'fire' box of at least 16 px with fire colours"):
        flame_colour(read_dataset(blank).dataset, CutoutConfig())


def test_the_command_prints_both_sides_and_json(tmp_path: Path, capsys) -> None:
    a, b = _flames(tmp_path / "a", WHITE, RED), _flames(tmp_path / "b", YELLOW, ORANGE)
    assert main(["synth", "colour", str(b), str(a)]) == 0
    out = capsys.readouterr().out
    assert "near-white" in out and out.count("\nsynthetic ") == 1 and out.count("\nreal ") == 1
    assert main(["synth", "colour", str(b), str(a), "--json"]) == 0
    got = json.loads(capsys.readouterr().out)
    assert got["synthetic"]["white"] == 0.0 and got["real"]["white"] > 0.2 and got["real"]["boxes"] == 2
    assert main(["synth", "colour", str(b), str(tmp_path / "nowhere")]) == 2
