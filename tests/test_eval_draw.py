"""Boxes drawn on pictures: outlines on the box's own pixels, labels on a strip above, inputs never modified."""

from __future__ import annotations

import numpy as np
import pytest

from eval import draw as D


def test_draw_boxes_outlines_without_touching_input():
    img = np.zeros((20, 20, 3), np.uint8)
    out = D.draw_boxes(img, [(2, 2, 10, 10)])
    assert img.max() == 0 and tuple(out[2, 5]) == (255, 64, 0) and out[6, 6].max() == 0
    assert D.draw_boxes(img, []).max() == 0


@pytest.mark.parametrize("shape", [(40, 60), (300, 200), (720, 1280)])
def test_outline_stays_on_the_box_and_the_label_above_it(shape):
    img = np.full((*shape, 3), 90, np.uint8)
    h, w = shape
    box = np.array([w * 0.25, h * 0.5, w * 0.75, h * 0.9])
    out = D.draw_detections(img, box[None], [0.87], [1], ["fire", "smoke"])
    changed = (out != img).any(axis=-1)
    x0, y0, x1, y1 = (int(round(v)) for v in box)
    t = D.line_width(img.shape)
    inside = np.zeros(shape, bool)
    inside[y0:y1, x0:x1] = True
    interior = np.zeros(shape, bool)
    interior[y0 + t : y1 - t, x0 + t : x1 - t] = True
    assert changed[inside & ~interior].all()  # the whole outline, in the class colour
    assert tuple(out[y1 - 1, (x0 + x1) // 2]) == D.class_colour(1) and not changed[interior].any()
    label = changed & ~inside
    rows, cols = np.nonzero(label)
    assert rows.size and rows.max() < y0 and rows.min() >= y0 - 40  # a strip just above the box
    assert cols.min() <= x0 + 1 < cols.max()  # from its left edge (moved left only when it would leave the image)


def test_label_goes_inside_when_the_box_touches_the_top():
    img = np.zeros((100, 100, 3), np.uint8)
    out = D.draw_labelled(img, [[10, 0, 60, 50]], ["fire 0.50"], [D.GROUND_TRUTH])
    changed = (out != img).any(axis=-1)
    assert not changed[50:].any() and not changed[:, 61:].any()  # nothing outside the box
    assert changed[2:8, 12:40].any()  # the label, inside the top edge
