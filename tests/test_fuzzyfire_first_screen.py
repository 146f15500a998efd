"""The answer's first screen: a gain is the flames' only beyond a control, "it helps" needs the interval and
every seed, runs that did not learn are not read, and each pool and class rule is said in plain words."""

from __future__ import annotations

import json
from pathlib import Path

from fuzzyfire import first_screen as fs
from ground.data.load import ClassChanges


def _cmp(mixture: str, baseline: str, value: float, low: float, high: float, seeds: list[float]) -> dict:
    return {"test_set": "common", "mixture": mixture, "baseline": baseline, "metric": "AP50",
            "delta": {"value": value, "low": low, "high": high, "p_value": 0.01, "resampled": "images and seeds"},
            "seeds": [{"seed": i, "delta": d} for i, d in enumerate(seeds)]}  # fmt: skip


def _rows(flagged: str | None = None) -> list[dict]:
    return [{"mixture": m, "seed": s, "test_set": "common", "AP50": 0.3, "learning": "x" if m == flagged else None}
            for m in ("R200_S0", "R200_S200", "R200_S200 copies") for s in range(3)]  # fmt: skip


def test_it_helps_needs_the_interval_and_every_seed() -> None:
    agree = _cmp("R200_S200", "R200_S0", 0.05, 0.02, 0.08, [0.04, 0.05, 0.06])
    split = _cmp("R200_S200", "R200_S0", 0.021, 0.002, 0.04, [0.038, 0.051, -0.027])  # the three seeds
    assert fs.verdict(agree, False) == "it helps"
    assert fs.verdict(split, False) == "the interval excludes 0 but 1 of 3 seeds disagree: not settled"
    assert fs.seeds_text(split) == "seeds agree 2 of 3 (+3.8, +5.1, -2.7)"
    assert fs.verdict(agree, True) == "not read: a run in it did not converge"
    assert fs.verdict(_cmp("B", "A", 0.01, -0.01, 0.03, [0.01] * 3), False) == "not distinguishable from 0"


def test_without_a_control_the_gain_is_worded_as_flames_and_more_images() -> None:
    c = _cmp("R200_S200", "R200_S0", 0.148, 0.127, 0.178, [0.14, 0.15, 0.16])
    (line,) = fs.headline_lines(_rows(), [c], lambda test: "AP50", "R200_S0")
    assert line.startswith("On common, 200 synthetic images (flames and more images together) against none")
    assert "No control was trained, so the share of the flames is unknown" in line and "grid.control=true" in line
    (smoke,) = fs.headline_lines(_rows(), [c], lambda test: "AP50", "R200_S0", "flames and smoke")
    assert "(flames and smoke and more images together)" in smoke and "share of the flames and smoke" in smoke
    more = _cmp("R400_S0", "R200_S0", 0.08, 0.05, 0.1, [0.07, 0.08, 0.09])  # a real-only mixture: more real images
    (line,) = fs.headline_lines(_rows(), [more], lambda test: "AP50", "R200_S0")
    assert line.startswith("On common, 200 more real images (R400_S0 vs R200_S0): AP50 +8.0") and "control" not in line
    assert fs.added_text(-100, 300) == ("300 synthetic images (flames and more images together) against none and "
                                        "100 fewer real images")  # fmt: skip


def test_with_a_control_the_flames_share_comes_first() -> None:
    c = _cmp("R200_S200", "R200_S0", 0.148, 0.127, 0.178, [0.14, 0.15, 0.16])
    ctrl = _cmp("R200_S200", "R200_S200 copies", 0.092, 0.06, 0.12, [0.08, 0.09, 0.1])
    (line,) = fs.headline_lines(_rows(), [c, ctrl], lambda test: "AP50", "R200_S0")
    assert line.startswith("On common, the flames of R200_S200 add AP50 +9.2 [+6.0, +12.0] points beyond copies of")
    assert "it helps" in line and "the copies alone (more images and steps) about +5.6" in line
    (smoke,) = fs.headline_lines(_rows(), [c, ctrl], lambda test: "AP50", "R200_S0", "flames and smoke")
    assert smoke.startswith("On common, the flames and smoke of R200_S200 add AP50 +9.2")
    (flagged,) = fs.headline_lines(_rows("R200_S200 copies"), [c, ctrl], lambda test: "AP50", "R200_S0")
    assert "not read: a run in it did not converge" in flagged


def test_a_comparison_over_other_seeds_on_each_side_says_so() -> None:
    c = {**_cmp("R200_S200", "R200_S0", 0.024, -0.026, 0.091, [0.01]), "baseline_seeds": [0], "mixture_seeds": [0, 1]}
    ctrl = {**_cmp("R200_S200", "R200_S200 copies", -0.027, -0.06, 0.004, [-0.048, -0.006]),
            "baseline_seeds": [0, 1], "mixture_seeds": [0, 1]}  # fmt: skip
    (line,) = fs.headline_lines(_rows(), [c, ctrl], lambda test: "AP50", "R200_S0")
    unequal = "(R200_S200 over seeds 0, 1; R200_S0 over seed 0: each side averaged over its own seeds)"
    assert f"the mixture reads +2.4 [-2.6, +9.1] {unequal};" in line
    assert line.count("over its own seeds") == 1  # the control's two sides hold the same seeds: nothing said
    (alone,) = fs.headline_lines(_rows(), [c], lambda test: "AP50", "R200_S0")
    assert f"AP50 +2.4 [-2.6, +9.1] points {unequal}" in alone
    assert fs.sides_text(_cmp("B", "A", 0.01, -0.01, 0.03, [0.01])) == ""  # rows that do not say: nothing


def test_each_class_of_a_two_class_set_gets_its_delta_on_the_first_screen() -> None:
    c = _cmp("R200_S200", "R200_S0", 0.03, 0.01, 0.05, [0.02, 0.03, 0.04])
    fire = {**_cmp("R200_S200", "R200_S0", 0.004, -0.02, 0.029, [0.0] * 3), "metric": "AP50 fire"}
    smoke = {**_cmp("R200_S200", "R200_S0", 0.061, 0.012, 0.11, [0.06] * 3), "metric": "AP50 smoke"}
    (line,) = fs.headline_lines(_rows(), [c, fire, smoke], lambda test: "AP50", "R200_S0")
    assert "Per class: fire +0.4 [-2.0, +2.9], smoke +6.1 [+1.2, +11.0]." in line
    ctrl = _cmp("R200_S200", "R200_S200 copies", 0.02, 0.0, 0.04, [0.02] * 3)
    smoke_ctrl = {**ctrl, "metric": "AP50 smoke", "delta": {"value": 0.05, "low": 0.01, "high": 0.09}}
    (line,) = fs.headline_lines(_rows(), [c, fire, smoke, ctrl, smoke_ctrl], lambda test: "AP50", "R200_S0")
    assert line.endswith("Per class beyond the control: smoke +5.0 [+1.0, +9.0].")  # not against R200_S0
    (line,) = fs.headline_lines(_rows(), [c], lambda test: "AP50", "R200_S0")
    assert "Per class" not in line  # one class: the set's AP50 is the class's


def test_a_pool_is_said_in_plain_words(tmp_path: Path) -> None:
    per_image = [{"photo": "a.jpg", "frame_boxes": [[0, 0, 5, 5]], "flames": [{}, {}]}] * 87
    per_image += [{"photo": "free.jpg", "flames": []}] * 113
    (tmp_path / "manifest.json").write_text(json.dumps({"args": {"per_image": per_image}}))
    said = fs.pool_sentence(tmp_path / "manifest.json", "cutouts")
    assert said == ("200 images: 87 of the real training frames with pasted flames, 113 fire-free photos as they are "
                    "(negatives); 174 cut-out flames (from the real training images)")  # fmt: skip
    plumes = [
        {"where": "above", "colour": "own"},
        {"where": "sky", "colour": "black"},
        {"where": "sky", "colour": "own"},
    ]
    per_image[0] = {**per_image[0], "plumes": plumes}
    (tmp_path / "manifest.json").write_text(json.dumps({"args": {"per_image": per_image}}))
    assert fs.pool_sentence(tmp_path / "manifest.json", "cutouts").endswith(
        "images); 3 plumes of smoke (1 above flames, 2 in the sky; 2 own, 1 black)"
    )
    lone = [{"photo": "a.jpg", "frame_boxes": [], "flames": [], "plumes": [{"where": "ground", "colour": "own"}]}] * 3
    (tmp_path / "manifest.json").write_text(json.dumps({"args": {"per_image": [*lone, {**lone[0], "plumes": []}]}}))
    assert fs.pool_sentence(tmp_path / "manifest.json", "cutouts") == (
        "4 images: 3 plumes of smoke (3 on the ground; 3 own), on 4 real training frames; no pasted flames"
    )  # a pool of plumes leads with them, and counts no flames


def test_classes_curation_and_alarm_resolution_are_said(tmp_path: Path) -> None:
    changes = {"common": ClassChanges(unstudied={"smoke": 2194}, emptied=342), "fire-free": ClassChanges()}
    said = fs.class_sentence(["fire"], True, changes)
    assert said == ("Classes studied: fire (as the config names them). common: smoke: 2,194 boxes not studied; 342 "
                    "images had only such boxes and left the set.")  # fmt: skip
    doc = {"counts": {"images": 2817, "removed_exact": 67, "removed_near": 32}, "splits": {"train": 1903, "test": 543}}
    (tmp_path / "curation.json").write_text(json.dumps(doc))
    assert fs.curation_sentence(tmp_path) == ("curation read 2,817 images, dropped 67 exact and 32 near duplicates (0 "
                                              "unreadable), split train 1,903 / test 543")  # fmt: skip
    assert fs.curation_sentence(tmp_path / "none") is None
    assert "one image = 1.5 per 100; fewer than 100" in fs.free_images_note(68)  # type: ignore[operator]
    assert "fewer than" not in fs.free_images_note(200)  # type: ignore[operator]


def test_how_sure_says_what_each_interval_resamples() -> None:
    two = _cmp("R200_S200", "R200_S0", 0.05, 0.02, 0.08, [0.04, 0.05, 0.06])
    one = {**two, "metric": "recall_at_10_alarms", "delta": {**two["delta"], "resampled": "images"}}
    said = fs.how_sure_line(_rows(), [two, one], 40)
    assert said == ("How sure: 3 seeds per mixture, 40 epochs each; the 95 % intervals resample test images and "
                    "seeds (a two-level paired bootstrap); recall@10 alarms/100: test images only.")  # fmt: skip
    only = fs.how_sure_line(_rows(), [one], 1)
    assert "1 epoch each" in only and "test images only (paired bootstrap): with fewer than 3 seeds" in only
    short = [r for r in _rows() if not (r["mixture"] == "R200_S200 copies" and r["seed"] == 2)]
    assert fs.how_sure_line(short, [two], 40).startswith("How sure: 3 seeds per mixture (R200_S200 copies 2 only), 40")


def test_runs_that_did_not_converge_are_told_to_train_longer_than_they_did() -> None:
    assert fs.unlearned_line(_rows(), 40) is None
    said = fs.unlearned_line(_rows("R200_S200"), 40)
    assert said == ("Caveat first: 3 of 9 runs did not converge (R200_S200 seed 0 x); their figures are not results "
                    "and no verdict is drawn from them: train longer (train.epochs, e.g. SET=\"train.epochs=60\").")  # fmt: skip
    assert [fs.longer(e) for e in (1, 5, 7, 40, 100)] == [10, 10, 20, 60, 150]


def test_runs_that_detect_nothing_are_named() -> None:
    rows = [{"mixture": "R200_S0", "seed": s, "silent": s == 0} for s in range(2)]
    assert fs.silent_line(rows) == ("1 run detects nothing at confidence 0.25 on any test set (R200_S0 seed 0): its "
                                    "false alarms are shown as not measured (–), not as 0.")  # fmt: skip
    assert fs.silent_line([{**r, "silent": False} for r in rows]) is None


def test_the_answer_names_what_the_pool_pastes() -> None:
    from synth.method2 import Method2Config
    from synth.smoke.library import SmokeConfig

    plumes = SmokeConfig(alone=1.0)
    shipped = Method2Config(own_frames=1.0, photo_negatives=1.0, smoke=plumes)
    no_flames = Method2Config(own_frames=1.0, negatives=1.0, smoke=plumes)  # plumes without flames
    photos_only = Method2Config(backgrounds=(Path("photos"),), negatives=1.0, photo_negatives=0.5)
    assert fs.pool_words(shipped.lays_flames, shipped.smoke.plumes) == "flames and smoke"
    assert fs.pool_words(no_flames.lays_flames, no_flames.smoke.plumes) == "smoke"
    assert photos_only.lays_flames and not Method2Config(own_frames=1.0, negatives=1.0).lays_flames
    assert fs.pool_words(True, False) == "flames" and fs.pool_words(False, False) == "images"
