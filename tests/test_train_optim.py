"""Parameter groups, weight decay scaling, warm-up and the linear schedule."""

from __future__ import annotations

import math

import pytest
import torch

from train.config import DetectorConfig, OptimConfig
from train.model import build_model
from train.optim import Schedule, accumulation, build_optimizer, parameter_groups

#: YOLOv5's SGD recipe (the defaults are AdamW's: see test_train_config.py).
SGD = OptimConfig(optimizer="sgd", lr0=0.01, momentum=0.937, warmup_epochs=3.0, warmup_min_iters=100, nominal_batch=64)


def _scratch():
    return build_model(1, DetectorConfig(backbone="cspdarknet"))


def test_groups_keep_decay_off_bn_and_bias() -> None:
    model = _scratch()
    decay, bn, bias = parameter_groups(model)
    assert len(decay) + len(bn) + len(bias) == len(list(model.parameters()))
    assert all(p.ndim == 4 for p in decay) and all(p.ndim == 1 for p in bn + bias)
    opt = build_optimizer(model, SGD, batch=16)
    assert [g["weight_decay"] for g in opt.param_groups] == [5e-4, 0.0, 0.0]  # 16 * 4 / 64 = 1
    assert opt.defaults["nesterov"] and opt.defaults["momentum"] == 0.937
    assert math.isclose(build_optimizer(model, SGD, batch=24).param_groups[0]["weight_decay"], 5e-4 * 72 / 64)


def test_accumulation_reaches_the_nominal_batch() -> None:
    assert accumulation(16, 64) == 4 and accumulation(64, 64) == 1 and accumulation(128, 64) == 1


def test_warmup_then_linear_decay() -> None:
    cfg = SGD
    sched = Schedule(cfg, epochs=10, batches_per_epoch=50, batch=16)
    assert sched.warmup_iters == 150
    opt = build_optimizer(_scratch(), cfg, 16)
    sched.apply(opt, 0, 0)
    assert [g["lr"] for g in opt.param_groups] == [0.0, 0.0, 0.1]
    assert opt.param_groups[0]["momentum"] == 0.8 and sched.accumulate(0) == 1
    sched.apply(opt, 75, 1)
    target = 0.01 * sched.lr_factor(1)
    assert opt.param_groups[0]["lr"] == pytest.approx(target / 2)
    assert opt.param_groups[2]["lr"] == pytest.approx((0.1 + target) / 2)
    sched.apply(opt, 400, 8)
    assert all(g["lr"] == pytest.approx(0.01 * (1 - 0.8 * 0.99)) for g in opt.param_groups)
    assert sched.accumulate(400) == 4 and opt.param_groups[1]["momentum"] == 0.937
    assert sched.lr_factor(10) == pytest.approx(0.01)


def test_frozen_weights_are_not_optimised_and_adamw_warms_its_beta1() -> None:
    model = build_model(1, DetectorConfig(backbone="efficientnet-lite0", freeze=7), imgsz=64)
    groups = parameter_groups(model)
    trainable = [p for p in model.parameters() if p.requires_grad]
    assert sum(len(g) for g in groups) == len(trainable) < len(list(model.parameters()))
    cfg = OptimConfig()
    opt = build_optimizer(model, cfg, 16)
    assert isinstance(opt, torch.optim.AdamW) and opt.param_groups[0]["betas"] == (0.9, 0.999)
    sched = Schedule(cfg, epochs=10, batches_per_epoch=50, batch=16)
    sched.apply(opt, 0, 0)
    assert opt.param_groups[0]["betas"] == (0.8, 0.999) and opt.param_groups[0]["lr"] == 0.0
    sched.apply(opt, 60, 1)
    assert opt.param_groups[0]["betas"] == (0.9, 0.999) and opt.param_groups[0]["lr"] == pytest.approx(
        0.002 * sched.lr_factor(1)
    )
    with pytest.raises(ValueError, match="unknown optimizer"):
        build_optimizer(model, OptimConfig(optimizer="adam"), 16)  # type: ignore[arg-type]
