"""Method 2 end to end at toy size: exact boxes (audit mean IoU 1.0), byte-identical reruns, resume."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

from synth import flames as F
from synth import method2 as M
from synth.audit import audit_dataset
from synth.blend import ALL_MODES, BlendConfig
from synth.distractors import DistractorConfig, overlaps
from synth.metering import mean_linear_luma
from synth.staging import staging_dir

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
    from synth.staging import Staging

    st = Staging(out)
    with M.render.Renderer(CFG.width, CFG.height) as r:
        views = M.ViewCache(CFG.seed, CFG.scenes, r, surfaces=CFG.stand == "surfaces")  # as generate() builds it
        for i in range(2):
            st.save(i, *M.make_image(CFG, i, library, views))
    assert staging.is_dir()
    M.run_method2(CFG, library, out)
    assert _files(out) == _files(written)


def test_smoke_class_boxes_come_from_the_smoke_masks(tmp_path):
    from dataclasses import replace

    p = F.FlameParams(rows=40, cols=28, frames=40, keep_every=20, warmup=30, smoke=4.0, soot=1.2)
    smoky = [F.generate_sequence("smoky", p, np.random.default_rng(0))]
    out = tmp_path / "smoke"
    M.run_method2(replace(CFG, n=4, smoke_class=True, max_flames=2), smoky, out)
    coco = json.loads((out / "annotations.json").read_text())
    assert [c["name"] for c in coco["categories"]] == ["fire", "smoke"]
    report = audit_dataset(out)
    assert report["mean_iou"] == 1.0 and report["smoke"]["boxes"] >= 1
    assert report["smoke"]["mean_iou"] == 1.0 and report["smoke"]["min_iou"] == 1.0
    assert len(list((out / "masks").glob("*.smoke.png"))) == 4


def test_closeups_frame_one_large_flame_at_the_bottom(library) -> None:
    from dataclasses import replace

    cfg = replace(CFG, closeup=1.0, closeup_height=(0.6, 1.0), max_flames=3)
    depth = np.full((cfg.height, cfg.width), 4.0, np.float32)
    for i in range(20):
        (placed,) = [p for p, _ in M.plan_flames(cfg, library, depth, 1.0, np.random.default_rng(i))]
        flame = placed.height * M.flame_extent(placed.sprite)[1] / placed.sprite.size[1]  # the flame, not its smoke
        assert 0.6 * cfg.height - 1 <= flame <= cfg.height + 1
        bottom = placed.y + placed.height
        assert 0.85 * cfg.height - 1 <= bottom <= 1.1 * cfg.height + 1
        assert cfg.width // 4 <= placed.x + placed.width // 2 <= 3 * cfg.width // 4 + 1
    far = [p for i in range(20) for p, _ in M.plan_flames(replace(CFG, negatives=0.0), library, depth, 1.0,
                                                          np.random.default_rng(i))]  # fmt: skip
    flames = [p.height * M.flame_extent(p.sprite)[1] / p.sprite.size[1] for p in far]
    assert max(flames) < 0.6 * cfg.height  # at 4 m the flames of 0.3-2.5 m stay smaller
    with pytest.raises(ValueError, match="closeup"):
        M.Method2Config(closeup=1.5)


def test_flame_glow_is_drawn_in_its_range(library) -> None:
    from dataclasses import replace

    cfg = replace(CFG, negatives=0.0, flame_glow=(0.7, 0.9))
    depth = np.full((cfg.height, cfg.width), 4.0, np.float32)
    glows = [p.glow for i in range(10) for p, _ in M.plan_flames(cfg, library, depth, 1.0, np.random.default_rng(i))]
    assert glows and all(0.7 <= g <= 0.9 for g in glows)
    with pytest.raises(ValueError, match="flame_glow"):
        M.Method2Config(flame_glow=(0.5, 0.2))


def test_log_flame_heights_stay_in_range_with_their_median_at_the_geometric_mean_and_draw_once() -> None:
    from dataclasses import replace

    cfg = replace(CFG, flame_height_m=(0.3, 2.7), flame_heights="log")
    rng, twin = np.random.default_rng(5), np.random.default_rng(5)
    logs = np.array([M.flame_height(cfg, rng) for _ in range(4000)])
    uniform = np.array([M.flame_height(replace(cfg, flame_heights="uniform"), twin) for _ in range(4000)])
    assert logs.min() >= 0.3 and logs.max() <= 2.7 and uniform.min() >= 0.3 and uniform.max() <= 2.7
    assert abs(np.median(logs) - 0.9) < 0.05  # sqrt(0.3 * 2.7): as many below 0.9 m as above
    assert abs(np.median(uniform) - 1.5) < 0.05
    assert rng.random() == twin.random()  # one draw each: a pool's other draws do not move
    with pytest.raises(ValueError, match="flame_heights"):
        M.Method2Config(flame_heights="normal")  # type: ignore[arg-type]


def test_separate_flames_never_overlap_on_a_site_and_the_default_draws_as_before(library) -> None:
    from dataclasses import replace

    cfg = replace(CFG, width=160, height=120, max_flames=3, negatives=0.0)
    depth = np.full((cfg.height, cfg.width), 3.0, np.float32)  # every pixel ground, 3 m away
    overlapping = 0
    for i in range(40):
        rng, twin = np.random.default_rng(i), np.random.default_rng(i)
        before = M.plan_flames(cfg, library, depth, 1.0, rng, avoid=[])
        assert before == M.plan_flames(replace(cfg, separate_flames=False), library, depth, 1.0, twin, avoid=[])
        apart = M.plan_flames(replace(cfg, separate_flames=True), library, depth, 1.0, np.random.default_rng(i), [])
        boxes = [M.mask_box(p) for p, _ in apart]
        for (p, _), (x, y, w, h) in zip(apart, boxes, strict=True):  # the box covers the mask as drawn
            rows, cols = np.nonzero(M.scaled_layers(p.sprite, p.width, p.height)[2])
            assert (
                x <= p.x + cols.min()
                and p.x + cols.max() < x + w
                and y <= p.y + rows.min()
                and p.y + rows.max() < y + h
            )
        assert apart and not any(overlaps(box, boxes[k + 1 :]) for k, box in enumerate(boxes)), (i, boxes)
        drawn = [M.mask_box(p) for p, _ in before]
        overlapping += any(overlaps(box, drawn[k + 1 :]) for k, box in enumerate(drawn))
    assert overlapping > 0  # without the key, flames do overlap on this crowded site


def test_frame_anchored_flames_stand_at_a_fires_foot_sized_like_it_and_the_default_draws_as_before(library) -> None:
    """``frame_anchored``: every flame on a frame with fires has its foot within ANCHOR_FOOT of a fire's foot and its
    height in ANCHOR_SCALE x that fire's height, clear of the fires; off, the anchors change nothing."""
    from dataclasses import replace

    cfg = replace(CFG, width=160, height=120, max_flames=3, negatives=0.0)
    depth = np.full((cfg.height, cfg.width), 3.0, np.float32)  # every pixel ground, 3 m away
    fires = [[10.0, 20.0, 20.0, 30.0], [120.0, 70.0, 16.0, 20.0]]  # feet at rows 50 and 90
    lo, hi = M.ANCHOR_SCALE
    feet = []
    for i in range(30):
        plain = M.plan_flames(cfg, library, depth, 1.0, np.random.default_rng(i), avoid=fires)
        assert plain == M.plan_flames(cfg, library, depth, 1.0, np.random.default_rng(i), fires, anchors=fires)
        spot = M.anchored_spot(fires, (1, 2), cfg, fires, np.random.default_rng(i))
        assert spot is not None
        bx, by, hpx = spot
        near = [f for f in fires if abs(by - (f[1] + f[3])) <= M.ANCHOR_FOOT * cfg.height + 1]
        assert near and any(lo * f[3] - 1 <= hpx <= hi * f[3] + 1 or hpx == 12 for f in near), (spot, near)
        assert not overlaps(M.flame_box(bx, by, hpx, (1, 2)), fires)
        on = replace(cfg, frame_anchored=True)
        anchored = M.plan_flames(on, library, depth, 1.0, np.random.default_rng(i), fires, anchors=fires)
        feet += [p.y + p.height for p, _ in anchored]  # where the sprite stands (its base row)
    reach = M.ANCHOR_FOOT * cfg.height + 1
    assert feet and all(any(abs(foot - (f[1] + f[3])) <= reach for f in fires) for foot in feet), feet
    assert (
        M.anchored_spot([[0.0, 0.0, 160.0, 120.0]], (1, 2), cfg, [[0, 0, 160, 120]], np.random.default_rng(0)) is None
    )


def test_a_config_with_no_place_is_refused_unless_the_experiment_adds_its_own_frames() -> None:
    with pytest.raises(ValueError, match="nothing to composite on"):
        M.Method2Config(scenes=0)
    assert M.Method2Config(scenes=0, own_frames=1.0).own_frames == 1.0


def _plain_flame(colour: tuple[int, int, int]) -> F.Sprite:
    emission = np.zeros((12, 8, 3), np.uint8)
    emission[:] = colour
    return F.Sprite(np.zeros((12, 8, 4), np.uint8), emission, np.ones((12, 8), bool))


def test_an_unseen_flame_is_erased_and_a_seen_one_boxed():
    from synth.composite import Placement
    from synth.effects import Effects

    wall = np.full((40, 40, 3), 235, np.uint8)
    faint = (Placement(_plain_flame((40, 12, 0)), 4, 4, 8, 12, glow=0.3), "faint")
    bright = (Placement(_plain_flame((255, 200, 60)), 24, 20, 8, 12, glow=0.3), "bright")
    effects = Effects(noise_sigma=3.0, noise_seed=1, jpeg_quality=80)
    image, result, shown, seen = M.visible_composite(wall, [faint, bright], effects, 4)
    assert [name for _, name in shown] == ["bright"] and len(result.flames) == len(seen) == 1
    assert seen[0].visible and M.mask_to_xywh(seen[0].part).tolist() == [24, 20, 8, 12]
    alone, *_ = M.visible_composite(wall, [bright], effects, 4)
    assert np.array_equal(image, alone)  # the faint flame and its glow are gone, not left unboxed
    plate, _, none, _ = M.visible_composite(wall, [faint], effects, 4)
    assert none == [] and np.array_equal(plate, M.apply_effects(wall, effects))


def test_audit_reports_the_visibility_of_the_boxes(written):
    v = audit_dataset(written)["visibility"]
    assert v["boxes"] == audit_dataset(written)["boxes"] and v["erased"] >= 0
    assert 10.0 <= v["min_contrast"] <= v["median_contrast"]  # every box is seen: ΔE >= MIN_DELTA_E


HARD = M.Method2Config(
    n=4, seed=3, width=96, height=72, scenes=1, images_per_view=2, max_flames=3, negatives=0.0,
    distractors=DistractorConfig(share=1.0, max=3), blend=BlendConfig(modes=ALL_MODES, harmonise=True,
                                                                      match_noise=True, decoys=1.0),
)  # fmt: skip


@pytest.fixture(scope="module")
def hard(tmp_path_factory, library):
    out = tmp_path_factory.mktemp("m2hard") / "a"
    M.run_method2(HARD, library, out)
    return out


def test_distractors_and_every_blend_keep_exact_boxes_and_get_none(hard):
    """Audit IoU 1.000 with every blend mode, decoys and distractors; neither has a box or overlaps one."""
    report = audit_dataset(hard)
    assert report["boxes"] > 0 and report["min_iou"] == 1.0 and report["mean_iou"] == 1.0
    per_image = json.loads((hard / "manifest.json").read_text())["args"]["per_image"]
    coco = json.loads((hard / "annotations.json").read_text())
    assert sum(len(m["distractors"]) for m in per_image) > 0 and all("decoys" in m for m in per_image)
    for k, meta in enumerate(per_image):
        boxes = [a["bbox"] for a in coco["annotations"] if a["image_id"] == coco["images"][k]["id"]]
        assert len(boxes) == len(meta["flames"])
        for thing in meta["distractors"] + meta["decoys"]:
            assert not overlaps(thing["box"], boxes)
    assert {f["blend"] for m in per_image for f in m["flames"]} <= set(ALL_MODES)


def test_distractors_leave_the_flames_as_they_were(written, hard, library, tmp_path):
    """The extra rng: distractors (no blend changes) keep every flame, box and camera effect of the default run;
    and a rerun of the hard config is byte-identical."""
    from dataclasses import replace

    only = tmp_path / "only"
    M.run_method2(replace(CFG, distractors=DistractorConfig(share=1.0)), library, only)
    for name in ("annotations.json",):
        assert (only / name).read_bytes() == (written / name).read_bytes()
    plain = json.loads((written / "manifest.json").read_text())["args"]["per_image"]
    dressed = json.loads((only / "manifest.json").read_text())["args"]["per_image"]
    assert any(m["distractors"] for m in dressed) and not any("distractors" in m for m in plain)

    def drop(flames, key="contrast"):
        return [{k: v for k, v in f.items() if k != key} for f in flames]

    assert [drop(m["flames"]) for m in plain] == [drop(m["flames"]) for m in dressed]
    contrast = [
        (f["contrast"], g["contrast"]) for a, b in zip(plain, dressed) for f, g in zip(a["flames"], b["flames"])
    ]
    assert max(abs(a - b) for a, b in contrast) < 1.0  # a lamp's bloom may reach the ring a flame's contrast is read on
    assert [m["effects"] for m in plain] == [m["effects"] for m in dressed]
    again = tmp_path / "again"
    M.run_method2(HARD, library, again)
    assert _files(again) == _files(hard)


def test_jittered_flames_keep_exact_boxes_the_same_flames_and_effects_and_change_their_widths(
    written, library, tmp_path
):
    """flame_jitter: the same flames, views and camera effects as without it (its own rng), each flame mirrored,
    stretched and recoloured; boxes still exact (audit IoU 1.000)."""
    from dataclasses import replace

    out = tmp_path / "jitter"
    M.run_method2(replace(CFG, flame_jitter=True), library, out)
    report = audit_dataset(out)
    assert report["boxes"] > 0 and report["min_iou"] == 1.0
    plain = json.loads((written / "manifest.json").read_text())["args"]["per_image"]
    varied = json.loads((out / "manifest.json").read_text())["args"]["per_image"]
    assert [m["effects"] for m in plain] == [m["effects"] for m in varied]
    names = lambda per_image: [[(f["flame"], f["blend"]) for f in m["flames"]] for m in per_image]  # noqa: E731
    assert sum(map(len, names(plain))) > 0 and names(varied) == names(plain)
    widths = lambda folder: [a["bbox"][2] for a in json.loads((folder / "annotations.json").read_text())["annotations"]]  # noqa: E731
    assert widths(out) != widths(written)
    planned = M.plan_flames(
        CFG, library, np.full((CFG.height, CFG.width), 4.0, np.float32), 1.0, np.random.default_rng(0)
    )
    for (p, name), (q, same) in zip(planned, M.varied(planned, np.random.default_rng(1)), strict=True):
        assert (
            name == same and q.height == p.height and q.y == p.y and abs((q.x + q.width / 2) - (p.x + p.width / 2)) <= 1
        )


def test_distractors_never_cover_a_photo_sites_people():
    """A site's people boxes are avoided like flames: nothing fire-like is drawn on a person."""
    from dataclasses import replace

    from synth.effects import Effects

    cfg = replace(CFG, width=128, height=96, distractors=DistractorConfig(share=1.0, max=3))
    rng = np.random.default_rng(0)
    background = rng.integers(60, 200, (96, 128, 3), dtype=np.uint8)
    depth = np.zeros((96, 128), np.float32)
    depth[40:] = np.linspace(20.0, 3.0, 56, dtype=np.float32)[:, None]  # ground below the horizon
    person = [30, 20, 40, 76]
    drawn = 0
    for seed in range(20):
        meta = {"horizon": 40 / 96, "site": True, "people": [person], "camera": {"yfov": 1.0}}
        _, added = M.dressed_scene(cfg, background, depth, meta, [], [], Effects(), 100.0, np.random.default_rng(seed))
        drawn += len(added["distractors"])
        assert all(not overlaps(d["box"], [person]) for d in added["distractors"])
    assert drawn >= 10


def test_labelled_frames_keep_their_fire_boxes_and_flames_stand_beside_them(tmp_path, library):
    """On labelled frames (synth.frames) each image's last boxes are its frame's own fires, cropped with it
    (unaudited, counted); every flame box is exact and overlaps none of them; the same seed, the same bytes."""
    from dataclasses import replace

    from factories import write_frames

    from curate.core.formats.coco import read_coco
    from synth.distractors import overlaps

    frames = write_frames(tmp_path)
    cfg = replace(CFG, n=8, scenes=0, frames=(frames,), width=128, height=96, images_per_view=1, max_flames=2)
    M.run_method2(cfg, library, tmp_path / "a")
    ds = read_coco(tmp_path / "a").dataset
    per_image = json.loads((tmp_path / "a" / "manifest.json").read_text())["args"]["per_image"]
    by_image = ds.annotations_by_image()
    flames = 0
    for img, meta in zip(ds.images, per_image):
        boxes = [list(a.bbox) for a in by_image[img.id]]
        own = meta["frame_boxes"]
        assert own and boxes[len(boxes) - len(own) :] == own and meta["photo"].startswith(frames.as_posix())
        flames += len(boxes) - len(own)
        assert not any(overlaps(b, own) for b in boxes[: len(boxes) - len(own)])
    report = audit_dataset(tmp_path / "a")
    assert flames >= 4 and report["boxes"] == flames and report["mean_iou"] == 1.0
    assert report["frame_boxes"] == sum(len(m["frame_boxes"]) for m in per_image)
    M.run_method2(cfg, library, tmp_path / "b")
    assert _files(tmp_path / "a") == _files(tmp_path / "b")


def test_frame_anchored_pools_keep_exact_boxes_and_their_bytes(tmp_path, library):
    """``frame_anchored`` end to end on labelled frames: every flame box exact (audit IoU 1.000), the frames' own
    fire boxes carried, the same seed the same bytes."""
    from dataclasses import replace

    from factories import write_frames

    frames = write_frames(tmp_path)
    cfg = replace(CFG, n=8, scenes=0, frames=(frames,), width=128, height=96, images_per_view=1, max_flames=2)
    on = replace(cfg, frame_anchored=True)
    M.run_method2(on, library, tmp_path / "a")
    per_image = json.loads((tmp_path / "a" / "manifest.json").read_text())["args"]["per_image"]
    report = audit_dataset(tmp_path / "a")
    assert report["boxes"] == sum(len(m["flames"]) for m in per_image) > 0 and report["mean_iou"] == 1.0
    assert report["frame_boxes"] == sum(len(m["frame_boxes"]) for m in per_image) > 0
    M.run_method2(on, library, tmp_path / "b")
    assert _files(tmp_path / "a") == _files(tmp_path / "b")


def test_swapped_frames_lose_their_own_fires_and_box_the_flames_drawn_in_their_place(tmp_path, library):
    """``frame_swap`` 1: every frame's fires are erased (no frame box is carried) and a flame is drawn over each
    box (``swapped`` counts them), boxed exactly by what is seen of it; the views and camera effects are the same
    as without the key (its own rng), and the same seed gives the same bytes."""
    from dataclasses import replace

    from factories import write_frames

    frames = write_frames(tmp_path)
    cfg = replace(CFG, n=6, scenes=0, frames=(frames,), width=128, height=96, images_per_view=1, max_flames=1)
    M.run_method2(cfg, library, tmp_path / "kept")
    M.run_method2(replace(cfg, frame_swap=1.0), library, tmp_path / "a")
    kept = json.loads((tmp_path / "kept" / "manifest.json").read_text())["args"]["per_image"]
    swapped = json.loads((tmp_path / "a" / "manifest.json").read_text())["args"]["per_image"]
    assert [m["photo"] for m in swapped] == [m["photo"] for m in kept]
    assert [m["effects"] for m in swapped] == [m["effects"] for m in kept]
    for before, after in zip(kept, swapped, strict=True):
        assert after["frame_boxes"] == [] and after["swapped"] == len(before["frame_boxes"]) > 0
        assert len(after["flames"]) + after["erased"] >= after["swapped"]
    report = audit_dataset(tmp_path / "a")
    assert report.get("frame_boxes", 0) == 0 and report["boxes"] == sum(len(m["flames"]) for m in swapped) > 0
    assert report["mean_iou"] == 1.0 and report["min_iou"] == 1.0
    M.run_method2(replace(cfg, frame_swap=1.0), library, tmp_path / "b")
    assert _files(tmp_path / "a") == _files(tmp_path / "b")
    with pytest.raises(ValueError, match="frame_swap"):
        replace(cfg, frame_swap=1.5)


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
        M.run_method2(replace(cfg, photo_negatives=share), library, out)
        per_image = json.loads((out / "manifest.json").read_text())["args"]["per_image"]
        kinds[share] = [("photo" in m, bool(m["flames"])) for m in per_image]
    assert [photo for photo, _ in kinds[None]] == [photo for photo, _ in kinds[1.0]]  # the same views
    assert {flames for photo, flames in kinds[1.0] if photo} == {False}
    assert any(flames for photo, flames in kinds[None] if photo) and all(f for p, f in kinds[1.0] if not p)
    frame = {"photo": "f.jpg", "frame_boxes": []}
    assert M.negative_share(replace(CFG, photo_negatives=1.0), frame) == CFG.negatives == 0.0
    assert M.negative_share(replace(CFG, photo_negatives=0.7), {"photo": "p.jpg"}) == 0.7
    with pytest.raises(ValueError, match="photo_negatives"):
        M.Method2Config(photo_negatives=1.5)


def test_n_images_on_at_least_n_photos_use_n_distinct_photos(tmp_path, library):
    """Each image on a photo gets a photo of its own (a crop is cheap): 12 images on 14 photos show 12 photos,
    though a rendered view carries 8 images; two processes write the same bytes as one."""
    from dataclasses import replace

    from factories import write_image

    for k in range(14):
        write_image(tmp_path / "photos" / f"p{k:02d}.jpg", 120, 90, seed=k)
    cfg = replace(CFG, n=32, scenes=0, images_per_view=8, backgrounds=(tmp_path / "photos",))
    one, two = tmp_path / "one", tmp_path / "two"
    M.run_method2(cfg, library, one)
    photos = [Path(m["photo"]).name for m in json.loads((one / "manifest.json").read_text())["args"]["per_image"]]
    assert len(set(photos[:12])) == 12 and len(set(photos[:14])) == 14  # every photo before any repeats
    assert photos[14:28] == photos[:14]
    M.run_method2(cfg, library, two, workers=2)
    assert _files(one) == _files(two)


def test_the_flames_of_a_pool_carry_its_compositing_rule(library):
    from dataclasses import replace

    depth = np.full((CFG.height, CFG.width), 4.0, np.float32)
    cfg = replace(CFG, never_darken=True, opaque_body=True)
    placed = [p for i in range(5) for p, _ in M.plan_flames(cfg, library, depth, 1.0, np.random.default_rng(i))]
    assert placed and all(p.never_darken and p.opaque_body for p in placed)


def test_source_box_is_the_placed_canvas_and_keeps_the_margins_of_a_partly_seen_flame():
    from synth.composite import Placement
    from synth.sprites import Sprite

    mask = np.zeros((30, 20), bool)
    mask[5:27, 4:16] = True  # flame rows 5..26, cols 4..15 of a 20 x 30 canvas
    sprite = Sprite(np.zeros((30, 20, 4), np.uint8), np.zeros((30, 20, 3), np.uint8), mask)
    p = Placement(sprite, 10, 8, 40, 60)  # scaled 2x
    part = np.zeros((100, 100), bool)
    part[8 + 10 : 8 + 54, 10 + 8 : 10 + 32] = True  # the whole flame, seen
    assert M.source_box(p, part) == [10, 8, 40, 60]
    lower = part.copy()
    lower[: 8 + 30] = False  # its top hidden: the seen part grows by the same margins
    assert M.source_box(p, lower) == [10, 8 + 30 - 10, 40, 60 - 30 + 10]
    edge = Placement(sprite, -20, 70, 40, 60)  # half outside the image: clipped to it
    seen = np.zeros((100, 100), bool)
    seen[80:100, 0:12] = True
    x, y, w, h = M.source_box(edge, seen)
    assert (x, y, x + w, y + h) == (0, 70, 20, 100)
    with pytest.raises(ValueError, match="cutout_box"):
        M.Method2Config(cutout_box="canvas")


def test_cutout_boxes_are_the_annotators_with_source_and_the_flame_pixels_without(tmp_path, library):
    """``cutout_box: source``: each cut-out flame's box holds its seen flame pixels (the mask kept beside the image)
    and the margin its annotator drew around them, so the audit finds it larger than the mask box; simulated
    flames in the same pool keep their exact mask boxes; the default pool is unchanged by the key's existence."""
    from dataclasses import replace

    from test_synth_library import _cutout_folder

    from curate.core.boxes import mask_to_xywh
    from synth.library import cutout_library

    folder = _cutout_folder(tmp_path / "cut")
    cfg = replace(CFG, n=8, images_per_view=1, max_flames=2)
    runs = {}
    for rule in ("mask", "source"):
        lib = cutout_library(folder, canvas=rule == "source") + list(library)
        M.run_method2(replace(cfg, cutout_box=rule), lib, tmp_path / rule)
        runs[rule] = audit_dataset(tmp_path / rule)
    assert runs["mask"]["mean_iou"] == 1.0 and runs["source"]["mean_iou"] < 0.95
    coco = json.loads((tmp_path / "source" / "annotations.json").read_text())
    per_image = json.loads((tmp_path / "source" / "manifest.json").read_text())["args"]["per_image"]
    by_image: dict[int, list] = {}
    for a in coco["annotations"]:
        by_image.setdefault(a["image_id"], []).append(a["bbox"])
    cut = sim = 0
    import cv2

    for img, meta in zip(coco["images"], per_image):
        labels = cv2.imread(str(tmp_path / "source" / "masks" / (Path(img["file_name"]).stem + ".png")), -1)
        for k, (box, flame) in enumerate(zip(by_image.get(img["id"], []), meta["flames"])):
            x, y, w, h = mask_to_xywh(labels == k + 1)
            inside = box[0] <= x and box[1] <= y and x + w <= box[0] + box[2] and y + h <= box[1] + box[3]
            assert inside and box[0] >= 0 and box[1] >= 0 and box[0] + box[2] <= cfg.width
            if flame["flame"].startswith("real-"):
                cut += box[2] * box[3] > w * h
            else:
                sim += list(box) == [x, y, w, h]
    assert cut >= 3 and sim >= 1


def test_a_cutout_is_never_drawn_above_its_upscale_cap_and_simulated_flames_are_as_drawn(tmp_path, library):
    """``cutout_max_upscale``: a real cut-out's drawn flame height is capped at the cap x its flame's own pixel
    height (a 28 px flame at 2x: 56 px at most); simulated flames, and every flame without a cap, keep their draw."""
    from dataclasses import replace

    from test_synth_library import _cutout_folder

    from synth.library import cutout_library

    cut = cutout_library(_cutout_folder(tmp_path / "cut"))[0]
    own = M.flame_extent(cut.sprites[0])[1]
    capped = replace(CFG, cutout_max_upscale=2.0)
    assert M.capped_height(capped, cut, cut.sprites[0], 300) == 2 * own
    assert M.capped_height(capped, cut, cut.sprites[0], 40) == 40
    assert M.capped_height(CFG, cut, cut.sprites[0], 300) == 300
    assert M.capped_height(capped, library[0], library[0].sprites[0], 300) == 300
    depth = np.full((CFG.height, CFG.width), 0.5, np.float32)  # near: flames drawn tall
    placed = [p for i in range(20) for p, _ in M.plan_flames(capped, [cut], depth, 1.0, np.random.default_rng(i))]
    assert placed and max(p.height for p in placed) <= 2 * cut.sprites[0].size[1]
    with pytest.raises(ValueError, match="cutout_max_upscale"):
        M.Method2Config(cutout_max_upscale=0.0)


def test_photo_distractors_are_cut_from_the_pools_fire_free_photos_and_get_no_box(tmp_path, library):
    """``distractors.kinds: [photo]``: images carry fire-like regions of the pool's own photos (never of a held-out
    photo), none boxed, none over a flame; the flames' boxes stay exact; the kind needs backgrounds."""
    from dataclasses import replace

    import cv2

    (tmp_path / "photos").mkdir()
    for k in range(3):
        photo = np.full((150, 200, 3), 60 + 20 * k, np.uint8)
        cv2.circle(photo, (60 + 30 * k, 50), 18, (30, 90, 230), -1)  # BGR: an orange disc, a lamp shade
        cv2.imwrite(str(tmp_path / "photos" / f"p{k}.png"), photo)
    from curate.core.holdout import held_out

    distractors = DistractorConfig(share=1.0, max=2, kinds=("photo",))
    cfg = replace(CFG, n=8, images_per_view=2, scenes=0, backgrounds=(tmp_path / "photos",), distractors=distractors,
                  background_holdout=0.4)  # fmt: skip
    kept = {p.name for p in (tmp_path / "photos").iterdir() if not held_out(p, 0.4)}
    assert 0 < len(kept) < 3  # the test needs a held-out photo and a kept one
    M.run_method2(cfg, library, tmp_path / "a")
    per_image = json.loads((tmp_path / "a" / "manifest.json").read_text())["args"]["per_image"]
    items = [d for m in per_image for d in m["distractors"]]
    assert len(items) >= 4 and {d["kind"] for d in items} == {"photo"} and {d["photo"] for d in items} <= kept
    coco = json.loads((tmp_path / "a" / "annotations.json").read_text())
    for img, m in zip(coco["images"], per_image):
        boxes = [a["bbox"] for a in coco["annotations"] if a["image_id"] == img["id"]]
        assert len(boxes) == len(m["flames"])  # a distractor gets no box
        assert not any(overlaps(d["box"], boxes) for d in m["distractors"])
    report = audit_dataset(tmp_path / "a")
    assert report["mean_iou"] == 1.0 and report["boxes"] == sum(len(m["flames"]) for m in per_image)
    M.run_method2(cfg, library, tmp_path / "b")
    assert _files(tmp_path / "a") == _files(tmp_path / "b")
    with pytest.raises(ValueError, match="kind photo"):
        replace(CFG, distractors=distractors)


def test_auto_exposure_darkens_only_the_scene_of_fire_images_and_keeps_boxes_exact(written, library, tmp_path):
    """``auto_exposure``: the same flames, places and effects (its own rng), each fire image's scene metered down
    (``exposure_gain`` < 1 in the manifest), boxes still the final masks' boxes; off, the pool is as before."""
    from dataclasses import replace

    out = tmp_path / "ae"
    M.run_method2(replace(CFG, auto_exposure=True), library, out)
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


def test_light_distractors_are_cut_from_the_pools_photos_with_their_glow_and_get_no_box(tmp_path, library):
    """``distractors.kinds: [photo, lights]``: a pool of lamp-lit photos carries their light sources, cut by the
    ``lights`` rule, unboxed and clear of the flames; the audit stays exact."""
    from dataclasses import replace

    import cv2

    (tmp_path / "photos").mkdir()
    y, x = np.mgrid[0:150, 0:200]
    for k in range(3):
        glow = np.exp(-0.5 * (((x - 60 - 30 * k) / 20.0) ** 2 + ((y - 50) / 20.0) ** 2))[..., None]
        photo = np.clip(np.array([35, 50, 70], np.float32) + glow * np.array([40, 110, 180], np.float32), 0, 255)
        photo[40:60, 52 + 30 * k : 68 + 30 * k] = 255  # BGR: a blown-out lamp shade in its warm glow
        cv2.imwrite(str(tmp_path / "photos" / f"p{k}.png"), photo.astype(np.uint8))
    distractors = DistractorConfig(share=1.0, max=2, kinds=("photo", "lights"))
    cfg = replace(CFG, n=8, images_per_view=2, scenes=0, backgrounds=(tmp_path / "photos",), distractors=distractors)
    M.run_method2(cfg, library, tmp_path / "a")
    per_image = json.loads((tmp_path / "a" / "manifest.json").read_text())["args"]["per_image"]
    items = [d for m in per_image for d in m["distractors"]]
    assert "lights" in {d["kind"] for d in items} and {d["kind"] for d in items} <= {"photo", "lights"}
    coco = json.loads((tmp_path / "a" / "annotations.json").read_text())
    for img, m in zip(coco["images"], per_image, strict=True):
        boxes = [a["bbox"] for a in coco["annotations"] if a["image_id"] == img["id"]]
        assert len(boxes) == len(m["flames"]) and not any(overlaps(d["box"], boxes) for d in m["distractors"])
    assert audit_dataset(tmp_path / "a")["mean_iou"] == 1.0
