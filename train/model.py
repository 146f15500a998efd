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
from train.config import DEFAULT_ANCHORS, MODEL_SIZES, ModelConfig

STRIDES: tuple[int, ...] = (8, 16, 32)


def _width(channels: int, multiple: float) -> int:
    """Channels scaled by ``multiple``, rounded up to a multiple of 8."""
    return int(math.ceil(channels * multiple / 8) * 8)


def _depth(repeats: int, multiple: float) -> int:
    return max(round(repeats * multiple), 1)


class Conv(nn.Module):
    """Conv2d (no bias, 'same' padding) + BatchNorm (eps 1e-3, momentum 0.03) + SiLU."""

    def __init__(self, c_in: int, c_out: int, k: int = 1, s: int = 1, p: int | None = None) -> None:
        super().__init__()
        self.conv = nn.Conv2d(c_in, c_out, k, s, k // 2 if p is None else p, bias=False)
        self.bn = nn.BatchNorm2d(c_out, eps=1e-3, momentum=0.03)
        self.act = nn.SiLU()

    def forward(self, x: Tensor) -> Tensor:
        return self.act(self.bn(self.conv(x)))


class Bottleneck(nn.Module):
    """1x1 conv then 3x3 conv, with a residual add when ``shortcut`` (channels unchanged)."""

    def __init__(self, c: int, shortcut: bool = True) -> None:
        super().__init__()
        self.cv1 = Conv(c, c, 1)
        self.cv2 = Conv(c, c, 3)
        self.add = shortcut

    def forward(self, x: Tensor) -> Tensor:
        y = self.cv2(self.cv1(x))
        return x + y if self.add else y


class C3(nn.Module):
    """CSP block: two 1x1 branches of half width, ``n`` bottlenecks on one, concat, 1x1 to ``c_out``."""

    def __init__(self, c_in: int, c_out: int, n: int = 1, shortcut: bool = True) -> None:
        super().__init__()
        hidden = c_out // 2
        self.cv1 = Conv(c_in, hidden, 1)
        self.cv2 = Conv(c_in, hidden, 1)
        self.m = nn.Sequential(*(Bottleneck(hidden, shortcut) for _ in range(n)))
        self.cv3 = Conv(2 * hidden, c_out, 1)

    def forward(self, x: Tensor) -> Tensor:
        return self.cv3(torch.cat((self.m(self.cv1(x)), self.cv2(x)), dim=1))


class SPPF(nn.Module):
    """Spatial pyramid pooling (fast): three chained 5x5 max-pools, concat with the input, 1x1 conv."""

    def __init__(self, c_in: int, c_out: int, k: int = 5) -> None:
        super().__init__()
        hidden = c_in // 2
        self.cv1 = Conv(c_in, hidden, 1)
        self.pool = nn.MaxPool2d(k, 1, k // 2)
        self.cv2 = Conv(4 * hidden, c_out, 1)

    def forward(self, x: Tensor) -> Tensor:
        x = self.cv1(x)
        y1 = self.pool(x)
        y2 = self.pool(y1)
        return self.cv2(torch.cat((x, y1, y2, self.pool(y2)), dim=1))


class Backbone(nn.Module):
    """CSP-Darknet: returns the P3, P4, P5 feature maps (strides 8, 16, 32)."""

    def __init__(self, depth: float, width: float) -> None:
        super().__init__()
        c = [_width(v, width) for v in (64, 128, 256, 512, 1024)]
        self.stem = Conv(3, c[0], 6, 2, 2)
        self.stage2 = nn.Sequential(Conv(c[0], c[1], 3, 2), C3(c[1], c[1], _depth(3, depth)))
        self.stage3 = nn.Sequential(Conv(c[1], c[2], 3, 2), C3(c[2], c[2], _depth(6, depth)))
        self.stage4 = nn.Sequential(Conv(c[2], c[3], 3, 2), C3(c[3], c[3], _depth(9, depth)))
        self.stage5 = nn.Sequential(Conv(c[3], c[4], 3, 2), C3(c[4], c[4], _depth(3, depth)), SPPF(c[4], c[4]))
        self.channels = (c[2], c[3], c[4])

    def forward(self, x: Tensor) -> tuple[Tensor, Tensor, Tensor]:
        p3 = self.stage3(self.stage2(self.stem(x)))
        p4 = self.stage4(p3)
        return p3, p4, self.stage5(p4)


class PAN(nn.Module):
    """Path-aggregation neck over (P3, P4, P5) with channels ``(c3, c4, c5)``; outputs the same channels."""

    def __init__(self, channels: Sequence[int], depth: float) -> None:
        super().__init__()
        c3, c4, c5 = channels
        n = _depth(3, depth)
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
    decoded (B, N, 5 + C) tensor in letterboxed input pixels."""

    def __init__(self, num_classes: int, cfg: ModelConfig | None = None, imgsz: int = 640) -> None:
        super().__init__()
        cfg = cfg or ModelConfig()
        depth, width = MODEL_SIZES[cfg.size]
        self.backbone = build_backbone(cfg.backbone, depth, width, imgsz, cfg.pretrained)
        self.neck = PAN(self.backbone.channels, depth)
        anchors = torch.tensor(cfg.anchors or DEFAULT_ANCHORS, dtype=torch.float32)
        if anchors.shape != (3, 3, 2):
            raise ValueError(f"anchors must be 3 levels x 3 anchors x (w, h), got shape {tuple(anchors.shape)}")
        self.head = Detect(num_classes, self.backbone.channels, anchors)
        self.head.init_biases()

    @property
    def num_classes(self) -> int:
        return self.head.nc

    def forward(self, images: Tensor) -> list[Tensor]:
        """images (B, 3, H, W) float RGB in [0, 1], H and W multiples of 32 -> per-level (B, 3, H/s, W/s, 5+C)."""
        return self.head(self.neck(self.backbone(images)))

    def predict(self, images: Tensor) -> Tensor:
        return self.head.decode(self.forward(images))


def build_model(num_classes: int, cfg: ModelConfig | None = None, imgsz: int = 640) -> Detector:
    """The detector for ``num_classes`` classes; ``imgsz`` only matters to backbones with fixed padding."""
    if num_classes < 1:
        raise ValueError(f"num_classes must be >= 1, got {num_classes}")
    return Detector(num_classes, cfg, imgsz)
