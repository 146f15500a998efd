"""Backbone registry: unknown names raise; the EfficientNet-Lite0 variant has the right taps and exports."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import onnxruntime as ort
import pytest
import torch

from train.backbones import build_backbone
from train.config import DetectorConfig
from train.export import export_onnx
from train.model import build_model


def _check_shapes(backbone: torch.nn.Module, imgsz: int) -> list[tuple[int, ...]]:
    """Shapes of the three outputs for a (1, 3, imgsz, imgsz) input."""
    with torch.no_grad():
        return [tuple(f.shape) for f in backbone(torch.zeros(1, 3, imgsz, imgsz))]


def test_unknown_backbone_raises() -> None:
    with pytest.raises(ValueError, match="unknown backbone 'resnet'"):
        build_backbone("resnet", 0.33, 0.25, 320, False)


def test_cspdarknet_taps() -> None:
    shapes = _check_shapes(build_backbone("cspdarknet", 0.33, 0.25, 64, False).eval(), 64)
    assert shapes == [(1, 64, 8, 8), (1, 128, 4, 4), (1, 256, 2, 2)]


def test_lite0_uses_imagenet_weights_and_exports(tmp_path: Path) -> None:
    from curate.effnet import efficientnet_lite0

    cfg = DetectorConfig(backbone="efficientnet-lite0")
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


@pytest.mark.parametrize("freeze", [0, 1, 3, 4, 5, 7])
def test_frozen_split_is_the_same_network(freeze: int) -> None:
    model = build_model(1, DetectorConfig(backbone="efficientnet-lite0", freeze=freeze), imgsz=64).eval()
    x = torch.rand(2, 3, 64, 64, generator=torch.Generator().manual_seed(1))
    with torch.no_grad():
        whole = model(x)
        split = model.forward_frozen(model.frozen_features(x))
    assert all(torch.equal(a, b) for a, b in zip(whole, split))
    frozen = [n for n, p in model.backbone.named_parameters() if not p.requires_grad]
    assert bool(frozen) == (freeze > 0) and model.has_frozen == (freeze > 0)
    if freeze:
        assert all(n.startswith(("stem", "blocks.")) for n in frozen)
        assert not any(n.startswith(f"blocks.{model.backbone.split}.") for n in frozen)


def test_frozen_stages_stay_in_inference_mode() -> None:
    model = build_model(1, DetectorConfig(backbone="efficientnet-lite0", freeze=3), imgsz=64).train()
    assert not model.backbone.stem_bn.training and not model.backbone.blocks[4]._bn2.training
    assert model.backbone.blocks[5]._bn2.training and model.neck.training
    before = model.backbone.blocks[4]._bn2.running_mean.clone()
    model(torch.rand(2, 3, 64, 64))
    assert torch.equal(before, model.backbone.blocks[4]._bn2.running_mean)


def test_freeze_needs_pretrained_lite0() -> None:
    with pytest.raises(ValueError, match="only efficientnet-lite0"):
        build_model(1, DetectorConfig(backbone="cspdarknet", freeze=3), imgsz=64)
    assert not build_model(1, DetectorConfig(backbone="cspdarknet"), imgsz=64).has_frozen
    assert build_model(1, DetectorConfig(), imgsz=64).backbone.freeze == 7  # the default: every Lite0 stage
    assert build_model(1, DetectorConfig(pretrained=False), imgsz=64).backbone.freeze == 0
    with pytest.raises(ValueError, match="pretrained is false"):
        build_model(1, DetectorConfig(backbone="efficientnet-lite0", freeze=3, pretrained=False), imgsz=64)
    with pytest.raises(ValueError, match="freeze must be 0..7"):
        build_model(1, DetectorConfig(backbone="efficientnet-lite0", freeze=8), imgsz=64)
