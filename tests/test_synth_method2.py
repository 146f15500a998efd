"""Method 2 end to end at toy size: exact boxes (audit mean IoU 1.0), byte-identical reruns, resume."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest
from factories import dataset_files, tiny_flames

from synth import method2 as M
from synth.audit import audit_dataset
from synth.compose.metering import mean_linear_luma
from synth.flames import simulate as F
from synth.generate import generate
from synth.staging import staging_dir

CFG = M.Method2Config(n=6, seed=3, width=96, height=72, scenes=2, images_per_view=3, max_flames=3, negatives=0.0)


@pytest.fixture(scope="module")
def written(tmp_path_factory, library):
    out = tmp_path_factory.mktemp("m2") / "a"
    generate(CFG, library, out)
    return out


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
    from synth.staging import Staging

    st = Staging(out)
    with M.render.Renderer(CFG.width, CFG.height) as r:
        views = M.ViewCache(CFG.seed, CFG.scenes, r, surfaces=True)  # as generate() builds it
        for i in range(2):
            st.save(i, *M.make_image(CFG, i, library, views))
    assert staging.is_dir()
    generate(CFG, library, out)
    assert dataset_files(out) == dataset_files(written)


def test_smoke_class_boxes_come_from_the_smoke_masks(tmp_path):
    from dataclasses import replace

    smoky = tiny_flames(1, "smoky", smoke=4.0, soot=1.2)
    out = tmp_path / "smoke"
    generate(replace(CFG, n=4, smoke_class=True, max_flames=2), smoky, out)
    coco = json.loads((out / "annotations.json").read_text())
    assert [c["name"] for c in coco["categories"]] == ["fire", "smoke"]
    report = audit_dataset(out)
    assert report["mean_iou"] == 1.0 and report["smoke"]["boxes"] >= 1
    assert report["smoke"]["mean_iou"] == 1.0 and report["smoke"]["min_iou"] == 1.0
    assert len(list((out / "masks").glob("*.smoke.png"))) == 4


def test_flame_glow_and_opacity_are_drawn_in_their_ranges(library) -> None:
    depth = np.full((CFG.height, CFG.width), 4.0, np.float32)
    placed = [p for i in range(10) for p, _ in M.plan_flames(CFG, library, depth, 1.0, np.random.default_rng(i))]
    assert placed and all(M.FLAME_GLOW[0] <= p.glow <= M.FLAME_GLOW[1] for p in placed)
    assert all(M.FLAME_OPACITY[0] <= p.opacity <= M.FLAME_OPACITY[1] for p in placed)


def test_a_config_with_no_place_is_refused_unless_the_experiment_adds_its_own_frames() -> None:
    with pytest.raises(ValueError, match="nothing to composite on"):
        M.Method2Config(scenes=0)
    assert M.Method2Config(scenes=0, own_frames=1.0).own_frames == 1.0


def _plain_flame(colour: tuple[int, int, int]) -> F.Sprite:
    emission = np.zeros((12, 8, 3), np.uint8)
    emission[:] = colour
    return F.Sprite(np.zeros((12, 8, 4), np.uint8), emission, np.ones((12, 8), bool))


def test_an_unseen_flame_is_erased_and_a_seen_one_boxed():
    from synth.compose.composite import Placement
    from synth.compose.effects import Effects

    wall = np.full((40, 40, 3), 235, np.uint8)
    faint = (Placement(_plain_flame((40, 12, 0)), 4, 4, 8, 12, glow=0.3), "faint")
    bright = (Placement(_plain_flame((255, 200, 60)), 24, 20, 8, 12, glow=0.3), "bright")
    effects = Effects(noise_sigma=3.0, noise_seed=1, jpeg_quality=80)
    shown = M.visible_composite(wall, [faint, bright], effects, 4)
    seen = shown.seen
    assert [name for _, name in shown.flames] == ["bright"] and len(shown.result.flames) == len(seen) == 1
    assert seen[0].visible and M.mask_to_xywh(seen[0].part).tolist() == [24, 20, 8, 12]
    alone = M.visible_composite(wall, [bright], effects, 4).image
    assert np.array_equal(shown.image, alone)  # the faint flame and its glow are gone, not left unboxed
    none = M.visible_composite(wall, [faint], effects, 4)
    assert none.flames == [] and np.array_equal(none.image, M.apply_effects(wall, effects))


def test_audit_reports_the_visibility_of_the_boxes(written):
    v = audit_dataset(written)["visibility"]
    assert v["boxes"] == audit_dataset(written)["boxes"] and v["erased"] >= 0
    assert 10.0 <= v["min_contrast"] <= v["median_contrast"]  # every box is seen: ΔE >= MIN_DELTA_E


def test_labelled_frames_keep_their_fire_boxes_and_flames_stand_beside_them(tmp_path, library):
    """On labelled frames (synth.places.frames) each image's last boxes are its frame's own fires, cropped with it
    (unaudited, counted); every flame box is exact and overlaps none of them; the same seed, the same bytes."""
    from dataclasses import replace

    from factories import write_frames

    from ground.data.boxes import xywh_overlaps_any
    from ground.data.formats.coco import read_coco

    frames = write_frames(tmp_path)
    cfg = replace(CFG, n=8, scenes=0, labelled_frames=(frames,), width=128, height=96, images_per_view=1, max_flames=2)
    generate(cfg, library, tmp_path / "a")
    ds = read_coco(tmp_path / "a").dataset
    per_image = json.loads((tmp_path / "a" / "manifest.json").read_text())["args"]["per_image"]
    by_image = ds.annotations_by_image()
    flames = 0
    for img, meta in zip(ds.images, per_image):
        boxes = [list(a.bbox) for a in by_image[img.id]]
        own = meta["frame_boxes"]
        assert own and boxes[len(boxes) - len(own) :] == own and meta["photo"].startswith(frames.as_posix())
        flames += len(boxes) - len(own)
        assert not any(xywh_overlaps_any(b, own) for b in boxes[: len(boxes) - len(own)])
    report = audit_dataset(tmp_path / "a")
    assert flames >= 4 and report["boxes"] == flames and report["mean_iou"] == 1.0
    assert report["frame_boxes"] == sum(len(m["frame_boxes"]) for m in per_image)
    generate(cfg, library, tmp_path / "b")
    assert dataset_files(tmp_path / "a") == dataset_files(tmp_path / "b")


def test_no_plume_is_laid_over_a_labelled_frames_fire_or_smoke(tmp_path, library):
    """On labelled frames a lone plume's box overlaps none of the frame's own boxes, fire or smoke
    (synth.smoke.placement): a plume over a labelled fire would hide the fire its box still claims."""
    from dataclasses import replace

    from factories import write_frames

    from ground.data.boxes import xywh_overlaps_any
    from synth.smoke.library import SmokeConfig, smoke_library

    frames = write_frames(tmp_path, n=2, fire=(60, 40))  # fires over most of the ground
    cfg = replace(CFG, n=8, scenes=0, labelled_frames=(frames,), width=128, height=96, images_per_view=1,
                  negatives=1.0, smoke_class=True, smoke=SmokeConfig(alone=1.0, sequences=2, frames=2))  # fmt: skip
    generate(cfg, library + smoke_library(cfg.smoke), tmp_path / "a")
    coco = json.loads((tmp_path / "a" / "annotations.json").read_text())
    smoke_id = next(c["id"] for c in coco["categories"] if c["name"] == "smoke")
    per_image = json.loads((tmp_path / "a" / "manifest.json").read_text())["args"]["per_image"]
    laid = 0
    for img, meta in zip(coco["images"], per_image):
        smoke = [a["bbox"] for a in coco["annotations"] if a["image_id"] == img["id"] and a["category_id"] == smoke_id]
        plumes = smoke[: len(smoke) - len(meta["frame_smoke_boxes"])]  # the frame's own smoke boxes come last
        assert len(plumes) <= len(meta.get("plumes", []))
        assert not any(xywh_overlaps_any(b, meta["frame_boxes"] + meta["frame_smoke_boxes"]) for b in plumes)
        laid += len(plumes)
    assert laid >= 2  # the rule left room for plumes


def test_photo_negatives_leave_every_fire_free_photo_without_flames_and_the_rest_as_before(tmp_path, library):
    """``photo_negatives`` 1: every image on a backgrounds photo has no flame and no box; the renders keep flames
    (``negatives`` 0); unset, the same pool has flames on photos too; a labelled frame keeps ``negatives``."""
    from dataclasses import replace

    from factories import write_image

    for k in range(3):
        write_image(tmp_path / "photos" / f"p{k}.jpg", 200, 150, seed=k)
    cfg = replace(CFG, n=16, images_per_view=1, backgrounds=(tmp_path / "photos",), photo_share=0.5)
    kinds = {}
    for share in (None, 1.0):
        out = tmp_path / f"neg{share}"
        generate(replace(cfg, photo_negatives=share), library, out)
        per_image = json.loads((out / "manifest.json").read_text())["args"]["per_image"]
        kinds[share] = [("photo" in m, bool(m["flames"])) for m in per_image]
    assert [photo for photo, _ in kinds[None]] == [photo for photo, _ in kinds[1.0]]  # the same views
    assert {flames for photo, flames in kinds[1.0] if photo} == {False}
    assert any(flames for photo, flames in kinds[None] if photo) and all(f for p, f in kinds[1.0] if not p)
    frame = {"photo": "f.jpg", "frame_boxes": []}
    photos = (tmp_path / "photos",)
    assert M.negative_share(replace(CFG, photo_negatives=1.0, backgrounds=photos), frame) == CFG.negatives == 0.0
    assert M.negative_share(replace(CFG, photo_negatives=0.7, backgrounds=photos), {"photo": "p.jpg"}) == 0.7
    with pytest.raises(ValueError, match="photo_negatives"):
        M.Method2Config(photo_negatives=1.5)
    with pytest.raises(ValueError, match="photo_negatives is the share of the backgrounds photos"):
        M.Method2Config(photo_negatives=0.5)


def test_every_flame_is_screened_or_added_and_never_darkens_its_background(library):
    depth = np.full((CFG.height, CFG.width), 4.0, np.float32)
    placed = [p for i in range(5) for p, _ in M.plan_flames(CFG, library, depth, 1.0, np.random.default_rng(i))]
    assert placed and all(p.never_darken and p.blend in ("screen", "add") for p in placed)
    assert {p.blend for p in placed} == {"screen", "add"}


def test_auto_exposure_darkens_only_the_scene_of_fire_images_and_keeps_boxes_exact(written, library, tmp_path):
    """``auto_exposure``: the same flames, places and effects (its own rng), each fire image's scene metered down
    (``exposure_gain`` < 1 in the manifest), boxes still the final masks' boxes; off, the pool is as before."""
    from dataclasses import replace

    out = tmp_path / "ae"
    generate(replace(CFG, auto_exposure=True), library, out)
    assert audit_dataset(out)["min_iou"] == 1.0
    plain = json.loads((written / "manifest.json").read_text())["args"]["per_image"]
    metered = json.loads((out / "manifest.json").read_text())["args"]["per_image"]
    assert [m["effects"] for m in plain] == [m["effects"] for m in metered]
    assert [[f["flame"] for f in m["flames"]] for m in plain] == [[f["flame"] for f in m["flames"]] for m in metered]
    gains = [m["exposure_gain"] for m in metered if m["flames"]]
    assert gains and all(0.25 <= g < 1.0 for g in gains) and not any("exposure_gain" in m for m in plain)
    coco = json.loads((written / "annotations.json").read_text())
    images = [img["file_name"] for img in coco["images"]]
    darker = [
        mean_linear_luma(_read(out / "images" / Path(f).name))
        < mean_linear_luma(_read(written / "images" / Path(f).name))
        for f, m in zip(images, metered)
        if m["flames"] and m["exposure_gain"] < 0.9
    ]
    assert darker and all(darker)


def _read(path: Path) -> np.ndarray:
    import cv2

    return cv2.cvtColor(cv2.imread(str(path)), cv2.COLOR_BGR2RGB)


def test_n_images_on_at_least_n_photos_use_n_distinct_photos(tmp_path, library):
    """Each image on a photo gets a photo of its own (a crop is cheap): 12 images on 14 photos show 12 photos,
    though a rendered view carries 8 images; two processes write the same bytes as one."""
    from dataclasses import replace

    from factories import write_image

    for k in range(14):
        write_image(tmp_path / "photos" / f"p{k:02d}.jpg", 120, 90, seed=k)
    cfg = replace(CFG, n=32, scenes=0, images_per_view=8, backgrounds=(tmp_path / "photos",))
    one, two = tmp_path / "one", tmp_path / "two"
    generate(cfg, library, one)
    photos = [Path(m["photo"]).name for m in json.loads((one / "manifest.json").read_text())["args"]["per_image"]]
    assert len(set(photos[:12])) == 12 and len(set(photos[:14])) == 14  # every photo before any repeats
    assert photos[14:28] == photos[:14]
    generate(cfg, library, two, workers=2)
    assert dataset_files(one) == dataset_files(two)


def _plume(rgb: tuple[int, int, int], x: int = 10, y: int = 5):
    """A planned plume of a flat-coloured, dense plume sprite at (x, y), 24 x 30 px."""
    from dataclasses import replace

    from synth.smoke.placement import Plume, smoke_placement
    from synth.smoke.plume import plume_library

    sprite = plume_library(1, seed=0, frames=1)[0].sprites[0]
    over = sprite.over.copy()
    over[..., :3] = rgb
    flat = replace(sprite, over=over)
    return Plume(smoke_placement(flat, [x, y, 24, 30]), "plume/0", "sky", "grey")


def test_a_plume_on_a_sky_of_its_own_colour_gets_no_box_and_a_seen_one_is_boxed_where_seen():
    from synth.compose.effects import Effects

    sky = np.full((48, 48, 3), (150, 160, 170), np.uint8)
    effects = Effects(noise_sigma=2.0, noise_seed=1)
    same = M.visible_composite(sky, [], effects, 4, None, [_plume((150, 160, 170))], judge_smoke=True)
    assert same.plumes == [] and np.array_equal(same.image, M.apply_effects(sky, effects))  # erased, not unboxed
    dark = M.visible_composite(sky, [], effects, 4, None, [_plume((40, 40, 45))], judge_smoke=True)
    (seen,) = [v for v in dark.smoke if v is not None]
    assert len(dark.plumes) == 1 and seen.visible and seen.part.any()
    assert (seen.part <= dark.result.smoke[0]).all()  # the box covers the seen part of the smoke mask only
    assert (M.delta_e(dark.image, M.apply_effects(sky, effects))[seen.part] >= M.SMOKE_DELTA_E).all()
    unjudged = M.visible_composite(sky, [], effects, 4, None, [_plume((150, 160, 170))])
    assert len(unjudged.plumes) == 1 and unjudged.smoke == [None]  # a pool that boxes no smoke judges none


def test_a_pool_with_smoke_boxes_every_seen_plume_exactly_and_reruns_byte_identically(tmp_path, library):
    from dataclasses import replace

    from synth.smoke.library import SmokeConfig, smoke_library

    cfg = replace(CFG, n=6, smoke_class=True, smoke=SmokeConfig(above=1.0, alone=1.0, sequences=2, frames=2))
    full = library + smoke_library(cfg.smoke)
    generate(cfg, full, tmp_path / "a")
    report = audit_dataset(tmp_path / "a")
    assert report["smoke"]["boxes"] >= 3 and report["smoke"]["min_iou"] == 1.0 and report["min_iou"] == 1.0
    per_image = json.loads((tmp_path / "a" / "manifest.json").read_text())["args"]["per_image"]
    assert all("plumes" in m and m["plumes_erased"] >= 0 for m in per_image)
    assert {p["where"] for m in per_image for p in m["plumes"]} >= {"above"}
    generate(cfg, full, tmp_path / "b")
    assert dataset_files(tmp_path / "a") == dataset_files(tmp_path / "b")


def test_a_pool_that_boxes_smoke_keeps_its_frames_smoke_boxes_last_and_unaudited(tmp_path, library):
    from dataclasses import replace

    from factories import write_frames

    frames = write_frames(tmp_path)
    cfg = replace(CFG, n=4, scenes=0, labelled_frames=(frames,), width=128, height=96, images_per_view=1,
                  smoke_class=True)  # fmt: skip
    generate(cfg, library, tmp_path / "a")
    coco = json.loads((tmp_path / "a" / "annotations.json").read_text())
    smoke_id = next(c["id"] for c in coco["categories"] if c["name"] == "smoke")
    per_image = json.loads((tmp_path / "a" / "manifest.json").read_text())["args"]["per_image"]
    for img, meta in zip(coco["images"], per_image):
        smoke = [a["bbox"] for a in coco["annotations"] if a["image_id"] == img["id"] and a["category_id"] == smoke_id]
        own = meta["frame_smoke_boxes"]
        assert smoke[len(smoke) - len(own) :] == own  # the frame's own smoke, cropped with it, last
    assert sum(len(m["frame_smoke_boxes"]) for m in per_image) >= 2  # (a crop can cut the corner box off)
    report = audit_dataset(tmp_path / "a")
    assert report["smoke"]["min_iou"] == 1.0 and report["frame_boxes"] == sum(
        len(m["frame_boxes"]) + len(m["frame_smoke_boxes"]) for m in per_image
    )
