"""Building blocks of the YOLOv5-shaped detector (published architecture, our code) and its from-scratch
CSP-Darknet backbone. Every Conv is Conv2d (no bias) + BatchNorm + SiLU; depth (block repeats) and width
(channels, rounded up to a multiple of 8) scale by the YOLOv5 multiples."""

from __future__ import annotations

import math
from collections.abc import Sequence

import torch
from torch import Tensor, nn


def scaled_width(channels: int, multiple: float) -> int:
    """Channels scaled by ``multiple``, rounded up to a multiple of 8."""
    return int(math.ceil(channels * multiple / 8) * 8)


def scaled_depth(repeats: int, multiple: float) -> int:
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


class CSPDarknet(nn.Module):
    """CSP-Darknet: returns the P3, P4, P5 feature maps (strides 8, 16, 32). Nothing is frozen: its frozen
    features are the images themselves (see :mod:`train.backbones`)."""

    has_frozen = False

    def __init__(self, depth: float, width: float) -> None:
        super().__init__()
        c = [scaled_width(v, width) for v in (64, 128, 256, 512, 1024)]
        self.stem = Conv(3, c[0], 6, 2, 2)
        self.stage2 = nn.Sequential(Conv(c[0], c[1], 3, 2), C3(c[1], c[1], scaled_depth(3, depth)))
        self.stage3 = nn.Sequential(Conv(c[1], c[2], 3, 2), C3(c[2], c[2], scaled_depth(6, depth)))
        self.stage4 = nn.Sequential(Conv(c[2], c[3], 3, 2), C3(c[3], c[3], scaled_depth(9, depth)))
        self.stage5 = nn.Sequential(Conv(c[3], c[4], 3, 2), C3(c[4], c[4], scaled_depth(3, depth)), SPPF(c[4], c[4]))
        self.channels = (c[2], c[3], c[4])

    def forward(self, x: Tensor) -> tuple[Tensor, Tensor, Tensor]:
        p3 = self.stage3(self.stage2(self.stem(x)))
        p4 = self.stage4(p3)
        return p3, p4, self.stage5(p4)

    def frozen_forward(self, x: Tensor) -> tuple[Tensor, ...]:
        return (x,)

    def trainable_forward(self, frozen: Sequence[Tensor]) -> tuple[Tensor, Tensor, Tensor]:
        (x,) = frozen
        return self.forward(x)
