"""The realism gap: real embeddings of small generated image sets, compared at equal sizes."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest
from curate_helpers import save, scene, transformed, use_session_cache, write_scene_dataset

from curate.embed import load_embedder
from fuzzyfire.cli import main
from synth.gap import (
    ImageSet,
    crop_box,
    dataset_boxes,
    dataset_images,
    embed_crops,
    embed_set,
    measure_gap,
    synthetic_boxes,
)


@pytest.fixture
def folders(tmp_path: Path, tmp_path_factory: pytest.TempPathFactory) -> dict[str, Path]:
    """``real``: 24 scenes; ``alike``: 12 other scenes of the same kind; ``flat``: 12 flat grey-ish images
    (plus one broken file)."""
    use_session_cache(tmp_path_factory)
    for i in range(24):
        save(scene(100 + i), tmp_path / "real" / f"r{i}.jpg")
    for i in range(12):
        save(transformed(scene(200 + i), "hflip"), tmp_path / "alike" / f"a{i}.jpg")
        grey = np.full((120, 160, 3), 90 + 3 * i, np.uint8)
        save(grey, tmp_path / "flat" / f"f{i}.png")
    (tmp_path / "flat" / "broken.png").write_bytes(b"not a png")
    return {k: tmp_path / k for k in ("real", "alike", "flat")}


def test_a_set_like_the_real_one_is_closer_than_a_flat_one(folders) -> None:
    embedder = load_embedder()
    real = embed_set("real", dataset_images(folders["real"], fmt="images"), embedder, None)
    alike = embed_set("alike", dataset_images(folders["alike"], fmt="images"), embedder, None)
    flat = embed_set("flat", dataset_images(folders["flat"], fmt="images"), embedder, None)
    assert len(real.vectors) == 24 and real.vectors.shape[1] == flat.vectors.shape[1] and not real.problems
    assert len(flat.vectors) == 12 and [Path(p.path).name for p in flat.problems] == ["broken.png"]
    near = measure_gap(alike, real, embedder.model_id, np.random.default_rng(0), draws=30)
    far = measure_gap(flat, real, embedder.model_id, np.random.default_rng(0), draws=30)
    assert near.gap.size == far.gap.size == 12
    assert near.gap.floor == far.gap.floor  # same seed: the same real halves
    assert far.gap.synthetic.low > near.gap.synthetic.high
    assert far.gap.ratio.median > 2 * near.gap.ratio.median
    assert near.to_json()["sets"]["synthetic"] == {"path": "alike", "images": 12}


def test_dataset_layouts_and_errors(tmp_path: Path, folders) -> None:
    ds = write_scene_dataset(tmp_path / "ds", {f"s{i}": (i, None) for i in range(4)})
    assert len(dataset_images(ds)) == 4 and len(dataset_images(ds, "train")) == 4
    with pytest.raises(ValueError, match=r"no split 'test' \(splits: 'train'\)"):
        dataset_images(ds, "test")
    plain = dataset_images(folders["real"])  # a plain folder of images: a negatives-only set, its images
    assert [p.resolve() for p in plain] == [p.resolve() for p in dataset_images(folders["real"], None, "images")]
    with pytest.raises(ValueError, match="split needs a dataset"):
        dataset_images(folders["real"], "train", "images")


def test_gap_command(folders, capsys) -> None:
    args = ["synth", "gap", str(folders["alike"]), str(folders["real"]), "--format", "images"]
    assert main([*args, "--real-format", "images", "--draws", "20", "--no-cache", "--json"]) == 0
    report = json.loads(capsys.readouterr().out)
    assert report["size"] == 12 and report["draws"] == 20 and report["sets"]["real"]["images"] == 24
    floor = report["frechet"]["floor"]
    assert floor["low"] <= floor["median"] <= floor["high"]
    assert main([*args, "--real-format", "images", "--draws", "20", "--no-cache"]) == 0
    assert "real vs real" in capsys.readouterr().out
    assert main([*args, "--draws", "20", "--no-cache", "--json"]) == 0  # REAL, a plain folder, read as images
    assert json.loads(capsys.readouterr().out) == report


def test_gap_settings_print_and_take_the_model_flags_into_their_model_section(tmp_path: Path, capsys) -> None:
    import yaml

    from curate.settings import EmbedderConfig
    from ground.config.loader import to_dict
    from synth.gap import GapConfig

    assert main(["synth", "gap", "--print-config"]) == 0  # no SYNTHETIC and REAL needed to print the settings
    assert yaml.safe_load(capsys.readouterr().out)["draws"] == GapConfig().draws
    argv = ["synth", "gap", "--print-config", "--crops", "--nhwc", "--mean", "1,2,3", "--workers", "2"]
    assert main([*argv, "--set", "context=0.2"]) == 0
    (tmp_path / "gap.yaml").write_text(capsys.readouterr().out)
    got = yaml.safe_load((tmp_path / "gap.yaml").read_text())
    model = EmbedderConfig(layout="nhwc", mean=(1.0, 2.0, 3.0), workers=2)
    assert got == yaml.safe_load(yaml.safe_dump(to_dict(GapConfig(crops=True, context=0.2, model=model))))
    assert main(["synth", "gap", "--config", str(tmp_path / "gap.yaml"), "--print-config"]) == 0
    assert yaml.safe_load(capsys.readouterr().out) == got  # the printed settings read back unchanged
    assert main(["synth", "gap", str(tmp_path)]) == 2
    assert "REAL is required" in capsys.readouterr().err


def test_a_mixed_pool_gets_a_gap_per_kind(folders, tmp_path, capsys) -> None:
    """Method 2 on photos and panoramas in one pool: the gap of each kind's images beside the whole pool's."""
    import cv2
    from factories import write_image

    for k in range(4):
        write_image(tmp_path / "photos" / f"p{k}.jpg", 160, 120, seed=k)
        pano = np.full((128, 256, 3), 60 + 40 * k, np.uint8)
        pano[64:] = np.random.default_rng(k).integers(0, 255, (64, 256, 3))
        cv2.imwrite(
            str(tmp_path / "panos" / f"h{k}.jpg") if (tmp_path / "panos").mkdir(exist_ok=True) is None else "", pano
        )
    flames = ["synth", "flames", "--out", str(tmp_path / "fl"), "--n", "1", "--frames", "60", "--keep-every", "30"]
    assert main(flames) == 0
    pool = tmp_path / "pool"
    args = ["synth", "method2", "--n", "60", "--out", str(pool), "--size", "64x48", "--flames", str(tmp_path / "fl")]
    assert main([*args, "--backgrounds", str(tmp_path / "photos"), "--environments", str(tmp_path / "panos")]) == 0
    capsys.readouterr()
    gap = ["synth", "gap", str(pool), str(folders["real"]), "--real-format", "images", "--draws", "10", "--json"]
    assert main([*gap, "--no-cache"]) == 0
    report = json.loads(capsys.readouterr().out)
    assert set(report["kinds"]) == {"photo", "panorama"}
    counts = [report["kinds"][k]["sets"]["synthetic"]["images"] for k in ("photo", "panorama")]
    assert sum(counts) == report["sets"]["synthetic"]["images"] == 60 and min(counts) >= 20


def _flat_dataset(root: Path, n: int) -> Path:
    """A YOLO folder like :func:`write_scene_dataset`'s, of flat grey images with one fire box each."""
    for i in range(n):
        save(np.full((120, 160, 3), 90 + 3 * i, np.uint8), root / "train" / "images" / f"f{i}.png")
        (root / "train" / "labels").mkdir(parents=True, exist_ok=True)
        (root / "train" / "labels" / f"f{i}.txt").write_text(f"0 0.5 0.5 {0.1 + 0.01 * i:.2f} 0.25\n")
    (root / "data.yaml").write_text("train: train/images\nnc: 1\nnames: [fire]\n")
    return root


def _pool_on_frames(root: Path, n: int) -> Path:
    """:func:`_flat_dataset` as a pool composited on labelled frames: each image a drawn flame (box 1, its mask
    value 1 in ``masks/``) and the frame's own fire after it (box 2, no mask), as Method 2 writes them."""
    _flat_dataset(root, n)
    for i in range(n):
        (root / "train" / "labels" / f"f{i}.txt").write_text("0 0.3 0.5 0.2 0.25\n0 0.75 0.5 0.2 0.25\n")
        mask = np.zeros((120, 160), np.uint8)
        mask[45:75, 32:64] = 1
        save(mask, root / "masks" / f"f{i}.png")
    return root


def test_synthetic_boxes_keep_only_the_drawn_flames(tmp_path: Path) -> None:
    pool = _pool_on_frames(tmp_path / "pool", 3)
    items = dataset_boxes(pool)
    assert [len(b) for _, b in items] == [2, 2, 2]
    kept, left = synthetic_boxes(pool, items)
    assert left == 3 and [b for _, b in kept] == [[items[0][1][0]], [items[1][1][0]], [items[2][1][0]]]
    (pool / "masks" / "f2.png").unlink()  # no mask: nothing of that image was drawn
    kept, left = synthetic_boxes(pool, items)
    assert left == 4 and len(kept) == 2
    plain = _flat_dataset(tmp_path / "plain", 2)  # no masks/ folder: every box kept
    assert synthetic_boxes(plain, dataset_boxes(plain)) == ([(p, list(b)) for p, b in dataset_boxes(plain)], 0)


def test_gap_command_with_crops_leaves_the_frames_own_fires_out(tmp_path: Path, capsys) -> None:
    real = write_scene_dataset(tmp_path / "real", {f"r{i}": (100 + i, None) for i in range(24)}, ("fire",))
    pool = _pool_on_frames(tmp_path / "pool", 12)
    args = ["synth", "gap", str(pool), str(real), "--crops", "--draws", "5", "--json"]
    assert main(args) == 0
    captured = capsys.readouterr()
    assert json.loads(captured.out)["sets"]["synthetic"]["images"] == 12
    assert "left out 12 boxes without a flame mask" in captured.err
    assert main([*args, "--all-boxes"]) == 0
    assert json.loads(capsys.readouterr().out)["sets"]["synthetic"]["images"] == 24


def test_crop_box_adds_context_and_clips() -> None:
    rgb = np.arange(100 * 80 * 3, dtype=np.uint8).reshape(100, 80, 3)
    assert crop_box(rgb, [20, 30, 10, 20]).shape == (24, 12, 3)  # 10 % of 10 x 20 on each side
    assert crop_box(rgb, [20, 30, 10, 20], context=0.0).shape == (20, 10, 3)
    assert np.array_equal(crop_box(rgb, [-5, 90, 20, 20], 0.0), rgb[90:100, 0:15])  # clipped to the image
    assert crop_box(rgb, [200, 10, 5, 5]) is None


def test_flame_gap_of_like_crops_is_near_the_floor_and_flat_crops_are_far(tmp_path: Path, folders) -> None:
    real = write_scene_dataset(tmp_path / "real", {f"r{i}": (100 + i, None) for i in range(24)}, ("fire",))
    alike = write_scene_dataset(tmp_path / "alike", {f"a{i}": (200 + i, "hflip") for i in range(12)}, ("fire",))
    flat = _flat_dataset(tmp_path / "flat", 12)
    embedder = load_embedder()
    sets = {
        k: embed_crops(k, dataset_boxes(p), embedder) for k, p in {"real": real, "alike": alike, "flat": flat}.items()
    }
    assert len(sets["real"].vectors) == 24 and len(sets["flat"].vectors) == 12
    near = measure_gap(sets["alike"], sets["real"], embedder.model_id, np.random.default_rng(0), 30, unit="crops")
    far = measure_gap(sets["flat"], sets["real"], embedder.model_id, np.random.default_rng(0), 30, unit="crops")
    assert near.gap.floor.median < far.gap.synthetic.low and near.gap.synthetic.high < far.gap.synthetic.low
    assert "12 crops per side" in "\n".join(far.lines()) and far.to_json()["unit"] == "crops"
    with pytest.raises(ValueError, match="no 'smoke' boxes"):
        dataset_boxes(real, category="smoke")
    with pytest.raises(ValueError, match="crops need boxes"):
        dataset_boxes(folders["real"], fmt="images")


def test_gap_command_with_crops(tmp_path: Path, capsys) -> None:
    real = write_scene_dataset(tmp_path / "real", {f"r{i}": (100 + i, None) for i in range(24)}, ("fire",))
    flat = _flat_dataset(tmp_path / "flat", 12)
    assert main(["synth", "gap", str(flat), str(real), "--crops", "--draws", "20", "--json"]) == 0
    report = json.loads(capsys.readouterr().out)
    assert report["unit"] == "crops" and report["size"] == 12 and report["sets"]["real"]["images"] == 24
    assert report["frechet"]["ratio"]["low"] > 1.0


def test_ratio_falls_toward_one_as_sets_shrink_and_the_report_says_so() -> None:
    rng = np.random.default_rng(0)
    real = ImageSet("real", rng.normal(size=(400, 16)).astype(np.float32), ())
    shifted = ImageSet("synthetic", (rng.normal(size=(200, 16)) + 0.3).astype(np.float32), ())
    full = measure_gap(shifted, real, "m", np.random.default_rng(1), 20)
    small = measure_gap(shifted, real, "m", np.random.default_rng(1), 20, size=20)
    assert full.gap.size == 200 and small.gap.size == 20
    assert 1.0 < small.gap.ratio.median < full.gap.ratio.median  # the floor grows faster than the distance
    assert full.size_note() == [] and "below the real set's half (200)" in small.lines()[-1]
