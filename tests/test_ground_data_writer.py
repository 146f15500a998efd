import json
import os

import pytest
from factories import write_yolo_dataset

from ground.data.formats.yolo import read_yolo
from ground.data.manifest import file_sha256
from ground.data.writer import OutputError, plan_image_names, write_dataset


@pytest.fixture()
def src(tmp_path):
    write_yolo_dataset(tmp_path / "src")
    return read_yolo(tmp_path / "src").dataset


def _snapshot(folder):
    return {p: (p.stat().st_mtime_ns, p.read_bytes()) for p in folder.rglob("*") if p.is_file()}


def test_source_folder_never_modified(src, tmp_path):
    before = _snapshot(tmp_path / "src")
    write_dataset(src, tmp_path / "out", ["coco", "yolo"])
    assert _snapshot(tmp_path / "src") == before


def test_refuses_output_inside_source_or_source_inside_output(src, tmp_path):
    with pytest.raises(OutputError, match="inside the source"):
        write_dataset(src, tmp_path / "src" / "converted", ["coco"])
    with pytest.raises(OutputError, match="inside the source"):
        write_dataset(src, tmp_path / "src", ["coco"])
    with pytest.raises(OutputError, match="lies inside the output"):
        write_dataset(src, tmp_path, ["coco"])


def test_refuses_foreign_non_empty_folder_and_needs_overwrite(src, tmp_path):
    (tmp_path / "busy").mkdir()
    (tmp_path / "busy" / "thesis.tex").write_text("precious")
    with pytest.raises(OutputError, match="not empty"):
        write_dataset(src, tmp_path / "busy", ["coco"])
    assert (tmp_path / "busy" / "thesis.tex").read_text() == "precious"
    write_dataset(src, tmp_path / "out", ["coco"])
    with pytest.raises(OutputError, match="--overwrite"):
        write_dataset(src, tmp_path / "out", ["coco"])
    write_dataset(src, tmp_path / "out", ["coco"], overwrite=True)


def test_manifest_hashes_sources_and_counts(src, tmp_path):
    write_dataset(src, tmp_path / "out", ["coco", "yolo"], command="convert", args={"to": "all"})
    man = json.loads((tmp_path / "out" / "manifest.json").read_text())
    assert man["command"] == "convert" and man["args"] == {"to": "all"}
    assert man["counts"] == {"images": 4, "boxes": 3, "negatives": 2, "categories": ["fire", "smoke"]}
    a = tmp_path / "src" / "train" / "images" / "a.jpg"
    entry = next(e for e in man["images"] if e["file"] == "images/train/a.jpg")
    assert entry == {
        "file": "images/train/a.jpg",
        "sha256": file_sha256(a),
        "bytes": a.stat().st_size,
        "source": a.resolve().as_posix(),
    }
    assert file_sha256(tmp_path / "out" / entry["file"]) == entry["sha256"]
    assert "numpy" in man["versions"] and "created" not in man


def test_generated_images_have_no_source_path(src, tmp_path):
    write_dataset(src, tmp_path / "out", ["coco"], generated=True, sources=[tmp_path / "src" / "data.yaml"])
    man = json.loads((tmp_path / "out" / "manifest.json").read_text())
    assert all(set(e) == {"file", "sha256", "bytes"} for e in man["images"])
    assert [s["path"].rsplit("/", 1)[-1] for s in man["sources"]] == ["data.yaml"]


@pytest.mark.parametrize("mode", ["hardlink", "symlink"])
def test_link_modes(src, tmp_path, mode):
    write_dataset(src, tmp_path / mode, ["yolo"], images=mode)
    placed = tmp_path / mode / "images" / "train" / "a.jpg"
    original = tmp_path / "src" / "train" / "images" / "a.jpg"
    assert placed.read_bytes() == original.read_bytes()
    if mode == "symlink":
        assert placed.is_symlink()
    else:
        assert os.path.samefile(placed, original)


def test_reference_mode_is_coco_only(src, tmp_path):
    write_dataset(src, tmp_path / "ref", ["coco"], images="reference")
    doc = json.loads((tmp_path / "ref" / "annotations.json").read_text())
    assert all(os.path.isabs(i["file_name"]) for i in doc["images"])
    assert not (tmp_path / "ref" / "images").exists()
    with pytest.raises(ValueError, match="YOLO needs labels"):
        write_dataset(src, tmp_path / "ref2", ["yolo"], images="reference")


def test_plan_makes_stems_unique_per_split(tmp_path):
    from ground.data.dataset import DatasetBuilder

    b = DatasetBuilder(tmp_path)
    b.add_image("x/fire.jpg", 10, 10, split="train")
    b.add_image("y/fire.png", 10, 10, split="train")
    b.add_image("z/FIRE.jpg", 10, 10, split="train")
    b.add_image("z/fire.jpg", 10, 10, split="test")
    plan = plan_image_names(b.build())
    assert plan == {
        1: "images/train/fire.jpg",
        2: "images/train/fire_2.png",
        3: "images/train/FIRE_3.jpg",
        4: "images/test/fire.jpg",
    }


def test_unknown_format_and_mode(src, tmp_path):
    with pytest.raises(ValueError, match="unknown output format"):
        write_dataset(src, tmp_path / "o1", ["voc"])
    with pytest.raises(ValueError, match="unknown image mode"):
        write_dataset(src, tmp_path / "o2", ["coco"], images="teleport")


def test_image_level_labels_survive_coco_and_are_refused_by_yolo(tmp_path):
    """COCO keeps an image-labelled set's per-image classes (read back as they were); YOLO, which has no form for
    them, refuses instead of writing its fire photos as negatives."""
    from factories import write_image

    from ground.data.formats.coco import read_coco
    from ground.data.formats.folders import read_folders

    write_image(tmp_path / "layout" / "fire" / "a.png", 8, 8)
    write_image(tmp_path / "layout" / "normal" / "b.png", 8, 8, seed=1)
    ds = read_folders(tmp_path / "layout").dataset
    write_dataset(ds, tmp_path / "out", ("coco",))
    back = read_coco(tmp_path / "out").dataset
    assert [i.labels for i in back.images] == [("fire",), ()] and back.category_names == ["fire"]
    with pytest.raises(ValueError, match="YOLO has no form for that"):
        write_dataset(ds, tmp_path / "yolo", ("yolo",))
    assert not (tmp_path / "yolo").exists()
