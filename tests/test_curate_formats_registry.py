import pytest
from factories import write_image, write_yolo_dataset

from curate.formats.registry import detect_format, read_dataset


def test_detects_each_format(tmp_path):
    write_yolo_dataset(tmp_path / "yolo")
    assert detect_format(tmp_path / "yolo") == "yolo"
    (tmp_path / "voc" / "Annotations").mkdir(parents=True)
    assert detect_format(tmp_path / "voc") == "voc"
    (tmp_path / "coco").mkdir()
    (tmp_path / "coco" / "annotations.json").write_text('{"images": []}')
    assert detect_format(tmp_path / "coco") == "coco"
    assert detect_format(tmp_path / "coco" / "annotations.json") == "coco"


def test_undetectable_and_unknown(tmp_path):
    write_image(tmp_path / "only" / "x.jpg", 5, 5)
    with pytest.raises(ValueError, match="cannot tell the dataset format"):
        detect_format(tmp_path / "only")
    with pytest.raises(FileNotFoundError):
        detect_format(tmp_path / "nothing")
    write_yolo_dataset(tmp_path / "yolo")
    with pytest.raises(ValueError, match="unknown format 'kitti'"):
        read_dataset(tmp_path / "yolo", "kitti")
