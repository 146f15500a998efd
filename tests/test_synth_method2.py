"""Method 2 end to end at toy size: exact boxes (audit mean IoU 1.0), byte-identical reruns, resume."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

from synth import flames as F
from synth import method2 as M
from synth.audit import audit_dataset
from synth.output import staging_dir

CFG = M.Method2Config(n=6, seed=3, width=96, height=72, scenes=2, images_per_view=3, max_flames=3, negatives=0.0)


@pytest.fixture(scope="module")
def library():
    p = F.FlameParams(rows=40, cols=28, frames=40, keep_every=20, warmup=30)
    return [F.generate_sequence(f"f{k}", p, np.random.default_rng(k)) for k in range(2)]


@pytest.fixture(scope="module")
def written(tmp_path_factory, library):
    out = tmp_path_factory.mktemp("m2") / "a"
    M.run_method2(CFG, library, out)
    return out


def _files(folder: Path) -> dict[str, bytes]:
    skip = {"manifest.json", "data.yaml"}  # these two name the output folder by absolute path
    return {
        p.relative_to(folder).as_posix(): p.read_bytes()
        for p in sorted(folder.rglob("*"))
        if p.is_file() and p.name not in skip
    }


def test_boxes_equal_the_final_mask_boxes(written):
    report = audit_dataset(written)
    assert report["images"] == CFG.n and report["boxes"] >= CFG.n
    assert report["mean_iou"] == 1.0 and report["min_iou"] == 1.0


def test_dataset_layout_and_manifest(written):
    coco = json.loads((written / "annotations.json").read_text())
    assert {img["source"] for img in coco["images"]} == {"synth:method2"}
    assert (written / "data.yaml").is_file() and (written / "contact_sheet.png").is_file()
    manifest = json.loads((written / "manifest.json").read_text())
    per_image = manifest["args"]["per_image"]
    assert len(per_image) == CFG.n and {"environment", "camera", "flames", "effects"} <= set(per_image[0])
    assert all(f["blend"] in ("screen", "add") for m in per_image for f in m["flames"])
    assert not staging_dir(written).exists()


def test_same_seed_gives_byte_identical_output_and_resume_matches(written, library, tmp_path):
    out = tmp_path / "b"
    staging = staging_dir(out)
    # interrupted run: only the first two images were staged
    from synth.output import Staging

    st = Staging(out)
    with M.render.Renderer(CFG.width, CFG.height) as r:
        views = M.ViewCache(CFG.seed, CFG.scenes, r)
        for i in range(2):
            st.save(i, *M.make_image(CFG, i, library, views))
    assert staging.is_dir()
    M.run_method2(CFG, library, out)
    assert _files(out) == _files(written)


def test_occluded_flames_lose_their_hidden_pixels():
    from synth.composite import Placement, composite
    from synth.sprites import Sprite

    over = np.zeros((10, 10, 4), np.uint8)
    emission = np.full((10, 10, 3), 200, np.uint8)
    sprite = Sprite(over, emission, np.ones((10, 10), bool))
    bg = np.zeros((20, 30, 3), np.uint8)
    image, masks = composite(
        bg, [Placement(sprite, 2, 2, 10, 10), Placement(sprite, 7, 2, 10, 10), Placement(sprite, 25, 15, 10, 10)]
    )
    assert masks[0].sum() == 50 and masks[1].sum() == 100  # the second flame hides half of the first
    assert masks[2].sum() == 5 * 5  # truncated at the image border
    assert image[5, 4].max() > 150
    with pytest.raises(ValueError, match="blend"):
        Placement(sprite, 0, 0, 5, 5, blend="multiply")
