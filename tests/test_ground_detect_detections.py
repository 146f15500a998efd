"""Post-processing: confidence threshold, multi-label, limits (the NMS itself: test_ground_detect_nms.py)."""

from __future__ import annotations

import numpy as np
import pytest

from ground.detect.detections import PostprocessConfig, postprocess


def test_postprocess_multi_label_and_thresholds():
    cxcywh = np.array([[10, 10, 4, 4], [30, 30, 4, 4]], np.float32)
    scores = np.array([[0.9, 0.5], [0.0005, 0.002]], np.float32)
    det = postprocess(cxcywh, scores, PostprocessConfig(conf=0.001))
    assert det.labels.tolist() == [0, 1, 1] and det.scores.tolist() == pytest.approx([0.9, 0.5, 0.002])
    np.testing.assert_allclose(det.boxes[0], [8, 8, 12, 12])
    best = postprocess(cxcywh, scores, PostprocessConfig(conf=0.001), multi_label=False)
    assert best.labels.tolist() == [0, 1] and len(postprocess(cxcywh, scores, PostprocessConfig(conf=0.95))) == 0
    assert len(postprocess(cxcywh[:0], scores[:0])) == 0


def test_postprocess_config_refuses_values_out_of_range_naming_the_key():
    for bad, key in (
        ({"conf": 1.0}, "conf"),
        ({"conf": -0.1}, "conf"),
        ({"iou": 0.0}, "iou"),
        ({"max_det": 0}, "max_det"),
    ):
        with pytest.raises(ValueError, match=rf"postprocess\.{key} must be"):
            PostprocessConfig(**bad)
    assert PostprocessConfig(conf=0.0, iou=1.0, max_det=1).conf == 0.0
