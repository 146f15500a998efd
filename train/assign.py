"""YOLOv5's ratio-based target assignment (published rule, our code).

A target matches an anchor of a level when both its width and height ratios to the anchor lie within
``[1 / anchor_t, anchor_t]``. Each match is assigned to the cell holding the target centre and to the two
neighbouring cells nearest to the centre (left or right, above or below), so one target trains up to
3 cells x 3 anchors per level; the decoded centre offset ``2 sigmoid - 0.5`` spans ``(-0.5, 1.5)`` cells,
which reaches a centre in a neighbour.
"""

from __future__ import annotations

from dataclasses import dataclass

import torch
from torch import Tensor

#: Cell offsets: own cell, then left, up, right, down neighbours (multiplied by 0.5 before flooring).
_OFFSETS = torch.tensor([[0.0, 0.0], [1.0, 0.0], [0.0, 1.0], [-1.0, 0.0], [0.0, -1.0]])


@dataclass(frozen=True)
class LevelTargets:
    """Matches of one level, M rows: image index ``b``, anchor ``a``, cell row ``gj`` / column ``gi``
    (all (M,) int64), ``box`` (M, 4) = (x offset from the cell corner, y offset, w, h) in cells,
    ``anchor`` (M, 2) anchor (w, h) in cells, ``cls`` (M,) 0-based class ids."""

    b: Tensor
    a: Tensor
    gj: Tensor
    gi: Tensor
    box: Tensor
    anchor: Tensor
    cls: Tensor


def assign_level(
    targets: Tensor, anchors_px: Tensor, stride: float, grid_hw: tuple[int, int], anchor_t: float = 4.0
) -> LevelTargets:
    """Targets (T, 6) ``[image index, class, cx, cy, w, h]`` in input pixels -> the matches of one level.

    ``anchors_px`` (A, 2) anchor (w, h) in input pixels; ``grid_hw`` the level's (H, W) in cells.
    """
    h, w = grid_hw
    anchors = anchors_px / stride
    t = targets.clone()
    t[:, 2:6] = t[:, 2:6] / stride
    ratio = t[None, :, 4:6] / anchors[:, None, :]  # (A, T, 2)
    match = torch.maximum(ratio, 1.0 / ratio).amax(dim=2) < anchor_t  # (A, T)
    a_idx, t_idx = match.nonzero(as_tuple=True)
    t = t[t_idx]
    gxy = t[:, 2:4]
    gxi = torch.tensor([w, h], dtype=gxy.dtype, device=gxy.device) - gxy
    near_low = (gxy % 1.0 < 0.5) & (gxy > 1.0)  # neighbour to the left / above
    near_high = (gxi % 1.0 < 0.5) & (gxi > 1.0)  # neighbour to the right / below
    use = torch.stack(
        (torch.ones_like(near_low[:, 0]), near_low[:, 0], near_low[:, 1], near_high[:, 0], near_high[:, 1])
    )  # (5, M)
    off_idx, m_idx = use.nonzero(as_tuple=True)
    t, a_idx = t[m_idx], a_idx[m_idx]
    gxy = t[:, 2:4]
    gij = (gxy - _OFFSETS.to(gxy)[off_idx] * 0.5).floor().long()
    gi = gij[:, 0].clamp(0, w - 1)
    gj = gij[:, 1].clamp(0, h - 1)
    box = torch.cat((gxy - torch.stack((gi, gj), 1).to(gxy.dtype), t[:, 4:6]), dim=1)
    return LevelTargets(t[:, 0].long(), a_idx, gj, gi, box, anchors[a_idx], t[:, 1].long())
