"""score(): test-set loading (splits, errors) and unreadable images left out of the metrics."""

from __future__ import annotations

import dataclasses

import pytest
from detector_factories import oracle_model, write_test_set

from eval.config import TestSetConfig
from eval.onnx_model import OnnxDetector
from eval.score import ScoreError, load_test_set, score, write_outputs


@pytest.fixture(scope="module")
def work(tmp_path_factory):
    root = tmp_path_factory.mktemp("scorefn")
    return root, write_test_set(root / "test"), OnnxDetector(oracle_model(root / "m.onnx"))


def test_split_selection(work):
    _, test, _ = work
    ds, problems, split, splits = load_test_set(test, TestSetConfig(split="test"))
    assert len(ds.images) == 6 and problems == [] and split == "test" and splits == ["test"]
    with pytest.raises(ScoreError, match="no split 'valid'"):
        load_test_set(test, TestSetConfig(split="valid"))


def test_default_split_is_test_then_val_never_train_silently(tmp_path):
    from eval.score import default_split
    from ground.data.dataset import DatasetBuilder

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


def test_metrics_are_pycocotools_numbers_on_the_records_written(work):
    """score() reports what pycocotools computes from the records it writes (the oracle's boxes, jittered
    copies and noise at several scores, so AP is neither 0 nor 1)."""
    import contextlib
    import io

    import numpy as np
    from pycocotools.coco import COCO
    from pycocotools.cocoeval import COCOeval

    from ground.detect.cocoeval import LOOSE_IOU, evaluate_predictions
    from ground.detect.detections import ImageDetections

    _, test, det = work
    ds = load_test_set(test).dataset
    result = score(det, ds)
    rng = np.random.default_rng(0)
    noisy = {}
    for image_id, d in result.predictions.by_image.items():
        extra = rng.uniform(0, 40, (6, 4)) + np.array([0, 0, 20, 20])
        boxes = np.concatenate([d.boxes, d.boxes + rng.normal(0, 4, d.boxes.shape), np.cumsum(extra, axis=1)])
        scores = np.concatenate([d.scores, d.scores * 0.9, np.full(6, 0.3)])  # ties among the noise
        labels = np.concatenate([d.labels, d.labels, rng.integers(0, 2, 6)])
        order = np.argsort(-scores, kind="stable")
        noisy[image_id] = ImageDetections(boxes[order], scores[order], labels[order])
    preds = dataclasses.replace(result.predictions, by_image=noisy)
    metrics, _, records = evaluate_predictions(ds, preds)
    doc = ds.to_coco()
    anns = [{**r, "id": i, "area": r["bbox"][2] * r["bbox"][3], "iscrowd": 0} for i, r in enumerate(records, 1)]
    refs = []
    for thresholds in (None, [LOOSE_IOU]):
        gt, dt = COCO(), COCO()
        gt.dataset, dt.dataset = doc, {"images": doc["images"], "categories": doc["categories"], "annotations": anns}
        with contextlib.redirect_stdout(io.StringIO()):
            gt.createIndex()
            dt.createIndex()
            ref = COCOeval(gt, dt, "bbox")
            ref.params.catIds = sorted({r["category_id"] for r in records})
            if thresholds:
                ref.params.iouThrs = np.asarray(thresholds)
            ref.evaluate()
            ref.accumulate()
            ref.summarize()
        refs.append(ref)
    names = ("AP", "AP50", "AP75", "AP_small", "AP_medium", "AP_large")
    for name, value in zip(names, refs[0].stats):
        assert (metrics.summary[name] is None and value == -1) or metrics.summary[name] == pytest.approx(
            value, abs=1e-6
        )
    assert metrics.summary["AP25"] == pytest.approx(refs[1].stats[0], abs=1e-6)
    assert 0.1 < metrics.summary["AP"] < 0.99
    for k, cat in enumerate(refs[0].params.catIds):
        name = next(c.name for c in ds.categories if c.id == cat)
        precision = refs[0].eval["precision"][:, :, k, 0, -1]
        assert metrics.per_class[name]["AP"] == pytest.approx(precision[precision > -1].mean(), abs=1e-6)


def test_records_are_built_from_the_evaluated_detections(work):
    from ground.detect.cocoeval import evaluate_predictions

    _, test, det = work
    ds = load_test_set(test).dataset
    result = score(det, ds)
    assert result.records == evaluate_predictions(ds, result.predictions)[2]
    assert len(result.records) == result.metrics.detections == len(result.detections) > 0
