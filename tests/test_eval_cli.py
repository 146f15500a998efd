"""``fuzzyfire score`` end to end on real ONNX models: letterbox, decode, NMS, back-mapping, pycocotools."""

from __future__ import annotations

import contextlib
import hashlib
import io
import json

import pytest
from detector_factories import IMAGES, NAMES, oracle_model, rows_for, write_test_set
from pycocotools.coco import COCO
from pycocotools.cocoeval import COCOeval

from curate.core.holdout import content_fraction, held_out
from fuzzyfire.cli import main


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


def test_compare_gives_the_paired_delta(work, capsys):
    good = oracle_model(work["root"] / "good.onnx")
    shifted = oracle_model(work["root"] / "shift.onnx", rows=rows_for(shift=3.0, duplicates=True))
    out = io.StringIO()
    with contextlib.redirect_stdout(out):
        argv = ["compare", str(good), str(shifted), "--data", str(work["test"]), "--samples", "200", "--json"]
        assert main([*argv, "--format", "yolov5"]) == 0
    doc = json.loads(out.getvalue())
    assert doc["A"]["AP"] == pytest.approx(1.0) and doc["B"]["AP"] < 1.0 and doc["images"] == 6
    assert doc["delta"]["AP"]["value"] == pytest.approx(doc["B"]["AP"] - doc["A"]["AP"])
    assert doc["delta"]["AP"]["low"] <= doc["delta"]["AP"]["value"] <= doc["delta"]["AP"]["high"] < 0
    assert doc["same_content"] == []
    copy = work["root"] / "copy-of-good.onnx"
    copy.write_bytes(good.read_bytes())
    assert main(["compare", str(good), str(copy), "--data", str(work["test"]), "--samples", "50"]) == 0
    lines = capsys.readouterr().out.splitlines()
    digest = hashlib.sha256(good.read_bytes()).hexdigest()
    assert lines[0] == (
        f"{good} and {copy} are one model (same content, sha256 {digest[:12]}…): the difference is 0 by construction"
    )  # first, then the table as always
    assert any(line.startswith("B - A  AP +0.0 points, 95% CI [+0.0, +0.0], p = 1.000") for line in lines)


def test_compare_names_the_models_both_sides_or_one_side_list_twice(tmp_path):
    from eval.cli import same_content, same_content_lines

    a0, a1, b1 = (tmp_path / n for n in ("a0.onnx", "a1.onnx", "b1.onnx"))
    a0.write_bytes(b"seed 0")
    a1.write_bytes(b"seed 1")
    b1.write_bytes(b"seed 1")  # a copy of a1
    h0, h1 = (hashlib.sha256(b).hexdigest()[:12] for b in (b"seed 0", b"seed 1"))
    same = same_content([a0, a1], [a0, b1])
    assert [(g["A"], g["B"]) for g in same] == [([str(a0)], [str(a0)]), ([str(a1)], [str(b1)])]
    assert same_content_lines(same, 2, 2) == [
        f"{a0} (A) and {a0} (B) are one model (same content, sha256 {h0}…)",
        f"{a1} (A) and {b1} (B) are one model (same content, sha256 {h1}…)",
        "A and B are the same 2 models: the difference is 0 by construction",
    ]
    assert same_content_lines(same_content([a0], [a0, b1]), 1, 2) == [
        f"{a0} (A) and {a0} (B) are one model (same content, sha256 {h0}…)"  # one shared run: no zero claimed
    ]
    assert same_content_lines(same_content([a1, b1], [a0]), 2, 1) == [
        f"A lists one model 2 times ({a1}, {b1}; same content, sha256 {h1}…): its mean counts it 2 times"
    ]


def test_compare_averages_several_runs_per_side(work, capsys):
    good = oracle_model(work["root"] / "good2.onnx")
    shifted = oracle_model(work["root"] / "shift2.onnx", rows=rows_for(shift=3.0, duplicates=True))
    data = ["--data", str(work["test"]), "--samples", "200", "--format", "yolov5"]
    assert main(["compare", str(good), str(shifted), *data, "--json"]) == 0
    single = json.loads(capsys.readouterr().out)
    assert main(["compare", f"{good},{good}", f"{good},{shifted}", *data, "--json"]) == 0
    doc = json.loads(capsys.readouterr().out)
    assert [run["model"] for run in doc["B"]["runs"]] == [str(good), str(shifted)]
    assert doc["B"]["AP"] == pytest.approx((1.0 + single["B"]["AP"]) / 2) and doc["A"]["AP"] == pytest.approx(1.0)
    assert doc["delta"]["AP"]["value"] == pytest.approx(single["delta"]["AP"]["value"] / 2)
    assert doc["delta"]["AP"]["low"] <= doc["delta"]["AP"]["value"] <= doc["delta"]["AP"]["high"] < 0
    assert main(["compare", f"{good},{good}", f"{good},{shifted}", *data]) == 0
    text = capsys.readouterr().out
    assert f"B      {shifted}  AP " in text and "B      mean of 2 runs  AP " in text


def test_compare_reads_both_models_at_the_alarm_budget_of_a_set_without_fire(work, tmp_path, capsys):
    import numpy as np
    from PIL import Image

    good = oracle_model(work["root"] / "good3.onnx")
    shifted = oracle_model(work["root"] / "shift3.onnx", rows=rows_for(shift=3.0, duplicates=True))
    for k, grey in enumerate((240, 240, 7, 7)):  # the oracles fire on the first two as on "large" (one box, 0.70)
        path = tmp_path / "photos" / f"p{k}.png"
        path.parent.mkdir(exist_ok=True)
        Image.fromarray(np.full((50, 60, 3), grey, dtype=np.uint8)).save(path)
    data = [
        "--data",
        str(work["test"]),
        "--samples",
        "100",
        "--format",
        "yolov5",
        "--negatives",
        str(tmp_path / "photos"),
    ]
    assert main(["compare", str(good), f"{good},{shifted}", *data, "--json"]) == 0
    doc = json.loads(capsys.readouterr().out)
    # 4 images without fire at 10 per 100: no alarm allowed, so the threshold lies just above 0.70 and the "large"
    # box (found at 0.70) is lost: 5 of the 6 boxes
    assert doc["negatives"]["images"] == 4 and doc["negatives"]["budget"] == 10.0
    run = doc["A"]["runs"][0]
    assert run["recall_at_10_alarms"] == pytest.approx(5 / 6) and 0.70 < run["threshold"] < 0.701
    assert doc["A"]["recall_at_10_alarms"] == pytest.approx(5 / 6)
    shifted_recall = doc["B"]["runs"][1]["recall_at_10_alarms"]
    assert doc["B"]["recall_at_10_alarms"] == pytest.approx((5 / 6 + shifted_recall) / 2)
    delta = doc["delta"]["recall_at_10_alarms"]
    assert delta["value"] == pytest.approx(doc["B"]["recall_at_10_alarms"] - 5 / 6) and delta["low"] <= delta["value"]
    assert main(["compare", str(good), str(good), *data, "--alarm-budget", "50"]) == 0  # two alarms allowed: all found
    text = capsys.readouterr().out
    assert "recall 1.000 at threshold 0.000" in text and "raises at most 50 alarms per 100 of them" in text
    assert "B - A  recall at 50 alarms/100 +0.0 points, 95% CI [+0.0, +0.0], p = 1.000" in text
    assert "of 6 images and 4 without fire" in text
    assert main(["compare", str(good), str(good), *data[:-1], str(work["test"])]) == 2  # a set with boxes
    assert "--negatives takes images without fire; 4 of its images hold a class (6 boxes)" in capsys.readouterr().err
    # held out by content: the two grey levels hash apart, so a share between them keeps one pair of photos
    fracs = sorted({content_fraction(p) for p in (tmp_path / "photos").iterdir()})
    share = 1.0 - (fracs[0] + fracs[1]) / 2
    assert main(["compare", str(good), str(good), *data, "--negatives-holdout", f"{share}", "--json"]) == 0
    held = json.loads(capsys.readouterr().out)["negatives"]
    assert held["images"] == 2 and held["holdout"] == pytest.approx(share)


def test_compare_refuses_an_empty_side(work, capsys):
    with pytest.raises(SystemExit):
        main(["compare", ",", str(work["root"] / "x.onnx"), "--data", str(work["test"])])
    assert "expected a model .onnx or a comma-separated list" in capsys.readouterr().err


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
    assert "a held-out share is in 0..1, got 2" in capsys.readouterr().err


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

    from curate.core.imageio import read_image
    from eval.draw import GROUND_TRUTH, PREDICTION

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


def test_compare_refuses_a_budget_or_resample_count_out_of_range_before_scoring(work, capsys):
    good = oracle_model(work["root"] / "good.onnx")
    for extra in (["--alarm-budget", "-3"], ["--samples", "0"]):
        assert main(["compare", str(good), str(good), "--data", str(work["test"]), *extra]) == 2
        assert "--alarm-budget must be > 0 and --samples >= 1" in capsys.readouterr().err


def test_compare_slices_finds_the_fires_one_model_misses(tmp_path, capsys):
    """40 frames, 20 at night and 20 by day; B misses every night fire (its boxes moved off them): --slices says
    B hurts at night (AP50, AP25 and image recall, Holm-corrected) and not by day, and draws the forest plot."""
    from detector_factories import TestImage, to_input_cxcywh

    night = [TestImage(f"n{i}", 200, 150, 10 + 2 * i, (0.32, 0.32), (0, 8), (("fire", (40, 30, 120, 100)),))
             for i in range(20)]  # fmt: skip
    day = [TestImage(f"d{i}", 200, 150, 150 + 4 * i, (0.32, 0.32), (0, 8), (("fire", (40, 30, 120, 100)),))
           for i in range(20)]  # fmt: skip
    test = write_test_set(tmp_path / "test", (*night, *day))

    def rows(miss_night: bool) -> list:
        return [(img.grey, to_input_cxcywh(img, img.boxes[0][1], 40.0 if miss_night and img in night else 0.0), 0,
                 0.95 - 0.01 * k) for k, img in enumerate((*night, *day))]  # fmt: skip

    a, b = oracle_model(tmp_path / "a.onnx", rows=rows(False)), oracle_model(tmp_path / "b.onnx", rows=rows(True))
    forest = tmp_path / "forest.png"
    argv = ["compare", str(a), str(b), "--data", str(test), "--samples", "200", "--format", "yolov5", "--slices"]
    assert main([*argv, "--forest", str(forest)]) == 0
    text = capsys.readouterr().out
    night_line = next(line for line in text.splitlines() if line.startswith("light=night"))
    day_line = next(line for line in text.splitlines() if line.startswith("light=day"))
    assert night_line.count("*") == 3 and "-100.0" in night_line and "*" not in day_line
    assert "B - A  image recall at confidence 0.25 -50.0 points" in text and forest.stat().st_size > 0
    assert main([*argv, "--json"]) == 0
    doc = json.loads(capsys.readouterr().out)
    verdicts = {(r["slice"], r["metric"]): r["verdict"] for r in doc["slices"] if r["attribute"] == "light"}
    assert verdicts == {("light=night", m): "hurts" for m in ("AP50", "AP25", "image_recall")} | {
        ("light=day", m): "-" for m in ("AP50", "AP25", "image_recall")
    }
    assert main(["compare", str(a), str(b), "--data", str(test), "--forest", str(forest)]) == 2  # needs --slices


@pytest.fixture(scope="module")
def photos(tmp_path_factory):
    """A classification layout (fire/: four grey levels, normal/: two) and two detectors: A fires on half the
    fire photos only, B on three fire photos and one normal photo."""
    from detector_factories import image_rows, write_class_layout

    root = tmp_path_factory.mktemp("photos")
    write_class_layout(root / "layout", (40, 80, 120, 160), (200, 240))
    return {
        "layout": root / "layout",
        "a": oracle_model(root / "a.onnx", rows=image_rows((40, 80))),
        "b": oracle_model(root / "b.onnx", rows=image_rows((40, 80, 120, 200))),
    }


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


def test_compare_on_image_labelled_sets_gives_the_image_recall_difference_only(photos, capsys):
    """No AP difference on a set without boxes; image recall at the layout's own normal photos' alarm budget (B
    alarms on one of the two: read above it, it finds nothing) or at --negatives; per side at 0.25."""
    assert main(["compare", str(photos["a"]), str(photos["b"]), "--data", str(photos["layout"]), "--samples", "50",
                 "--json"]) == 0  # fmt: skip
    doc = json.loads(capsys.readouterr().out)
    assert set(doc["delta"]) == {"image_recall"} and doc["own_negatives"] == 2
    assert doc["delta"]["image_recall"]["value"] == pytest.approx(-0.5)
    assert (doc["A"]["image_recall_at_conf"], doc["B"]["image_recall_at_conf"]) == (0.5, 0.75)
    assert main(["compare", str(photos["a"]), str(photos["b"]), "--data", str(photos["layout"] / "fire"),
                 "--label", "fire", "--negatives", str(photos["layout"] / "normal"), "--samples", "50"]) == 0  # fmt: skip
    out = capsys.readouterr().out
    assert "AP   -    AP50   -    image recall 0.500 at 0.25" in out
    assert "B - A  image recall at 10 false-alarm images/100 -50.0 points" in out and "B - A  AP" not in out
    assert main(["compare", str(photos["a"]), str(photos["b"]), "--data", str(photos["layout"] / "fire"),
                 "--label", "fire", "--samples", "50"]) == 0  # fmt: skip
    assert "B - A  image recall at confidence 0.25 +25.0 points" in capsys.readouterr().out
    assert main(["compare", str(photos["a"]), str(photos["b"]), "--data", str(photos["layout"] / "fire"),
                 "--negatives", str(photos["layout"])]) == 2  # fmt: skip
    assert "--negatives takes images without fire; 4 of its images hold a class" in capsys.readouterr().err
