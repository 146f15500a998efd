from dataclasses import dataclass, field
from pathlib import Path
from typing import Literal, Optional

import pytest

from ground.config.loader import ConfigError, apply_overrides, build_config, load_config, to_dict


@dataclass(frozen=True)
class Inner:
    epochs: int = 3
    lr: float = 0.01
    mode: Literal["fast", "slow"] = "fast"


@dataclass(frozen=True)
class Outer:
    name: str
    inner: Inner = field(default_factory=Inner)
    items: tuple[Inner, ...] = ()
    path: Optional[Path] = None
    tags: dict[str, int] = field(default_factory=dict)
    flag: bool = False


def test_builds_nested_typed_objects():
    cfg = build_config(
        {"name": "x", "inner": {"epochs": 5, "lr": 1}, "items": [{"mode": "slow"}], "path": "a/b", "tags": {"k": 2}},
        Outer,
    )
    assert cfg.inner == Inner(5, 1.0, "fast") and isinstance(cfg.inner.lr, float)
    assert cfg.items == (Inner(mode="slow"),) and cfg.path == Path("a/b") and cfg.tags == {"k": 2}
    assert to_dict(cfg)["path"] == "a/b"


@pytest.mark.parametrize(
    "raw,message",
    [
        ({"name": "x", "inner": {"epoch": 5}}, "inner.epoch: unknown key"),
        ({"name": "x", "inner": {"epochs": "5"}}, "inner.epochs: expected an integer"),
        ({"name": "x", "inner": {"epochs": True}}, "inner.epochs: expected an integer"),
        ({"name": "x", "items": [{}, {"mode": "medium"}]}, "items[1].mode: 'medium' is not one of"),
        ({"name": "x", "flag": "yes"}, "flag: expected true or false"),
        ({"inner": {}}, "name: required key is missing"),
        ({"name": "x", "tags": {"k": 1.5}}, "tags.k: expected an integer"),
        ({"name": 3}, "name: expected a string"),
    ],
)
def test_rejects_with_key_path(raw, message):
    with pytest.raises(ConfigError, match=message.replace("[", r"\[").replace("]", r"\]")):
        build_config(raw, Outer)


def test_overrides_go_through_validation(tmp_path):
    path = tmp_path / "c.yaml"
    path.write_text("# comment\nname: x\ninner:\n  epochs: 2  # epochs\nitems:\n  - mode: fast\n")
    cfg = load_config(path, Outer, ["inner.epochs=7", "items.0.mode=slow", "flag=true"])
    assert cfg.inner.epochs == 7 and cfg.items[0].mode == "slow" and cfg.flag is True
    with pytest.raises(ConfigError, match="inner.epochs: expected an integer"):
        load_config(path, Outer, ["inner.epochs=many"])
    with pytest.raises(ConfigError, match="inner.bogus: unknown key"):
        load_config(path, Outer, ["inner.bogus=1"])
    with pytest.raises(ConfigError, match="expected KEY=VALUE"):
        load_config(path, Outer, ["inner.epochs"])
    with pytest.raises(ConfigError, match="no list item 4"):
        apply_overrides({"items": []}, ["items.4.mode=slow"])


def test_invalid_yaml(tmp_path):
    (tmp_path / "bad.yaml").write_text("a: [1, 2\n")
    with pytest.raises(ConfigError, match="invalid YAML"):
        load_config(tmp_path / "bad.yaml", Outer)
    (tmp_path / "list.yaml").write_text("- 1\n")
    with pytest.raises(ConfigError, match="top level must be a mapping"):
        load_config(tmp_path / "list.yaml", Outer)


def test_a_file_extends_another_in_its_folder(tmp_path):
    (tmp_path / "base.yaml").write_text(
        "name: base\ninner: {epochs: 2, lr: 0.5}\nitems: [{mode: slow}]\ntags: {a: 1}\npath: a/b\n"
    )
    (tmp_path / "mid.yaml").write_text("extends: base.yaml\ninner: {epochs: 4}\nitems: []\n")
    (tmp_path / "top.yaml").write_text("extends: mid.yaml\nname: top\ntags: {b: 2}\npath: null\n")
    cfg = load_config(tmp_path / "top.yaml", Outer, ["inner.lr=0.25"])
    assert cfg.name == "top" and cfg.inner == Inner(4, 0.25)  # mappings merge key by key, through the chain
    assert cfg.items == () and cfg.path is None and cfg.tags == {"a": 1, "b": 2}  # a list or null replaces
    assert load_config(tmp_path / "mid.yaml", Outer).inner == Inner(4, 0.5)  # the base file is only read


@pytest.mark.parametrize(
    ("text", "message"),
    [
        ("extends: loop.yaml\nname: x\n", "extends itself through loop.yaml"),
        ("extends: ../base.yaml\n", "expected the name of a .yaml file in the same folder"),
        ("extends: [base.yaml]\n", "expected the name of a .yaml file in the same folder"),
        ("extends: nowhere.yaml\n", "extends nowhere.yaml: no such file"),
    ],
)
def test_extends_refuses_what_it_cannot_read(tmp_path, text, message):
    (tmp_path / "loop.yaml").write_text(text)
    with pytest.raises(ConfigError, match=message):
        load_config(tmp_path / "loop.yaml", Outer)


def test_shipped_configs_load():
    from curate.sources import MergeConfig

    repo = Path(__file__).resolve().parents[1]
    cfg = load_config(repo / "configs" / "merge-shared.yaml", MergeConfig)
    assert cfg.classes == ("fire", "smoke") and cfg.sources[1].drop_classes == ("default",)
