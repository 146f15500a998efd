"""Ratio-based assignment: anchor ratio rule, neighbouring cells, offsets in cells."""

from __future__ import annotations

import torch

from train.assign import assign_level


def _target(cx: float, cy: float, w: float, h: float, cls: int = 0, image: int = 0) -> torch.Tensor:
    return torch.tensor([[image, cls, cx, cy, w, h]], dtype=torch.float32)


def test_ratio_rule_selects_anchors() -> None:
    anchors = torch.tensor([[10.0, 10.0], [40.0, 40.0], [200.0, 200.0]])
    m = assign_level(_target(36, 36, 38, 38), anchors, 8, (8, 8), anchor_t=4.0)
    assert set(m.a.tolist()) == {0, 1}  # 38/10 = 3.8 < 4 and 40/38 fit; 200/38 > 4 does not
    assert len(assign_level(_target(36, 36, 38, 38), anchors[2:], 8, (8, 8)).b) == 0


def test_centre_cell_and_two_nearest_neighbours() -> None:
    anchors = torch.tensor([[16.0, 16.0]])
    # centre (3.25, 2.75) cells: left neighbour (x frac < .5) and lower neighbour (y frac > .5)
    m = assign_level(_target(3.25 * 8, 2.75 * 8, 16, 16), anchors, 8, (8, 8))
    cells = sorted(zip(m.gi.tolist(), m.gj.tolist()))
    assert cells == [(2, 2), (3, 2), (3, 3)]
    for gi, gj, box in zip(m.gi.tolist(), m.gj.tolist(), m.box):
        assert torch.allclose(box, torch.tensor([3.25 - gi, 2.75 - gj, 2.0, 2.0]))
        assert -0.5 < float(box[0]) < 1.5 and -0.5 < float(box[1]) < 1.5
    assert torch.allclose(m.anchor, torch.tensor([[2.0, 2.0]] * 3))


def test_no_neighbour_outside_the_grid() -> None:
    anchors = torch.tensor([[16.0, 16.0]])
    m = assign_level(_target(0.25 * 8, 0.25 * 8, 16, 16), anchors, 8, (4, 4))
    assert list(zip(m.gi.tolist(), m.gj.tolist())) == [(0, 0)]


def test_image_index_and_class_carried() -> None:
    anchors = torch.tensor([[16.0, 16.0]])
    m = assign_level(_target(20, 20, 16, 16, cls=2, image=5), anchors, 8, (8, 8))
    assert set(m.b.tolist()) == {5} and set(m.cls.tolist()) == {2}


def test_empty_targets() -> None:
    m = assign_level(torch.zeros(0, 6), torch.tensor([[16.0, 16.0]]), 8, (8, 8))
    assert len(m.b) == 0 and m.box.shape == (0, 4)
