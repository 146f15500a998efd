import pytest
from factories import write_yolo_dataset

from curate.sources import MergeConfig, SourceConfig, merge_sources


def test_merge_two_sources(tmp_path):
    write_yolo_dataset(tmp_path / "a")
    write_yolo_dataset(tmp_path / "b", names=("Flame", "default"))
    cfg = MergeConfig(
        sources=(
            SourceConfig(path=tmp_path / "a", name="A"),
            SourceConfig(path=tmp_path / "b", name="B", drop_classes=("default",)),
        ),
        classes=("fire", "smoke"),
    )
    ds, problems = merge_sources(cfg, tmp_path, tmp_path / "out")
    assert len(ds.images) == 8 and ds.category_names == ["fire", "smoke"]
    assert {i.source for i in ds.images} == {"real:A", "real:B"}
    assert len(ds.annotations) == 3 + 2


def test_unlisted_class_is_an_error(tmp_path):
    write_yolo_dataset(tmp_path / "b", names=("fire", "default"))
    cfg = MergeConfig(sources=(SourceConfig(path=tmp_path / "b"),), classes=("fire",))
    with pytest.raises(ValueError, match=r"classes \['default'\] are not in classes"):
        merge_sources(cfg, tmp_path, tmp_path / "out")


def test_without_classes_the_sources_classes_are_merged_known_first(tmp_path):
    write_yolo_dataset(tmp_path / "a", names=("Smoke", "Flame"))
    write_yolo_dataset(tmp_path / "b", names=("fire", "default"))
    cfg = MergeConfig(sources=(SourceConfig(path=tmp_path / "a"), SourceConfig(path=tmp_path / "b")))
    ds, _ = merge_sources(cfg, tmp_path, tmp_path / "out")
    assert ds.category_names == ["fire", "smoke", "default"]  # Flame is fire by synonym: one class with b's fire
    assert sum(1 for a in ds.annotations if a.category_id == 1) == 3
