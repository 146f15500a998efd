"""Flame cut-outs from labelled images: the colour rule, the RGBA crop, and the command's sequence folders."""

from __future__ import annotations

import json
from pathlib import Path

import cv2
import numpy as np
import pytest

from fuzzyfire.cli import main
from ground.data.formats.registry import read_dataset
from ground.data.problems import Problem
from synth.flames.cutouts import (
    MIN_KEPT,
    CutoutConfig,
    cut,
    cutouts,
    filled,
    grabcut_mask,
    pixel_box,
    write_cutouts,
)
from synth.flames.firepixels import fire_mask
from synth.flames.sprites import load_library, write_png

ORANGE, CORE, BLUE, GREY = (240, 120, 20), (255, 240, 200), (30, 60, 200), (128, 128, 128)


def _image_with_disc(size: tuple[int, int] = (120, 160), centre: tuple[int, int] = (60, 50), r: int = 20) -> np.ndarray:
    """(h, w, 3) RGB: blue background, an orange disc with a bright core at ``centre`` (x, y)."""
    img = np.zeros(size + (3,), np.uint8)
    img[:] = BLUE
    cv2.circle(img, centre, r, ORANGE, -1)
    cv2.circle(img, centre, r // 3, CORE, -1)
    return img


def test_holes_are_filled_and_the_outside_stays_empty() -> None:
    ring = np.zeros((40, 40), np.uint8)
    cv2.circle(ring, (20, 20), 12, 1, 3)
    out = filled(ring.astype(bool))
    assert out[20, 20] and out[20, 10] and not out[0, 0] and not out[39, 39]


def test_a_cutout_is_the_crop_with_the_flame_as_alpha() -> None:
    img = _image_with_disc()
    got = cut(img, (30, 20, 60, 60), CutoutConfig(min_cover=0.08))
    assert got is not None
    rgba, cover = got
    assert rgba.shape == (60, 60, 4) and np.array_equal(rgba[..., :3], img[20:80, 30:90])
    assert rgba[30, 30, 3] == 255 and rgba[0, 0, 3] == 0  # disc centre opaque, blue corner transparent
    assert 0.25 < cover < 0.45  # pi 20^2 / 60^2 = 0.35
    assert cut(img, (100, 0, 50, 30), CutoutConfig(min_cover=0.08)) is None  # only sky


WALL = (190, 110, 60)  # a warm wall lit by the fire: fire-coloured by the colour rule


def _flame_on_a_lit_wall() -> tuple[np.ndarray, np.ndarray]:
    """(h, w, 3) RGB: a flame disc (r 22 at (80, 60)) on a lit wall wider than its box; and the disc's true mask."""
    img = np.zeros((120, 160, 3), np.uint8)
    img[:] = (60, 70, 90)
    img[10:110, 20:140] = WALL
    cv2.circle(img, (80, 60), 22, ORANGE, -1)
    cv2.circle(img, (80, 60), 9, CORE, -1)
    truth = np.zeros((120, 160), np.uint8)
    cv2.circle(truth, (80, 60), 22, 1, -1)
    return img, truth.astype(bool)


def _iou(a: np.ndarray, b: np.ndarray) -> float:
    return float((a & b).sum() / (a | b).sum())


def test_grabcut_cuts_the_flame_out_of_a_fire_lit_wall_the_colour_rule_takes_whole() -> None:
    img, truth = _flame_on_a_lit_wall()
    box = (50, 30, 60, 60)
    inside = truth[30:90, 50:110]
    colour, cover = cut(img, box, CutoutConfig(mask="colour"))
    grab, same_cover = cut(img, box, CutoutConfig(mask="grabcut"))
    assert cover == same_cover == 1.0  # the whole box passes the colour rule: the skip rule is unchanged
    assert (colour[8:52, 8:52, 3] >= 128).all()  # the whole box, softened at its sides ...
    assert _no_straight_side(colour[..., 3])  # ... so no rectangle of the source frame shows
    assert _iou(grab[..., 3] >= 128, inside) > 0.95 and grab[0, 0, 3] == 0 and grab[30, 30, 3] == 255
    assert np.array_equal(grab[..., :3], colour[..., :3])  # the same pixels, another alpha
    assert (
        cut(_image_with_disc(), (30, 20, 60, 60), CutoutConfig())[0][0, 0, 3] == 0
    )  # sky corner stays out (default rule)
    with pytest.raises(ValueError, match="unknown cut-out mask rule 'snake'; choose one of colour, grabcut"):
        CutoutConfig(mask="snake")


def _no_straight_side(alpha: np.ndarray) -> bool:
    """Whether the (h, w) alpha is 0 on the box's outer rows and columns and in its corners' 1/12 squares."""
    h, w = alpha.shape
    ch, cw = max(h // 12, 1), max(w // 12, 1)
    sides = [alpha[0], alpha[-1], alpha[:, 0], alpha[:, -1], alpha[:ch, :cw], alpha[-ch:, -cw:]]
    return all(int(part.max()) == 0 for part in sides)


@pytest.mark.parametrize("rule", ["colour", "grabcut"])
def test_a_flame_filling_its_box_is_no_rectangular_patch(rule: str) -> None:
    img = np.zeros((100, 100, 3), np.uint8)
    img[:] = ORANGE  # fire fills the frame, so its box: both rules keep the whole box
    rgba, _ = cut(img, (20, 20, 60, 40), CutoutConfig(mask=rule))
    assert _no_straight_side(rgba[..., 3]) and rgba[20, 30, 3] == 255


def test_grabcut_masks_are_deterministic_and_independent_of_earlier_cuts() -> None:
    img, _ = _flame_on_a_lit_wall()
    other = _image_with_disc(centre=(100, 70), r=25)
    alone = cut(img, (50, 30, 60, 60), CutoutConfig())[0]
    cut(other, (75, 45, 50, 50), CutoutConfig())  # k-means draws from OpenCV's RNG: reset before each cut
    cv2.setRNGSeed(12345)
    assert cut(img, (50, 30, 60, 60), CutoutConfig())[0].tobytes() == alone.tobytes()


def test_grabcut_keeps_the_colour_mask_without_background_to_learn_from_or_when_it_keeps_too_little() -> None:
    orange = np.zeros((40, 40, 3), np.uint8)
    orange[:] = ORANGE
    start = filled(fire_mask(orange))
    assert (
        grabcut_mask(orange, (0, 0, 40, 40), start, CutoutConfig().context) is start
    )  # the box is the image and all flame
    img, _ = _flame_on_a_lit_wall()
    speck = np.zeros((60, 60), bool)
    speck[0, 0] = True  # a start GrabCut reduces to under MIN_KEPT of the box
    got = grabcut_mask(img, (50, 30, 60, 60), speck, CutoutConfig().context)
    assert got is speck or got.mean() >= MIN_KEPT


def test_pixel_boxes_cover_the_float_box_and_stay_in_the_image() -> None:
    assert pixel_box((10.2, 5.7, 20.5, 10.0), 100, 100) == (10, 5, 21, 11)
    assert pixel_box((-4.0, 90.5, 20.0, 20.0), 100, 100) == (0, 90, 16, 10)


def _write_yolo(root: Path, images: dict[str, tuple[np.ndarray, list[str]]]) -> None:
    for split in ("train", "valid"):
        (root / split / "images").mkdir(parents=True)
        (root / split / "labels").mkdir(parents=True)
    for name, (img, rows) in images.items():
        split = "valid" if name.startswith("v") else "train"
        cv2.imwrite(str(root / split / "images" / f"{name}.png"), cv2.cvtColor(img, cv2.COLOR_RGB2BGR))
        (root / split / "labels" / f"{name}.txt").write_text("".join(r + "\n" for r in rows))
    (root / "data.yaml").write_text("names: [fire, smoke]\nnc: 2\n")


@pytest.fixture
def labelled(tmp_path: Path) -> Path:
    """train: a0 (a flame box, a 10-px fire box, a sky box, a smoke box over the flame), a1 (a flame box);
    valid: v0 (a flame box)."""
    root = tmp_path / "real"

    def row(cls: int, x: int, y: int, w: int, h: int) -> str:  # pixel box of a 160x120 image -> a YOLO row
        return f"{cls} {(x + w / 2) / 160:.9f} {(y + h / 2) / 120:.9f} {w / 160:.9f} {h / 120:.9f}"

    flame = row(0, 30, 20, 60, 60)  # the disc
    _write_yolo(
        root,
        {
            "a0": (_image_with_disc(), [flame, row(0, 140, 5, 10, 10), row(0, 100, 2, 48, 30), row(1, 30, 20, 60, 60)]),
            "a1": (_image_with_disc(centre=(100, 70), r=25), [row(0, 75, 45, 50, 50)]),
            "v0": (_image_with_disc(), [flame]),
        },
    )
    return root


def test_cutouts_skip_small_and_sky_boxes_and_other_classes(labelled: Path) -> None:
    ds = read_dataset(labelled).dataset.select_split("train")
    problems: list[Problem] = []
    items = list(cutouts(ds, CutoutConfig(class_name="fire", min_side=16, min_cover=0.08), problems))
    assert [(Path(c.file).stem, c.box) for c in items] == [("a0", (30, 20, 60, 60)), ("a1", (75, 45, 50, 50))]
    assert not problems
    assert [c.box for c in cutouts(ds, CutoutConfig(class_name="Flames"))] == [
        c.box for c in items
    ]  # a synonym of fire
    with pytest.raises(ValueError, match=r"--class 'flamme': no such class \(classes: 'fire', 'smoke'\)"):
        list(cutouts(ds, CutoutConfig(class_name="flamme")))


def test_an_unreadable_image_is_named_and_the_rest_is_cut(labelled: Path) -> None:
    ds = read_dataset(labelled).dataset.select_split("train")
    (labelled / "train" / "images" / "a1.png").write_bytes(b"not a png")  # broken after the listing
    problems: list[Problem] = []
    items = list(cutouts(ds, CutoutConfig(), problems))
    assert [Path(c.file).stem for c in items] == ["a0"]
    assert len(problems) == 1 and problems[0].path.endswith("a1.png")


def test_the_command_writes_a_flame_library_and_refuses_to_overwrite(labelled: Path, tmp_path: Path, capsys) -> None:
    out = tmp_path / "cutouts"
    assert main(["synth", "cutouts", str(labelled), "--split", "train", "--out", str(out)]) == 0
    assert "wrote 2 cut-outs" in capsys.readouterr().out
    index = json.loads((out / "cutouts.json").read_text())
    assert [(e["png"], e["box"]) for e in index] == [
        ("real-000/00000.png", [30, 20, 60, 60]),
        ("real-000/00001.png", [75, 45, 50, 50]),
    ]
    (seq,) = load_library([out])
    assert len(seq.sprites) == 2 and all(s.mask.any() for s in seq.sprites)
    assert seq.sprites[0].size[0] <= 60 and seq.sprites[0].mask.mean() > 0.5  # cropped to the disc
    assert main(["synth", "cutouts", str(labelled), "--out", str(out)]) == 2
    assert "holds cut-outs already" in capsys.readouterr().err
    assert main(["synth", "cutouts", str(labelled), "--split", "test", "--out", str(tmp_path / "x")]) == 2


def test_a_mistyped_class_or_a_used_folder_fails_before_any_cut(labelled: Path, tmp_path: Path, capsys) -> None:
    out = tmp_path / "cutouts"
    assert main(["synth", "cutouts", str(labelled), "--class", "flamme", "--out", str(out)]) == 2
    assert "--class 'flamme': no such class (classes: 'fire', 'smoke')" in capsys.readouterr().err
    assert not out.exists()
    (out / "mine").mkdir(parents=True)
    assert main(["synth", "cutouts", str(labelled), "--out", str(out)]) == 2
    assert "is not an empty folder" in capsys.readouterr().err
    assert [p.name for p in out.iterdir()] == ["mine"]  # the user's folder untouched


def test_a_failed_write_removes_what_it_wrote(labelled: Path, tmp_path: Path, monkeypatch) -> None:
    import synth.flames.cutouts as module

    ds = read_dataset(labelled).dataset.select_split("train")
    written = []

    def write_once(path: Path, rgba) -> None:
        if written:
            raise OSError("disk full")
        written.append(path)
        write_png(path, rgba)

    monkeypatch.setattr(module, "write_png", write_once)
    (tmp_path / "empty").mkdir()
    for out in (tmp_path / "new", tmp_path / "empty"):
        written.clear()
        with pytest.raises(OSError, match="disk full"):
            module.write_cutouts(cutouts(ds, CutoutConfig()), out)
        assert written and not written[0].exists()
    assert not (tmp_path / "new").exists() and (tmp_path / "empty").is_dir()


def test_smoke_boxes_become_soft_smoke_sequences_and_flame_cutouts_carry_no_smoke(tmp_path: Path) -> None:
    """A light plume over a textured scene, boxed as smoke beside a flame box: ``class_name: smoke`` mattes it into a
    smoke sprite sequence (no flame, soft alpha, no side showing) that loads as smoke; the flames cut beside it load
    as flames whose dim edge is no smoke."""
    from synth.flames.sprites import is_smoke

    rng = np.random.default_rng(0)
    img = _image_with_disc(centre=(30, 90), r=14)  # a flame at the lower left
    img[:, 60:] = rng.integers(40, 120, (120, 100, 3))  # a textured wall on the right ...
    yy, xx = np.mgrid[0:120, 0:100]
    alpha = 0.9 * np.exp(-(((xx - 50) / 25.0) ** 2 + ((yy - 50) / 30.0) ** 2))[..., None]
    img[:, 60:] = (img[:, 60:] * (1 - alpha) + 230 * alpha).astype(np.uint8)  # ... with white smoke over it

    def row(cls: int, x: int, y: int, w: int, h: int) -> str:
        return f"{cls} {(x + w / 2) / 160:.9f} {(y + h / 2) / 120:.9f} {w / 160:.9f} {h / 120:.9f}"

    _write_yolo(tmp_path / "real", {"s0": (img, [row(0, 16, 76, 28, 28), row(1, 70, 5, 80, 90)])})
    ds = read_dataset(tmp_path / "real").dataset
    smoke = list(cutouts(ds, CutoutConfig(class_name="smoke")))
    assert [(c.category, c.box) for c in smoke] == [("smoke", (70, 5, 80, 90))]
    fire = list(cutouts(ds, CutoutConfig()))
    assert write_cutouts(iter(fire + smoke), tmp_path / "cut") == 2
    index = json.loads((tmp_path / "cut" / "cutouts.json").read_text())
    assert [(e["class"], e.get("sequence")) for e in index] == [("fire", None), ("smoke", "smoke-000")]
    flames, plumes = ([s for s in load_library([tmp_path / "cut"]) if is_smoke(s) == k] for k in (False, True))
    (plume,) = plumes[0].sprites
    assert not plume.mask.any() and plume.smoke_mask().any() and plume.over[0, :, 3].max() == 0
    assert all(not sp.smoke and not sp.smoke_mask().any() for seq in flames for sp in seq.sprites)
