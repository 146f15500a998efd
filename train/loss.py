"""YOLOv5's detection loss (published equations, our code): CIoU box loss, BCE objectness with IoU targets,
BCE classes; objectness weighted per level by ``balance``; gains rescaled for class count and image size.

``loss = B * (gain_box * sum_l (1 - CIoU) + gain_obj * sum_l balance_l * BCE(obj_l, IoU) + gain_cls * sum_l
BCE(cls_l, onehot))`` with ``B`` the batch size (YOLOv5 scales by it so the gradient per image is constant).
With one class no class loss is computed (the class probability is defined as 1 when decoding).

CIoU lives here rather than in ``ground/data/boxes.py``: it is a differentiable torch loss, not box bookkeeping.
"""

from __future__ import annotations

import math
from collections.abc import Sequence

import torch
from torch import Tensor, nn

from train.assign import assign_level
from train.config import LossConfig


def ciou_cxcywh(pred: Tensor, target: Tensor, eps: float = 1e-7) -> Tensor:
    """Complete IoU of paired boxes (M, 4) ``cx, cy, w, h`` (any common unit) -> (M,) in [-1.5, 1].

    ``CIoU = IoU - rho^2 / c^2 - alpha v`` with ``rho`` the centre distance, ``c`` the enclosing box diagonal,
    ``v = 4 / pi^2 (atan(w_t / h_t) - atan(w_p / h_p))^2`` and ``alpha = v / (v - IoU + 1 + eps)``.
    """
    p1, p2 = pred[:, :2] - pred[:, 2:] / 2, pred[:, :2] + pred[:, 2:] / 2
    t1, t2 = target[:, :2] - target[:, 2:] / 2, target[:, :2] + target[:, 2:] / 2
    inter = (torch.minimum(p2, t2) - torch.maximum(p1, t1)).clamp(min=0).prod(dim=1)
    union = pred[:, 2:].prod(dim=1) + target[:, 2:].prod(dim=1) - inter + eps
    iou = inter / union
    enclose = torch.maximum(p2, t2) - torch.minimum(p1, t1)
    c2 = (enclose**2).sum(dim=1) + eps
    rho2 = ((pred[:, :2] - target[:, :2]) ** 2).sum(dim=1)
    v = (4 / math.pi**2) * (
        torch.atan(target[:, 2] / (target[:, 3] + eps)) - torch.atan(pred[:, 2] / (pred[:, 3] + eps))
    ) ** 2
    with torch.no_grad():
        alpha = v / (v - iou + (1 + eps))
    return iou - (rho2 / c2 + v * alpha)


def scaled_gains(cfg: LossConfig, num_classes: int, imgsz: int, levels: int = 3) -> dict[str, float]:
    """Gains of the recipe (given for 80 classes, 640 px, 3 levels) rescaled for this run."""
    per_level = 3.0 / levels
    return {
        "box": cfg.box * per_level,
        "obj": cfg.obj * (imgsz / 640) ** 2 * per_level,
        "cls": cfg.cls * num_classes / 80 * per_level,
    }


class DetectionLoss:
    """Callable: ``(raw per-level logits, targets (T, 6)) -> (total loss, {"box", "obj", "cls"} floats)``.

    Targets rows are ``[image index, class (0-based), cx, cy, w, h]`` in input pixels.
    """

    def __init__(
        self, anchors_px: Tensor, strides: Sequence[int], num_classes: int, imgsz: int, cfg: LossConfig
    ) -> None:
        if len(cfg.balance) != len(strides):
            raise ValueError(f"loss.balance has {len(cfg.balance)} values for {len(strides)} levels")
        self.anchors = anchors_px.detach().float()
        self.strides = list(strides)
        self.nc = num_classes
        self.cfg = cfg
        self.gains = scaled_gains(cfg, num_classes, imgsz, len(strides))
        self.bce = nn.BCEWithLogitsLoss()

    def __call__(self, raw: Sequence[Tensor], targets: Tensor) -> tuple[Tensor, dict[str, float]]:
        zero = raw[0].new_zeros(())
        lbox, lobj, lcls = zero, zero, zero
        for level, p in enumerate(raw):
            h, w = p.shape[2:4]
            m = assign_level(targets, self.anchors[level], self.strides[level], (h, w), self.cfg.anchor_t)
            tobj = torch.zeros(p.shape[:4], dtype=p.dtype, device=p.device)
            if len(m.b):
                ps = p[m.b, m.a, m.gj, m.gi]  # (M, 5 + C)
                pxy = ps[:, :2].sigmoid() * 2 - 0.5
                pwh = (ps[:, 2:4].sigmoid() * 2) ** 2 * m.anchor
                iou = ciou_cxcywh(torch.cat((pxy, pwh), 1), m.box)
                lbox = lbox + (1.0 - iou).mean()
                # Where several targets share a cell, the best-fitting one sets the objectness target.
                flat = ((m.b * p.shape[1] + m.a) * h + m.gj) * w + m.gi
                tobj = tobj.view(-1).scatter_reduce(0, flat, iou.detach().clamp(min=0), "amax").view(tobj.shape)
                if self.nc > 1:
                    tcls = torch.zeros_like(ps[:, 5:])
                    tcls[torch.arange(len(m.cls), device=ps.device), m.cls] = 1.0
                    lcls = lcls + self.bce(ps[:, 5:], tcls)
            lobj = lobj + self.bce(p[..., 4], tobj) * self.cfg.balance[level]
        lbox, lobj, lcls = lbox * self.gains["box"], lobj * self.gains["obj"], lcls * self.gains["cls"]
        bsz = raw[0].shape[0]
        total = (lbox + lobj + lcls) * bsz
        return total, {"box": float(lbox.detach()), "obj": float(lobj.detach()), "cls": float(lcls.detach())}
