"""One config path per command: CONFIG.yaml, the flags (aliases of keys, with the keys' defaults), then --set."""

from __future__ import annotations

import argparse
import dataclasses
import io
from dataclasses import dataclass, field
from pathlib import Path

import pytest
import yaml

from ground.cli.options import Alias, add_config_options, add_settings, config_from_args, key_default, print_config
from ground.config.loader import ConfigError


@dataclass(frozen=True)
class Inner:
    depth: float = 0.5  # how deep


@dataclass(frozen=True)
class Settings:
    n: int = 3  # count
    name: str = "a"  # label
    paths: tuple[Path, ...] = ()  # folders
    inner: Inner = field(default_factory=Inner)  # nested

    def __post_init__(self) -> None:
        if self.n < 1:
            raise ValueError(f"n must be >= 1, got {self.n}")


ALIASES = (
    Alias("--n", ("n",), "count", {"type": int}),
    Alias("--paths", ("paths",), "folders", {"type": Path, "nargs": "+"}),
    Alias("--deep", ("inner.depth",), "go deep", {"action": "store_true"}, lambda _: {"inner.depth": 1.0}),
)


def _parser(schema=Settings) -> argparse.ArgumentParser:
    from ground.cli.commands import HelpFormatter

    p = argparse.ArgumentParser(formatter_class=HelpFormatter)
    add_config_options(p, schema, ALIASES, "docs/config.md#settings")
    return p


def _build(*argv: str) -> Settings:
    return config_from_args(_parser().parse_args(list(argv)), Settings, ALIASES)


def test_no_file_no_flags_gives_the_dataclass_defaults() -> None:
    assert _build() == Settings()


def test_file_then_flags_then_set_later_wins(tmp_path: Path) -> None:
    cfg = tmp_path / "s.yaml"
    cfg.write_text("n: 5\nname: b\ninner: {depth: 0.1}\n")
    assert _build(str(cfg)) == Settings(n=5, name="b", inner=Inner(0.1))
    assert _build(str(cfg), "--n", "7").n == 7
    assert _build(str(cfg), "--n", "7", "--set", "n=9").n == 9
    assert _build(str(cfg), "--deep").inner.depth == 1.0
    assert _build("--paths", "a", "b/c").paths == (Path("a"), Path("b/c"))
    with pytest.raises(ConfigError, match="n must be >= 1, got 0"):  # a flag given 0 is given, not left out
        _build(str(cfg), "--n", "0")


def test_errors_name_the_file_and_the_key(tmp_path: Path) -> None:
    cfg = tmp_path / "s.yaml"
    cfg.write_text("n: 0\n")
    with pytest.raises(ConfigError, match=r"s\.yaml: n must be >= 1, got 0"):
        _build(str(cfg))
    with pytest.raises(ConfigError, match="nope: unknown key"):
        _build("--set", "nope=1")
    with pytest.raises(ConfigError, match="inner.depth: expected a number"):
        _build("--set", "inner.depth=deep")
    with pytest.raises(ConfigError, match="is a folder, not a settings file"):
        _build(str(tmp_path))
    with pytest.raises(ConfigError, match="does not exist, not a settings file"):
        _build(str(tmp_path / "nope.yaml"))


def test_help_shows_each_flags_key_and_its_dataclass_default() -> None:
    for schema in (Settings, lambda: Settings):  # the class, or a function importing it when the help is printed
        text = _parser(schema).format_help()
        assert "[n=3]" in text and "[paths=[]]" in text and "[inner.depth=0.5]" in text
    assert key_default(Settings, "inner.depth") == 0.5
    with pytest.raises(KeyError, match="no key 'deep'"):
        key_default(Settings, "inner.deep")


def test_the_file_may_be_an_option_for_a_command_whose_positionals_are_inputs(tmp_path: Path) -> None:
    p = argparse.ArgumentParser()
    p.add_argument("model")
    add_config_options(p, Settings, ALIASES, "docs/config.md#settings", flag="--config")
    cfg = tmp_path / "s.yaml"
    cfg.write_text("n: 5\n")
    for argv in (["m.onnx", "--config", str(cfg), "--n", "6"], ["--n", "6", "--config", str(cfg), "m.onnx"]):
        args = p.parse_args(argv)
        assert args.model == "m.onnx" and config_from_args(args, Settings, ALIASES) == Settings(n=6)
    assert config_from_args(p.parse_args(["m.onnx"]), Settings, ALIASES) == Settings()
    with pytest.raises(ConfigError, match=r"nope\.yaml: does not exist, not a settings file$"):
        config_from_args(p.parse_args(["m.onnx", "--config", str(tmp_path / "nope.yaml")]), Settings, ALIASES)


def test_a_commands_settings_follow_its_own_arguments_and_name_its_section(tmp_path: Path) -> None:
    """add_settings: the settings after the command's own arguments, what it runs, and the docs/config.md section
    of the command as typed (``synth toy`` -> ``#synth-toy``) unless one is named."""
    from ground.cli.commands import add_command

    def run(args: argparse.Namespace) -> int:
        return 0

    parser = argparse.ArgumentParser(prog="fuzzyfire")
    sub = parser.add_subparsers(dest="command")
    p = add_command(sub, "toy", help="a toy", description="A toy.")
    p.add_argument("--out")
    add_settings(p, lambda: Settings, ALIASES, run, required=True)
    inner = add_command(sub, "synth", help="a group", description="A group.").add_subparsers(dest="inner")
    q = add_command(inner, "toy", help="a toy", description="A toy.")
    q.add_argument("src")
    add_settings(q, Settings, ALIASES, run, flag="--config")
    r = add_command(inner, "other", help="a toy", description="A toy.")
    add_settings(r, Settings, ALIASES, run, section="flame library")

    def reference(parser: argparse.ArgumentParser) -> str:
        help = next(a.help for a in parser._actions if a.dest == "config")
        return help.partition("every key: ")[2].partition(")")[0]

    assert [reference(x) for x in (p, q, r)] == [
        "docs/config.md#toy",
        "docs/config.md#synth-toy",
        "docs/config.md#flame-library",
    ]
    assert [a.dest for a in p._actions][:4] == ["help", "out", "config", "set"]
    assert [a.dest for a in q._actions][:4] == ["help", "src", "config", "set"]
    (tmp_path / "c.yaml").write_text("name: b\n")
    args = parser.parse_args(["toy", str(tmp_path / "c.yaml"), "--n", "4"])
    assert args.func is run and config_from_args(args, Settings, ALIASES) == Settings(n=4, name="b")
    assert parser.parse_args(["synth", "toy", "s"]).config is None
    with pytest.raises(SystemExit):
        parser.parse_args(["toy"])  # CONFIG.yaml required


def test_printed_config_reads_back_as_the_same_settings(tmp_path: Path) -> None:
    cfg = _build("--n", "4", "--paths", "x", "--set", "inner.depth=0.25")
    out = io.StringIO()
    print_config(cfg, out)
    (tmp_path / "back.yaml").write_text(out.getvalue())
    assert yaml.safe_load(out.getvalue())["inner"] == {"depth": 0.25}
    assert _build(str(tmp_path / "back.yaml")) == cfg


def _commands():
    from curate.cli.curate import ALIASES as CURATE_ALIASES
    from curate.cli.dataset import MERGE_ALIASES
    from curate.cli.dedup import DEDUP_ALIASES, LEAKAGE_ALIASES
    from curate.cli.mix import ALIASES as MIX_ALIASES
    from curate.curation import CurateConfig
    from curate.mix import MixConfig
    from curate.settings import DedupJobConfig, LeakageJobConfig
    from curate.sources import MergeConfig
    from eval.cli.compare import ALIASES as COMPARE_ALIASES
    from eval.cli.predict import ALIASES as PREDICT_ALIASES
    from eval.cli.score import ALIASES as SCORE_ALIASES
    from eval.config import CompareConfig, PredictConfig, ScoreConfig
    from synth.cli import (
        COLOUR_ALIASES,
        CUTOUT_ALIASES,
        FLAME_ALIASES,
        GAP_ALIASES,
        METHOD1_ALIASES,
        METHOD2_ALIASES,
        SCENES_ALIASES,
    )
    from synth.flames.cutouts import CutoutConfig
    from synth.flames.library import FlameLibraryConfig
    from synth.gap import GapConfig
    from synth.method1 import Method1Config
    from synth.method2 import Method2Config
    from synth.places.scenes import ScenesConfig
    from train.cli import ALIASES as TRAIN_ALIASES
    from train.config import TrainConfig

    return [
        (FlameLibraryConfig, FLAME_ALIASES),
        (Method1Config, METHOD1_ALIASES),
        (Method2Config, METHOD2_ALIASES),
        (CutoutConfig, CUTOUT_ALIASES),
        (CutoutConfig, COLOUR_ALIASES),
        (ScenesConfig, SCENES_ALIASES),
        (GapConfig, GAP_ALIASES),
        (TrainConfig, TRAIN_ALIASES),
        (ScoreConfig, SCORE_ALIASES),
        (CompareConfig, COMPARE_ALIASES),
        (PredictConfig, PREDICT_ALIASES),
        (DedupJobConfig, DEDUP_ALIASES),
        (LeakageJobConfig, LEAKAGE_ALIASES),
        (MixConfig, MIX_ALIASES),
        (CurateConfig, CURATE_ALIASES),
        (MergeConfig, MERGE_ALIASES),
    ]


def test_every_flag_of_every_command_is_a_key_of_its_config_with_that_default() -> None:
    """Each shipped command's flags name real keys; with no flag given the command builds its dataclass' defaults
    (the flags hold no defaults of their own)."""
    for schema, aliases in _commands():
        p = argparse.ArgumentParser()
        add_config_options(p, schema, aliases, "docs/config.md")
        for a in aliases:
            for key in a.keys:
                key_default(schema, key)  # raises for a key the dataclass does not have
            assert p.get_default(a.dest) is None, a.flag
        required = [f.name for f in dataclasses.fields(schema) if f.default is f.default_factory is dataclasses.MISSING]
        argv = [arg for name in required for arg in ("--set", f"{name}=[]")]  # merge's and curate's sources
        built = config_from_args(p.parse_args(argv), schema, aliases)
        assert built == schema(**dict.fromkeys(required, ())), schema.__name__
