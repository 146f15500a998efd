"""``fuzzyfire mix``: a grid of mixtures per seed, checked before anything is written; the --val option."""

from __future__ import annotations

import json
from pathlib import Path

import pytest
from factories import tiny_pool

from fuzzyfire.cli import main
from ground.data.dataset import Dataset


@pytest.fixture(scope="module")
def pools(tmp_path_factory: pytest.TempPathFactory) -> tuple[Dataset, Dataset]:
    base = tmp_path_factory.mktemp("pools")
    return tiny_pool(base / "real", 40, "real:cams"), tiny_pool(base / "synth", 40, "synth:method2", "fire")


def test_cli_writes_grid_per_seed(pools: tuple[Dataset, Dataset], tmp_path: Path) -> None:
    from ground.data.writer import write_dataset

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

    from ground.data.writer import write_dataset

    real, synth = pools
    write_dataset(real, tmp_path / "real", ("coco", "yolo"), "copy")
    write_dataset(synth, tmp_path / "synth", ("coco",), "copy")
    args = ["mix", "--real", str(tmp_path / "real"), "--synth", str(tmp_path / "synth"), "--mixtures", "R5_S5"]
    assert main([*args, "--val", str(tmp_path / "real"), "--out", str(tmp_path / "o")]) == 0
    doc = yaml.safe_load((tmp_path / "o" / "seed0" / "R5_S5" / "data.yaml").read_text())
    assert doc["val"] == str((tmp_path / "real" / "images").absolute())
    dotted = tmp_path / "synth" / ".." / "real"  # a relative-looking path: data.yaml names the folder resolved
    assert main([*args, "--val", str(dotted), "--out", str(tmp_path / "o3")]) == 0
    doc = yaml.safe_load((tmp_path / "o3" / "seed0" / "R5_S5" / "data.yaml").read_text())
    assert doc["val"] == str((tmp_path / "real" / "images").resolve()) and ".." not in doc["val"]
    assert main([*args, "--val", str(tmp_path / "synth"), "--out", str(tmp_path / "o2")]) == 2


def _split_pools(pools: tuple[Dataset, Dataset], root: Path) -> tuple[Path, Path]:
    """The real pool written with train/valid splits, the synthetic one without splits."""
    from dataclasses import replace

    from ground.data.writer import write_dataset

    real, synth = pools
    real = replace(real, images=tuple(replace(i, split="train" if i.id % 4 else "valid") for i in real.images))
    write_dataset(real, root / "real", ("coco",), "copy")
    write_dataset(synth, root / "synth", ("coco",), "copy")
    return root / "real", root / "synth"


def test_each_source_has_its_own_split_option(pools, tmp_path: Path, capsys) -> None:
    real, synth = _split_pools(pools, tmp_path)
    args = ["mix", "--real", str(real), "--synth", str(synth), "--mixtures", "R10_S10"]
    assert main([*args, "--split", "valid", "--out", str(tmp_path / "o")]) == 2
    err = capsys.readouterr().err
    assert f"{synth}: no split 'valid' (no splits: its 40 images are one set)" in err
    assert not (tmp_path / "o").exists()
    assert main([*args, "--real-split", "valid", "--out", str(tmp_path / "o")]) == 0
    record = json.loads((tmp_path / "o" / "seed0" / "R10_S10" / "mixture.json").read_text())
    assert sum(i["source"].startswith("real:") for i in record["images"]) == 10
    assert main([*args, "--real-split", "vaild", "--out", str(tmp_path / "o2")]) == 2
    assert "no split 'vaild' (splits: 'train', 'valid')" in capsys.readouterr().err


@pytest.mark.parametrize(
    ("extra", "message"),
    [
        (["--mixtures", "R5_S5", "--classes", "fire,smok"], "--classes 'smok': no such class (classes: 'fire')"),
        (["--mixtures", "R5_S5", "--total", "500"], "--total size the --paper-grid"),
        (["--mixtures", "R5_S5", "--val-split", "valid"], "--val-split describe --val, which is not given"),
        (["--mixtures", "R5_S5", "--real-format", "kitti"], "invalid choice: 'kitti'"),
    ],
)
def test_options_that_name_nothing_or_do_nothing_are_refused(pools, tmp_path: Path, capsys, extra, message) -> None:
    real, synth = _split_pools(pools, tmp_path)
    argv = ["mix", "--real", str(real), "--synth", str(synth), "--out", str(tmp_path / "o"), *extra]
    try:
        code = main(argv)
    except SystemExit as exc:  # argparse's own refusal
        code = exc.code
    assert code == 2 and message in capsys.readouterr().err
    assert not (tmp_path / "o").exists()


def test_every_output_folder_is_checked_before_the_first_is_written(pools, tmp_path: Path, capsys) -> None:
    real, synth = _split_pools(pools, tmp_path)
    args = ["mix", "--real", str(real), "--synth", str(synth), "--out", str(tmp_path / "o")]
    assert main([*args, "--mixtures", "R10_S0"]) == 0
    assert main([*args, "--mixtures", "R5_S5,R10_S0"]) == 2
    assert "pass --overwrite" in capsys.readouterr().err
    assert not (tmp_path / "o" / "seed0" / "R5_S5").exists()


def test_a_folder_of_images_without_labels_mixes_as_negatives(pools, tmp_path: Path, capsys) -> None:
    from factories import write_image

    _, synth = _split_pools(pools, tmp_path)
    for k in range(4):
        write_image(tmp_path / "photos" / f"p{k}.jpg", 16, 12, seed=k)
    args = ["mix", "--real", str(tmp_path / "photos"), "--synth", str(synth), "--out", str(tmp_path / "o")]
    assert main([*args, "--mixtures", "R4_S4"]) == 0
    doc = json.loads((tmp_path / "o" / "seed0" / "R4_S4" / "annotations.json").read_text())
    boxed = {a["image_id"] for a in doc["annotations"]}
    real = [i for i in doc["images"] if i["source"].startswith("real:")]
    assert len(real) == 4 and not boxed & {i["id"] for i in real}


def test_a_settings_file_names_the_mixtures_and_the_flags_override_it(pools, tmp_path: Path, capsys) -> None:
    real, synth = _split_pools(pools, tmp_path)
    (tmp_path / "m.yaml").write_text("mixtures: [R5_S5, R10_S0]\nseeds: [1]\nimages: copy\n")
    args = ["mix", str(tmp_path / "m.yaml"), "--real", str(real), "--synth", str(synth)]
    assert main([*args, "--print-config", "--seeds", "2-3"]) == 0  # no --out needed to print
    assert "seeds: [2, 3]" in capsys.readouterr().out
    assert main([*args, "--out", str(tmp_path / "o")]) == 0
    made = sorted(p.relative_to(tmp_path / "o").as_posix() for p in (tmp_path / "o").glob("*/*"))
    assert made == ["seed1/R10_S0", "seed1/R5_S5"]
    manifest = json.loads((tmp_path / "o" / "seed1" / "R5_S5" / "manifest.json").read_text())
    recorded = manifest["args"]
    assert recorded["images"] == "copy" and recorded["mixtures"] == ["R5_S5", "R10_S0"] and recorded["seed"] == 1
    assert recorded["real"] == str(real) and not any(k.startswith("alias_") or k == "set" for k in recorded)
    images = [p for p in (tmp_path / "o" / "seed1" / "R5_S5" / "images").rglob("*") if p.suffix]
    assert len(images) == 10 and not any(p.is_symlink() for p in images)  # images: copy
