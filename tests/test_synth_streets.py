"""Kit streets (synth/streets.py) on tiny generated kits: deterministic layouts, nothing on the carriageway,
buildings facing the road, flames standing on the up-facing ground of the fire zones, exact boxes; and a few
Method 2 images from the real Kenney kits (slow, skipped without ../shared/data)."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest
from factories import write_tiny_kits

from synth import flames as F
from synth import render, streets
from synth.audit import audit_dataset
from synth.kits import find_kits, load_kit
from synth.method1 import Method1Config, run_method1
from synth.method2 import Method2Config, run_method2
from synth.standing import ZONE_TOP_M, standing_mask, world_points, zone_mask
from synth.views import ViewCache

BUILDINGS = ("house", "building")


@pytest.fixture(scope="module")
def kit_root(tmp_path_factory) -> Path:
    return write_tiny_kits(tmp_path_factory.mktemp("kits"))


@pytest.fixture(scope="module")
def kits(kit_root):
    return [load_kit(folder) for folder in find_kits([kit_root])]


@pytest.fixture(scope="module")
def library():
    p = F.FlameParams(rows=40, cols=28, frames=40, keep_every=20, warmup=30)
    return [F.generate_sequence(f"f{k}", p, np.random.default_rng(k)) for k in range(2)]


def _summary(layout: streets.StreetLayout) -> list[tuple]:
    return [(p.role, p.part.kit, p.part.name, np.round(p.pose, 9).tobytes()) for p in layout.placements]


def test_the_same_seed_lays_out_the_same_street(kits) -> None:
    first, again = streets.lay_out_street(kits, 3, 7), streets.lay_out_street(kits, 3, 7)
    assert _summary(first) == _summary(again) and first.zones == again.zones
    assert _summary(first) != _summary(streets.lay_out_street(kits, 3, 8))
    assert {streets.lay_out_street(kits, k, 0).kit.name for k in range(2)} == {k.name for k in kits}


def test_parts_stay_off_the_road_and_buildings_do_not_overlap(kits) -> None:
    for index in range(6):
        layout = streets.lay_out_street(kits, index, 0)
        road = (-np.inf, np.inf, -layout.road_half, layout.road_half)
        props = [p for p in layout.placements if p.role != "road"]
        assert props and not any(streets.overlaps(p.rect(), road) for p in props)
        shells = [p.rect() for p in props if p.role == "house"]  # whole houses: none may touch another
        assert not any(streets.overlaps(a, b) for k, a in enumerate(shells) for b in shells[k + 1 :])
        blocks = [p for p in props if p.role == "building"]  # wall blocks stack: none may share a storey
        cells = [(round(p.rect()[0], 3), round(p.rect()[2], 3), round(p.pose[1, 3], 3)) for p in blocks]
        assert len(cells) == len(set(cells))


def test_buildings_face_the_road(kits) -> None:
    for index in range(4):
        layout = streets.lay_out_street(kits, index, 0)
        fronts = [p for p in layout.placements if p.role in BUILDINGS]
        assert fronts
        for p in fronts:
            centre_z = p.pose[2, 3]
            assert np.sign(p.front()[2]) == -np.sign(centre_z)  # the facade's normal points at the road
            mesh, pose = p.part.meshes[0]
            door = mesh.vertices[np.abs(mesh.vertices[:, 2]).argmax()]  # the facade slab sticks out furthest
            world = p.pose @ pose @ np.array([*door, 1.0])
            assert abs(world[2]) < abs(centre_z)  # ... on the side nearer the road


def test_fire_zones_are_in_front_of_facades_and_bins(kits) -> None:
    layout = streets.lay_out_street(kits, 1, 0)  # a terrace street: facades on the pavement's edge
    for p in (p for p in layout.placements if p.role == "building" and p.pose[1, 3] == 0.0):
        x0, x1, z0, z1 = p.rect()
        facade = z1 if p.pose[2, 3] < 0 else z0
        at = ((x0 + x1) / 2, facade - np.sign(p.pose[2, 3]) * 1.0)  # 1 m in front of the facade
        assert any(a <= at[0] <= b and c <= at[1] <= d for a, b, c, d in layout.zones)
    for p in (p for q in range(4) for p in streets.lay_out_street(kits, q, 0).placements if p.role == "bin"):
        x0, x1, z0, z1 = p.rect()
        assert x1 > x0 and z1 > z0


def test_flames_stand_on_up_facing_ground_of_the_fire_zones(kits) -> None:
    with render.Renderer(96, 72) as renderer:
        views = ViewCache(0, 0, renderer, views=4, kits=kits, streets_count=2)
        for v in range(4):
            _, depth, meta = views.background(v)
            view = views.view(v)
            assert meta["kind"] == "street" and meta["site"] == "surfaces" and (depth > 0).any()
            cam = view.camera
            up = standing_mask(view.depth, cam.pose, cam.yfov)
            points = world_points(view.depth, cam.pose, cam.yfov)
            assert np.all(up[depth > 0])  # every pixel a flame may stand on faces up
            assert np.all(zone_mask(points, view.env.zones)[depth > 0])  # and lies in a fire zone
            assert points[depth > 0][:, 1].max() <= ZONE_TOP_M


def test_method2_on_kit_streets_is_exact_deterministic_and_credits_the_kits(kit_root, library, tmp_path) -> None:
    streets_of_kits = {"scenes": 0, "streets": 2, "kits": (kit_root,)}
    cfg = Method2Config(n=6, seed=1, width=96, height=72, images_per_view=2, negatives=0.0, **streets_of_kits)
    run_method2(cfg, library, tmp_path / "a")
    report = audit_dataset(tmp_path / "a")
    assert report["boxes"] >= 1 and report["mean_iou"] == 1.0 and report["min_iou"] == 1.0
    manifest = json.loads((tmp_path / "a" / "manifest.json").read_text())
    assert {m["kind"] for m in manifest["args"]["per_image"]} == {"street"}
    assert [c["kit"] for c in manifest["args"]["kit_credits"]] == ["kenney_city_kit_suburban", "kenney_retro_urban"]
    assert sum(Path(s["path"]).name == "LICENSE.txt" for s in manifest["sources"]) == 2
    run_method2(cfg, library, tmp_path / "b")
    images = sorted((tmp_path / "a" / "images").rglob("*.jpg"))
    assert images and all(
        p.read_bytes() == (tmp_path / "b" / p.relative_to(tmp_path / "a")).read_bytes() for p in images
    )


def test_method1_planes_stand_in_the_fire_zones(kit_root, library, tmp_path) -> None:
    cfg = Method1Config(n=4, seed=2, width=96, height=72, scenes=0, streets=2, kits=(kit_root,), negatives=0.0)
    run_method1(cfg, library, tmp_path / "m1")
    report = audit_dataset(tmp_path / "m1")
    assert report["modes"]["visible"]["mean_iou"] == 1.0
    per_image = json.loads((tmp_path / "m1" / "manifest.json").read_text())["args"]["per_image"]
    kits = [load_kit(folder) for folder in find_kits([kit_root])]
    zones = {f"street-{k:03d}": streets.lay_out_street(kits, k, cfg.seed).zones for k in range(2)}
    bases = [(m["environment"], f["plane"]["pose"]) for m in per_image for f in m["flames"]]
    assert bases and {m["kind"] for m in per_image} == {"street"}
    margin = cfg.clearance_m[1]  # a plane stands up to this far in front of its spot, towards the camera
    for env, pose in bases:
        x, y, z = np.asarray(pose)[:3, 3]
        assert y <= ZONE_TOP_M + margin
        assert any(a - margin <= x <= b + margin and c - margin <= z <= d + margin for a, b, c, d in zones[env])


def test_bad_kits_and_street_settings_are_one_line_errors(tmp_path, kit_root) -> None:
    with pytest.raises(FileNotFoundError, match="no such kit folder"):
        find_kits([tmp_path / "missing"])
    (tmp_path / "odd" / "glb").mkdir(parents=True)
    (tmp_path / "odd" / "glb" / "chair.glb").write_bytes((kit_root / "kenney_retro_urban/glb/wall-a.glb").read_bytes())
    with pytest.raises(ValueError, match="not a building kit this street layout knows") as err:
        find_kits([tmp_path / "odd"])
    assert "\n" not in str(err.value)
    with pytest.raises(ValueError, match="no kits are given"):
        Method2Config(streets=2)
    with pytest.raises(ValueError, match="streets is 0"):
        Method1Config(kits=(kit_root,))
    with pytest.raises(ValueError, match="no kits"):
        streets.lay_out_street([], 0, 0)


@pytest.mark.slow
def test_method2_renders_streets_of_the_real_kits(shared_data, library, tmp_path) -> None:
    kits = shared_data / "kits"
    if not kits.is_dir():
        pytest.skip("no kits in ../shared/data")
    cfg = Method2Config(n=4, seed=0, width=160, height=120, scenes=0, streets=2, kits=(kits,), images_per_view=1)
    run_method2(cfg, library, tmp_path / "real")
    report = audit_dataset(tmp_path / "real")
    assert report["images"] == 4 and report["mean_iou"] == 1.0 and report["min_iou"] == 1.0
    per_image = json.loads((tmp_path / "real" / "manifest.json").read_text())["args"]["per_image"]
    assert {m["environment"] for m in per_image} == {"street-000", "street-001"}
    assert {m["kind"] for m in per_image} == {"street"}
