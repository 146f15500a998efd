"""The dedup job's pieces: JSON document content and the --apply materialisation."""

from __future__ import annotations

from pathlib import Path

import pytest
from curate_helpers import save, scene, transformed, use_session_cache

from curate.dedupjob import apply_selection, dedup_document, dedup_options, run_dedup, unreadable_summary
from curate.embed import load_embedder
from curate.scan import list_image_files
from curate.settings import RankConfig
from ground.data.problems import Problem


def test_document_counts_and_selection(tmp_path: Path, tmp_path_factory: pytest.TempPathFactory) -> None:
    use_session_cache(tmp_path_factory)
    for i in range(5):
        save(scene(40 + i), tmp_path / "in" / f"x{i}.jpg")
    save(transformed(scene(40), "crop"), tmp_path / "in" / "x0_crop.jpg")
    opts = dedup_options(rank=RankConfig("kcenter", top=2))
    run = run_dedup(list_image_files([tmp_path / "in"]), load_embedder(), None, opts)
    doc = dedup_document(run, opts, [str(tmp_path / "in")])
    assert doc["counts"] == {
        "images": 6,
        "kept": 5,
        "removed_exact": 0,
        "removed_near": 1,
        "groups": 1,
        "unreadable": 0,
        "from_cache": 0,
    }
    assert [Path(r["path"]).name for r in doc["removed"]] == ["x0_crop.jpg"]
    assert len(doc["selected"]) == 2 and set(doc["selected"]) <= set(doc["kept"])
    assert {r["path"] for r in doc["ranking"]} == set(doc["kept"])


def test_apply_copies_below_root_name_and_refuses_unsafe_targets(tmp_path: Path) -> None:
    src = tmp_path / "photos"
    a = save(scene(1), src / "a.jpg")
    b = save(scene(2), src / "deep" / "b.jpg")
    assert apply_selection([str(a), str(b)], [src], tmp_path / "to", "copy") == 2
    assert (tmp_path / "to" / "photos" / "deep" / "b.jpg").read_bytes() == b.read_bytes()
    assert apply_selection([str(a)], [src], tmp_path / "linked", "link") == 1
    with pytest.raises(ValueError, match="not empty"):
        apply_selection([str(a)], [src], tmp_path / "to", "copy")
    with pytest.raises(ValueError, match="inside an input"):
        apply_selection([str(a)], [src], src / "out", "copy")
    with pytest.raises(ValueError, match="unknown apply mode"):
        apply_selection([str(a)], [src], tmp_path / "x", "move")
    assert a.is_file() and b.is_file()


def test_a_report_group_shows_its_kept_images_first_and_its_totals() -> None:
    from curate.dedupjob import REPORT_GROUP_IMAGES, _report_group

    chain = [4, 7, 9]  # 7 like 4 and like 9, 4 unlike 9: both ends kept
    assert _report_group(chain, {7: "near"}) == ("3 images: 2 kept, 1 removed", [4, 9, 7])
    big = list(range(128))
    heading, shown = _report_group(big, {i: "near" for i in big if i % 40})
    assert heading == "128 images: 4 kept, 124 removed (showing 12 of 128)"
    assert shown[:4] == [0, 40, 80, 120] and len(shown) == REPORT_GROUP_IMAGES


def test_the_summary_names_the_first_unreadable_files_and_counts_the_rest() -> None:
    problems = [Problem(f"/data/x{k}.jpg", "truncated JPEG") for k in range(5)]
    assert unreadable_summary(problems[:2]) == "2 unreadable (x0.jpg, x1.jpg)"
    assert unreadable_summary(problems) == "5 unreadable (x0.jpg, x1.jpg, x2.jpg and 2 more)"
    assert unreadable_summary([]) == "0 unreadable"
