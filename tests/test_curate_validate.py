from factories import write_yolo_dataset

from curate.validate import validate


def test_truncated_image_found_only_by_full_decode(tmp_path):
    write_yolo_dataset(tmp_path / "ds")
    img = tmp_path / "ds" / "train" / "images" / "a.jpg"
    data = img.read_bytes()
    img.write_bytes(data[: len(data) * 2 // 3])  # header intact, tail gone
    _, header_only = validate(tmp_path / "ds", decode=False)
    assert not any(p.level == "error" for p in header_only)
    ds, problems = validate(tmp_path / "ds")
    assert [str(p) for p in problems if p.level == "error"] == [
        f"{img}: unreadable image: truncated JPEG (no end-of-image marker)"
    ]
    assert [p.level for p in problems] == sorted((p.level for p in problems), key=["error", "warning", "info"].index)
    assert len(ds.images) == 4


def test_clean_dataset_has_no_errors(tmp_path):
    write_yolo_dataset(tmp_path / "ds")
    _, problems = validate(tmp_path / "ds")
    assert [p.level for p in problems] == ["info"]
