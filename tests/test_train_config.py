"""The training schema: YOLOv5 recipe defaults, strict loading through ground.config.loader."""

from __future__ import annotations

import pytest

from ground.config.loader import ConfigError, build_config, to_dict
from train.config import MODEL_SIZES, TrainConfig


def test_defaults_are_the_measured_detector_on_the_published_recipe() -> None:
    cfg = TrainConfig()
    assert (cfg.model.backbone, cfg.model.freeze, cfg.feature_views, cfg.imgsz) == ("efficientnet-lite0", None, 20, 416)
    assert (cfg.optim.optimizer, cfg.optim.lr0, cfg.optim.momentum, cfg.optim.nominal_batch) == (
        "adamw",
        0.002,
        0.9,
        16,
    )
    assert (cfg.ema_decay, cfg.ema_tau, cfg.device) == (0.99, 100.0, "auto")
    assert (cfg.optim.lrf, cfg.optim.weight_decay, cfg.loss.anchor_t, cfg.loss.balance) == (
        0.01,
        5e-4,
        4.0,
        (4.0, 1.0, 0.4),
    )
    a = cfg.augment
    assert (a.mosaic, a.translate, a.scale, a.hsv_h, a.hsv_s, a.hsv_v, a.fliplr) == (
        0.5,
        0.1,
        0.3,
        0.015,
        0.7,
        0.4,
        0.5,
    )
    assert MODEL_SIZES["n"] == (0.33, 0.25) and MODEL_SIZES["s"] == (0.33, 0.50)


def test_round_trip_and_strictness() -> None:
    raw = {"epochs": 3, "model": {"size": "s", "backbone": "efficientnet-lite0"}, "augment": {"mosaic": 0.5}}
    cfg = build_config(raw, TrainConfig)
    assert cfg.model.size == "s" and cfg.augment.mosaic == 0.5
    assert build_config(to_dict(cfg), TrainConfig) == cfg
    with pytest.raises(ConfigError, match="optim.lr: unknown key"):
        build_config({"optim": {"lr": 0.1}}, TrainConfig)
    with pytest.raises(ConfigError, match="model.backbone"):
        build_config({"model": {"backbone": "resnet"}}, TrainConfig)


def test_real_finetune_is_at_most_the_epochs() -> None:
    assert TrainConfig(epochs=5, real_finetune=5).real_finetune == 5
    for bad in (-1, 6):
        with pytest.raises(ValueError, match="real_finetune"):
            TrainConfig(epochs=5, real_finetune=bad)


def test_validation_post_processing_is_scorings_one_section() -> None:
    from ground.detect.detections import PostprocessConfig

    assert TrainConfig().postprocess == PostprocessConfig()
    cfg = build_config({"postprocess": {"conf": 0.01}}, TrainConfig)
    assert (cfg.postprocess.conf, cfg.postprocess.max_det) == (0.01, PostprocessConfig().max_det)
    with pytest.raises(ValueError, match=r"postprocess\.iou must be in \(0, 1\]"):
        build_config({"postprocess": {"iou": 0}}, TrainConfig)
