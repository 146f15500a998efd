from dataclasses import replace
from pathlib import Path

from ground.data.fingerprint import fingerprint
from ground.data.writer import write_dataset
from tests.factories import tiny_pool, write_image


def _split(ds, names):
    return replace(ds, images=tuple(replace(im, split=s) for im, s in zip(ds.images, names)))


def test_fingerprint_covers_pictures_splits_and_boxes_not_names_or_places(tmp_path: Path):
    ds = _split(tiny_pool(tmp_path / "a", 4, "real:x"), ["train", "train", "valid", "test"])
    fp = fingerprint(ds)
    assert fp.images == 4 and fp.splits == {"test": 1, "train": 2, "valid": 1} and len(fp.digest) == 16
    assert fp.describe() == f"4 images (test 1, train 2, valid 1), fingerprint {fp.digest}"

    copy = write_dataset(ds, tmp_path / "copy", ("coco",), "copy")  # another folder, same contents
    from ground.data.formats.coco import read_coco

    assert fingerprint(read_coco(tmp_path / "copy").dataset) == fp, copy
    reordered = replace(ds, images=ds.images[::-1])
    assert fingerprint(reordered) == fp

    assert fingerprint(_split(ds, ["train", "valid", "valid", "test"])).digest != fp.digest  # another split
    moved = replace(ds, annotations=(replace(ds.annotations[0], bbox=(2.0, 1.0, 4.0, 3.0)), *ds.annotations[1:]))
    assert fingerprint(moved).digest != fp.digest  # another box
    write_image(tmp_path / "a" / "img001.png", 16, 12, seed=77)
    assert fingerprint(ds).digest != fp.digest  # another picture under the same name
