"""CIoU, gain rescaling and a tiny overfit: the loss must fall."""

from __future__ import annotations

import math

import torch

from train.config import DetectorConfig, LossConfig
from train.loss import DetectionLoss, ciou_cxcywh, scaled_gains
from train.model import STRIDES, build_model


def test_ciou_identity_and_penalties() -> None:
    box = torch.tensor([[10.0, 10.0, 4.0, 6.0]])
    assert torch.allclose(ciou_cxcywh(box, box), torch.ones(1), atol=1e-5)
    shifted = torch.tensor([[12.0, 10.0, 4.0, 6.0]])  # IoU 12/36, centre distance^2 4, enclosing 6 x 6
    expected = 1.0 / 3.0 - 4.0 / 72.0
    assert math.isclose(float(ciou_cxcywh(shifted, box)), expected, rel_tol=1e-4)
    far = torch.tensor([[100.0, 100.0, 4.0, 6.0]])
    assert float(ciou_cxcywh(far, box)) < 0


def test_gains_rescaled() -> None:
    gains = scaled_gains(LossConfig(), num_classes=2, imgsz=320)
    assert math.isclose(gains["box"], 0.05)
    assert math.isclose(gains["obj"], 0.25)
    assert math.isclose(gains["cls"], 0.5 * 2 / 80)


def test_loss_falls_on_a_tiny_overfit() -> None:
    torch.manual_seed(0)
    model = build_model(2, DetectorConfig()).train()
    images = torch.rand(2, 3, 64, 64)
    targets = torch.tensor([[0, 0, 20.0, 24.0, 16.0, 20.0], [1, 1, 40.0, 30.0, 30.0, 24.0]])
    loss_fn = DetectionLoss(model.head.anchors, STRIDES, 2, 64, LossConfig())
    opt = torch.optim.Adam(model.parameters(), lr=3e-3)
    history = []
    for _ in range(30):
        loss, parts = loss_fn(model(images), targets)
        opt.zero_grad()
        loss.backward()
        opt.step()
        history.append(float(loss.detach()))
        assert set(parts) == {"box", "obj", "cls"}
    assert history[-1] < 0.5 * history[0]


def test_no_targets_gives_objectness_only() -> None:
    model = build_model(1).train()
    loss_fn = DetectionLoss(model.head.anchors, STRIDES, 1, 64, LossConfig())
    loss, parts = loss_fn(model(torch.rand(1, 3, 64, 64)), torch.zeros(0, 6))
    assert parts["box"] == 0.0 and parts["cls"] == 0.0 and parts["obj"] > 0.0
    loss.backward()
