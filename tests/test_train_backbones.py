"""Backbone registry: unknown names raise; the EfficientNet-Lite0 variant has the right taps and exports."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import onnxruntime as ort
import pytest
import torch

from train.backbones import _check_shapes, build_backbone
from train.config import ModelConfig
from train.export import export_onnx
from train.model import build_model


def test_unknown_backbone_raises() -> None:
    with pytest.raises(ValueError, match="unknown backbone 'resnet'"):
        build_backbone("resnet", 0.33, 0.25, 320, False)


def test_cspdarknet_taps() -> None:
    shapes = _check_shapes(build_backbone("cspdarknet", 0.33, 0.25, 64, False).eval(), 64)
    assert shapes == [(1, 64, 8, 8), (1, 128, 4, 4), (1, 256, 2, 2)]


def test_lite0_uses_imagenet_weights_and_exports(tmp_path: Path) -> None:
    from curate.effnet import efficientnet_lite0

    cfg = ModelConfig(backbone="efficientnet-lite0")
    model = build_model(1, cfg, imgsz=64).eval()
    reference = efficientnet_lite0()
    assert torch.equal(model.backbone.blocks[3]._depthwise_conv.weight, reference._blocks[3]._depthwise_conv.weight)
    assert _check_shapes(model.backbone, 64) == [(1, 40, 8, 8), (1, 112, 4, 4), (1, 320, 2, 2)]
    path = export_onnx(model, tmp_path / "lite0.onnx", 64, ["fire"])
    x = torch.rand(1, 3, 64, 64, generator=torch.Generator().manual_seed(0))
    with torch.no_grad():
        expected = model.predict(x).numpy()
    (got,) = ort.InferenceSession(str(path), providers=["CPUExecutionProvider"]).run(None, {"images": x.numpy()})
    np.testing.assert_allclose(got, expected, rtol=1e-3, atol=1e-4)
