from factories import write_yolo_dataset

from curate.stats import dataset_stats, plot_box_sizes, relative_box_sizes
from ground.data.formats.yolo import read_yolo


def test_counts(tmp_path):
    write_yolo_dataset(tmp_path / "ds")
    result = read_yolo(tmp_path / "ds")
    stats = dataset_stats(result.dataset, result.unlabelled)
    assert stats["images"] == 4 and stats["boxes"] == 3 and stats["negatives"] == 2
    assert stats["boxes_per_class"] == {"fire": 2, "smoke": 1}
    # valid: c.jpg has an empty label file, d.png none
    assert stats["negatives_by_origin"] == {"no_label_file": 1, "empty_labels": 1}
    assert stats["per_split"] == {
        "train": {"images": 2, "boxes": 3, "negatives": 0, "no_label_file": 0, "empty_labels": 0},
        "valid": {"images": 2, "boxes": 0, "negatives": 2, "no_label_file": 1, "empty_labels": 1},
    }
    assert sum(stats["box_sizes"].values()) == 3
    assert stats["boxes_by_crowding"] == {"1": 1, "2": 2, "3-4": 0, "5+": 0}  # a.jpg holds two, b.jpg one


def test_histogram_png(tmp_path):
    write_yolo_dataset(tmp_path / "ds")
    ds = read_yolo(tmp_path / "ds").dataset
    sizes = relative_box_sizes(ds)
    assert all(((v > 0) & (v <= 1)).all() for v in sizes.values())
    png = plot_box_sizes(ds, tmp_path / "plots" / "sizes.png")
    assert png.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
