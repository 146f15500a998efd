from factories import write_yolo_dataset

from curate.validate import validate

ORDER = ["error", "warning", "info"]


def test_truncated_image_found_when_reading(tmp_path):
    write_yolo_dataset(tmp_path / "ds")
    img = tmp_path / "ds" / "train" / "images" / "a.jpg"
    data = img.read_bytes()
    img.write_bytes(data[: len(data) * 2 // 3])  # header intact, tail gone
    result = validate(tmp_path / "ds", decode=False)
    ds, problems = result.dataset, result.problems
    expected = [f"{img}: unreadable image: truncated JPEG (no end-of-image marker) (skipped)"]
    assert [str(p) for p in problems if p.level == "error"] == expected
    assert [p.level for p in problems] == sorted((p.level for p in problems), key=ORDER.index)
    assert len(ds.images) == 3


def test_corrupt_body_found_only_by_full_decode(tmp_path):
    write_yolo_dataset(tmp_path / "ds")
    img = tmp_path / "ds" / "train" / "images" / "b.jpg"
    data = bytearray(img.read_bytes())
    start = data.index(b"\xff\xda")  # start of scan: wipe the entropy-coded data, keep the end marker
    data[start + 4 : -2] = b"\xff" * (len(data) - start - 6)
    img.write_bytes(bytes(data))
    header_only = validate(tmp_path / "ds", decode=False).problems
    assert not any(p.level == "error" for p in header_only)
    problems = validate(tmp_path / "ds").problems
    assert [p.path for p in problems if p.level == "error"] == [str(img)]


def test_garbled_scan_data_is_an_error_naming_the_image(tmp_path):
    from factories import garbled_jpeg

    write_yolo_dataset(tmp_path / "ds")
    img = tmp_path / "ds" / "train" / "images" / "b.jpg"
    img.write_bytes(garbled_jpeg())  # OpenCV decodes it mostly grey, with only a libjpeg warning on stderr
    result = validate(tmp_path / "ds")
    errors = [p for p in result.problems if p.level == "error"]
    assert [p.path for p in errors] == [str(img)] and "corrupt JPEG data" in errors[0].reason
    assert "b.jpg" not in {im.file_name.rsplit("/", 1)[-1] for im in result.dataset.images}


def test_clean_dataset_has_no_errors(tmp_path):
    write_yolo_dataset(tmp_path / "ds")
    problems = validate(tmp_path / "ds").problems
    assert {p.level for p in problems} == {"info"}  # d.png without label; data.yaml entries point elsewhere


def test_extraneous_bytes_in_a_jpeg_are_a_warning_naming_the_image(tmp_path, capfd):
    from factories import extraneous_jpeg

    write_yolo_dataset(tmp_path / "ds")
    img = tmp_path / "ds" / "train" / "images" / "b.jpg"
    img.write_bytes(extraneous_jpeg()[1])  # libjpeg alone: "Corrupt JPEG data: 1 extraneous bytes ..." unnamed
    problems = validate(tmp_path / "ds").problems
    assert [str(p) for p in problems if p.level == "warning" and "JPEG" in p.reason] == [
        f"{img}: corrupt JPEG data (1 extraneous bytes before marker 0xdb): skipped, the image decodes"
    ]
    assert not any(p.level == "error" for p in problems)
    assert "Corrupt JPEG" not in capfd.readouterr().err
