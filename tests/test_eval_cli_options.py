"""The model options of score, compare and predict: parsing, defaults, and the detector they build."""

from __future__ import annotations

import argparse

import pytest
from detector_factories import oracle_model

from eval import cli_options as O


def test_parsers():
    assert O.parse_names(" fire, smoke ,") == ["fire", "smoke"]
    assert O.parse_size("320") == (320, 320) and O.parse_size("640x480") == (640, 480)
    with pytest.raises(argparse.ArgumentTypeError, match="640x480"):
        O.parse_size("big")
    assert O.parse_device("cpu") == "cpu"
    with pytest.raises(argparse.ArgumentTypeError):
        O.parse_device("tpu")


def test_defaults_and_the_detector_they_build(tmp_path):
    p = argparse.ArgumentParser()
    O.add_model_args(p, conf=0.25)
    args = p.parse_args(["--iou", "0.5", "--device", "cpu"])
    assert (args.conf, args.iou, args.max_det, args.resize) == (0.25, 0.5, 300, "area")
    detector, options = O.build_detector(oracle_model(tmp_path / "m.onnx"), args)
    assert detector.spec.class_names == ("fire", "smoke")
    assert (options.conf, options.iou, options.max_det, options.resize) == (0.25, 0.5, 300, "area")
    scoring = argparse.ArgumentParser()
    O.add_model_args(scoring)
    assert scoring.parse_args([]).conf == 0.001
