"""ONNX export: torch and onnxruntime agree (rtol 1e-3), the contract's shapes and metadata hold."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import onnx
import onnxruntime as ort
import pytest
import torch

from train.export import export_onnx
from train.model import build_model


@pytest.fixture(scope="module")
def exported(tmp_path_factory: pytest.TempPathFactory) -> tuple[torch.nn.Module, Path]:
    torch.manual_seed(0)
    model = build_model(2).eval()
    with torch.no_grad():  # make the outputs informative: perturb BN statistics away from identity
        for m in model.modules():
            if isinstance(m, torch.nn.BatchNorm2d):
                m.running_mean.uniform_(-0.1, 0.1)
                m.running_var.uniform_(0.5, 1.5)
    path = export_onnx(model, tmp_path_factory.mktemp("onnx") / "best.onnx", 96, ["fire", "smoke"])
    return model, path


def test_torch_and_onnxruntime_agree(exported) -> None:
    model, path = exported
    x = torch.rand(2, 3, 96, 96, generator=torch.Generator().manual_seed(1))
    with torch.no_grad():
        expected = model.predict(x).numpy()
    session = ort.InferenceSession(str(path), providers=["CPUExecutionProvider"])
    (got,) = session.run(None, {"images": x.numpy()})
    assert got.shape == expected.shape == (2, 3 * (12 * 12 + 6 * 6 + 3 * 3), 7)
    np.testing.assert_allclose(got, expected, rtol=1e-3, atol=1e-4)
    (single,) = session.run(None, {"images": x[:1].numpy()})  # dynamic batch
    np.testing.assert_allclose(single, expected[:1], rtol=1e-3, atol=1e-4)


def test_contract_metadata(exported) -> None:
    _, path = exported
    proto = onnx.load(str(path))
    meta = {p.key: p.value for p in proto.metadata_props}
    assert json.loads(meta["names"]) == ["fire", "smoke"]
    assert json.loads(meta["imgsz"]) == [96, 96]
    assert meta["output_format"] == "yolov5" and meta["box_format"] == "cxcywh" and meta["scores"] == "obj*cls"
    assert json.loads(meta["preprocessing"])["pad_value"] == 114
    assert [i.name for i in proto.graph.input] == ["images"]


def test_class_name_count_checked(tmp_path: Path) -> None:
    with pytest.raises(ValueError, match="class names"):
        export_onnx(build_model(2), tmp_path / "x.onnx", 64, ["fire"])
