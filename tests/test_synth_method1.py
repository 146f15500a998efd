"""Method 1: planes in the 3D scene; paper boxes (projected corners) vs visible boxes (segmentation ∧ warped flame
mask ∧ occlusion); audit numbers, determinism, resume."""

from __future__ import annotations

import json

import cv2
import numpy as np
import pytest
import trimesh
from factories import dataset_files, tiny_flames

from ground.data.boxes import box_iou_xyxy, mask_to_xywh, xywh_to_xyxy
from synth import method1 as M
from synth.audit import audit_dataset
from synth.flames.sprites import Sprite
from synth.generate import generate
from synth.places import camera as C
from synth.places import render as R
from synth.places.scenes import translate
from synth.places.views import View, ViewCache
from synth.staging import Staging, staging_dir

CFG = M.Method1Config(n=6, seed=5, width=128, height=96, scenes=3, max_flames=3, negatives=0.0, min_box_px=2)
W, H = 128, 96


@pytest.fixture(scope="module")
def written(tmp_path_factory, library):
    out = tmp_path_factory.mktemp("m1") / "a"
    generate(CFG, library, out)
    return out


@pytest.fixture(scope="module")
def renderer():
    with R.Renderer(W, H) as r:
        yield r


def _sprite(h=40, w=30, flame_rows=slice(None), alpha=255):
    """An emissive sprite: flame (bright, opaque) in ``flame_rows``, faint smoke of ``alpha`` elsewhere."""
    over = np.zeros((h, w, 4), np.uint8)
    over[..., :3], over[..., 3] = 60, alpha
    emission = np.zeros((h, w, 3), np.uint8)
    mask = np.zeros((h, w), bool)
    mask[flame_rows] = True
    emission[mask] = (255, 160, 40)
    return Sprite(over, emission, mask)


def _view(renderer, occluders=()):
    """A test view: camera at (0, 1, 4) looking along -Z at a dark back wall at z = -3, optional occluding boxes
    given as (extents, centre)."""
    pr = renderer.pyrender
    scene = pr.Scene(bg_color=(0, 0, 0, 1), ambient_light=(0.3, 0.3, 0.3))
    wall = trimesh.creation.box((20, 10, 0.1))
    scene.add(pr.Mesh.from_trimesh(wall, smooth=False), pose=translate(0, 0, -3))
    for extents, centre in occluders:
        scene.add(pr.Mesh.from_trimesh(trimesh.creation.box(extents), smooth=False), pose=translate(*centre))
    cam = C.CameraView(R.look_at(np.array([0.0, 1.0, 4.0]), np.array([0.0, 1.0, 0.0])), np.pi / 3)
    depth = R.render_view(renderer, scene, cam.pose, cam.yfov, True)[1]
    return View(None, scene, cam, depth)  # type: ignore[arg-type]


def _boxes(renderer, view, planes):
    """(paper boxes, visible masks, coverage passes) of ``planes`` seen in ``view``."""
    k = R.intrinsics(view.camera.yfov, W, H)
    corners = [R.project(p.corners(), view.camera.pose, k)[:, :2] for p in planes]
    rgb, passes = M.render_planes(renderer, view, planes)
    layers = [M.plane_layers(p, c, W, H) for p, c in zip(planes, corners)]
    return [M.paper_box(c, W, H) for c in corners], M.visible_masks(layers, passes), passes, rgb


def _iou(a, b) -> float:
    return float(box_iou_xyxy(xywh_to_xyxy(a), xywh_to_xyxy(b))[0, 0])


def test_visible_boxes_are_exact_and_paper_boxes_are_not(written):
    report = audit_dataset(written)
    assert report["images"] == CFG.n and report["boxes"] >= CFG.n
    assert report["mean_iou"] == 1.0 and report["min_iou"] == 1.0
    modes = report["modes"]
    assert modes["visible"]["mean_iou"] == 1.0 and modes["visible"]["min_iou"] == 1.0
    assert modes["paper"]["boxes"] >= modes["visible"]["boxes"]
    assert modes["paper"]["mean_iou"] < 0.9  # semi-transparent margins and smoke inflate the paper's boxes


def test_paper_mode_writes_the_same_images_with_paper_boxes(written, library, tmp_path):
    from dataclasses import replace

    out = tmp_path / "paper"
    generate(replace(CFG, box_mode="paper"), library, out)
    a, b = dataset_files(written), dataset_files(out)
    assert {k: v for k, v in a.items() if k.startswith("images/")} == {
        k: v for k, v in b.items() if k.startswith("images/")
    }
    report = audit_dataset(out)
    assert report["mean_iou"] < 0.9 and report["modes"] == audit_dataset(written)["modes"]
    coco = json.loads((out / "annotations.json").read_text())
    assert {img["source"] for img in coco["images"]} == {"synth:method1"}


def test_dataset_layout_and_manifest(written):
    manifest = json.loads((written / "manifest.json").read_text())
    per_image = manifest["args"]["per_image"]
    assert len(per_image) == CFG.n and {"environment", "camera", "flames", "effects", "box_mode"} <= set(per_image[0])
    flame = per_image[0]["flames"][0]
    assert {"flame", "plane", "paper_box", "visible_box"} <= set(flame) and len(flame["plane"]["pose"]) == 4
    assert (written / "masks" / "box_modes.json").is_file()
    sheet = cv2.imread(str(written / "contact_sheet.png")).astype(int)
    yellow = (np.abs(sheet - (0, 220, 255)).max(axis=-1) < 40).sum()  # BGR: the paper boxes under the red ones
    red = (np.abs(sheet - (0, 0, 255)).max(axis=-1) < 40).sum()
    assert yellow > 50 and red > 50
    assert not staging_dir(written).exists()


def test_same_seed_gives_byte_identical_output_and_resume_matches(written, library, tmp_path):
    out = tmp_path / "b"
    st = Staging(out)  # an interrupted run: two images staged
    with R.Renderer(CFG.width, CFG.height) as r:
        views = ViewCache(CFG.seed, CFG.scenes, r)
        for i in (0, 3):
            st.save(i, *M.make_image(CFG, i, library, views))
    generate(CFG, library, out)
    assert dataset_files(out) == dataset_files(written)


def test_projected_corners_match_the_rendered_outline(renderer):
    view = _view(renderer)
    for yaw in (0.0, 35.0):
        plane = M.Plane(_sprite(), "t", translate(0.2, 0.3, 0.0, yaw_deg=yaw), 1.2, 1.5)
        (paper,), _, passes, _ = _boxes(renderer, view, [plane])
        drawn = mask_to_xywh(passes[0][0])
        assert np.abs(xywh_to_xyxy(drawn) - xywh_to_xyxy(paper)).max() <= 1.0, (yaw, drawn, paper)


def test_warped_flame_mask_lands_on_the_rendered_flame(renderer):
    """Flame only in the sprite's top half: the warped mask covers the top of the plane, where the render is bright."""
    view = _view(renderer)
    plane = M.Plane(_sprite(flame_rows=slice(0, 20), alpha=0), "t", translate(0, 0.3, 0, yaw_deg=20), 1.0, 1.4)
    (paper,), masks, passes, rgb = _boxes(renderer, view, [plane])
    vis = mask_to_xywh(masks[0])
    assert vis[1] == pytest.approx(paper[1], abs=1) and vis[3] == pytest.approx(paper[3] / 2, abs=1.5)
    inside = masks[0]
    outside = passes[0][0] & ~inside
    # the transparent half shows the grey wall (lit warm by the flame's light), far darker than the flame
    assert rgb[inside][:, 0].mean() > 200 and rgb[outside][:, 0].mean() < 0.6 * rgb[inside][:, 0].mean()


def test_semi_transparent_margins_make_paper_boxes_too_big(renderer):
    view = _view(renderer)
    plane = M.Plane(_sprite(flame_rows=slice(10, 40), alpha=40), "t", translate(0, 0.3, 0), 1.0, 1.4)
    (paper,), masks, _, _ = _boxes(renderer, view, [plane])
    assert _iou(paper, mask_to_xywh(masks[0])) == pytest.approx(30 / 40, abs=0.05)


def test_occluded_plane_gives_a_smaller_visible_box(renderer):
    plane = M.Plane(_sprite(), "t", translate(0, 0.3, 0), 1.0, 1.4)
    (free_paper,), free, _, _ = _boxes(renderer, _view(renderer), [plane])
    (hidden_paper,), hidden, _, _ = _boxes(renderer, _view(renderer, [((0.5, 3.0, 0.1), (-0.35, 1.0, 1.0))]), [plane])
    assert np.allclose(free_paper, hidden_paper)  # the paper's box ignores occlusion
    a, b = mask_to_xywh(free[0]), mask_to_xywh(hidden[0])
    assert _iou(a, free_paper) > 0.9
    assert b[2] < 0.7 * a[2] and b[0] > a[0] and b[0] + b[2] == a[0] + a[2]  # left part hidden, right edge kept


def test_nearer_planes_hide_only_with_their_opaque_parts(renderer):
    view = _view(renderer)
    back = M.Plane(_sprite(), "back", translate(0, 0.3, -1.0), 1.0, 1.4)
    opaque = M.Plane(_sprite(), "front", translate(-0.5, 0.3, 0.5), 0.8, 1.4)
    clear = M.Plane(_sprite(flame_rows=slice(0, 0), alpha=0), "glass", translate(-0.5, 0.3, 0.5), 0.8, 1.4)
    _, masks, passes, _ = _boxes(renderer, view, [back, opaque])
    alone = passes[0][0].sum()
    assert 0 < masks[0].sum() < 0.8 * alone and not (masks[0] & masks[1]).any()
    _, masks, _, _ = _boxes(renderer, view, [back, clear])
    assert masks[0].sum() >= alone - 2 and not masks[1].any()


def test_placement_follows_the_rules(renderer, library):
    cfg = M.Method1Config(width=W, height=H, yaw_jitter_deg=0.0, distance_m=(1.0, 30.0))
    view = _view(renderer)
    rng = np.random.default_rng(0)
    eye = view.camera.pose[:3, 3]
    for _ in range(10):
        plane = M.place_plane(cfg, library[0].sprites[0], view, rng)
        assert plane is not None
        normal = plane.pose[:3, 2]
        assert abs(normal[1]) < 1e-9  # upright
        to_eye = (eye - plane.pose[:3, 3]) * (1, 0, 1)
        assert np.dot(normal, to_eye / np.linalg.norm(to_eye)) == pytest.approx(1.0)  # faces the camera
        assert cfg.flame_height_m[0] <= plane.height <= cfg.flame_height_m[1]


def test_config_rejects_unknown_box_mode():
    with pytest.raises(ValueError, match="box mode"):
        M.Method1Config(box_mode="tight")


def test_smoke_class_boxes_come_from_the_visible_smoke(tmp_path):
    from dataclasses import replace

    smoky = tiny_flames(1, "smoky", smoke=4.0, soot=1.2)
    out = tmp_path / "smoke"
    generate(replace(CFG, n=3, smoke_class=True, max_flames=2), smoky, out)
    report = audit_dataset(out)
    assert report["mean_iou"] == 1.0 and report["smoke"]["boxes"] >= 1
    assert report["smoke"]["mean_iou"] == 1.0 and report["smoke"]["min_iou"] == 1.0


def test_smoke_mask_is_warped_like_the_flame(renderer):
    """Smoke above the flame in the sprite lands above it in the image; the occluder test applies to it too."""
    over = np.zeros((40, 30, 4), np.uint8)
    over[:20, :, 3] = 220
    sprite = _sprite(flame_rows=slice(20, 40), alpha=0)
    sprite = Sprite(over, sprite.emission, sprite.mask)
    plane = M.Plane(sprite, "t", translate(0, 0.3, 0), 1.0, 1.4)
    view = _view(renderer)
    k = R.intrinsics(view.camera.yfov, W, H)
    corners = R.project(plane.corners(), view.camera.pose, k)[:, :2]
    _, passes = M.render_planes(renderer, view, [plane])
    layers = [M.plane_layers(plane, corners, W, H)]
    smoke, flame = M.visible_masks(layers, passes, 2)[0], M.visible_masks(layers, passes, 0)[0]
    s, f = mask_to_xywh(smoke), mask_to_xywh(flame)
    assert s[1] + s[3] == f[1] and abs(s[3] - f[3]) <= 1 and not (smoke & flame).any()


def test_flames_light_their_surroundings_and_flicker_with_their_frames():
    from synth.flames.sprites import Sprite
    from synth.method1 import FLAME_LIGHT, Plane, flame_light

    def plane(value: int) -> Plane:
        emission = np.zeros((8, 4, 3), np.uint8)
        emission[..., 0], emission[..., 1] = value, value // 2
        sprite = Sprite(np.zeros((8, 4, 4), np.uint8), emission, np.ones((8, 4), bool))
        return Plane(sprite, "", np.eye(4), 0.5, 1.0)

    colour, bright = flame_light(plane(255))
    _, dim = flame_light(plane(102))
    assert np.allclose(colour, (1.0, 127 / 255, 0.0)) and bright == pytest.approx(FLAME_LIGHT * 1.0)
    assert dim == pytest.approx(0.4 * bright)
