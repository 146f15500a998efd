"""``fuzzyfire curate CONFIG`` end to end: a written dataset, byte-identical reruns, safe outputs, real data."""

from __future__ import annotations

import json
from pathlib import Path

import pytest
from curate_helpers import use_session_cache, write_scene_dataset

from fuzzyfire.cli import main

CONFIG = """
classes: [fire, smoke]
sources:
  - {path: src, name: gen}
dedup: {threshold: 0.45}
rank: {method: score, k: 3}
split: {sizes: {train: 6, valid: 2, test: 2}, group_threshold: 0.6, seed: 0}
images: copy
"""


@pytest.fixture(scope="module")
def config(tmp_path_factory: pytest.TempPathFactory) -> Path:
    use_session_cache(tmp_path_factory)
    base = tmp_path_factory.mktemp("cfg")
    items = {f"s{i}": (i, None) for i in range(12)} | {"s0_flip": (0, "hflip"), "s1_small": (1, "resize")}
    write_scene_dataset(base / "src", items)
    (base / "c.yaml").write_text(CONFIG)
    return base / "c.yaml"


def _files(root: Path) -> dict[str, bytes]:
    return {p.relative_to(root).as_posix(): p.read_bytes() for p in sorted(root.rglob("*")) if p.is_file()}


def test_curate_writes_dataset_and_is_deterministic(config: Path, tmp_path: Path) -> None:
    src_before = _files(config.parent / "src")
    assert main(["curate", str(config), "--out", str(tmp_path / "a")]) == 0
    assert main(["curate", str(config), "--out", str(tmp_path / "b")]) == 0
    a = tmp_path / "a"
    coco = json.loads((a / "annotations.json").read_text())
    assert len(coco["images"]) == 10 and {im["split"] for im in coco["images"]} == {"train", "valid", "test"}
    assert len(list((a / "labels").rglob("*.txt"))) == 10 and (a / "data.yaml").is_file()
    doc = json.loads((a / "curation.json").read_text())
    assert doc["splits"] == {"train": 6, "valid": 2, "test": 2} and doc["counts"]["removed_near"] == 2
    assert (a / "report.html").is_file() and json.loads((a / "manifest.json").read_text())["command"] == "curate"
    same = ("annotations.json",)  # data.yaml holds the absolute output path
    assert {k: _files(a)[k] for k in same} == {k: _files(tmp_path / "b")[k] for k in same}
    labels = {k: v for k, v in _files(a).items() if k.startswith(("labels/", "images/"))}
    assert labels == {k: v for k, v in _files(tmp_path / "b").items() if k.startswith(("labels/", "images/"))}
    assert _files(config.parent / "src") == src_before


def test_curate_refuses_bad_config_and_unsafe_out(config: Path, tmp_path: Path, capsys) -> None:
    assert main(["curate", str(config), "--out", str(tmp_path / "x"), "--set", "dedup.nope=1"]) == 2
    assert main(["curate", str(config), "--out", str(config.parent / "src" / "out")]) == 2
    (tmp_path / "busy").mkdir()
    (tmp_path / "busy" / "mine.txt").write_text("user file")
    assert main(["curate", str(config), "--out", str(tmp_path / "busy")]) == 2
    err = capsys.readouterr().err
    assert "dedup.nope" in err and "inside the source" in err and "not empty" in err


def test_shared_config_parses() -> None:
    from curate.curation import CurateConfig
    from ground.config.loader import load_config

    cfg = load_config(Path(__file__).parents[1] / "configs" / "curate-shared.yaml", CurateConfig)
    assert [s.name for s in cfg.sources] == ["fire-cctv-416", "fire-smoke-608"]
    assert cfg.sources[1].drop_classes == ("default",)


@pytest.mark.slow
def test_curate_real_data_without_leakage(shared_data: Path, tmp_path: Path) -> None:
    """fire-smoke-608 (its test split shares near duplicates with train): curated splits do not."""
    (tmp_path / "c.yaml").write_text(
        f"sources:\n  - {{path: {shared_data / 'fire-smoke-608'}, name: fs, drop_classes: [default]}}\n"
        "split: {sizes: {train: 0.8, valid: 0.1, test: 0.1}}\nimages: symlink\n"
    )
    assert main(["curate", str(tmp_path / "c.yaml"), "--out", str(tmp_path / "out")]) == 0
    out = tmp_path / "out"
    assert main(["leakage", str(out / "images" / "train"), str(out / "images" / "test")]) == 0
