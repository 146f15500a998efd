"""EMA: ramped decay, averaging of floats, copying of integer buffers, state round trip."""

from __future__ import annotations

import math

import torch
from torch import nn

from train.ema import ModelEMA


def test_decay_ramp_and_average() -> None:
    model = nn.Sequential(nn.Linear(2, 2), nn.BatchNorm1d(2))
    ema = ModelEMA(model, decay=0.9, tau=1.0)
    assert ema.decay_at(0) == 0.0 and math.isclose(ema.decay_at(1), 0.9 * (1 - math.exp(-1)))
    before = ema.ema[0].weight.clone()
    with torch.no_grad():
        model[0].weight.add_(1.0)
    model[1].num_batches_tracked += 5
    ema.update(model)
    d = ema.decay_at(1)
    assert torch.allclose(ema.ema[0].weight, d * before + (1 - d) * model[0].weight)
    assert int(ema.ema[1].num_batches_tracked) == 5
    assert not ema.ema.training and not any(p.requires_grad for p in ema.ema.parameters())


def test_state_round_trip() -> None:
    model = nn.Linear(3, 1)
    ema = ModelEMA(model)
    ema.update(model)
    other = ModelEMA(nn.Linear(3, 1))
    other.load_state_dict(ema.state_dict())
    assert other.updates == 1 and torch.equal(other.ema.weight, ema.ema.weight)
