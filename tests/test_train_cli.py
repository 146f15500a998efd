"""``fuzzyfire train`` end to end on a tiny painted dataset (COCO folders written by curate)."""

from __future__ import annotations

import json
from pathlib import Path

import pytest
from factories_train import painted_dataset

from fuzzyfire.cli import main
from ground.data.writer import write_dataset


@pytest.fixture(scope="module")
def folders(tmp_path_factory: pytest.TempPathFactory) -> tuple[Path, Path]:
    base = tmp_path_factory.mktemp("cli")
    write_dataset(painted_dataset(base / "src_train", 8, seed=0), base / "train", ("coco",), "copy")
    write_dataset(painted_dataset(base / "src_val", 4, seed=1), base / "val", ("coco",), "copy")
    return base / "train", base / "val"


def test_train_command_writes_a_run(folders, tmp_path: Path, capsys) -> None:
    train, val = folders
    args = ["train", "--train", str(train), "--val", str(val), "--out", str(tmp_path / "run")]
    assert main([*args, "--epochs", "1", "--imgsz", "64", "--batch", "4", "--seed", "1"]) == 0
    out = capsys.readouterr().out
    assert "best epoch 1" in out and "best.onnx" in out
    results = json.loads((tmp_path / "run" / "results.json").read_text())
    assert results["config"]["imgsz"] == 64 and (tmp_path / "run" / "best.onnx").is_file()
    assert results["best"]["epoch"] == 1  # the epoch the console names, counted the same way


def test_bad_arguments_are_errors(folders, tmp_path: Path) -> None:
    train, _ = folders
    same = ["train", "--train", str(train), "--val", str(train), "--out", str(tmp_path / "r")]
    assert main(same) == 2  # same images for training and validation
    assert main([*same[:4], str(folders[1]), "--out", str(tmp_path / "r"), "--imgsz", "100"]) == 2


def test_a_missing_val_entry_of_data_yaml_is_named_when_train_falls_back(tmp_path: Path, capsys) -> None:
    """data.yaml's val: names no folder: the refusal to validate on the training images names the file and key."""
    from factories import write_image

    root = tmp_path / "ds"
    for k in range(2):
        write_image(root / "images" / "train" / f"i{k}.jpg", 40, 30, seed=k)
        (root / "labels" / "train").mkdir(parents=True, exist_ok=True)
        (root / "labels" / "train" / f"i{k}.txt").write_text("0 0.5 0.5 0.5 0.5\n")
    (root / "data.yaml").write_text("path: .\ntrain: images/train\nval: images/val\nnames: [fire]\n")
    assert main(["train", "--train", str(root), "--val", str(root), "--out", str(tmp_path / "run")]) == 2
    err = capsys.readouterr().err
    assert f"{root / 'data.yaml'}: val: 'images/val' (no {root / 'images' / 'val'}) is not a folder" in err
    assert not (tmp_path / "run").exists()


def test_device_flag(folders, tmp_path: Path, capsys) -> None:
    import torch

    train, val = folders
    args = ["train", "--train", str(train), "--val", str(val), "--epochs", "1", "--imgsz", "64", "--batch", "4"]
    assert main([*args, "--out", str(tmp_path / "cpu"), "--device", "cpu", "--backbone", "cspdarknet"]) == 0
    assert json.loads((tmp_path / "cpu" / "results.json").read_text())["device"] == "cpu"
    capsys.readouterr()
    assert main([*args, "--out", str(tmp_path / "bad"), "--device", "gpu0"]) == 2
    assert "expected auto | cpu | cuda | cuda:N" in capsys.readouterr().err
    if not torch.cuda.is_available():
        assert main([*args, "--out", str(tmp_path / "cuda"), "--device", "cuda"]) == 2
        err = capsys.readouterr().err.strip()
        assert "no CUDA GPU is available" in err and len(err.splitlines()) == 1
        assert not (tmp_path / "cuda").exists()


@pytest.mark.parametrize(
    ("extra", "message"),
    [
        (["--drop-class", "smok"], "--drop-class 'smok': no such class (classes: 'fire', 'smoke')"),
        (["--classes", "fire,smok"], "--classes 'smok': no such class (classes: 'fire', 'smoke')"),
        (["--val-split", "valid"], "no split 'valid' (no splits: its 4 images are one set)"),
    ],
)
def test_a_name_that_matches_nothing_fails_before_training(folders, tmp_path: Path, capsys, extra, message) -> None:
    train, val = folders
    argv = ["train", "--train", str(train), "--val", str(val), "--out", str(tmp_path / "run"), *extra]
    assert main(argv) == 2
    assert message in capsys.readouterr().err and not (tmp_path / "run").exists()


ROW = "0 0.5 0.5 0.4 0.4\n"


def _flawed_yolo(root: Path) -> Path:
    """A YOLO folder (train/valid) whose training labels hold one box outside its image (an error: dropped) and
    one reaching outside it (clipped, a warning)."""
    from factories import write_image

    for split, rows in (("train", "0 0.5 0.5 0.4 0.4\n0 1.5 1.5 0.2 0.2\n0 0.9 0.5 0.4 0.4\n"), ("valid", ROW)):
        write_image(root / split / "images" / "a.jpg", 40, 30)
        (root / split / "labels").mkdir(parents=True)
        (root / split / "labels" / "a.txt").write_text(rows)
    (root / "classes.txt").write_text("fire\n")
    return root


def test_data_with_errors_is_refused_in_one_line_before_training(tmp_path: Path, capsys, monkeypatch) -> None:
    import train.loop

    root = _flawed_yolo(tmp_path / "ds")
    argv = ["train", "--train", str(root), "--val", str(root), "--out", str(tmp_path / "run")]
    assert main(argv) == 2
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1 and err.startswith(f"error: train: 1 validation error in {root} (")
    assert "lies outside the 40x30 image (dropped)" in err
    assert err.endswith("; fix the data or pass --allow-errors (train key allow_errors) to train anyway")
    assert not (tmp_path / "run").exists()

    def fake_fit(cfg, train_ds, val_ds, out):
        assert cfg.allow_errors and len(train_ds.annotations) == 2  # the dropped box left out, the clipped one kept
        return {"selected": {"epoch": 1, "AP": 0.0, "AP50": 0.0, "fitness": 0.0}, "onnx": "best.onnx"}

    monkeypatch.setattr(train.loop, "fit", fake_fit)
    assert main([*argv, "--allow-errors"]) == 0
    out, err = capsys.readouterr()
    assert err.strip().startswith(f"train: 1 validation error in {root} (") and len(err.splitlines()) == 1
    assert err.strip().endswith(": training anyway (allow_errors)")
    assert f"; 1 box in {root} reached outside its image and was clipped to it" in out.splitlines()[0]
    assert main(["train", "--allow-errors", "--print-config"]) == 0
    assert "allow_errors: true" in capsys.readouterr().out
