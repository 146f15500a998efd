"""Detector shapes, width/depth multiples and the decoding equations."""

from __future__ import annotations

import pytest
import torch

from train.config import DetectorConfig
from train.model import STRIDES, build_model


@pytest.mark.parametrize(("size", "low", "high"), [("n", 1.6e6, 1.9e6), ("s", 6.8e6, 7.3e6)])
def test_parameter_counts_match_the_family(size: str, low: float, high: float) -> None:
    count = sum(p.numel() for p in build_model(1, DetectorConfig(size=size, backbone="cspdarknet")).parameters())
    assert low < count < high


def test_raw_and_decoded_shapes() -> None:
    torch.manual_seed(0)
    model = build_model(3).eval()
    x = torch.rand(2, 3, 64, 96)
    raw = model(x)
    assert [tuple(r.shape) for r in raw] == [(2, 3, 64 // s, 96 // s, 8) for s in STRIDES]
    with torch.no_grad():
        out = model.predict(x)
    assert out.shape == (2, 3 * sum((64 // s) * (96 // s) for s in STRIDES), 8)
    assert float(out[..., 4:].min()) >= 0.0 and float(out[..., 4:].max()) <= 1.0


def test_decoding_follows_the_equations() -> None:
    model = build_model(2).eval()
    raw = [torch.zeros(1, 3, 64 // s, 64 // s, 7) for s in STRIDES]
    out = model.head.decode(raw)  # sigmoid(0) = 0.5: centre = cell + 0.5, size = anchor
    first = out[0, 0]
    assert torch.allclose(first[:4], torch.tensor([4.0, 4.0, 10.0, 13.0]))
    level1_anchor2_cell = 3 * 8 * 8 + 2 * 4 * 4 + 1 * 4 + 3  # level 1, anchor 2, row 1, column 3
    assert torch.allclose(out[0, level1_anchor2_cell, :4], torch.tensor([56.0, 24.0, 59.0, 119.0]))
    assert torch.allclose(out[0, :, 4:], torch.full((out.shape[1], 3), 0.5))


def test_single_class_probability_is_one() -> None:
    with torch.no_grad():
        out = build_model(1).eval().predict(torch.rand(1, 3, 64, 64))
    assert torch.all(out[..., 5] == 1.0)


def test_bad_arguments() -> None:
    with pytest.raises(ValueError, match="num_classes"):
        build_model(0)
    with pytest.raises(ValueError, match="anchors"):
        build_model(1, DetectorConfig(anchors=(((10.0, 10.0),),)))
