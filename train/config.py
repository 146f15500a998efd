"""Training hyper-parameters as frozen dataclasses (``ground.config.loader`` builds them from commented YAML).

The defaults are the study's detector, chosen by AP per CPU-minute on real data (docs/findings.md, "Which detector recipe, and why?"):
ImageNet EfficientNet-Lite0 with every stage frozen, its features computed once for 20 augmented views
per image, a YOLOv5n-width PAN neck and head trained with AdamW (lr 0.002, ultralytics' choice for short runs),
one step per batch of 16, a short warm-up, an EMA over ~100 steps, mosaic 0.5 and scale 0.3, 40 epochs at 416 px.

The rest is YOLOv5's published recipe (values only): linear learning-rate decay to lr0 * lrf (lrf 0.01),
weight decay 5e-4, loss gains box 0.05 / obj 1.0 / cls 0.5 at 640 px and 80 classes (rescaled for the run,
see :func:`train.loss.scaled_gains`), anchor_t 4, translate 0.1, HSV 0.015/0.7/0.4, horizontal flip 0.5.
Its "scratch-low" recipe for the from-scratch YOLOv5n: ``model.backbone: cspdarknet``, ``optim: {optimizer: sgd,
lr0: 0.01, momentum: 0.937, warmup_epochs: 3, nominal_batch: 64}``, ``augment: {mosaic: 1.0, scale: 0.5}``,
``ema_decay: 0.9999``, ``ema_tau: 2000``.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Literal, Optional

from ground.detect.detections import PostprocessConfig

#: Depth and width multiples of the YOLOv5 family (published values).
MODEL_SIZES: dict[str, tuple[float, float]] = {"n": (0.33, 0.25), "s": (0.33, 0.50), "m": (0.67, 0.75)}

#: YOLOv5's default anchors at 640 px, (w, h) in input pixels, for strides 8, 16, 32.
DEFAULT_ANCHORS: tuple[tuple[tuple[float, float], ...], ...] = (
    ((10, 13), (16, 30), (33, 23)),
    ((30, 61), (62, 45), (59, 119)),
    ((116, 90), (156, 198), (373, 326)),
)


@dataclass(frozen=True)
class DetectorConfig:
    size: Literal["n", "s", "m"] = "n"  # depth/width multiples from MODEL_SIZES
    anchors: Optional[tuple[tuple[tuple[float, float], ...], ...]] = None  # anchors per level, (w, h) input
    # pixels; null = DEFAULT_ANCHORS, re-fitted by k-means when they fit badly
    autoanchor: bool = True  # run the best-possible-recall check and k-means when recall < 0.98
    backbone: Literal["cspdarknet", "efficientnet-lite0"] = "efficientnet-lite0"  # cspdarknet (YOLOv5, from
    # scratch) or efficientnet-lite0 (ImageNet weights); see train/backbones.py
    pretrained: bool = True  # efficientnet-lite0: start from the ImageNet weights of the installed package
    freeze: Optional[int] = None  # efficientnet-lite0: stages 1..freeze (and the stem) keep their ImageNet
    # weights, 0..7; null = the backbone's default (7 for pretrained efficientnet-lite0, 0 for cspdarknet)


@dataclass(frozen=True)
class OptimConfig:
    optimizer: Literal["sgd", "adamw"] = "adamw"  # AdamW (momentum = beta1) or SGD nesterov (YOLOv5)
    lr0: float = 0.002  # initial learning rate (YOLOv5's SGD: 0.01)
    lrf: float = 0.01  # final learning rate = lr0 * lrf (linear schedule)
    momentum: float = 0.9  # AdamW beta1 or SGD momentum (YOLOv5's SGD: 0.937)
    weight_decay: float = 5e-4  # at the nominal batch; not applied to BatchNorm weights or biases
    warmup_epochs: float = 1.0  # linear warm-up length in epochs (at least warmup_min_iters iterations)
    warmup_min_iters: int = 50  # warm-up lasts at least this many iterations
    warmup_momentum: float = 0.8  # momentum at the start of warm-up
    warmup_bias_lr: float = 0.1  # bias learning rate at the start of warm-up
    nominal_batch: int = 16  # gradients accumulate until this many images before a step (YOLOv5: 64)


@dataclass(frozen=True)
class LossConfig:
    box: float = 0.05  # CIoU box loss gain (at 3 levels)
    obj: float = 1.0  # objectness gain (at 640 px, 3 levels)
    cls: float = 0.5  # class gain (at 80 classes, 3 levels)
    anchor_t: float = 4.0  # a target matches an anchor when both w and h ratios are within [1/t, t]
    balance: tuple[float, ...] = (4.0, 1.0, 0.4)  # objectness weight per level P3, P4, P5


@dataclass(frozen=True)
class AugmentConfig:
    mosaic: float = 0.5  # probability of a 4-image mosaic (YOLOv5: 1.0)
    translate: float = 0.1  # random translation, fraction of the image size (+/-)
    scale: float = 0.3  # random scale gain in [1 - scale, 1 + scale] (YOLOv5: 0.5)
    hsv_h: float = 0.015  # hue gain (fraction)
    hsv_s: float = 0.7  # saturation gain (fraction)
    hsv_v: float = 0.4  # value gain (fraction)
    fliplr: float = 0.5  # probability of a horizontal flip
    min_box_px: float = 2.0  # boxes narrower or lower than this after augmentation are dropped
    min_area_ratio: float = 0.1  # boxes keeping less than this fraction of their area are dropped


@dataclass(frozen=True)
class TrainConfig:
    epochs: int = 40  # training epochs, >= 1
    imgsz: int = 416  # square training and validation size (multiple of 32)
    batch: int = 16  # images per forward/backward pass
    seed: int = 0  # weights, augmentations and batch order
    ema_decay: float = 0.99  # EMA decay, ramped as decay * (1 - exp(-updates / ema_tau)); 0.99 averages ~100 steps
    # (YOLOv5: 0.9999, made for 100k-step COCO runs)
    ema_tau: float = 100.0  # EMA ramp length, optimizer steps (YOLOv5: 2000)
    select: Literal["best", "last"] = "best"  # exported weights: the EMA of the epoch with the best validation
    # fitness (YOLOv5's best.pt), or of the last epoch (steadier when the validation set is small)
    real_finetune: int = 0  # the last N epochs train only on the real images (not ``synth:``), and a real image's
    # mosaic partners are real in every epoch: synthetic data as a warm start; 0 = never
    threads: int = 0  # torch threads; 0 = leave torch's default (all cores)
    device: str = "auto"  # auto | cpu | cuda | cuda:N; auto = the first CUDA GPU when there is one, else the CPU
    workers: Optional[int] = None  # data-loading processes; null = none on the CPU (a thread), 8 on a GPU
    feature_views: int = 20  # frozen features (model.freeze > 0): augmented views per image whose features are
    # computed once and reused (epoch e trains on view e mod views); 0 = a fresh view every epoch (train/features.py)
    feature_cache_gb: float = 4.0  # RAM for cached views; fewer views are kept when they would not fit
    allow_errors: bool = False  # fuzzyfire train only (not read by the experiment): train on data whose reading
    # found errors (their boxes or images left out); false = refuse before training, naming the first error
    model: DetectorConfig = field(default_factory=DetectorConfig)  # the detector
    optim: OptimConfig = field(default_factory=OptimConfig)  # optimizer and schedule
    loss: LossConfig = field(default_factory=LossConfig)  # loss gains
    augment: AugmentConfig = field(default_factory=AugmentConfig)  # augmentations
    postprocess: PostprocessConfig = field(default_factory=PostprocessConfig)  # validation's confidence threshold,
    # NMS and boxes per image (those of fuzzyfire score: the AP that picks the best epoch is scoring's)

    def __post_init__(self) -> None:
        for name in ("epochs", "batch"):
            if getattr(self, name) < 1:
                raise ValueError(f"train.{name} must be >= 1, got {getattr(self, name)}")
        if self.imgsz < 32 or self.imgsz % 32:
            raise ValueError(f"train.imgsz must be a positive multiple of 32, got {self.imgsz}")
        if not 0.0 <= self.ema_decay < 1.0 or self.ema_tau <= 0:
            raise ValueError(f"train.ema_decay must be in [0, 1) and ema_tau > 0, got {self.ema_decay}, {self.ema_tau}")
        if self.threads < 0 or self.feature_views < 0 or (self.workers is not None and self.workers < 0):
            raise ValueError("train.threads, feature_views and workers must be >= 0")
        if self.feature_cache_gb < 0:
            raise ValueError(f"train.feature_cache_gb must be >= 0, got {self.feature_cache_gb}")
        if not 0 <= self.real_finetune <= self.epochs:
            raise ValueError(f"train.real_finetune must be in 0..epochs ({self.epochs}), got {self.real_finetune}")
