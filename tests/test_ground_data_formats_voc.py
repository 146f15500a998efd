import numpy as np
from factories import write_image

from ground.data.formats.voc import read_voc
from ground.data.writer import write_dataset


def _xml(filename: str, w: int, h: int, objects: list[tuple[str, list[float], int]]) -> str:
    objs = "".join(
        f"<object><name>{n}</name><difficult>{d}</difficult><bndbox><xmin>{b[0]}</xmin><ymin>{b[1]}</ymin>"
        f"<xmax>{b[2]}</xmax><ymax>{b[3]}</ymax></bndbox></object>"
        for n, b, d in objects
    )
    return f"<annotation><filename>{filename}</filename><size><width>{w}</width><height>{h}</height><depth>3</depth></size>{objs}</annotation>"


def _voc(root):
    (root / "Annotations").mkdir(parents=True)
    write_image(root / "JPEGImages" / "one.jpg", 100, 50)
    write_image(root / "JPEGImages" / "two.jpg", 60, 60)
    write_image(root / "JPEGImages" / "neg.jpg", 30, 30)
    (root / "Annotations" / "one.xml").write_text(
        _xml("one.jpg", 100, 50, [("Fire", [1, 1, 10, 20], 0), ("smoke", [51, 11, 100, 50], 1)])
    )
    (root / "Annotations" / "two.xml").write_text(_xml("two.jpg", 60, 60, [("flame", [5.5, 6.5, 30, 40], 0)]))
    (root / "ImageSets" / "Main").mkdir(parents=True)
    (root / "ImageSets" / "Main" / "train.txt").write_text("one\ntwo\n")
    (root / "ImageSets" / "Main" / "val.txt").write_text("neg\n")


def test_voc_reads_one_based_boxes_difficult_and_splits(tmp_path):
    _voc(tmp_path / "voc")
    result = read_voc(tmp_path / "voc")
    ds = result.dataset
    by_name = {img.file_name: img for img in ds.images}
    assert set(by_name) == {"JPEGImages/one.jpg", "JPEGImages/two.jpg", "JPEGImages/neg.jpg"}
    assert by_name["JPEGImages/one.jpg"].split == "train" and by_name["JPEGImages/neg.jpg"].split == "val"
    anns = {(ds.categories[a.category_id - 1].name, a.bbox, a.iscrowd) for a in ds.annotations}
    assert anns == {
        ("fire", (0.0, 0.0, 10.0, 20.0), 0),
        ("smoke", (50.0, 10.0, 50.0, 40.0), 1),  # difficult -> ignore region
        ("fire", (4.5, 5.5, 25.5, 34.5), 0),  # synonym 'flame' -> fire, float coordinates kept
    }
    assert any("image without annotation file" in p.reason and p.level == "info" for p in result.problems)


def test_voc_to_coco_round_trip_exact(tmp_path):
    _voc(tmp_path / "voc")
    ds = read_voc(tmp_path / "voc").dataset
    write_dataset(ds, tmp_path / "out", ["coco"])
    from ground.data.formats.coco import read_coco

    back = read_coco(tmp_path / "out").dataset
    a = sorted((x.bbox, x.iscrowd) for x in ds.annotations)
    b = sorted((x.bbox, x.iscrowd) for x in back.annotations)
    np.testing.assert_allclose([x[0] for x in a], [x[0] for x in b], atol=1e-9)
    assert [x[1] for x in a] == [x[1] for x in b]


def test_voc_problems(tmp_path):
    root = tmp_path / "side"
    write_image(root / "a.jpg", 40, 30)
    objects = [("fire", [0, 0, 50, 10], 0), ("fire", [5, 5, "x", 9], 0), ("sparks", [1, 1, 5, 5], 0)]
    (root / "a.xml").write_text(_xml("a.jpg", 999, 999, objects))
    (root / "ghost.xml").write_text(_xml("ghost.jpg", 10, 10, []))
    (root / "broken.xml").write_text("<annotation><filename>")
    result = read_voc(root)
    text = "\n".join(str(p) for p in result.problems)
    assert "<size> says 999x999 but the image is 40x30" in text
    assert "reaches outside the 40x30 image (clipped)" in text
    assert "object 2: bndbox" in text and "not numeric" in text
    assert "ghost.xml: annotation without an image (its <filename> 'ghost.jpg' not found)" in text
    assert "broken.xml: unreadable XML" in text
    assert f"{root / 'a.xml'} object 3: name: class 'sparks' is not a known class" in text  # the file and key
    assert len(result.dataset.images) == 1 and len(result.dataset.annotations) == 2
