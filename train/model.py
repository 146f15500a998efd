"""A YOLOv5-shaped detector written from the published architecture (no YOLOv5 code).

Backbone (default ``cspdarknet``; see :mod:`train.backbones` for EfficientNet-Lite0): Conv(6x6, s2) - Conv(s2) - C3 x3 - Conv(s2) - C3 x6 - Conv(s2) - C3 x9 - Conv(s2) - C3 x3 - SPPF.
Neck: a PAN (top-down 1x1 conv + nearest upsample + concat + C3, then bottom-up 3x3 s2 conv + concat + C3).
Head: one 1x1 conv per level (strides 8, 16, 32) predicting, for each of 3 anchors, ``(tx, ty, tw, th, obj,
cls_1..cls_C)`` logits. Every Conv is Conv2d (no bias) + BatchNorm + SiLU; depth (block repeats) and width
(channels, rounded up to a multiple of 8) scale by the YOLOv5 multiples (n: 0.33/0.25, s: 0.33/0.50).

Decoding (YOLOv5 v6 equations), with ``s = sigmoid(logits)``, cell ``(i, j)``, stride ``k``, anchor ``(aw, ah)``
in input pixels:  ``cx = (2 s_x - 0.5 + i) k``, ``cy = (2 s_y - 0.5 + j) k``, ``w = (2 s_w)^2 aw``,
``h = (2 s_h)^2 ah``.
"""

from __future__ import annotations

import math
from collections.abc import Sequence

import torch
from torch import Tensor, nn

from train.backbones import build_backbone
from train.blocks import C3, Conv, scaled_depth, scaled_width
from train.config import DEFAULT_ANCHORS, MODEL_SIZES, DetectorConfig

STRIDES: tuple[int, ...] = (8, 16, 32)


class Lateral(nn.Module):
    """1x1 Conv from each backbone level's channels to the neck's; the identity where they already agree
    (cspdarknet), so a pretrained backbone of any width feeds a neck of the family's width."""

    def __init__(self, c_in: Sequence[int], c_out: Sequence[int]) -> None:
        super().__init__()
        self.m = nn.ModuleList(nn.Identity() if a == b else Conv(a, b, 1) for a, b in zip(c_in, c_out))

    def forward(self, feats: Sequence[Tensor]) -> tuple[Tensor, Tensor, Tensor]:
        p3, p4, p5 = (m(f) for m, f in zip(self.m, feats))
        return p3, p4, p5


class PAN(nn.Module):
    """Path-aggregation neck over (P3, P4, P5) with channels ``(c3, c4, c5)``; outputs the same channels."""

    def __init__(self, channels: Sequence[int], depth: float) -> None:
        super().__init__()
        c3, c4, c5 = channels
        n = scaled_depth(3, depth)
        self.reduce5 = Conv(c5, c4, 1)
        self.up = nn.Upsample(scale_factor=2.0, mode="nearest")
        self.td4 = C3(2 * c4, c4, n, shortcut=False)
        self.reduce4 = Conv(c4, c3, 1)
        self.td3 = C3(2 * c3, c3, n, shortcut=False)
        self.down3 = Conv(c3, c3, 3, 2)
        self.bu4 = C3(2 * c3, c4, n, shortcut=False)
        self.down4 = Conv(c4, c4, 3, 2)
        self.bu5 = C3(2 * c4, c5, n, shortcut=False)

    def forward(self, feats: tuple[Tensor, Tensor, Tensor]) -> tuple[Tensor, Tensor, Tensor]:
        p3, p4, p5 = feats
        r5 = self.reduce5(p5)
        r4 = self.reduce4(self.td4(torch.cat((self.up(r5), p4), 1)))
        out3 = self.td3(torch.cat((self.up(r4), p3), 1))
        out4 = self.bu4(torch.cat((self.down3(out3), r4), 1))
        out5 = self.bu5(torch.cat((self.down4(out4), r5), 1))
        return out3, out4, out5


class Detect(nn.Module):
    """Per-level 1x1 prediction convs. ``anchors`` buffer: (levels, 3, 2) (w, h) in input pixels."""

    def __init__(self, num_classes: int, channels: Sequence[int], anchors: Tensor) -> None:
        super().__init__()
        self.nc = num_classes
        self.no = 5 + num_classes
        self.na = anchors.shape[1]
        self.register_buffer("anchors", anchors.clone().float())
        self.register_buffer("strides", torch.tensor(STRIDES, dtype=torch.float32))
        self.m = nn.ModuleList(nn.Conv2d(c, self.na * self.no, 1) for c in channels)

    def init_biases(self) -> None:
        """Prior biases: ~8 objects per 640 px image, class prior 0.6 / (C - 0.99) (YOLOv5's published init)."""
        with torch.no_grad():
            for conv, stride in zip(self.m, STRIDES):
                b = conv.bias.view(self.na, self.no)
                b[:, 4] += math.log(8 / (640 / stride) ** 2)
                b[:, 5:] += math.log(0.6 / (self.nc - 0.99)) if self.nc > 1 else 0.0

    def forward(self, feats: Sequence[Tensor]) -> list[Tensor]:
        """Raw logits per level, each (B, 3, H_l, W_l, 5 + C)."""
        out = []
        for conv, x in zip(self.m, feats):
            b, _, h, w = x.shape
            out.append(conv(x).view(b, self.na, self.no, h, w).permute(0, 1, 3, 4, 2).contiguous())
        return out

    def decode(self, raw: Sequence[Tensor]) -> Tensor:
        """(B, N, 5 + C): ``cx, cy, w, h`` in input pixels, objectness, class probabilities (all post-sigmoid).

        N = 3 * sum(H_l * W_l), ordered level, anchor, row, column. With one class the class probability
        is defined as 1 (single-class YOLOv5 trains no class logit), so the score is the objectness.
        """
        outs = []
        for level, p in enumerate(raw):
            b, na, h, w, no = p.shape
            s = p.sigmoid()
            ys = torch.arange(h, dtype=p.dtype, device=p.device)
            xs = torch.arange(w, dtype=p.dtype, device=p.device)
            grid = torch.stack(torch.meshgrid(xs, ys, indexing="xy"), dim=-1).view(1, 1, h, w, 2)
            stride = self.strides[level]
            xy = (s[..., 0:2] * 2.0 - 0.5 + grid) * stride
            wh = (s[..., 2:4] * 2.0) ** 2 * self.anchors[level].view(1, na, 1, 1, 2)
            cls = torch.ones_like(s[..., 5:]) if self.nc == 1 else s[..., 5:]
            outs.append(torch.cat((xy, wh, s[..., 4:5], cls), dim=-1).view(b, -1, no))
        return torch.cat(outs, dim=1)


class Detector(nn.Module):
    """Backbone + PAN + Detect. ``forward`` returns raw per-level logits (for the loss); ``predict`` the
    decoded (B, N, 5 + C) tensor in letterboxed input pixels.

    Training and validation may start after the backbone's frozen part: ``frozen_features(images)`` once, then
    ``forward_frozen`` / ``predict_frozen`` on what it returned (see :mod:`train.backbones`)."""

    def __init__(self, num_classes: int, cfg: DetectorConfig | None = None, imgsz: int = 640) -> None:
        super().__init__()
        cfg = cfg or DetectorConfig()
        depth, width = MODEL_SIZES[cfg.size]
        self.backbone = build_backbone(cfg.backbone, depth, width, imgsz, cfg.pretrained, cfg.freeze)
        channels = tuple(scaled_width(c, width) for c in (256, 512, 1024))  # the family's P3-P5 widths
        self.lateral = Lateral(self.backbone.channels, channels)
        self.neck = PAN(channels, depth)
        anchors = torch.tensor(cfg.anchors or DEFAULT_ANCHORS, dtype=torch.float32)
        if anchors.shape != (3, 3, 2):
            raise ValueError(f"anchors must be 3 levels x 3 anchors x (w, h), got shape {tuple(anchors.shape)}")
        self.head = Detect(num_classes, channels, anchors)
        self.head.init_biases()

    @property
    def num_classes(self) -> int:
        return self.head.nc

    @property
    def has_frozen(self) -> bool:
        """Whether part of the backbone is frozen (then its features can be computed once and cached)."""
        return bool(self.backbone.has_frozen)

    def forward(self, images: Tensor) -> list[Tensor]:
        """images (B, 3, H, W) float RGB in [0, 1], H and W multiples of 32 -> per-level (B, 3, H/s, W/s, 5+C)."""
        return self.head(self.neck(self.lateral(self.backbone(images))))

    def predict(self, images: Tensor) -> Tensor:
        return self.head.decode(self.forward(images))

    @torch.no_grad()
    def frozen_features(self, images: Tensor) -> tuple[Tensor, ...]:
        """images (B, 3, H, W) in [0, 1] -> the backbone's frozen features (``(images,)`` when none is frozen)."""
        return self.backbone.frozen_forward(images)

    def forward_frozen(self, frozen: Sequence[Tensor]) -> list[Tensor]:
        """:meth:`forward` from the frozen features of the images."""
        return self.head(self.neck(self.lateral(self.backbone.trainable_forward(frozen))))

    def predict_frozen(self, frozen: Sequence[Tensor]) -> Tensor:
        return self.head.decode(self.forward_frozen(frozen))


def build_model(num_classes: int, cfg: DetectorConfig | None = None, imgsz: int = 640) -> Detector:
    """The detector for ``num_classes`` classes; ``imgsz`` only matters to backbones with fixed padding."""
    if num_classes < 1:
        raise ValueError(f"num_classes must be >= 1, got {num_classes}")
    return Detector(num_classes, cfg, imgsz)
