"""Training hyper-parameters as frozen dataclasses (``fuzzyfire.config`` builds them from commented YAML).

Defaults are YOLOv5's published "scratch-low" recipe (values only): SGD nesterov, momentum 0.937,
lr0 0.01 falling linearly to lr0 * lrf (lrf 0.01), 3 warm-up epochs, weight decay 5e-4 at a nominal batch
of 64, loss gains box 0.05 / obj 1.0 / cls 0.5 at 640 px and 80 classes (rescaled for the run, see
:func:`train.loss.scaled_gains`), anchor_t 4, augmentations mosaic 1.0, translate 0.1, scale 0.5,
HSV 0.015/0.7/0.4, horizontal flip 0.5.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Literal, Optional

#: Depth and width multiples of the YOLOv5 family (published values).
MODEL_SIZES: dict[str, tuple[float, float]] = {"n": (0.33, 0.25), "s": (0.33, 0.50), "m": (0.67, 0.75)}

#: YOLOv5's default anchors at 640 px, (w, h) in input pixels, for strides 8, 16, 32.
DEFAULT_ANCHORS: tuple[tuple[tuple[float, float], ...], ...] = (
    ((10, 13), (16, 30), (33, 23)),
    ((30, 61), (62, 45), (59, 119)),
    ((116, 90), (156, 198), (373, 326)),
)


@dataclass(frozen=True)
class ModelConfig:
    size: Literal["n", "s", "m"] = "n"  # depth/width multiples from MODEL_SIZES
    # anchors per level, (w, h) input pixels; None = DEFAULT_ANCHORS, re-fitted by k-means when they fit badly
    anchors: Optional[tuple[tuple[tuple[float, float], ...], ...]] = None
    autoanchor: bool = True  # run the best-possible-recall check and k-means when recall < 0.98
    # "cspdarknet" (YOLOv5, from scratch) or "efficientnet-lite0" (ImageNet weights); see train/backbones.py
    backbone: Literal["cspdarknet", "efficientnet-lite0"] = "cspdarknet"
    pretrained: bool = True  # efficientnet-lite0: start from the ImageNet weights of the installed package
    freeze: int = 0  # efficientnet-lite0: stages 1..freeze (and the stem) keep their ImageNet weights, 0..7


@dataclass(frozen=True)
class OptimConfig:
    optimizer: Literal["sgd", "adamw"] = "sgd"  # SGD nesterov (YOLOv5) or AdamW (momentum = beta1)
    lr0: float = 0.01  # initial learning rate
    lrf: float = 0.01  # final learning rate = lr0 * lrf (linear schedule)
    momentum: float = 0.937  # SGD momentum (nesterov)
    weight_decay: float = 5e-4  # at the nominal batch; not applied to BatchNorm weights or biases
    warmup_epochs: float = 3.0  # linear warm-up length in epochs (at least warmup_min_iters iterations)
    warmup_min_iters: int = 100
    warmup_momentum: float = 0.8  # momentum at the start of warm-up
    warmup_bias_lr: float = 0.1  # bias learning rate at the start of warm-up
    nominal_batch: int = 64  # gradients accumulate until this many images before a step


@dataclass(frozen=True)
class LossConfig:
    box: float = 0.05  # CIoU box loss gain (at 3 levels)
    obj: float = 1.0  # objectness gain (at 640 px, 3 levels)
    cls: float = 0.5  # class gain (at 80 classes, 3 levels)
    anchor_t: float = 4.0  # a target matches an anchor when both w and h ratios are within [1/t, t]
    balance: tuple[float, ...] = (4.0, 1.0, 0.4)  # objectness weight per level P3, P4, P5


@dataclass(frozen=True)
class AugmentConfig:
    mosaic: float = 1.0  # probability of a 4-image mosaic
    translate: float = 0.1  # random translation, fraction of the image size (+/-)
    scale: float = 0.5  # random scale gain in [1 - scale, 1 + scale]
    hsv_h: float = 0.015  # hue gain (fraction)
    hsv_s: float = 0.7  # saturation gain (fraction)
    hsv_v: float = 0.4  # value gain (fraction)
    fliplr: float = 0.5  # probability of a horizontal flip
    min_box_px: float = 2.0  # boxes narrower or lower than this after augmentation are dropped
    min_area_ratio: float = 0.1  # boxes keeping less than this fraction of their area are dropped


@dataclass(frozen=True)
class TrainConfig:
    epochs: int = 30
    imgsz: int = 320  # square training and validation size (multiple of 32)
    batch: int = 16  # images per forward/backward pass
    seed: int = 0
    ema_decay: float = 0.9999  # EMA decay, ramped as decay * (1 - exp(-updates / ema_tau))
    ema_tau: float = 2000.0
    val_conf: float = 0.001  # validation: score threshold before NMS
    val_iou: float = 0.6  # validation: NMS IoU threshold
    max_det: int = 300  # validation: detections kept per image
    threads: int = 0  # torch threads; 0 = leave torch's default (all cores)
    device: str = "auto"  # auto | cpu | cuda | cuda:N; auto = the first CUDA GPU when there is one, else the CPU
    workers: Optional[int] = None  # data-loading processes; null = none on the CPU (a thread), 8 on a GPU
    # frozen features (model.freeze > 0): augmented views per image whose features are computed once and reused
    # (epoch e trains on view e mod views); 0 = a fresh view every epoch. See train/features.py
    feature_views: int = 0
    feature_cache_gb: float = 4.0  # RAM for cached views; fewer views are kept when they would not fit
    model: ModelConfig = field(default_factory=ModelConfig)
    optim: OptimConfig = field(default_factory=OptimConfig)
    loss: LossConfig = field(default_factory=LossConfig)
    augment: AugmentConfig = field(default_factory=AugmentConfig)
