"""Loading detector ONNX files: metadata, layout detection, overrides and errors."""

from __future__ import annotations

import json

import numpy as np
import pytest
from detector_factories import SIZE, oracle_model, rows_for

from eval.onnx_model import ModelError, OnnxDetector, infer_format, parse_names, read_metadata


def test_parse_names_variants():
    assert parse_names("{0: 'fire', 1: 'smoke'}") == ["fire", "smoke"]
    assert parse_names('{"1": "smoke", "0": "fire"}') == ["fire", "smoke"]
    assert parse_names('["fire"]') == ["fire"] and parse_names("fire, smoke") == ["fire", "smoke"]


#: Metadata as train/export.py writes it (the contract ``--format fuzzyfire`` follows).
OURS = {
    "names": json.dumps(["fire", "smoke"]),
    "imgsz": json.dumps([SIZE, SIZE]),
    "output_format": "yolov5",
    "box_format": "cxcywh",
    "scores": "obj*cls",
    "preprocessing": json.dumps({"resize": "letterbox", "pad_value": 114, "color": "RGB", "scale": "1/255"}),
    "stride": "32",
    "producer": "fuzzyfire",
}


def test_read_metadata_ours_and_ultralytics():
    ours = read_metadata(OURS)
    assert ours["ours"] and ours["names"] == ["fire", "smoke"] and ours["size"] == (SIZE, SIZE)
    assert ours["layout"] == "yolov5" and ours["pad_value"] == 114
    ultra = read_metadata({"names": "{0: 'fire'}", "imgsz": "[480, 640]"})
    assert not ultra["ours"] and ultra["size"] == (640, 480) and ultra["layout"] is None  # imgsz is [h, w]


def test_infer_format():
    assert infer_format((1, 6300, 7), 2) == "yolov5"
    assert infer_format((1, 6, 6300), 2) == "yolov8"
    assert infer_format((1, 6, 6300), None) == "yolov8" and infer_format((1, 6300, 7), None) == "yolov5"
    with pytest.raises(ModelError, match="fits both"):
        infer_format((1, 6, 7), 2)
    with pytest.raises(ModelError, match="fits neither"):
        infer_format((1, 100, 9), 2)
    with pytest.raises(ModelError, match="shape"):
        infer_format((1, 100), 2)


@pytest.mark.parametrize("layout", ["yolov5", "yolov8"])
def test_auto_detects_layout_and_decodes_scores(tmp_path, layout):
    det = OnnxDetector(oracle_model(tmp_path / "m.onnx", layout))
    assert det.spec.format == layout and det.spec.class_names == ("fire", "smoke")
    assert (det.spec.input_width, det.spec.input_height) == (SIZE, SIZE) and det.spec.batch is None
    batch = np.full((2, 3, SIZE, SIZE), 40 / 255, np.float32)  # the grey of the "wide" test image
    boxes, scores = det(batch)
    rows = rows_for()
    assert boxes.shape == (2, len(rows), 4) and scores.shape == (2, len(rows), 2)
    np.testing.assert_allclose(boxes[1, 0], rows[0][1], rtol=1e-6)
    assert scores[0, 0, 0] == pytest.approx(0.95) and scores[0, 0, 1] == 0.0
    assert scores[0, -1].max() == 0.0  # rows of other images are gated off


def test_ours_metadata_selects_fuzzyfire_even_when_the_shape_is_ambiguous(tmp_path):
    rows = rows_for()[:6]  # output (1, 6, 7) fits both layouts; the metadata decides
    det = OnnxDetector(oracle_model(tmp_path / "m.onnx", rows=rows, metadata=OURS))
    assert det.spec.format == "fuzzyfire" and det.spec.class_names == ("fire", "smoke")
    with pytest.raises(ModelError, match="fits both"):
        OnnxDetector(oracle_model(tmp_path / "n.onnx", rows=rows))


def test_overrides_and_errors(tmp_path):
    path = oracle_model(tmp_path / "m.onnx", "yolov5")
    assert OnnxDetector(path, names=["a", "b"]).spec.class_names == ("a", "b")
    with pytest.raises(ModelError, match="for 3 class names"):
        OnnxDetector(path, names=["a", "b", "c"])
    with pytest.raises(ModelError, match="class names"):
        OnnxDetector(path, fmt="yolov8")
    with pytest.raises(ModelError, match="takes 64x64"):
        OnnxDetector(path, image_size=(32, 32))
    with pytest.raises(ValueError, match="unknown model format"):
        OnnxDetector(path, fmt="yolov7")
    dynamic = oracle_model(tmp_path / "d.onnx", "yolov5", dynamic_size=True, metadata={"names": "fire,smoke"})
    with pytest.raises(ModelError, match="--imgsz"):
        OnnxDetector(dynamic)
    assert OnnxDetector(dynamic, image_size=(SIZE, SIZE)).spec.input_width == SIZE
    with pytest.raises(ValueError, match="does not match"):
        OnnxDetector(path)(np.zeros((1, 3, 32, 32), np.float32))


def test_fixed_batch_model_runs_any_batch(tmp_path):
    det = OnnxDetector(oracle_model(tmp_path / "b1.onnx", batch=1))
    assert det.spec.batch == 1
    boxes, scores = det(np.zeros((3, 3, SIZE, SIZE), np.float32))
    assert boxes.shape[0] == scores.shape[0] == 3


def test_a_forced_wrong_format_names_the_layout_shape_and_classes(tmp_path):
    model = oracle_model(tmp_path / "v5.onnx", layout="yolov5")
    with pytest.raises(ModelError) as info:
        OnnxDetector(model, "yolov8")
    text = str(info.value)
    assert "does not fit the yolov8 layout as asked with --format" in text
    assert "for the 2 class names ['fire', 'smoke'] it expects (B, 4+2, N) = (B, 6, N)" in text
    assert "output shape (1, " in text and text.endswith("it fits --format yolov5")
    with pytest.raises(ModelError, match=r"yolov5 layout as asked .* check --names"):
        OnnxDetector(model, "yolov5", names=["fire"])
