"""The flags score, compare and predict share: the parsers of their values, the settings they build (a flag, then
``--config``'s file under it, then ``--set``), and the detector those describe."""

from __future__ import annotations

import argparse

import pytest
from detector_factories import oracle_model

from eval.cli import options as O
from eval.config import PredictConfig, ScoreConfig
from ground.cli.options import add_config_options, command_config
from ground.config.loader import ConfigError


def test_parsers():
    assert O.parse_names(" fire, smoke ,") == ["fire", "smoke"]
    assert O.parse_size("320") == (320, 320) and O.parse_size("640x480") == (640, 480)
    with pytest.raises(argparse.ArgumentTypeError, match="640x480"):
        O.parse_size("big")
    assert O.parse_alias(" Flame = fire") == ("Flame", "fire")
    with pytest.raises(argparse.ArgumentTypeError, match="NAME=CLASS"):
        O.parse_alias("Flame")


def _parser(schema, aliases) -> argparse.ArgumentParser:
    p = argparse.ArgumentParser()
    p.add_argument("model")
    add_config_options(p, lambda: schema, aliases, "docs/config.md#score", flag="--config")
    return p


def _settings(schema, aliases, *argv: str):
    return command_config(_parser(schema, aliases).parse_args(["m.onnx", *argv]), schema, aliases)


def test_flags_set_their_keys_and_the_file_goes_under_them(tmp_path):
    from eval.cli.score import ALIASES

    cfg = _settings(ScoreConfig, ALIASES)
    assert cfg == ScoreConfig() and cfg.inference.postprocess.conf == 0.001
    argv = ["--conf", "0.2", "--imgsz", "640x480", "--names", "fire,smoke", "--alias", "Flame=fire", "--alias",
            "Smoke=smoke", "--drop-class", "default,other", "--drop-class", "x", "--split", "all", "--device", "cpu"]  # fmt: skip
    cfg = _settings(ScoreConfig, ALIASES, *argv)
    assert (cfg.inference.postprocess.conf, cfg.inference.device) == (0.2, "cpu")
    assert (cfg.model.imgsz, cfg.model.names) == ((640, 480), ("fire", "smoke"))
    assert cfg.data.aliases == {"Flame": "fire", "Smoke": "smoke"} and cfg.data.drop_class == ("default", "other", "x")
    assert cfg.data.split == "all"
    settings = tmp_path / "score.yaml"
    settings.write_text("inference: {postprocess: {iou: 0.5}, batch: 4}\nci: 100\n")
    cfg = _settings(ScoreConfig, ALIASES, "--config", str(settings), "--batch", "8", "--set", "ci=50")
    assert (cfg.inference.postprocess.iou, cfg.inference.batch, cfg.ci) == (0.5, 8, 50)
    with pytest.raises(ConfigError, match=r"does not exist, not a settings file$"):
        _settings(ScoreConfig, ALIASES, "--config", str(tmp_path / "nope.yaml"))
    with pytest.raises(ConfigError, match=r"postprocess\.conf must be in \[0, 1\)"):
        _settings(ScoreConfig, ALIASES, "--conf", "1.5")
    with pytest.raises(ConfigError, match="device 'tpu': expected auto"):
        _settings(ScoreConfig, ALIASES, "--device", "tpu")


def test_predict_draws_at_an_alarms_confidence_and_prints_its_settings(capsys):
    import yaml

    from eval.cli.predict import ALIASES
    from eval.errors import ALARM_CONF

    assert _settings(PredictConfig, ALIASES).inference.postprocess.conf == ALARM_CONF
    assert _settings(PredictConfig, ALIASES, "--iou", "0.5").inference.postprocess.conf == ALARM_CONF
    assert _settings(PredictConfig, ALIASES, "--print-config", "--classes", "fire") is None
    printed = yaml.safe_load(capsys.readouterr().out)
    assert printed["classes"] == ["fire"] and printed["inference"]["postprocess"]["conf"] == ALARM_CONF


def test_the_detector_the_settings_describe(tmp_path):
    from eval.cli.predict import ALIASES

    cfg = _settings(PredictConfig, ALIASES, "--device", "cpu", "--names", "flame,smoke")
    detector = O.open_detector(oracle_model(tmp_path / "m.onnx"), cfg.model, cfg.inference)
    assert detector.spec.class_names == ("flame", "smoke")
