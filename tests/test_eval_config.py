"""eval's settings: each default once, values out of range refused naming the key, YAML round trips."""

from __future__ import annotations

import pytest

from eval import config as C
from eval.errors import ALARM_CONF
from eval.operating import ALARM_BUDGET
from ground.config.loader import build_config, to_dict
from ground.detect.detections import PostprocessConfig


def test_defaults_score_as_coco_does_and_draw_at_an_alarms_confidence() -> None:
    assert C.InferenceConfig().postprocess == PostprocessConfig()
    assert C.ScoreConfig().inference == C.InferenceConfig() == C.CompareConfig().inference
    assert C.ScoreConfig().alarm_conf == ALARM_CONF and C.CompareConfig().alarm_budget == ALARM_BUDGET
    drawn, scored = C.PredictConfig().inference, C.InferenceConfig()
    assert drawn.postprocess.conf == ALARM_CONF > scored.postprocess.conf
    assert (drawn.postprocess.iou, drawn.postprocess.max_det, drawn.batch) == (
        scored.postprocess.iou,
        scored.postprocess.max_det,
        scored.batch,
    )
    partial = build_config({"inference": {"postprocess": {"iou": 0.5}, "batch": 4}}, C.PredictConfig).inference
    assert (partial.postprocess.conf, partial.postprocess.iou, partial.batch) == (ALARM_CONF, 0.5, 4)


@pytest.mark.parametrize(
    "schema, raw, match",
    [
        (C.InferenceConfig, {"batch": 0}, "batch must be >= 1"),
        (C.InferenceConfig, {"workers": -1}, "workers and threads >= 0"),
        (C.InferenceConfig, {"device": "tpu"}, "device 'tpu'"),
        (C.InferenceConfig, {"resize": "cubic"}, "resize: 'cubic' is not one of"),
        (C.InferenceConfig, {"postprocess": {"max_det": 0}}, r"postprocess\.max_det must be >= 1"),
        (C.OnnxModelConfig, {"format": "yolov9"}, "format: 'yolov9' is not one of"),
        (C.OnnxModelConfig, {"imgsz": [640]}, r"model\.imgsz must be \[width, height\]"),
        (C.OnnxModelConfig, {"imgsz": [640, 0]}, r"model\.imgsz must be \[width, height\]"),
        (C.TestSetConfig, {"format": "csv"}, r"data\.format 'csv': choose one of auto, coco"),
        (C.TestSetConfig, {"holdout": 1.5}, r"data\.holdout must be in \[0, 1\]"),
        (C.ScoreConfig, {"ci": -1}, "ci must be >= 0"),
        (C.CompareConfig, {"samples": 0}, "samples >= 1"),
        (C.CompareConfig, {"alarm_budget": 0}, "alarm_budget must be > 0"),
        (C.CompareConfig, {"negatives_holdout": -0.1}, r"negatives_holdout must be in \[0, 1\]"),
    ],
)
def test_values_out_of_range_are_refused_naming_the_key(schema, raw, match) -> None:
    with pytest.raises(ValueError, match=match):
        build_config(raw, schema)


def test_every_command_config_reads_back_from_its_yaml() -> None:
    for schema in (C.ScoreConfig, C.CompareConfig, C.PredictConfig, C.InferenceConfig):
        cfg = schema()
        assert build_config(to_dict(cfg), schema) == cfg
    raw = {"model": {"imgsz": [640, 480], "names": ["fire"]}, "data": {"aliases": {"Flame": "fire"}}}
    cfg = build_config(raw, C.ScoreConfig)
    assert cfg.model.imgsz == (640, 480) and cfg.data.aliases == {"Flame": "fire"}
