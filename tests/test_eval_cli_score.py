"""``fuzzyfire score`` end to end on real ONNX models: letterbox, decode, NMS, back-mapping, pycocotools."""

from __future__ import annotations

import contextlib
import io
import json

import pytest
from detector_factories import IMAGES, NAMES, layout_and_two_detectors, oracle_model, rows_for, write_test_set
from pycocotools.coco import COCO
from pycocotools.cocoeval import COCOeval

from fuzzyfire.cli import main
from ground.data.holdout import held_out


@pytest.fixture(scope="module")
def work(tmp_path_factory):
    root = tmp_path_factory.mktemp("score")
    return {"root": root, "test": write_test_set(root / "test")}


def run_json(*argv: str) -> dict:
    out = io.StringIO()
    with contextlib.redirect_stdout(out):
        assert main(["score", *map(str, argv), "--json"]) == 0
    return json.loads(out.getvalue())


@pytest.mark.parametrize(
    "kwargs",
    [
        {"layout": "yolov5"},
        {"layout": "yolov8", "metadata": {"names": "{0: 'fire', 1: 'smoke'}", "imgsz": "[64, 64]"}},
        {"layout": "yolov5", "batch": 1},
        {"layout": "yolov5", "metadata": {"names": '["fire", "smoke"]', "imgsz": "[64, 64]", "producer": "fuzzyfire"}},
        {"layout": "yolov8", "dynamic_size": True, "metadata": {"names": "['Fire', 'Smoke']", "imgsz": "64"}},
    ],
    ids=["yolov5", "yolov8", "fixed-batch-1", "fuzzyfire", "dynamic-size"],
)
def test_ground_truth_model_scores_ap_1_with_negatives(work, kwargs):
    model = oracle_model(work["root"] / f"m{len(list(work['root'].glob('*.onnx')))}.onnx", **kwargs)
    doc = run_json(model, "--data", work["test"], "--batch", 3)
    assert doc["AP"] == pytest.approx(1.0) and doc["AP50"] == pytest.approx(1.0)
    assert doc["images"] == len(IMAGES) == 6
    assert doc["boxes"] == sum(len(i.boxes) for i in IMAGES)
    assert doc["detections"] == doc["boxes"]  # NMS removed every duplicate, negatives got nothing
    assert {k: v["AP"] for k, v in doc["per_class"].items()} == {
        "fire": pytest.approx(1.0),
        "smoke": pytest.approx(1.0),
    }
    assert [doc[k] for k in ("AP_small", "AP_medium", "AP_large")] == pytest.approx([1.0, 1.0, 1.0])


def test_without_nms_the_duplicates_cost_ap(work):
    model = oracle_model(work["root"] / "dups.onnx")
    doc = run_json(model, "--data", work["test"], "--iou", 1.0)
    assert doc["detections"] > doc["boxes"]
    assert doc["AP"] < 0.95


def test_shifted_boxes_give_the_ap_pycocotools_computes(work, tmp_path):
    shift = 3.0  # letterboxed pixels to the right
    model = oracle_model(work["root"] / "shifted.onnx", rows=rows_for(shift=shift, duplicates=False))
    doc = run_json(model, "--data", work["test"], "--format", "yolov5")  # (1, 6, 7) fits both layouts
    gt = COCO(str(work["test"] / "annotations.json"))
    ids = {img["file_name"].split("/")[-1][:-4]: img["id"] for img in gt.dataset["images"]}
    score, results = 0.95, []
    for img in IMAGES:
        for cls, (x, y, w, h) in img.boxes:  # shift mapped to original pixels by hand
            box = [x + shift / img.scale[0], y, w, h]
            results.append(
                {"image_id": ids[img.name], "category_id": NAMES.index(cls) + 1, "bbox": box, "score": score}
            )
            score -= 0.05
    ev = COCOeval(gt, gt.loadRes(results), "bbox")
    ev.evaluate(), ev.accumulate(), ev.summarize()
    assert 0.0 < ev.stats[0] < 1.0
    assert doc["AP"] == pytest.approx(ev.stats[0], abs=1e-9)
    assert doc["AP50"] == pytest.approx(ev.stats[1], abs=1e-9)


def test_out_writes_predictions_metrics_and_pr_curve(work, tmp_path):
    model = oracle_model(work["root"] / "out.onnx")
    assert main(["score", str(model), "--data", str(work["test"]), "--out", str(tmp_path / "o")]) == 0
    preds = json.loads((tmp_path / "o" / "predictions.json").read_text())
    assert len(preds) == 6 and {"image_id", "category_id", "bbox", "score"} <= set(preds[0])
    assert json.loads((tmp_path / "o" / "metrics.json").read_text())["AP"] == pytest.approx(1.0)
    assert (tmp_path / "o" / "pr_curve.png").read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"


def test_text_output_lists_classes(work, capsys):
    model = oracle_model(work["root"] / "text.onnx")
    assert main(["score", str(model), "--data", str(work["test"])]) == 0
    out = capsys.readouterr().out
    assert "AP 1.000" in out and "smoke" in out and "2 negatives" in out


def test_bad_model_is_a_clear_error(work, tmp_path, capsys):
    bad = tmp_path / "broken.onnx"
    bad.write_bytes(b"not a model")
    assert main(["score", str(bad), "--data", str(work["test"])]) == 2
    assert "broken.onnx: onnxruntime cannot load it" in capsys.readouterr().err
    assert main(["score", str(tmp_path / "missing.onnx"), "--data", str(work["test"])]) == 2
    assert "missing.onnx: file not found" in capsys.readouterr().err


def test_model_without_names_asks_for_them(work, capsys):
    model = oracle_model(work["root"] / "nonames.onnx", metadata={})
    assert main(["score", str(model), "--data", str(work["test"])]) == 2
    assert "--names" in capsys.readouterr().err
    assert run_json(model, "--data", work["test"], "--names", "fire,smoke")["AP"] == pytest.approx(1.0)


def test_help_shows_an_example(capsys):
    with pytest.raises(SystemExit):
        main(["score", "--help"])
    assert "example:" in capsys.readouterr().out


def test_bootstrap_interval_is_deterministic_and_brackets_ap(work):
    model = oracle_model(work["root"] / "ci.onnx", rows=rows_for(shift=3.0, duplicates=False))
    args = (model, "--data", work["test"], "--format", "yolov5", "--ci", 200, "--seed", 3)
    doc, again = run_json(*args), run_json(*args)
    ci = doc["AP_ci"]
    assert ci == again["AP_ci"] and ci["samples"] == 200 and ci["value"] == doc["AP"]
    assert ci["low"] <= doc["AP"] <= ci["high"] and ci["low"] < ci["high"]


def test_test_set_aliases_drops_and_matches_file(work, tmp_path):
    from eval.stats import MatchTable

    model = oracle_model(work["root"] / "alias.onnx")
    doc = run_json(model, "--data", work["test"], "--drop-class", "smoke", "--out", tmp_path / "o")
    assert list(doc["per_class"]) == ["fire"] and doc["negatives"] == 2  # "wide" keeps its fire box
    assert MatchTable.load(tmp_path / "o" / "matches.npz").ap()["AP"] == pytest.approx(doc["AP"])
    merged = run_json(model, "--data", work["test"], "--alias", "smoke=fire")
    assert merged["per_class"]["fire"]["boxes"] == 6 and merged["classes"]["not_in_test"] == ["smoke"]


def test_errors_breakdown_from_the_cli(work, tmp_path):
    model = oracle_model(work["root"] / "errs.onnx")
    doc = run_json(model, "--data", work["test"], "--errors", "--out", tmp_path / "o")
    errors = doc["errors"]
    assert errors["AP50"] == pytest.approx(doc["AP50"])  # the breakdown's AP50 is the scored AP50
    assert set(errors["delta_AP50"]) == {"classification", "localisation", "both", "duplicate", "background", "missed"}
    assert all(v == pytest.approx(0.0) for v in errors["delta_AP50"].values())  # the oracle makes no error
    assert errors["negatives"] >= 1 and errors["false_alarms_per_100_negatives"] == 0.0
    found = doc["boxes_found"]  # the oracle finds every box at the alarm threshold
    assert found["outcomes"]["found"] == found["boxes"] > 0 and found["conf"] == errors["alarm_conf"]
    assert json.loads((tmp_path / "o" / "errors.json").read_text()) == {**errors, "boxes_found": found}


def test_a_mistyped_test_set_class_is_an_error_before_scoring(work, capsys):
    model = oracle_model(work["root"] / "typo.onnx")
    assert main(["score", str(model), "--data", str(work["test"]), "--drop-class", "smok"]) == 2
    captured = capsys.readouterr()
    assert "--drop-class 'smok': no such class (classes: 'fire', 'smoke')" in captured.err and not captured.out


def test_the_scored_split_is_named_as_the_dataset_names_it(work, tmp_path, capsys):
    from factories import write_yolo_dataset

    model = oracle_model(work["root"] / "names.onnx")
    write_yolo_dataset(tmp_path / "ds")
    assert main(["score", str(model), "--data", str(tmp_path / "ds"), "--split", "val"]) == 0
    assert "\ndata   split valid: 2 images (2 negatives)" in capsys.readouterr().out
    assert main(["score", str(model), "--data", str(work["test"])]) == 0
    assert "\ndata   split test: 6 images" in capsys.readouterr().out
    assert main(["score", str(model), "--data", str(tmp_path / "ds"), "--split", "all"]) == 0
    assert "\ndata   all splits: 4 images" in capsys.readouterr().out


def test_holdout_scores_only_the_photos_held_out_by_content(work, tmp_path, capsys):
    from factories import write_image

    model = oracle_model(work["root"] / "held.onnx")
    photos = [write_image(tmp_path / "photos" / f"p{k}.jpg", 64, 48, seed=k) for k in range(10)]
    kept = sum(held_out(p, 0.5) for p in photos)
    assert 0 < kept < 10
    args = ["score", str(model), "--data", str(tmp_path / "photos"), "--errors"]
    assert main([*args, "--holdout", "0.5"]) == 0
    assert (
        f"data   every image (no splits), held out at 0.5: {kept} images ({kept} negatives)" in capsys.readouterr().out
    )
    assert main([*args, "--holdout", "0.5", "--json"]) == 0
    doc = json.loads(capsys.readouterr().out)
    assert doc["images"] == kept and doc["holdout"] == 0.5
    assert main([*args, "--holdout", "1e-9"]) == 2
    assert "none of its 10 images is held out at share 1e-09" in capsys.readouterr().err
    assert main([*args, "--holdout", "2"]) == 2
    assert "data.holdout must be in [0, 1], got 2.0" in capsys.readouterr().err


def test_a_folder_of_images_without_labels_is_scored_as_negatives(work, tmp_path, capsys):
    from factories import write_image

    model = oracle_model(work["root"] / "negatives.onnx")
    for k in range(3):
        write_image(tmp_path / "photos" / f"p{k}.jpg", 64, 48, seed=k)
    assert main(["score", str(model), "--data", str(tmp_path / "photos"), "--errors"]) == 0
    captured = capsys.readouterr()
    assert "photos: 3 images, no label files: a negatives-only set" in captured.err
    assert "data   every image (no splits): 3 images (3 negatives), 0 boxes" in captured.out
    assert "per 100 images without fire (0% of the 3 such images raise one)" in captured.out


def test_errors_out_draws_the_worst_false_alarms_and_misses(work, tmp_path):
    from detector_factories import to_input_cxcywh

    from eval.draw import GROUND_TRUTH, PREDICTION
    from ground.image.imageio import read_image

    imgs = {i.name: i for i in IMAGES}
    missed_box = imgs["big"].boxes[1][1]  # (70, 72, 40, 40): its row left out
    rows = [r for r in rows_for(duplicates=False) if r[1] != to_input_cxcywh(imgs["big"], missed_box)]
    alarm = (5, 5, 20, 30)
    rows.append((imgs["neg1"].grey, to_input_cxcywh(imgs["neg1"], alarm), 0, 0.66))
    model = oracle_model(work["root"] / "planted.onnx", rows=rows)
    out = tmp_path / "o"
    assert (
        main(["score", str(model), "--data", str(work["test"]), "--format", "yolov5", "--errors", "--out", str(out)])
        == 0
    )
    index = json.loads((out / "errors" / "index.json").read_text())
    assert [(e["picture"], e["kind"], e["bbox"]) for e in index] == [
        ("false_alarm_01_neg1.png", "false_alarm", list(alarm)),
        ("missed_01_big.png", "missed", list(missed_box)),
    ]
    assert index[0]["score"] == pytest.approx(0.66) and index[0]["iou"] == 0.0
    assert sorted(p.name for p in (out / "errors").iterdir()) == [
        "false_alarm_01_neg1.png",
        "index.json",
        "missed_01_big.png",
    ]
    for entry, colour in zip(index, (PREDICTION, GROUND_TRUTH)):
        original = read_image(work["test"] / entry["file_name"])
        picture = read_image(out / "errors" / entry["picture"])
        k = picture.shape[0] // original.shape[0]
        assert k > 1 and picture.shape[:2] == (k * original.shape[0], k * original.shape[1])  # enlarged, whole factor
        x, y, w, h = (k * int(v) for v in entry["bbox"])
        assert tuple(picture[y + h - 1, x + w // 2]) == colour  # the box's bottom edge, in its colour
        assert tuple(picture[y + h // 2, x + w // 2]) == tuple(original[0, 0])  # its inside untouched


@pytest.fixture(scope="module")
def photos(tmp_path_factory):
    """A classification layout and two detectors (:func:`detector_factories.layout_and_two_detectors`)."""
    return layout_and_two_detectors(tmp_path_factory.mktemp("photos"))


def test_score_reads_a_classification_layout_and_a_declared_folder_by_image_recall(photos, capsys):
    """A detector that fires on half the fire photos gets image recall 0.5, AP is undefined; the layout and the
    declared folder say what they were read as; the same folder undeclared is negatives only."""
    for argv in (["--data", photos["layout"]], ["--data", photos["layout"] / "fire", "--label", "fire"]):
        doc = run_json(photos["a"], *argv)
        level = doc["image_level"]
        assert doc["AP"] is None and doc["AP50"] is None and doc["boxes"] == 0
        assert (level["fire_images"], level["recall_at_conf"]) == (4, 0.5)
    assert level["free_images"] == 0 and level["budget_recall"] is None
    err = capsys.readouterr().err
    assert "classification layout: fire/ 4 images (fire), normal/ 2 images (no class)" in err
    assert "4 images, each declared 'fire' (label: fire): an image-labelled set" in err
    assert main(["score", str(photos["b"]), "--data", str(photos["layout"])]) == 0
    out = capsys.readouterr().out
    assert "3 of 4 images holding fire detected at confidence >= 0.25: image recall 0.750" in out
    assert "1 of its 2 images without fire raise an alarm" in out
    undeclared = run_json(photos["a"], "--data", photos["layout"] / "fire")
    assert "image_level" not in undeclared and "a negatives-only set" in capsys.readouterr().err


def test_settings_from_a_file_under_the_flags_and_data_required_unless_printed(work, tmp_path, capsys):
    import yaml

    model = oracle_model(work["root"] / "settings.onnx")
    assert main(["score", str(model)]) == 2
    assert "--data is required (unless --print-config)" in capsys.readouterr().err
    settings = tmp_path / "score.yaml"
    settings.write_text("inference: {postprocess: {iou: 1.0}}\nmodel: {format: yolov5}\n")
    assert main(["score", str(model), "--config", str(settings), "--batch", "3", "--print-config"]) == 0
    printed = yaml.safe_load(capsys.readouterr().out)
    assert printed["inference"]["postprocess"] == {"conf": 0.001, "iou": 1.0, "max_det": 300}
    assert (printed["inference"]["batch"], printed["model"]["format"]) == (3, "yolov5")
    (tmp_path / "printed.yaml").write_text(yaml.safe_dump(printed))
    via_file = run_json(model, "--data", work["test"], "--config", tmp_path / "printed.yaml")
    assert via_file == run_json(model, "--data", work["test"], "--iou", 1.0, "--batch", 3, "--format", "yolov5")
    assert via_file["detections"] > via_file["boxes"]  # without NMS (IoU 1.0), as test_without_nms_...
