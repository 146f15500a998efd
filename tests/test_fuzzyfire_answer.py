"""The answer's sentences come from the numbers: best mixture per set, each comparison with its interval and
verdict, the slices kept by Holm's correction, the alarms, and caveats."""

from __future__ import annotations

from fuzzyfire.answer import answer, headline_metric


def _rows() -> list[dict]:
    rows = []
    for seed, (base, mixed) in enumerate(((0.28, 0.31), (0.30, 0.33))):
        for mixture, ap50 in (("R200_S0", base), ("R200_S200", mixed)):
            rows.append({"mixture": mixture, "seed": seed, "test_set": "common", "AP50": ap50, "image_recall": 0.6})
            rows.append(
                {"mixture": mixture, "seed": seed, "test_set": "rare", "AP50": None, "image_recall": 0.4 + ap50}
            )
            rows.append({"mixture": mixture, "seed": seed, "test_set": "fire-free", "AP50": None,
                         "alarms_per_100": 20.0 if mixture == "R200_S0" else 8.0})  # fmt: skip
    return rows


def _delta(value: float, low: float, high: float) -> dict:
    return {"value": value, "low": low, "high": high, "level": 0.95, "p_value": 0.01}


def test_headline_metric_is_ap50_else_image_recall_else_none() -> None:
    rows = _rows()
    assert [headline_metric(rows, t) for t in ("common", "rare", "fire-free")] == ["AP50", "image_recall", None]


def test_sentences_carry_the_numbers_and_verdicts() -> None:
    comparisons = [
        {"test_set": "common", "mixture": "R200_S200", "baseline": "R200_S0", "metric": "AP50",
         "delta": _delta(0.03, 0.005, 0.055)},
        {"test_set": "common", "mixture": "R200_S200", "baseline": "R200_S0", "metric": "image_recall",
         "delta": _delta(0.0, -0.1, 0.1)},  # not the common set's headline: not said
        {"test_set": "rare", "mixture": "R200_S200", "baseline": "R200_S0", "metric": "image_recall",
         "delta": _delta(0.03, -0.02, 0.08)},
    ]  # fmt: skip
    slices = [
        {"test_set": "common", "mixture": "R200_S200", "baseline": "R200_S0", "slice": "light=night",
         "fire_images": 25, "metric": "image_recall", "delta": _delta(0.2, 0.1, 0.3), "verdict": "helps"},
        {"test_set": "common", "mixture": "R200_S200", "baseline": "R200_S0", "slice": "light=day",
         "fire_images": 80, "metric": "image_recall", "delta": _delta(0.0, -0.1, 0.1), "verdict": "-"},
    ]  # fmt: skip
    said = answer(_rows(), comparisons, slices, ["rare: 369 leaked images dropped."])
    assert said[0] == "Best on common by AP50: R200_S200 (R200_S200 32.0 ± 1.4; R200_S0 29.0 ± 1.4)."
    assert said[1].startswith("Best on rare by image recall: R200_S200")
    assert "On common, R200_S200 against R200_S0: AP50 +3.0 [+0.5, +5.5] points, it helps." in said
    assert (
        "On rare, R200_S200 against R200_S0: image recall +3.0 [-2.0, +8.0] points, not distinguishable from 0." in said
    )
    assert not any("image recall +0.0" in s for s in said)
    assert any(s.startswith("On common, R200_S200 against R200_S0 helps on light=night (25 fire images)") for s in said)
    assert (
        "False alarms on fire-free (detections at confidence 0.25 per 100 images): R200_S0 20.0; R200_S200 8.0." in said
    )
    assert (
        any(s.startswith("Caveat: 2 seeds per mixture") for s in said)
        and said[-1] == "rare: 369 leaked images dropped."
    )


def test_no_slice_kept_is_said_too() -> None:
    slices = [
        {
            "test_set": "common",
            "mixture": "B",
            "baseline": "A",
            "slice": f"s{i}",
            "fire_images": 30,
            "metric": m,
            "delta": _delta(0, -1, 1),
            "verdict": "-",
        }
        for i in range(4)
        for m in ("AP50", "AP25")
    ]
    said = answer([], [], slices)
    assert said == ["On common, no slice separates B from A after Holm's correction (4 slices x 2 metrics)."]


def test_many_kept_slices_are_named_by_size_and_the_rest_counted() -> None:
    slices = [{"test_set": "common", "mixture": "B", "baseline": "A", "slice": f"s{i}", "fire_images": 30,
               "metric": m, "delta": _delta(-0.01 * (i + 1) * (2 if m == "AP25" else 1), -1, -0.001),
               "verdict": "hurts"} for i in range(6) for m in ("AP50", "AP25")]  # fmt: skip
    (said,) = answer([], [], slices)
    assert said.startswith("On common, B against A hurts on s5 (30 fire images) AP25 -12.0 [-100.0, -0.1]; s4 ")
    assert said.endswith("; and 2 more slices (tables/slices.csv) (Holm-corrected).") and " s1 " not in said
    (two,) = answer([], [], slices, positives="images with fire or smoke")
    assert two.startswith("On common, B against A hurts on s5 (30 images with fire or smoke) AP25 -12.0")
