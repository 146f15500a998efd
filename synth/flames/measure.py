"""Flame colour: how the flames of a labelled set look, in four figures a person can check against a photo.

The flame gap (:mod:`synth.gap`, ``--crops``) is a distance between CNN embeddings; it has not ranked the flame
looks tried on this project the way the eye does (docs/findings.md, "Does the flame look matter?"). These figures do, and they tell
what to change. Over the flame pixels of every ``class_name`` box of a set - the cut-out mask of
:func:`synth.flames.cutouts.cutouts` (alpha >= 0.5; GrabCut at the :class:`~synth.flames.cutouts.CutoutConfig` defaults), the same rule for a synthetic pool and a real set, so that neither
side is measured on truer masks than the other:

- ``white``: the share of flame pixels that are near-white (HSV value > 0.9, saturation < 0.25): cores
  over-exposed as cameras record fires;
- ``saturation``: the median HSV saturation of the flame pixels;
- ``hue``: the median hue, in degrees, of the colourful flame pixels (saturation > 0.25, value > 0.5): 0 red,
  30 orange, 60 yellow;
- ``red``: the share of those colourful pixels that are red (hue below 12 or above 340 degrees).

Pixels are (N, 3) uint8 RGB; hue in degrees 0..360.
"""

from __future__ import annotations

from dataclasses import asdict, dataclass

import cv2
import numpy as np
from numpy.typing import NDArray

from ground.data.dataset import Dataset
from ground.data.problems import Problem
from synth.flames.cutouts import CutoutConfig, cutouts

#: HSV value and saturation bounds of a near-white pixel.
WHITE_VALUE, WHITE_SATURATION = 0.9, 0.25
#: HSV saturation and value above which a pixel is colourful (its hue counts).
COLOURFUL_SATURATION, COLOURFUL_VALUE = 0.25, 0.5
#: Hues (degrees) that count as red: below the first or above the second.
RED_HUES = (12.0, 340.0)


@dataclass(frozen=True)
class FlameColour:
    """The four figures of the module docstring over ``pixels`` flame pixels of ``boxes`` boxes."""

    boxes: int
    pixels: int
    white: float
    saturation: float
    hue: float
    red: float

    def to_dict(self) -> dict[str, float | int]:
        return asdict(self)


def colour_of(pixels: NDArray[np.uint8], boxes: int) -> FlameColour:
    """The figures of (N, 3) uint8 RGB flame ``pixels`` (N >= 1) from ``boxes`` boxes."""
    if len(pixels) == 0:
        raise ValueError("no flame pixels to measure")
    hsv = cv2.cvtColor(np.ascontiguousarray(pixels, np.uint8).reshape(-1, 1, 3), cv2.COLOR_RGB2HSV_FULL)
    hsv = hsv.reshape(-1, 3).astype(np.float64)
    hue, sat, val = hsv[:, 0] * (360.0 / 256.0), hsv[:, 1] / 255.0, hsv[:, 2] / 255.0
    colourful = (sat > COLOURFUL_SATURATION) & (val > COLOURFUL_VALUE)
    hues = hue[colourful]
    return FlameColour(
        boxes=boxes,
        pixels=len(pixels),
        white=float(((val > WHITE_VALUE) & (sat < WHITE_SATURATION)).mean()),
        saturation=float(np.median(sat)),
        hue=float(np.median(hues)) if len(hues) else float("nan"),
        red=float(((hues < RED_HUES[0]) | (hues > RED_HUES[1])).mean()) if len(hues) else float("nan"),
    )


def flame_colour(ds: Dataset, cfg: CutoutConfig, problems: list[Problem] | None = None) -> FlameColour:
    """The figures of the flame pixels of the boxes of ``ds`` that :func:`synth.flames.cutouts.cutouts` cuts by
    ``cfg`` (its ``class_name``, at least ``min_side`` px on both sides, ``min_cover`` fire-coloured). ValueError when
    no box gives a cut-out; unreadable images are appended to ``problems``."""
    parts, boxes = [], 0
    for item in cutouts(ds, cfg, problems):
        parts.append(item.rgba[..., :3][item.rgba[..., 3] >= 128])
        boxes += 1
    if not boxes:
        raise ValueError(
            f"{ds.root}: no {cfg.class_name!r} box of at least {cfg.min_side} px with fire colours to measure"
        )
    return colour_of(np.concatenate(parts), boxes)
