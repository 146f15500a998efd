import cv2
import numpy as np
import pytest

from ground.image.imageio import ImageError
from synth.flames import simulate as F
from synth.flames import sprites as S


def _seq():
    p = F.FlameParams(rows=40, cols=32, frames=40, keep_every=20, warmup=30)
    return F.generate_sequence("s0", p, np.random.default_rng(0))


def test_save_load_round_trip_is_lossless(tmp_path):
    seq = _seq()
    S.save_sequence(tmp_path / "s0", seq)
    back = S.load_sequence(tmp_path / "s0")
    assert back.name == "s0" and len(back.sprites) == len(seq.sprites)
    for a, b in zip(seq.sprites, back.sprites):
        assert np.array_equal(a.over, b.over) and np.array_equal(a.emission, b.emission)
        assert np.array_equal(a.mask, b.mask)
    assert back.meta["params"]["rows"] == 40


def test_only_frames_with_smoke_write_a_smoke_layer_and_old_folders_still_load(tmp_path):
    smoky = _seq()
    clear = F.generate_sequence(
        "c", F.FlameParams(rows=40, cols=32, frames=40, keep_every=20, warmup=30, smoke=0.0), np.random.default_rng(0)
    )
    assert all(sp.over[..., 3].any() for sp in smoky.sprites) and not any(sp.over[..., 3].any() for sp in clear.sprites)
    S.save_sequence(tmp_path / "smoky", smoky)
    S.save_sequence(tmp_path / "clear", clear)
    assert len(list((tmp_path / "smoky").glob("*_smoke.png"))) == len(smoky.sprites)
    assert not list((tmp_path / "clear").glob("*_smoke.png")) and not list(tmp_path.rglob("*_over.png"))
    for folder in (tmp_path / "smoky", tmp_path / "clear"):  # no file a viewer shows as empty
        for path in folder.glob("*.png"):
            assert cv2.imread(str(path), cv2.IMREAD_UNCHANGED).max() > 0, path
    back = S.load_sequence(tmp_path / "clear")
    for a, b in zip(clear.sprites, back.sprites):  # loads as a transparent layer: composites the same
        assert not b.over.any() and np.array_equal(a.emission, b.emission) and np.array_equal(a.mask, b.mask)
    assert "NNNN_smoke.png" in back.meta["layers"]
    for path in sorted((tmp_path / "smoky").glob("*_smoke.png")):  # a folder from before the rename
        path.rename(path.with_name(path.name.replace("_smoke", "_over")))
    old = S.load_sequence(tmp_path / "smoky")
    assert all(np.array_equal(a.over, b.over) for a, b in zip(smoky.sprites, old.sprites))


def test_crop_to_content_keeps_every_visible_pixel():
    over = np.zeros((20, 30, 4), np.uint8)
    over[5:8, 10:12, 3] = 200
    emission = np.zeros((20, 30, 3), np.uint8)
    emission[12, 20] = 50
    sp = S.crop_to_content(S.Sprite(over, emission, np.zeros((20, 30), bool)), pad=0)
    assert sp.size == (11, 8)
    assert S.crop_to_content(S.Sprite(over * 0, emission * 0, np.zeros((20, 30), bool))) is None


def test_user_rgba_folder(tmp_path):
    rgba = np.zeros((40, 30, 4), np.uint8)
    rgba[10:30, 5:25] = (255, 160, 40, 255)  # bright orange flame
    rgba[2:10, 5:25] = (60, 60, 60, 150)  # grey smoke, not flame
    cv2.imwrite(str(tmp_path / "f0.png"), cv2.cvtColor(rgba, cv2.COLOR_RGBA2BGRA))
    seq = S.load_sequence(tmp_path)
    sp = seq.sprites[0]
    rows = np.nonzero(sp.mask.any(axis=1))[0]
    assert sp.mask.sum() == 20 * 20 and rows[0] == 1 + 8  # smoke rows are not flame (1 px crop pad)
    cv2.imwrite(str(tmp_path / "f1.png"), np.zeros((5, 5, 3), np.uint8))
    with pytest.raises(ImageError, match="no alpha"):
        S.load_sequence(tmp_path)
    with pytest.raises(FileNotFoundError):
        S.load_sequence(tmp_path / "missing")
