import contextlib
import io
import json

import pytest
from factories import write_image, write_yolo_dataset
from pycocotools.coco import COCO
from pycocotools.cocoeval import COCOeval

from ground.data.formats.coco import read_coco
from ground.data.formats.yolo import read_yolo
from ground.data.writer import write_dataset


def _evaluate(gt_file, detections):
    with contextlib.redirect_stdout(io.StringIO()):
        gt = COCO(str(gt_file))
        dt = gt.loadRes(detections) if detections else COCO()
        ev = COCOeval(gt, dt, "bbox")
        ev.evaluate()
        ev.accumulate()
        ev.summarize()
    return ev.stats


def test_pycocotools_gives_ap_1_on_ground_truth_with_negatives(tmp_path):
    write_yolo_dataset(tmp_path / "src")
    ds = read_yolo(tmp_path / "src").dataset
    write_dataset(ds, tmp_path / "out", ["coco"])
    doc = json.loads((tmp_path / "out" / "annotations.json").read_text())
    assert min(a["id"] for a in doc["annotations"]) == 1
    assert len(doc["images"]) == 4  # negatives kept
    dets = [
        {"image_id": a["image_id"], "category_id": a["category_id"], "bbox": a["bbox"], "score": 1.0}
        for a in doc["annotations"]
    ]
    stats = _evaluate(tmp_path / "out" / "annotations.json", dets)
    assert stats[0] == pytest.approx(1.0) and stats[1] == pytest.approx(1.0)


def test_false_positive_on_a_negative_image_lowers_ap(tmp_path):
    write_yolo_dataset(tmp_path / "src")
    write_dataset(read_yolo(tmp_path / "src").dataset, tmp_path / "out", ["coco"])
    doc = json.loads((tmp_path / "out" / "annotations.json").read_text())
    negative = next(i["id"] for i in doc["images"] if i["id"] not in {a["image_id"] for a in doc["annotations"]})
    dets = [
        {"image_id": a["image_id"], "category_id": a["category_id"], "bbox": a["bbox"], "score": 0.5}
        for a in doc["annotations"]
    ]
    dets.append({"image_id": negative, "category_id": 1, "bbox": [0, 0, 10, 10], "score": 0.9})
    assert _evaluate(tmp_path / "out" / "annotations.json", dets)[1] < 1.0


def test_reads_foreign_coco_with_zero_ids_and_reports_problems(tmp_path):
    write_image(tmp_path / "imgs" / "p.jpg", 50, 40)
    write_image(tmp_path / "imgs" / "q.jpg", 20, 20)
    doc = {
        "images": [
            {"id": 0, "file_name": "p.jpg", "width": 50, "height": 40},
            {"id": 1, "file_name": "q.jpg", "width": 21, "height": 20},
            {"id": 2, "file_name": "missing.jpg", "width": 5, "height": 5},
        ],
        "annotations": [
            {"id": 0, "image_id": 0, "category_id": 0, "bbox": [1, 2, 3, 4], "iscrowd": 0},
            {"id": 1, "image_id": 0, "category_id": 5, "bbox": [1, 2, 3, 4]},
            {"id": 2, "image_id": 9, "category_id": 0, "bbox": [1, 2, 3, 4]},
            {"id": 3, "image_id": 1, "category_id": 1, "bbox": [10, 10, 20, 20]},
            {"id": 4, "image_id": 1, "category_id": 1, "bbox": [1, 1, float("nan"), 2]},
        ],
        "categories": [{"id": 0, "name": "Fire"}, {"id": 1, "name": "smoke"}],
    }
    path = tmp_path / "ann.json"
    path.write_text(json.dumps(doc))
    result = read_coco(path, image_root=tmp_path / "imgs")
    ds = result.dataset
    assert [a.id for a in ds.annotations] == [1, 2] and [i.id for i in ds.images] == [1, 2]
    assert ds.category_names == ["fire", "smoke"]
    assert ds.annotations[1].bbox == (10.0, 10.0, 10.0, 10.0)  # clipped to 20x20
    text = "\n".join(str(p) for p in result.problems)
    assert "missing.jpg: unreadable image: file not found" in text
    assert f"(file_name 'missing.jpg' of image id 2 in {path}; skipped with its boxes)" in text
    assert "category id 5 out of range" in text
    assert "unknown or unreadable image id 9" in text
    assert f"width x height 21x20 of image id 1 in {tmp_path / 'ann.json'}, but the image is 20x20" in text
    assert "NaN" in text


def test_coco_writer_is_deterministic(tmp_path):
    write_yolo_dataset(tmp_path / "src")
    ds = read_yolo(tmp_path / "src").dataset
    write_dataset(ds, tmp_path / "a", ["coco", "yolo"])
    write_dataset(ds, tmp_path / "b", ["coco", "yolo"])
    for name in ("annotations.json", "labels/train/a.txt"):
        assert (tmp_path / "a" / name).read_bytes() == (tmp_path / "b" / name).read_bytes()
    ma = json.loads((tmp_path / "a" / "manifest.json").read_text())
    mb = json.loads((tmp_path / "b" / "manifest.json").read_text())
    assert ma["images"] == mb["images"]


def test_not_coco():
    with pytest.raises(FileNotFoundError):
        read_coco("/nonexistent")


def test_invalid_json(tmp_path):
    (tmp_path / "x.json").write_text("{nope")
    with pytest.raises(ValueError, match="not valid JSON"):
        read_coco(tmp_path / "x.json")
    (tmp_path / "y.json").write_text("[1, 2]")
    with pytest.raises(ValueError, match="not a COCO"):
        read_coco(tmp_path / "y.json")
