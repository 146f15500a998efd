"""score(): test-set loading (splits, errors) and unreadable images left out of the metrics."""

from __future__ import annotations

import dataclasses

import pytest
from detector_factories import oracle_model, write_test_set

from eval.onnx_model import OnnxDetector
from eval.score import ScoreError, load_test_set, score, write_outputs


@pytest.fixture(scope="module")
def work(tmp_path_factory):
    root = tmp_path_factory.mktemp("scorefn")
    return root, write_test_set(root / "test"), OnnxDetector(oracle_model(root / "m.onnx"))


def test_split_selection(work):
    _, test, _ = work
    ds, problems, split, splits = load_test_set(test, split="test")
    assert len(ds.images) == 6 and problems == [] and split == "test" and splits == ["test"]
    with pytest.raises(ScoreError, match="no split 'valid'"):
        load_test_set(test, split="valid")


def test_default_split_is_test_then_val_never_train_silently(tmp_path):
    from curate.core.dataset import DatasetBuilder
    from eval.score import default_split

    def dataset(splits: tuple[str, ...]):
        builder = DatasetBuilder(tmp_path, ["fire"])
        for k, split in enumerate(splits):
            builder.add_image(f"{split}/{k}.jpg", 10, 10, "real:x", split)
        return builder.build({})

    assert default_split(dataset(("train", "valid", "test"))) == "test"
    assert default_split(dataset(("train", "valid"))) == "valid"
    assert default_split(dataset(("train", "val"))) == "val"
    assert default_split(dataset(("",))) == "all"
    with pytest.raises(ScoreError, match="no test or validation split .* --split all"):
        default_split(dataset(("train", "extra")))
    ds = dataset(("train", "valid"))
    assert ds.resolve_split("val") == "valid" and len(ds.select_split("val").images) == 1
    assert dataset(("val",)).resolve_split("valid") == "val" and ds.resolve_split("test") is None


def test_unreadable_image_is_left_out_and_reported(work, tmp_path):
    root, test, det = work
    ds = load_test_set(test).dataset
    (tmp_path / "images").mkdir()
    for img in ds.images:
        src = ds.image_path(img)
        data = src.read_bytes()
        (tmp_path / img.file_name).write_bytes(data[: len(data) // 2] if img.id == 1 else data)
    result = score(det, dataclasses.replace(ds, root=tmp_path))
    assert result.metrics.images == 5 and result.metrics.summary["AP"] == pytest.approx(1.0)
    assert [p.level for p in result.problems] == ["error"] and "wide.png" in result.problems[0].path
    files = write_outputs(result, tmp_path / "out")
    assert all(p.is_file() for p in files.values())


def test_operating_data_cover_the_images_and_classes_scored(work, tmp_path):
    import numpy as np
    from PIL import Image

    from eval.score import score_operating

    _, test, det = work
    fire = score(det, load_test_set(test).dataset)
    for k, grey in enumerate((240, 7, 7)):  # the oracle fires on grey 240 as on "large": one box at 0.70
        Image.fromarray(np.full((40, 40, 3), grey, dtype=np.uint8)).save(tmp_path / f"p{k}.png")
    (tmp_path / "p3.png").write_bytes(b"not a picture")  # unreadable: not an image without fire that was scored
    photos = load_test_set(tmp_path).dataset
    negatives = score(det, photos.with_categories(["fire", "smoke"]))
    found, alarms = score_operating(fire, negatives)
    assert found.boxes == 6 and found.recall(0.0) == pytest.approx(1.0)  # the oracle finds every box
    assert alarms.images == 3 and alarms.scores.tolist() == pytest.approx([0.70], abs=1e-6)


def test_score_settings_out_of_range_are_refused_before_any_work() -> None:
    import pytest

    from eval.score import ScoreConfig

    for bad in ({"conf": 1.0}, {"conf": -0.1}, {"iou": 0.0}, {"max_det": 0}, {"batch": 0}, {"workers": -1}):
        with pytest.raises(ValueError, match="must be"):
            ScoreConfig(**bad)
    assert ScoreConfig(conf=0.0, iou=1.0).conf == 0.0
