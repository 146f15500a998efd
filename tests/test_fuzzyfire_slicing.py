"""The study's slices: attributes computed once per test set (and the user's added), a run's image hits and
loose matches derived once from its predictions, the slice table as valid CSV, and no AP50 per slice on a set
too small for AP."""

from __future__ import annotations

import csv
import io
import json
from pathlib import Path

import cv2
import numpy as np

from eval.imagelevel import IMAGELEVEL
from fuzzyfire.datasets import DataRef
from fuzzyfire.slicing import run_hits, run_matches25, set_attributes, slices_csv, study_slices
from ground.data.dataset import DatasetBuilder


class Loader:
    """``Datasets.get`` of one dataset; counts the reads."""

    def __init__(self, ds) -> None:
        self.ds, self.reads = ds, 0

    def get(self, ref):
        self.reads += 1
        return self.ds


def _night_and_day(root: Path, n: int = 40):
    """``n`` images with one fire box each, the first half dark (night), the rest bright (day)."""
    b = DatasetBuilder(root, ["fire"])
    for i in range(n):
        pixels = np.full((60, 80, 3), 20 if i < n // 2 else 200, np.uint8)
        pixels[10:40, 10:40] = (250, 90, 10)
        cv2.imwrite(str(root / f"{i}.png"), pixels[:, :, ::-1])
        b.add_box(b.add_image(f"{i}.png", 80, 60), "fire", [10, 10, 30, 30])
    return b.build()


def _scores(folder: Path, ds, find_night: bool, seed: int) -> Path:
    rng = np.random.default_rng(seed)
    records = [{"image_id": img.id, "category_id": 1, "bbox": [10, 10, 30, 30], "score": 0.5 + 0.4 * rng.random()}
               for k, img in enumerate(ds.images) if find_night or k >= len(ds.images) // 2]  # fmt: skip
    folder.mkdir(parents=True)
    (folder / "predictions.json").write_text(json.dumps(records), encoding="utf-8")
    return folder


def test_attributes_are_kept_and_the_users_added(tmp_path: Path) -> None:
    ds = _night_and_day(tmp_path)
    loader = Loader(ds)
    ref = DataRef(tmp_path, {"kind": "x"})
    first = set_attributes(loader, ref, tmp_path / "out")  # type: ignore[arg-type]
    assert first[ds.images[0].id]["light"] == "night" and first[ds.images[-1].id]["light"] == "day"
    (tmp_path / "0.png").unlink()  # kept: not read again
    assert set_attributes(loader, ref, tmp_path / "out") == first  # type: ignore[arg-type]
    mine = tmp_path / "mine.csv"
    mine.write_text("image,attribute,value\n1.png,camera,north\n", encoding="utf-8")
    given = set_attributes(loader, ref, tmp_path / "out", mine)  # type: ignore[arg-type]
    assert given[ds.images[1].id]["camera"] == "north" and given[ds.images[2].id]["camera"] is None


def test_a_runs_views_are_derived_once_and_again_when_scored_again(tmp_path: Path) -> None:
    ds = _night_and_day(tmp_path)
    loader = Loader(ds)
    folder = _scores(tmp_path / "run" / "common", ds, False, 0)
    hits = run_hits(loader, folder, None)  # type: ignore[arg-type]
    loose = run_matches25(loader, folder, None)  # type: ignore[arg-type]
    assert hits.recall(0.0) == 0.5 and loader.reads == 2 and loose.ap()["AP50"] < 1.0
    again = run_hits(loader, folder, None)  # type: ignore[arg-type]
    assert loader.reads == 2 and np.array_equal(again.best, hits.best) and np.array_equal(again.fire, hits.fire)
    run_matches25(loader, folder, None)  # type: ignore[arg-type]
    assert loader.reads == 2
    _scores(tmp_path / "run2" / "common", ds, True, 0)
    (folder / "predictions.json").write_bytes((tmp_path / "run2" / "common" / "predictions.json").read_bytes())
    assert run_hits(loader, folder, None).recall(0.0) == 1.0 and loader.reads == 3  # type: ignore[arg-type]


def _study_rows(tmp_path: Path, ds, ap50: float | None) -> list[dict]:
    rows = []
    for mixture, find_night in (("R200_S0", False), ("R200_S200", True)):
        for seed in (0, 1):
            folder = _scores(tmp_path / mixture / f"seed{seed}" / "common", ds, find_night, seed)
            from eval.stats import MatchTable
            from ground.detect.cocoeval import run_cocoeval

            records = json.loads((folder / "predictions.json").read_text())
            MatchTable(run_cocoeval(ds, records, [1])).save(folder / "matches.npz")
            hits = run_hits(Loader(ds), folder, None)  # type: ignore[arg-type]
            rows.append({"mixture": mixture, "seed": seed, "test_set": "common", "tables": ["table2"], "AP50": ap50,
                         "matches": (folder / "matches.npz").as_posix(), IMAGELEVEL: (hits, 0.25)})  # fmt: skip
    return rows


def test_study_slices_find_the_night_fires_and_write_valid_csv(tmp_path: Path) -> None:
    ds = _night_and_day(tmp_path)
    rows = _study_rows(tmp_path, ds, 0.5)
    pairs = [("table2", "R200_S0", "R200_S0", "R200_S200")]
    sliced, sets = study_slices(rows, pairs, {"common": DataRef(tmp_path, {"kind": "x"})}, Loader(ds), tmp_path / "out",  # type: ignore[arg-type]
                                np.random.default_rng(0), 200)  # fmt: skip
    assert [s["slice"] for s in sets["common"]] == ["light=night", "light=day", "sky=no sky", "sky=sky"][
        : len(sets["common"])
    ]
    helped = {(r["slice"], r["metric"]) for r in sliced if r["verdict"] == "helps"}
    assert ("light=night", "image_recall") in helped and ("light=night", "AP50") in helped
    assert not any(r["slice"] == "light=day" and r["verdict"] != "-" for r in sliced)
    merged = [{**sliced[0], "slice": "size=small,medium"}]  # a merged slice's name holds a comma
    parsed = list(csv.DictReader(io.StringIO(slices_csv(merged))))
    assert parsed[0]["slice"] == "size=small,medium" and parsed[0]["verdict"] == sliced[0]["verdict"]


def test_a_set_too_small_for_ap_has_no_ap50_per_slice(tmp_path: Path) -> None:
    ds = _night_and_day(tmp_path)
    rows = _study_rows(tmp_path, ds, None)  # its rows carry no AP50: too few fire images for AP
    pairs = [("table2", "R200_S0", "R200_S0", "R200_S200")]
    sliced, _ = study_slices(rows, pairs, {"common": DataRef(tmp_path, {"kind": "x"})}, Loader(ds), tmp_path / "out",  # type: ignore[arg-type]
                             np.random.default_rng(0), 100)  # fmt: skip
    assert sliced and {r["metric"] for r in sliced} == {"AP25", "image_recall"}


def test_an_image_labelled_set_is_sliced_by_image_recall_on_its_whole_photos(tmp_path: Path) -> None:
    """Photos labelled fire per image (no boxes): slices by what needs no box (light, colour over the whole photo),
    image recall only, and no run's loose matches are derived (no box to match)."""
    from dataclasses import replace

    from eval.imagelevel import IMAGE_LABELLED, image_hits

    boxed = _night_and_day(tmp_path)
    ds = replace(boxed, annotations=(), images=tuple(replace(i, labels=("fire",)) for i in boxed.images))

    def hits(r: dict):
        return image_hits(ds, json.loads((Path(r["matches"]).parent / "predictions.json").read_text()), [1])

    rows = [{**r, "test_set": "photos", IMAGE_LABELLED: True, "AP50": None, IMAGELEVEL: (hits(r), 0.25)}
            for r in _study_rows(tmp_path, boxed, None)]  # fmt: skip
    for r in rows:  # the labelled set's own hits: every photo is a fire photo
        assert r[IMAGELEVEL][0].fire.all()
    pairs = [("table2", "R200_S0", "R200_S0", "R200_S200")]
    sliced, sets = study_slices(rows, pairs, {"photos": DataRef(tmp_path, {"kind": "y"})}, Loader(ds), tmp_path / "out",  # type: ignore[arg-type]
                                np.random.default_rng(0), 200)  # fmt: skip
    assert {r["metric"] for r in sliced} == {"image_recall"} and not list(tmp_path.rglob("matches25.json"))
    assert ("light=night", "helps") in {(r["slice"], r["verdict"]) for r in sliced}
    assert not any(s["slice"].startswith("size=") for s in sets["photos"])
    attrs = set_attributes(Loader(ds), DataRef(tmp_path, {"kind": "y"}), tmp_path / "out")  # type: ignore[arg-type]
    assert all(a["colour"] is not None and a["size"] is None for a in attrs.values())  # read over the whole photo
