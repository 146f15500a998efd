"""Experiment schema: every shipped config loads strictly; the paper's protocol is exact; contradictions raise;
named test sets parse strictly and their labels are unique."""

from __future__ import annotations

from pathlib import Path

import pytest
from conftest import REPO

from curate.mix import paper_grid, parse_mixture
from fuzzyfire.experiment_config import EvalSetConfig, ExperimentConfig, ExperimentConfigError
from ground.config.loader import ConfigError, build_config, load_config

CONFIGS = REPO / "configs"


def _load(name: str, *overrides: str) -> ExperimentConfig:
    cfg = load_config(CONFIGS / name, ExperimentConfig, overrides)
    cfg.check()
    return cfg


@pytest.mark.parametrize("name", ["demo.yaml", "paper.yaml", "shared-data.yaml"])
def test_shipped_configs_load(name: str) -> None:
    cfg = _load(name)
    assert cfg.classes == ("fire",)
    assert all(parse_mixture(m).total for m in (*cfg.grid.mixtures, *cfg.grid.table1))


#: The keys that make shared-data.yaml's study the recommended pool (docs/findings.md, "Own cut-out flames").
OWN_FLAMES = ("grid.table1=[]", "synth.method1=null", "report.gap_draws=0", "report.baseline=R200_S0",
              "grid.control=false", "synth.method2.backgrounds=[../../shared/data/fire-free]",
              "synth.method2.own_frames=1.0",
              "synth.method2.photo_negatives=1.0", "synth.method2.flames.source=cutouts",
              "synth.method2.auto_exposure=true", "grid.mixtures=[R200_S0,R200_S200]")  # fmt: skip


def test_own_flames_is_shared_data_with_the_best_pools_keys() -> None:
    """configs/own-flames.yaml extends shared-data.yaml: the same study (and so the same pools and runs) as
    shared-data.yaml with the documented --set keys; its pool holds out the fire-free test set's quarter."""
    own = _load("own-flames.yaml")
    assert own == _load("shared-data.yaml", *OWN_FLAMES)
    assert own.resolved(CONFIGS).synth.method2.background_holdout == own.tests["fire-free"].holdout == 0.25
    assert _load("own-flames.yaml", "grid.seeds=[0]").grid.seeds == (0,)


def test_every_key_of_the_shipped_configs_is_commented() -> None:
    for path in CONFIGS.glob("*.yaml"):
        if path.name not in ("demo.yaml", "paper.yaml", "paper-ultralytics.yaml", "shared-data.yaml"):
            continue
        text = path.read_text()
        assert text.lstrip().startswith("#") and text.count("#") > 30, path


def test_demo_is_small_offline_and_a_stand_in() -> None:
    cfg = _load("demo.yaml")
    assert cfg.real.source() == "standin" and cfg.rare.source() == "standin"
    assert cfg.real.standin.kind == "common" and cfg.rare.standin.kind == "rare"
    sizes = [cfg.real.standin.width, cfg.rare.standin.width, cfg.synth.method1.width, cfg.synth.method2.width]
    assert max(sizes) <= 320 and cfg.train.imgsz <= 320
    assert cfg.grid.seeds == (0, 1) and cfg.synth.method1.flames.generator == "fluid"
    assert cfg.executor.name == "local"


def test_paper_is_the_papers_protocol() -> None:
    cfg = _load("paper.yaml")
    assert list(cfg.grid.mixtures) == [m.name for m in paper_grid()]
    assert cfg.grid.seeds == (0, 1, 2, 3, 4) and cfg.grid.table1 == ("R0_S1000",)
    assert (cfg.train.epochs, cfg.train.imgsz, cfg.train.batch) == (100, 640, 64)
    assert cfg.synth.method1.n == cfg.synth.method2.n == 1000
    cur = cfg.real.curate_config()
    assert cur.rank.top == 1400 and cur.split.sizes == {"train": 1000, "valid": 200, "test": 200}
    assert cur.sources[0].path == cfg.real.path and cfg.rare.path is not None


def test_paper_ultralytics_is_the_same_protocol_trained_by_a_command() -> None:
    yolo, ours = _load("paper-ultralytics.yaml"), _load("paper.yaml")
    yolo.check()
    assert yolo.engine.name == "command" and ours.engine.name == "fuzzyfire"
    assert yolo.engine.train.startswith("yolo detect train data={data_yaml}") and "{seed}" in yolo.engine.train
    assert "format=onnx" in yolo.engine.export and yolo.engine.onnx == "train/weights/best.onnx"
    assert (yolo.grid, yolo.real, yolo.rare, yolo.synth) == (ours.grid, ours.real, ours.rare, ours.synth)


def test_overrides_go_through_the_schema() -> None:
    cfg = _load("paper.yaml", "real.path=/data/mine", "grid.seeds=[7]", "executor.name=ray")
    assert cfg.real.path == Path("/data/mine") and cfg.grid.seeds == (7,) and cfg.executor.name == "ray"
    with pytest.raises(ConfigError, match="train.epoch"):
        _load("demo.yaml", "train.epoch=3")
    with pytest.raises(ConfigError, match="grid.seeds"):
        _load("demo.yaml", "grid.seeds=zero")


def test_contradictions_raise() -> None:
    with pytest.raises(ExperimentConfigError, match="give path"):
        build_config({"real": {}}, ExperimentConfig).check()
    with pytest.raises(ExperimentConfigError, match="standin excludes"):
        build_config({"real": {"path": "x", "standin": {}}}, ExperimentConfig).check()
    with pytest.raises(ExperimentConfigError, match="not both"):
        build_config({"real": {"curate": {"sources": []}}}, ExperimentConfig).check()
    with pytest.raises(ExperimentConfigError, match="synth.method2 is null"):
        build_config({"real": {"path": "x"}, "synth": {"method2": None}}, ExperimentConfig).check()
    with pytest.raises(ExperimentConfigError, match="rare"):
        build_config({"real": {"path": "x"}, "rare": {}}, ExperimentConfig).check()


def test_named_test_sets_parse_and_refuse_unknown_keys() -> None:
    cfg = build_config(
        {
            "real": {"path": "x"},
            "tests": {"fire-free": {"path": "photos", "holdout": 0.25}, "b": {"path": "y", "name": "B"}},
        },
        ExperimentConfig,
    )
    cfg.check()
    assert isinstance(cfg.tests["fire-free"], EvalSetConfig) and cfg.tests["fire-free"].holdout == 0.25
    assert cfg.test_names() == {"fire-free": "fire-free", "b": "B"} and cfg.tests["b"].split is None
    with pytest.raises(ConfigError, match="tests.fire-free.holdot: unknown key"):
        build_config({"real": {"path": "x"}, "tests": {"fire-free": {"holdot": 0.25}}}, ExperimentConfig)
    with pytest.raises(ConfigError, match="tests.fire-free.holdout: expected a number"):
        build_config({"real": {"path": "x"}, "tests": {"fire-free": {"holdout": "a"}}}, ExperimentConfig)
    assert build_config({"real": {"path": "x"}}, ExperimentConfig).tests == {}


@pytest.mark.parametrize(
    ("tests", "message"),
    [
        ({"a": {}}, "tests.a: give exactly one of path, standin"),
        ({"a": {"path": "p", "standin": {}}}, "tests.a: give exactly one of path, standin"),
        ({"a": {"path": "p", "holdout": 1.5}}, "tests.a: holdout must be in 0..1"),
        ({"a": {"standin": {}, "holdout": 0.5}}, "tests.a: holdout picks photos of a folder"),
        ({"common": {"path": "p"}}, "tests.common: the label 'common' is taken"),
        ({"a": {"path": "p", "name": "rare"}}, "the label 'rare' is taken"),
        ({"a b": {"path": "p"}, "a_b": {"path": "q"}}, "tests.a_b: the label 'a_b' is taken"),  # one scores folder
    ],
)
def test_named_test_sets_that_do_not_fit_raise(tests: dict, message: str) -> None:
    cfg = build_config({"real": {"path": "x"}, "rare": {"path": "r"}, "tests": tests}, ExperimentConfig)
    with pytest.raises(ExperimentConfigError, match=message):
        cfg.check()


def test_shipped_configs_have_a_fire_free_set() -> None:
    shared, demo = _load("shared-data.yaml"), _load("demo.yaml")
    free = shared.tests["fire-free"]
    assert free.path.as_posix().endswith("shared/data/fire-free") and free.holdout == 0.25 and free.split is None
    assert demo.tests["fire-free"].standin.negatives == 1.0 and demo.tests["fire-free"].source() == "standin"
    assert _load("paper.yaml").tests == {} and shared.rare.name == "rare" and shared.rare.holdout == 0.0


def _photo_study(m2: dict, **tests: dict) -> ExperimentConfig:
    """A study whose Method 2 pool composites on ``photos`` (``m2``: more of its keys) and whose ``tests`` are given."""
    synth = {"method2": {"scenes": 0, "backgrounds": ["photos"], **m2}}
    return build_config({"real": {"path": "x"}, "synth": synth, "tests": tests}, ExperimentConfig)


def test_the_test_sets_holdout_is_the_one_key_of_the_pools_held_out_share(tmp_path: Path) -> None:
    """A test set on a folder of the pool's backgrounds states the share once; the pool holds it out (the largest
    of several); a conflicting background_holdout, or a share that leaves the pool no photo, is refused."""
    on = {"path": "photos", "holdout": 0.25}
    assert _photo_study({}, free=on).resolved(tmp_path).synth.method2.background_holdout == 0.25
    assert (
        _photo_study({}, free=on, more={"path": str(tmp_path / "photos"), "holdout": 0.5})
        .resolved(tmp_path)
        .synth.method2.background_holdout
        == 0.5
    )  # the same folder, given another way: a share nested in 0.5
    assert (
        _photo_study({"background_holdout": 0.25}, free=on).resolved(tmp_path).synth.method2.background_holdout == 0.25
    )
    other = _photo_study({"background_holdout": 0.1}, free={"path": "elsewhere", "holdout": 0.25})
    assert other.resolved(tmp_path).synth.method2.background_holdout == 0.1  # not the pool's photos: as given
    with pytest.raises(ExperimentConfigError, match="background_holdout 0.1 and tests.free.holdout 0.25 cut the"):
        _photo_study({"background_holdout": 0.1}, free=on).resolved(tmp_path)
    with pytest.raises(ExperimentConfigError, match="tests.free.holdout 1 holds out every photo"):
        _photo_study({}, free={"path": "photos", "holdout": 1.0}).resolved(tmp_path)


def test_a_pool_section_is_read_by_its_method_name_and_an_executor_by_its_own() -> None:
    cfg = _load("demo.yaml")
    assert cfg.synth.section("method1") is cfg.synth.method1 and cfg.synth.section("method2") is cfg.synth.method2
    with pytest.raises(ValueError, match="unknown synthesis method 'method3'"):
        cfg.synth.section("method3")
    with pytest.raises(ConfigError, match="executor.name: 'dask' is not one of"):
        _load("demo.yaml", "executor.name=dask")
