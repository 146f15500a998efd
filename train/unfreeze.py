"""Late unfreezing: the last ``unfreeze.epochs`` epochs also train the backbone's stages after
``unfreeze.freeze``, at ``lr_scale`` times the scheduled learning rate, while the features cached for the
frozen split keep feeding them (the split must end a feature level: stage 3 or 5; see
:meth:`train.backbones.EfficientLite0Backbone.trainable_forward`).
"""

from __future__ import annotations

import torch

from train.config import TrainConfig
from train.model import Detector
from train.optim import add_param_groups

#: Splits whose frozen features are the first entries of a deeper split's (they end a feature level).
LEVEL_SPLITS = (3, 5)


def unfreeze_epoch(cfg: TrainConfig) -> int | None:
    """The first epoch that trains the unfrozen stages, or None when the run never unfreezes."""
    u = cfg.unfreeze
    if u.epochs <= 0:
        return None
    if u.freeze not in LEVEL_SPLITS:
        raise ValueError(
            f"unfreeze.freeze must be one of {LEVEL_SPLITS} (a split ending a feature level), got {u.freeze}"
        )
    if u.epochs > cfg.epochs:
        raise ValueError(f"unfreeze.epochs {u.epochs} > epochs {cfg.epochs}")
    return cfg.epochs - u.epochs


def check_unfreeze(cfg: TrainConfig, model: Detector) -> None:
    """Raise when ``cfg.unfreeze`` cannot apply to ``model`` (no frozen Lite0 stages beyond its split)."""
    if unfreeze_epoch(cfg) is None:
        return
    current = getattr(model.backbone, "freeze", 0)
    if current <= cfg.unfreeze.freeze:
        raise ValueError(f"unfreeze.freeze {cfg.unfreeze.freeze} must be below the model's freeze ({current})")


def enter_unfreeze(cfg: TrainConfig, model: Detector, ema_model: Detector, optimizer: torch.optim.Optimizer) -> None:
    """Move the split of ``model`` and of its EMA copy to ``cfg.unfreeze.freeze``; the newly trainable
    parameters join ``optimizer`` at ``lr_scale`` times the schedule."""
    before = {id(p) for p in model.parameters() if p.requires_grad}
    model.backbone.set_freeze(cfg.unfreeze.freeze)
    ema_model.backbone.set_freeze(cfg.unfreeze.freeze, trainable=False)
    ema_model.eval()
    new = [p for p in model.backbone.parameters() if p.requires_grad and id(p) not in before]
    add_param_groups(optimizer, model.backbone, {id(p) for p in new}, cfg.optim, cfg.batch, cfg.unfreeze.lr_scale)
