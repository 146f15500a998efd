"""Late unfreezing: when it starts, which splits are allowed, and what it changes in the model and optimizer."""

from __future__ import annotations

from dataclasses import replace

import pytest
import torch

from train.config import ModelConfig, TrainConfig, UnfreezeConfig
from train.ema import ModelEMA
from train.model import build_model
from train.optim import Schedule, build_optimizer
from train.unfreeze import check_unfreeze, enter_unfreeze, unfreeze_epoch


def test_start_epoch_and_allowed_splits() -> None:
    assert unfreeze_epoch(TrainConfig()) is None
    assert unfreeze_epoch(replace(TrainConfig(epochs=40), unfreeze=UnfreezeConfig(epochs=8))) == 32
    with pytest.raises(ValueError, match="feature level"):
        unfreeze_epoch(replace(TrainConfig(), unfreeze=UnfreezeConfig(epochs=2, freeze=4)))
    with pytest.raises(ValueError, match="> epochs"):
        unfreeze_epoch(replace(TrainConfig(epochs=3), unfreeze=UnfreezeConfig(epochs=5)))
    model = build_model(1, ModelConfig(freeze=3), imgsz=64)
    with pytest.raises(ValueError, match="below the model's freeze"):
        check_unfreeze(replace(TrainConfig(), unfreeze=UnfreezeConfig(epochs=2, freeze=3)), model)


def test_enter_unfreeze_trains_late_stages_at_a_scaled_rate() -> None:
    cfg = replace(TrainConfig(epochs=4), unfreeze=UnfreezeConfig(epochs=2, freeze=3, lr_scale=0.1))
    model = build_model(1, ModelConfig(), imgsz=64)
    ema = ModelEMA(model)
    optimizer = build_optimizer(model, cfg.optim, cfg.batch)
    x = torch.rand(2, 3, 64, 64)
    feats = model.frozen_features(x)  # cached with every stage frozen
    with torch.no_grad():
        before = model.eval().forward_frozen(feats)
    enter_unfreeze(cfg, model, ema.ema, optimizer)
    assert model.backbone.freeze == ema.ema.backbone.freeze == 3
    assert model.backbone.blocks[5]._project_conv.weight.requires_grad
    assert not model.backbone.blocks[4]._project_conv.weight.requires_grad
    assert not any(p.requires_grad for p in ema.ema.parameters())
    assert len(optimizer.param_groups) == 6 and optimizer.param_groups[3]["lr_scale"] == 0.1
    with torch.no_grad():
        after = model.eval().forward_frozen(feats)  # the deeper cache still feeds the shallower split
    assert all(torch.allclose(a, b, atol=1e-5) for a, b in zip(before, after))
    Schedule(cfg.optim, cfg.epochs, 10, cfg.batch).apply(optimizer, 100, 3)
    assert optimizer.param_groups[3]["lr"] == pytest.approx(0.1 * optimizer.param_groups[0]["lr"])
