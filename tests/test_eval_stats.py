"""Seed statistics and the image-level bootstrap: parity with pycocotools, determinism, paired deltas."""

from __future__ import annotations

import numpy as np
import pytest

from eval.stats import MatchTable, bootstrap_ap, mean_std, paired_bootstrap, resample_weights
from ground.data.dataset import DatasetBuilder
from ground.detect.cocoeval import run_cocoeval


def test_mean_std_is_the_sample_std():
    m = mean_std([0.40, 0.42, 0.44])
    assert m.mean == pytest.approx(0.42) and m.std == pytest.approx(0.02) and m.n == 3
    assert m.format() == "42.0 ± 2.0"
    single = mean_std([0.5])
    assert single.std is None and single.format() == "50.0"
    with pytest.raises(ValueError):
        mean_std([])


def make_case(tmp_path, seed: int, images: int = 40, copies: np.ndarray | None = None):
    """A random test set (2 classes, negatives, a crowd box) and noisy detections as COCO records.
    ``copies[i]`` repeats image i that many times (new ids), as a bootstrap resample would."""
    rng = np.random.default_rng(seed)
    copies = np.ones(images, dtype=int) if copies is None else copies
    scenes = []
    for _ in range(images):
        boxes = [(rng.integers(0, 2), rng.uniform(0, 60, 2), rng.uniform(8, 40, 2)) for _ in range(rng.integers(0, 4))]
        dets = []
        for cls, xy, wh in boxes:
            if rng.random() < 0.8:
                dets.append((cls, xy + rng.normal(0, 3, 2), wh * rng.uniform(0.8, 1.2, 2), rng.random()))
        for _ in range(rng.integers(0, 3)):  # false positives
            dets.append((rng.integers(0, 2), rng.uniform(0, 60, 2), rng.uniform(8, 40, 2), rng.random() * 0.7))
        if len(scenes) == 3:  # a crowd box with a detection on it: ignored, neither TP nor FP
            boxes.append((0, np.array([50.0, 50.0]), np.array([30.0, 30.0])))
            dets.append((0, np.array([52.0, 51.0]), np.array([28.0, 29.0]), 0.6))
        scenes.append((boxes, dets))
    b = DatasetBuilder(tmp_path, ["fire", "smoke"])
    records = []
    for i, (boxes, dets) in enumerate(scenes):
        for _ in range(copies[i]):
            image_id = b.add_image(f"{i}.jpg", 100, 100)
            for j, (cls, xy, wh) in enumerate(boxes):
                b.add_box(image_id, ("fire", "smoke")[cls], (*xy, *wh), iscrowd=int(i == 3 and j == len(boxes) - 1))
            for cls, xy, wh, score in dets:
                records.append({"image_id": image_id, "category_id": int(cls) + 1, "bbox": [*xy, *wh], "score": score})
    return b.build(), records


@pytest.mark.parametrize("seed", [0, 1])
def test_unit_weights_reproduce_pycocotools_exactly(tmp_path, seed):
    ds, records = make_case(tmp_path, seed)
    ev = run_cocoeval(ds, records, [1, 2])
    table = MatchTable(ev)
    np.testing.assert_array_equal(table.precision(), ev.eval["precision"][:, :, :, 0, -1])
    assert table.ap() == {"AP": ev.stats[0], "AP50": ev.stats[1]}


def test_a_class_table_gives_that_class_ap_as_pycocotools_does(tmp_path):
    ds, records = make_case(tmp_path, 3)
    ev = run_cocoeval(ds, records, [1, 2])
    table = MatchTable(ev)
    for k in range(2):
        alone = table.of_class(k)
        assert alone.cat_ids == [k + 1] and np.array_equal(alone.image_ids, table.image_ids)
        np.testing.assert_array_equal(alone.precision()[:, :, 0], ev.eval["precision"][:, :, k, 0, -1])
    weights = np.random.default_rng(0).integers(0, 3, len(table.image_ids))
    both = table.precision(weights)
    np.testing.assert_array_equal(np.concatenate([table.of_class(k).precision(weights) for k in range(2)], 2), both)


def accumulate_every_pair(table: MatchTable, w: np.ndarray) -> np.ndarray:
    """(T, R, K) precision the way pycocotools accumulates it: cumulative TP/FP over every (threshold,
    detection) pair, precision made monotone from the right, read at the recall thresholds."""
    out = -np.ones((table.classes[0].tp.shape[0], len(table.rec_thrs), len(table.classes)))
    for k, cm in enumerate(table.classes):
        npig = float(w @ cm.npig)
        if npig == 0:
            continue
        wd = w[cm.image]
        tp, fp = np.cumsum(cm.tp * wd, axis=1), np.cumsum(cm.fp * wd, axis=1)
        pr = np.maximum.accumulate((tp / (tp + fp + np.spacing(1)))[:, ::-1], axis=1)[:, ::-1]
        for t in range(tp.shape[0]):
            idx = np.searchsorted(tp[t] / npig, table.rec_thrs, side="left")
            out[t, :, k] = np.where(idx < len(wd), pr[t, np.minimum(idx, max(len(wd) - 1, 0))], 0.0)
    return out


@pytest.mark.parametrize("seed", [0, 5])
def test_true_positive_accumulation_equals_every_pair(tmp_path, seed):
    """The re-accumulation that reads precision at true positives only is exactly the all-pairs one, for weights
    with zeros and repeats, ignored detections (the crowd box) and classes left without ground truth."""
    ds, records = make_case(tmp_path, seed=seed, images=60)
    table = MatchTable(run_cocoeval(ds, records, [1, 2]))
    assert any((cm.tp | cm.fp).sum() < cm.tp.size for cm in table.classes)  # some detections are ignored
    rng = np.random.default_rng(seed)
    weights = [*resample_weights(60, 30, rng), np.zeros(60), (np.arange(60) < 3).astype(float)]
    for w in weights:
        np.testing.assert_array_equal(table.precision(w), accumulate_every_pair(table, np.asarray(w, float)))


def test_weights_equal_pycocotools_on_the_resampled_set(tmp_path):
    copies = resample_weights(40, 1, np.random.default_rng(7))[0]
    assert copies.max() >= 2 and copies.min() == 0
    ds, records = make_case(tmp_path, seed=3)
    table = MatchTable(run_cocoeval(ds, records, [1, 2]))
    ds2, records2 = make_case(tmp_path, seed=3, copies=copies)
    ev2 = run_cocoeval(ds2, records2, [1, 2])
    got = table.ap(copies)
    assert got["AP"] == pytest.approx(ev2.stats[0], abs=1e-12) and got["AP50"] == pytest.approx(ev2.stats[1], abs=1e-12)


def test_bootstrap_is_deterministic_and_contains_the_point(tmp_path):
    ds, records = make_case(tmp_path, seed=5, images=200)
    table = MatchTable(run_cocoeval(ds, records, [1, 2]))
    ci = bootstrap_ap(table, np.random.default_rng(0), num_samples=1000)
    again = bootstrap_ap(table, np.random.default_rng(0), num_samples=1000)
    other = bootstrap_ap(table, np.random.default_rng(1), num_samples=1000)
    for key in ("AP", "AP50"):
        assert ci[key].low < ci[key].point < ci[key].high
        np.testing.assert_array_equal(ci[key].samples, again[key].samples)
        assert not np.array_equal(ci[key].samples, other[key].samples)
    assert ci["AP"].high - ci["AP"].low > 0.01


def test_paired_bootstrap_of_a_model_with_itself_is_zero(tmp_path):
    ds, records = make_case(tmp_path, seed=2)
    table = MatchTable(run_cocoeval(ds, records, [1, 2]))
    same = paired_bootstrap(table, table, np.random.default_rng(0), num_samples=200)
    for delta in same.values():
        assert delta.interval.point == 0 and delta.interval.low == delta.interval.high == 0 and delta.p_value == 1.0


def test_paired_bootstrap_sees_a_better_model(tmp_path):
    ds, records = make_case(tmp_path, seed=4, images=80)
    noisy = MatchTable(run_cocoeval(ds, records, [1, 2]))
    gt = [
        {"image_id": a.image_id, "category_id": a.category_id, "bbox": list(a.bbox), "score": 0.9}
        for a in ds.annotations
    ]
    perfect = MatchTable(run_cocoeval(ds, gt, [1, 2]))
    delta = paired_bootstrap(noisy, perfect, np.random.default_rng(0), num_samples=300)["AP"]
    assert delta.interval.point > 0 and delta.interval.low > 0 and delta.p_value < 0.01
    small, _ = make_case(tmp_path, seed=4, images=10)
    with pytest.raises(ValueError, match="same test images"):
        paired_bootstrap(noisy, MatchTable(run_cocoeval(small, [], [1, 2])), np.random.default_rng(0))


def test_save_and_load_round_trip(tmp_path):
    ds, records = make_case(tmp_path, seed=6)
    table = MatchTable(run_cocoeval(ds, records, [1, 2]))
    loaded = MatchTable.load(table.save(tmp_path / "m.npz"))
    w = resample_weights(40, 1, np.random.default_rng(0))[0]
    assert loaded.ap(w) == table.ap(w) and loaded.cat_ids == [1, 2]


def test_paired_bootstrap_averages_several_seeds(tmp_path):
    ds, records = make_case(tmp_path, seed=8, images=60)
    rng = np.random.default_rng(1)
    worse = [r | {"score": r["score"] * rng.uniform(0.5, 1.0)} for r in records]
    a = [MatchTable(run_cocoeval(ds, records, [1, 2])), MatchTable(run_cocoeval(ds, worse, [1, 2]))]
    both = paired_bootstrap(a, a[::-1], np.random.default_rng(0), num_samples=100)["AP"]
    assert both.interval.point == pytest.approx(0.0, abs=1e-12) and both.p_value == 1.0
    one = paired_bootstrap(a[0], a[1], np.random.default_rng(0), num_samples=100)["AP"]
    assert one.interval.point == pytest.approx(a[1].ap()["AP"] - a[0].ap()["AP"])


def test_seeds_that_disagree_in_sign_widen_the_two_level_interval(tmp_path):
    """Three seeds per side: seed 0 and 1 of b beat a by a wide margin, seed 2 loses by more. Resampling images
    alone averages the seeds in every draw (a tight interval around their mean); resampling the seeds too draws
    resamples where the losing seed weighs more, so the interval is wider and says so."""
    ds, records = make_case(tmp_path, seed=10, images=60)
    gt = [{"image_id": a.image_id, "category_id": a.category_id, "bbox": list(a.bbox), "score": 0.9}
          for a in ds.annotations]  # fmt: skip
    none = [r | {"bbox": [r["bbox"][0] + 500, r["bbox"][1], *r["bbox"][2:]]} for r in records]  # all misses
    noisy, perfect, blind = (MatchTable(run_cocoeval(ds, r, [1, 2])) for r in (records, gt, none))
    a, b = [noisy, noisy, perfect], [perfect, perfect, blind]
    images = paired_bootstrap(a, b, np.random.default_rng(0), num_samples=300)["AP50"]
    both = paired_bootstrap(a, b, np.random.default_rng(0), num_samples=300, seeds=True)["AP50"]
    assert images.resampled == "images" and both.resampled == "images and seeds"
    assert both.interval.point == images.interval.point  # the same runs, the same point
    assert both.interval.high - both.interval.low > 3 * (images.interval.high - images.interval.low)
    assert both.interval.low < 0 < both.interval.high  # a sign the seeds do not agree on is not settled
    two = paired_bootstrap(a[:2], b[:2], np.random.default_rng(0), num_samples=50, seeds=True)["AP50"]
    assert two.resampled == "images"  # fewer than MIN_SEEDS_RESAMPLED seeds: images only, and it says so
