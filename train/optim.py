"""SGD (YOLOv5's recipe) or AdamW, with YOLOv5's schedule (published values, our code).

- Three parameter groups: conv/linear weights (weight decay), BatchNorm weights and all biases (no decay).
- Weight decay is given at the nominal batch (64) and scaled by ``batch * accumulate / nominal``.
- Gradients accumulate over ``accumulate = round(nominal / batch)`` batches before a step.
- Learning rate ``lr0 * lf(epoch)`` with ``lf(e) = (1 - e / epochs) (1 - lrf) + lrf`` (linear to ``lr0 lrf``).
- Warm-up over ``max(warmup_epochs * batches_per_epoch, warmup_min_iters)`` iterations: learning rates rise
  linearly from 0 (biases: fall from ``warmup_bias_lr``) to the scheduled value, momentum from
  ``warmup_momentum`` to ``momentum``, and accumulation from 1 to its full value.
- AdamW (``optimizer: adamw``): ``momentum`` is its beta1 (beta2 0.999); ultralytics picks it, at lr 0.002 for
  one class, for runs under 10,000 iterations, where a freshly initialised neck and head learn faster with it.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import torch
from torch import nn

from train.config import OptimConfig

BIAS_GROUP = 2


def accumulation(batch: int, nominal: int) -> int:
    """Batches per optimizer step so each step sees about ``nominal`` images."""
    return max(round(nominal / batch), 1)


def parameter_groups(model: nn.Module) -> tuple[list[nn.Parameter], list[nn.Parameter], list[nn.Parameter]]:
    """``(weights with decay, BatchNorm weights, biases)`` of the trainable parameters (frozen ones left out)."""
    decay, bn, bias = [], [], []
    for module in model.modules():
        for name, p in module.named_parameters(recurse=False):
            if not p.requires_grad:
                continue
            if name == "bias":
                bias.append(p)
            elif isinstance(module, nn.modules.batchnorm._BatchNorm):
                bn.append(p)
            else:
                decay.append(p)
    return decay, bn, bias


def _groups(decay: list, bn: list, bias: list, cfg: OptimConfig, batch: int) -> list[dict]:
    wd = cfg.weight_decay * batch * accumulation(batch, cfg.nominal_batch) / cfg.nominal_batch
    return [
        {"params": decay, "weight_decay": wd},
        {"params": bn, "weight_decay": 0.0},
        {"params": bias, "weight_decay": 0.0},
    ]


def build_optimizer(model: nn.Module, cfg: OptimConfig, batch: int) -> torch.optim.Optimizer:
    """SGD nesterov or AdamW over the three groups (group order: decay, BatchNorm, bias)."""
    groups = _groups(*parameter_groups(model), cfg, batch)
    if cfg.optimizer == "adamw":
        return torch.optim.AdamW(groups, lr=cfg.lr0, betas=(cfg.momentum, 0.999))
    if cfg.optimizer != "sgd":
        raise ValueError(f"unknown optimizer {cfg.optimizer!r}; choose sgd or adamw")
    return torch.optim.SGD(groups, lr=cfg.lr0, momentum=cfg.momentum, nesterov=True)


def _set_momentum(group: dict, value: float) -> None:
    if "betas" in group:
        group["betas"] = (value, group["betas"][1])
    else:
        group["momentum"] = value


@dataclass(frozen=True)
class Schedule:
    """Learning rate, momentum and accumulation as functions of the global iteration and the epoch."""

    cfg: OptimConfig
    epochs: int
    batches_per_epoch: int
    batch: int

    @property
    def warmup_iters(self) -> int:
        return max(round(self.cfg.warmup_epochs * self.batches_per_epoch), self.cfg.warmup_min_iters)

    def lr_factor(self, epoch: int) -> float:
        return (1.0 - epoch / self.epochs) * (1.0 - self.cfg.lrf) + self.cfg.lrf

    def accumulate(self, iteration: int) -> int:
        full = self.cfg.nominal_batch / self.batch
        if iteration >= self.warmup_iters:
            return accumulation(self.batch, self.cfg.nominal_batch)
        return max(1, int(np.interp(iteration, [0, self.warmup_iters], [1, full]).round()))

    def apply(self, optimizer: torch.optim.Optimizer, iteration: int, epoch: int) -> None:
        """Set every group's ``lr`` and ``momentum`` for global ``iteration`` (batches seen) in ``epoch``."""
        warm = iteration < self.warmup_iters
        span = [0, self.warmup_iters]
        for j, group in enumerate(optimizer.param_groups):
            target = self.cfg.lr0 * self.lr_factor(epoch)
            if warm:
                start = self.cfg.warmup_bias_lr if j == BIAS_GROUP else 0.0
                group["lr"] = float(np.interp(iteration, span, [start, target]))
                _set_momentum(group, float(np.interp(iteration, span, [self.cfg.warmup_momentum, self.cfg.momentum])))
            else:
                group["lr"] = target
                _set_momentum(group, self.cfg.momentum)
