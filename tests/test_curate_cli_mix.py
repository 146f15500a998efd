"""``fuzzyfire mix``: a grid of mixtures per seed, checked before anything is written; the --val option."""

from __future__ import annotations

from pathlib import Path

import pytest
from factories import tiny_pool

from curate.core.dataset import Dataset
from fuzzyfire.cli import main


@pytest.fixture(scope="module")
def pools(tmp_path_factory: pytest.TempPathFactory) -> tuple[Dataset, Dataset]:
    base = tmp_path_factory.mktemp("pools")
    return tiny_pool(base / "real", 40, "real:cams"), tiny_pool(base / "synth", 40, "synth:method2", "fire")


def test_cli_writes_grid_per_seed(pools: tuple[Dataset, Dataset], tmp_path: Path) -> None:
    from curate.core.writer import write_dataset

    real, synth = pools
    write_dataset(real, tmp_path / "real", ("coco",), "copy")
    write_dataset(synth, tmp_path / "synth", ("coco",), "copy")
    args = ["mix", "--real", str(tmp_path / "real"), "--synth", str(tmp_path / "synth"), "--out", str(tmp_path / "o")]
    assert main([*args, "--mixtures", "R20_S0,R10_S10", "--seeds", "0-1"]) == 0
    made = sorted(p.relative_to(tmp_path / "o").as_posix() for p in (tmp_path / "o").glob("*/*"))
    assert made == ["seed0/R10_S10", "seed0/R20_S0", "seed1/R10_S10", "seed1/R20_S0"]
    assert main([*args, "--mixtures", "R5_S5,R99_S0", "--out", str(tmp_path / "o2")]) == 2
    assert not (tmp_path / "o2").exists()  # checked before anything is written


def test_cli_val_option(pools: tuple[Dataset, Dataset], tmp_path: Path) -> None:
    import yaml

    from curate.core.writer import write_dataset

    real, synth = pools
    write_dataset(real, tmp_path / "real", ("coco", "yolo"), "copy")
    write_dataset(synth, tmp_path / "synth", ("coco",), "copy")
    args = ["mix", "--real", str(tmp_path / "real"), "--synth", str(tmp_path / "synth"), "--mixtures", "R5_S5"]
    assert main([*args, "--val", str(tmp_path / "real"), "--out", str(tmp_path / "o")]) == 0
    doc = yaml.safe_load((tmp_path / "o" / "seed0" / "R5_S5" / "data.yaml").read_text())
    assert doc["val"] == str((tmp_path / "real" / "images").absolute())
    assert main([*args, "--val", str(tmp_path / "synth"), "--out", str(tmp_path / "o2")]) == 2
