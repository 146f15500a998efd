"""Every kind of odd input users have, through every command that reads a dataset (convert, validate, stats,
dedup, mix, score): no traceback, a clear message naming each bad file, the good files all read, and nothing in
the source touched (hashed before and after)."""

from __future__ import annotations

import contextlib
import hashlib
import io
import json
import os
import struct
import zlib
from pathlib import Path

import cv2
import numpy as np
import pytest
import yaml
from detector_factories import oracle_model
from factories import jpeg_bytes, write_image
from PIL import Image

from fuzzyfire.cli import main

W, H = 64, 48
ROW = "0 0.5 0.5 0.25 0.5"  # a good box: 16 x 24 px at (24, 12)


def _png_header_only(width: int, height: int) -> bytes:
    """A PNG whose IHDR claims ``width`` x ``height`` with a tiny IDAT: a decompression bomb's header."""

    def chunk(kind: bytes, data: bytes) -> bytes:
        return struct.pack(">I", len(data)) + kind + data + struct.pack(">I", zlib.crc32(kind + data))

    ihdr = struct.pack(">IIBBBBB", width, height, 8, 2, 0, 0, 0)
    return b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", ihdr) + chunk(b"IDAT", zlib.compress(b"\0" * 64)) + chunk(b"IEND", b"")


def _good_images(folder: Path) -> dict[str, tuple[int, int]]:
    """Readable images in every form a viewer opens; name -> displayed (width, height)."""
    folder.mkdir(parents=True, exist_ok=True)
    rgb = np.random.default_rng(0).integers(0, 255, (H, W, 3), dtype=np.uint8)
    write_image(folder / "rgb.jpg", W, H, seed=1)
    cv2.imwrite(str(folder / "deep16.png"), (rgb.astype(np.uint16) * 257))
    Image.fromarray(np.dstack([rgb, np.full((H, W), 128, np.uint8)])).save(folder / "rgba.png")
    Image.fromarray(rgb).convert("CMYK").save(folder / "cmyk.jpg")
    Image.fromarray(rgb[:, :, 0]).save(folder / "grey.png")
    (folder / "rotated.jpg").write_bytes(jpeg_bytes(W, H, seed=2, orientation=6))  # shown as 48 x 64
    base = write_image(folder / "padded.jpg", W, H, seed=3).read_bytes()
    (folder / "padded.jpg").write_bytes(base + b"\0" * 25_000)  # phone export padding
    trailing = write_image(folder / "trailing.jpg", W, H, seed=4).read_bytes()
    (folder / "trailing.jpg").write_bytes(trailing + b"appended by a metadata tool" * 10)
    write_image(folder / "feu de forêt 火.jpg", W, H, seed=5)
    write_image(folder / "twin.jpg", W, H, seed=6)
    sizes = {p.name: (W, H) for p in folder.iterdir()}
    sizes["rotated.jpg"] = (H, W)
    return sizes


def _bad_images(folder: Path) -> dict[str, str]:
    """Files named like images that no viewer shows (or that would take gigabytes); name -> expected reason."""
    good = write_image(folder / "tmp.jpg", W, H, seed=9).read_bytes()
    (folder / "tmp.jpg").unlink()
    (folder / "corrupt.jpg").write_bytes(b"\xff\xd8\xff\xe0" + bytes(range(256)) * 4 + b"\xff\xd9")
    (folder / "empty.jpg").write_bytes(b"")
    (folder / "text.png").write_text("not an image", encoding="utf-8")
    (folder / "truncated.jpg").write_bytes(good[: len(good) // 2])
    (folder / "huge.png").write_bytes(_png_header_only(30_000, 30_000))
    (folder / "twin.png").write_bytes(good)  # same stem as twin.jpg: both would own twin.txt
    return {
        "corrupt.jpg": "not an image",
        "empty.jpg": "empty file",
        "text.png": "not an image",
        "truncated.jpg": "truncated JPEG",
        "huge.png": "decoding budget",
        "twin.png": "duplicate file stem",
    }


@pytest.fixture(scope="module")
def fuzz(tmp_path_factory) -> dict:
    root = tmp_path_factory.mktemp("fuzz")
    ds = root / "yolo"
    images, labels = ds / "train" / "images", ds / "train" / "labels"
    good = _good_images(images)
    bad = _bad_images(images)
    labels.mkdir(parents=True)
    for name in good:
        (labels / Path(name).with_suffix(".txt").name).write_text(ROW + "\n", encoding="utf-8")
    (labels / "rgb.txt").write_text(
        "\n".join(
            [
                ROW,
                "0 nan 0.5 0.1 0.1",
                "0 0.5 inf 0.1 0.1",
                "0 0.5 0.5 -0.2 0.1",
                "0 1.5 0.5 0.2 0.2",  # entirely right of the image
                "0 0.5 0.5 0.2 0.2 0.9",  # 6 columns: a prediction row with a confidence
                "0 0.1 0.1 0.3 0.1 0.3 0.4",  # 7 columns: a polygon, read as its bounding box
            ]
        )
        + "\n",
        encoding="utf-8",
    )
    (labels / "rotated.txt").write_bytes(f"{ROW}\r\n{ROW}\r\n".encode())  # CRLF
    (labels / "feu de forêt 火.txt").write_bytes(b"\xef\xbb\xbf" + f"{ROW}\n".encode())  # BOM
    (labels / "lonely.txt").write_text(ROW + "\n", encoding="utf-8")  # no image
    (ds / "data.yaml").write_text(yaml.safe_dump({"names": ["fire", "smoke"], "nc": 2}), encoding="utf-8")
    os.symlink("../..", images / "loop")  # a link back to an ancestor: walked once
    coco = _coco_dataset(root / "coco")
    return {"root": root, "yolo": ds, "images": images, "good": good, "bad": bad, "coco": coco}


def _coco_dataset(folder: Path) -> Path:
    """COCO with image ids from 0, ids as strings, no ``area``, a BOM-prefixed file."""
    write_image(folder / "a.jpg", W, H, seed=11)
    write_image(folder / "b.jpg", W, H, seed=12)
    doc = {
        "images": [
            {"id": 0, "file_name": "a.jpg", "width": W, "height": H},
            {"id": "1", "file_name": "b.jpg"},
        ],
        "annotations": [
            {"id": 0, "image_id": 0, "category_id": "0", "bbox": [1, 2, 10, 12]},
            {"id": "1", "image_id": 1, "category_id": 0, "bbox": [3, 4, 20, 10], "iscrowd": 0},
        ],
        "categories": [{"id": 0, "name": "fire"}],
    }
    (folder / "annotations.json").write_bytes(b"\xef\xbb\xbf" + json.dumps(doc).encode())
    return folder


def _hashes(root: Path) -> dict[str, str]:
    return {
        p.relative_to(root).as_posix(): hashlib.sha256(p.read_bytes()).hexdigest()
        for p in sorted(root.rglob("*"))
        if p.is_file() and not p.is_symlink()
    }


def _run(*argv: str | Path) -> tuple[int, str, str]:
    out, err = io.StringIO(), io.StringIO()
    with contextlib.redirect_stdout(out), contextlib.redirect_stderr(err):
        code = main([str(a) for a in argv])
    return code, out.getvalue(), err.getvalue()


@pytest.fixture(scope="module")
def validated(fuzz) -> dict:
    before = _hashes(fuzz["yolo"])
    code, out, _ = _run("validate", fuzz["yolo"], "--json")
    assert _hashes(fuzz["yolo"]) == before
    return {"code": code, "doc": json.loads(out)}


def test_validate_names_every_bad_file_and_reads_every_good_one(fuzz, validated):
    doc = validated["doc"]
    assert validated["code"] == 1  # errors found
    by_path: dict[str, list[str]] = {}
    for p in doc["problems"]:
        by_path.setdefault(Path(p["path"]).name, []).append(p["reason"])
    for name, reason in fuzz["bad"].items():
        assert name in by_path, f"{name} not reported"
        assert any(reason in r for r in by_path[name]), (name, by_path[name])
    good_named = [
        n for n in fuzz["good"] if any(p["level"] == "error" for p in doc["problems"] if p["path"].endswith(n))
    ]
    assert good_named == []
    assert doc["images"] == len(fuzz["good"])  # twin.png lost to the stem clash, every bad file skipped
    reasons = [f"{Path(p['path'].split(':')[0]).name}: {p['reason']}" for p in doc["problems"]]
    rgb = [r for r in reasons if r.startswith("rgb.txt")]
    assert any("NaN or infinite" in r for r in rgb) and sum("NaN or infinite" in r for r in rgb) == 2
    assert any("zero or negative area" in r for r in rgb)
    assert any("outside the 64x48 image" in r for r in rgb)
    assert any("6 values" in r for r in rgb)
    assert any(r.startswith("lonely.txt: label file without an image") for r in reasons)


def test_crlf_bom_polygon_rows_and_rotation_read_like_any_other(fuzz):
    from ground.data.formats.yolo import read_yolo

    result = read_yolo(fuzz["yolo"])
    ds = result.dataset
    sizes = {Path(img.file_name).name: (img.width, img.height) for img in ds.images}
    assert sizes == fuzz["good"]
    boxes = {Path(img.file_name).name: [] for img in ds.images}
    names = {img.id: Path(img.file_name).name for img in ds.images}
    for ann in ds.annotations:
        boxes[names[ann.image_id]].append(ann.bbox)
    assert boxes["rotated.jpg"] == [(18.0, 16.0, 12.0, 32.0)] * 2  # CRLF: both rows, in the 48 x 64 frame
    assert boxes["feu de forêt 火.jpg"] == [(24.0, 12.0, 16.0, 24.0)]  # BOM: the first row is kept
    assert len(boxes["rgb.jpg"]) == 2  # the good row and the polygon's bounding box
    assert all(not Path(img.file_name).parts[:-1].count("loop") for img in ds.images)  # loop walked once


def test_stats_and_convert_read_the_same_good_files(fuzz, tmp_path):
    before = _hashes(fuzz["yolo"])
    code, out, _ = _run("stats", fuzz["yolo"], "--json")
    assert code == 0
    stats = json.loads(out)
    assert stats["images"] == len(fuzz["good"]) and stats["negatives"] == 0
    code, out, err = _run("convert", fuzz["yolo"], "--to", "coco", "--out", tmp_path / "c", "--images", "copy")
    assert code == 0, err
    back = json.loads((tmp_path / "c" / "annotations.json").read_text(encoding="utf-8"))
    assert len(back["images"]) == stats["images"] and len(back["annotations"]) == stats["boxes"]
    assert "Traceback" not in err and _hashes(fuzz["yolo"]) == before


def test_coco_ids_from_zero_or_as_strings_and_no_area(fuzz):
    code, out, err = _run("validate", fuzz["coco"], "--json")
    doc = json.loads(out)
    assert code == 0, doc["problems"]
    assert doc["images"] == 2 and doc["boxes"] == 2


def test_dedup_reports_the_bad_files_and_keeps_the_source(fuzz, tmp_path):
    before = _hashes(fuzz["yolo"])
    code, _, err = _run("dedup", fuzz["images"], "--out", tmp_path / "d")
    assert code == 0, err
    doc = json.loads((tmp_path / "d" / "dedup.json").read_text(encoding="utf-8"))
    named = {Path(p["path"]).name for p in doc["problems"]}
    assert {"corrupt.jpg", "empty.jpg", "text.png", "truncated.jpg", "huge.png"} <= named
    kept = {Path(k if isinstance(k, str) else k["path"]).name for k in doc["kept"]}
    removed = {Path(r["path"]).name for r in doc["removed"]}
    assert set(fuzz["good"]) <= kept | removed  # every good file was read (the padded copies may be duplicates)
    assert _hashes(fuzz["yolo"]) == before


def test_mix_and_score_run_on_the_fuzz_set(fuzz, tmp_path):
    before = _hashes(fuzz["yolo"])
    code, _, err = _run(
        "mix", "--real", fuzz["yolo"], "--synth", fuzz["coco"], "--mixtures", "R4_S1", "--seeds", "0",
        "--out", tmp_path / "m",
    )  # fmt: skip
    assert code == 0, err
    assert len(list((tmp_path / "m").rglob("images/train/*"))) == 5
    model = oracle_model(tmp_path / "m.onnx")
    code, out, err = _run("score", model, "--data", fuzz["yolo"], "--split", "train", "--json")
    assert code == 0, err
    assert json.loads(out)["images"] == len(fuzz["good"])
    assert "Traceback" not in err and _hashes(fuzz["yolo"]) == before
