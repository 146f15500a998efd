"""``fuzzyfire convert | validate | stats | merge`` (curate/cli/dataset.py)."""

import json

import pytest
from factories import write_yolo_dataset

from fuzzyfire.cli import main


def test_convert_yolo_to_coco(tmp_path, capsys):
    write_yolo_dataset(tmp_path / "src")
    assert main(["convert", str(tmp_path / "src"), "--to", "coco", "--out", str(tmp_path / "out")]) == 0
    assert "4 images, 3 boxes, 2 negatives" in capsys.readouterr().out
    doc = json.loads((tmp_path / "out" / "annotations.json").read_text())
    assert len(doc["images"]) == 4
    man = json.loads((tmp_path / "out" / "manifest.json").read_text())
    assert "func" not in man["args"] and man["args"]["to"] == "coco"
    assert main(["convert", str(tmp_path / "src"), "--to", "coco", "--out", str(tmp_path / "out")]) == 2
    assert "--overwrite" in capsys.readouterr().err


def test_convert_drop_class_and_alias(tmp_path, capsys):
    write_yolo_dataset(tmp_path / "src", names=("flame_big", "default"))
    code = main(
        [
            "convert",
            str(tmp_path / "src"),
            "--to",
            "coco",
            "--out",
            str(tmp_path / "o"),
            "--alias",
            "flame_big=fire",
            "--drop-class",
            "default",
        ]
    )
    assert code == 0
    doc = json.loads((tmp_path / "o" / "annotations.json").read_text())
    assert [c["name"] for c in doc["categories"]] == ["fire"] and len(doc["annotations"]) == 2
    assert "not a known class" not in capsys.readouterr().err  # the user dropped it: no warning


def test_validate_exit_codes_and_json(tmp_path, capsys):
    write_yolo_dataset(tmp_path / "ok")
    assert main(["validate", str(tmp_path / "ok")]) == 0
    out = capsys.readouterr().out
    assert out.strip().endswith("d.png: image without label file (kept as a negative)")
    (tmp_path / "ok" / "train" / "labels" / "b.txt").write_text("5 0.5 0.5 0.1 0.1\n")
    assert main(["validate", str(tmp_path / "ok"), "--json"]) == 1
    doc = json.loads(capsys.readouterr().out)
    assert doc["counts"]["error"] == 1 and "class id 5 out of range" in doc["problems"][0]["reason"]


def test_stats_json_and_png(tmp_path, capsys):
    write_yolo_dataset(tmp_path / "ds")
    assert main(["stats", str(tmp_path / "ds"), "--json", "--png", str(tmp_path / "h.png")]) == 0
    assert json.loads(capsys.readouterr().out)["boxes"] == 3 and (tmp_path / "h.png").is_file()


def test_missing_source_is_a_clear_error(tmp_path, capsys):
    assert main(["convert", str(tmp_path / "nope"), "--to", "coco", "--out", str(tmp_path / "o")]) == 2
    assert "no such file or folder" in capsys.readouterr().err


@pytest.mark.shared_data
def test_convert_fire_cctv_416(shared_data, tmp_path, capsys):
    assert main(["convert", str(shared_data / "fire-cctv-416"), "--to", "all", "--out", str(tmp_path / "c")]) == 0
    doc = json.loads((tmp_path / "c" / "annotations.json").read_text())
    assert len(doc["images"]) == 3996
    assert len(list((tmp_path / "c" / "labels").rglob("*.txt"))) == 3996


def test_an_ultralytics_data_yaml_is_its_dataset_in_every_command(tmp_path, capsys):
    import yaml
    from factories import write_image

    from eval.config import TestSetConfig
    from eval.score import load_test_set

    root = tmp_path / "ds"
    for split, n in (("train", 3), ("val", 2)):
        for k in range(n):
            write_image(root / "images" / split / f"{split}{k}.jpg", 32, 24, seed=k)
            (root / "labels" / split).mkdir(parents=True, exist_ok=True)
            (root / "labels" / split / f"{split}{k}.txt").write_text("0 0.5 0.5 0.5 0.5\n")
    data_yaml = root / "data.yaml"
    data_yaml.write_text(
        yaml.safe_dump({"path": str(root), "train": "images/train", "val": "images/val", "names": ["fire"]})
    )
    assert main(["stats", str(data_yaml), "--json"]) == 0
    stats = json.loads(capsys.readouterr().out)
    assert stats["images"] == 5 and set(stats["per_split"]) == {"train", "val"}
    assert main(["validate", str(data_yaml)]) == 0
    assert main(["convert", str(data_yaml), "--to", "coco", "--out", str(tmp_path / "c")]) == 0
    test = load_test_set(data_yaml, TestSetConfig(split="valid"))  # valid and val are one name
    assert test.split == "val" and len(test.dataset.images) == 2
    assert load_test_set(data_yaml).split == "val"  # no test split: the validation split, never train


def test_merge_command(tmp_path, capsys):
    write_yolo_dataset(tmp_path / "data" / "a")
    (tmp_path / "m.yaml").write_text("classes: [fire, smoke]\nsources:\n  - path: data/a\n    name: first\n")
    assert main(["merge", str(tmp_path / "m.yaml"), "--out", str(tmp_path / "out")]) == 0
    doc = json.loads((tmp_path / "out" / "annotations.json").read_text())
    assert len(doc["images"]) == 4 and (tmp_path / "out" / "data.yaml").is_file()
    assert main(["merge", str(tmp_path / "m.yaml"), "--out", str(tmp_path / "o2"), "--set", "classes=fire"]) == 2
    assert "classes: expected a list" in capsys.readouterr().err


@pytest.mark.parametrize("command", ["convert", "validate", "stats"])
@pytest.mark.parametrize(("flag", "value"), [("--drop-class", "defualt"), ("--alias", "Flames=fire")])
def test_a_class_the_data_lacks_is_an_error_listing_its_classes_before_any_work(tmp_path, capsys, command, flag, value):
    """A mistyped --drop-class, or an --alias of a class the data lacks: one line, nothing written."""
    write_yolo_dataset(tmp_path / "src", names=("fire", "default"))
    out = ["--to", "coco", "--out", str(tmp_path / "o")] if command == "convert" else []
    assert main([command, str(tmp_path / "src"), *out, flag, value]) == 2
    err = capsys.readouterr().err
    name = value.partition("=")[0]
    assert err.count("\n") == 1 and f"{flag} {name!r}: no such class (classes: 'fire', 'default')" in err
    assert not (tmp_path / "o").exists()
    if flag == "--alias":
        assert main([command, str(tmp_path / "src"), *out, "--alias", "DEFAULT=fire"]) == 0  # any spelling of a class


def test_validate_honours_drop_class_as_stats_does(tmp_path, capsys):
    write_yolo_dataset(tmp_path / "src", names=("fire", "default"))
    assert main(["validate", str(tmp_path / "src"), "--drop-class", "default", "--json"]) == 0
    doc = json.loads(capsys.readouterr().out)
    assert main(["stats", str(tmp_path / "src"), "--drop-class", "default", "--json"]) == 0
    stats = json.loads(capsys.readouterr().out)
    assert (doc["boxes"], doc["negatives"]) == (stats["boxes"], stats["negatives"]) == (2, 2)
    assert not any("not a known class" in p["reason"] for p in doc["problems"])
    with pytest.raises(SystemExit):  # validate shows no source tag: --source is not offered
        main(["validate", str(tmp_path / "src"), "--source", "real:x"])


@pytest.mark.parametrize("fmt", [[], ["--from", "yolo"], ["--from", "images"]])
def test_a_folder_of_images_without_labels_is_a_negatives_only_set(tmp_path, capsys, fmt):
    from factories import write_image

    for k in range(3):
        write_image(tmp_path / "photos" / f"p{k}.jpg", 40, 30, seed=k)
    assert main(["validate", str(tmp_path / "photos"), *fmt]) == 0
    captured = capsys.readouterr()
    assert captured.out == f"{tmp_path / 'photos'}: 3 images, no label files: a negatives-only set\n"
    assert "0 errors, 0 warnings, 1 info" in captured.err
    assert main(["stats", str(tmp_path / "photos"), *fmt]) == 0
    out = capsys.readouterr().out
    assert "images     3  (negatives 3: 3 without a label file" in out
    assert "set        3 images, no label files: a negatives-only set" in out


def test_an_empty_folder_is_named_as_such(tmp_path, capsys):
    (tmp_path / "empty").mkdir()
    assert main(["validate", str(tmp_path / "empty")]) == 2
    assert "empty: no images, labels or annotations found" in capsys.readouterr().err
