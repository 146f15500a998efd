"""Panorama backgrounds: views agree with the pinhole model (horizon row, ground depth, a marker's pixel), are
seeded and byte-reproducible, use every panorama before repeating, say when they are soft, tone-map HDR, and name
broken files, bad sidecars and sky-only configurations."""

from __future__ import annotations

from pathlib import Path

import cv2
import numpy as np
import pytest

from ground.image.imageio import ImageError
from synth.places import render
from synth.places.panorama import (
    PanoramaBackgrounds,
    ground_depth,
    is_panorama,
    list_panoramas,
    panorama_fingerprints,
    read_panorama,
    render_view,
)

PW, PH = 512, 256
SKY = (40, 90, 230)  # RGB


def equirect(seed: int = 0) -> np.ndarray:
    """(PH, PW, 3) uint8 RGB: blue sky above the middle row, a checkerboard ground below (8 x 8 px squares)."""
    img = np.empty((PH, PW, 3), np.uint8)
    img[: PH // 2] = SKY
    yy, xx = np.mgrid[PH // 2 : PH, 0:PW]
    check = ((yy // 8 + xx // 8) % 2).astype(bool)
    img[PH // 2 :] = np.where(check[..., None], (200, 190, 170), (60 + 20 * seed, 50, 40)).astype(np.uint8)
    return img


def write_rgb(path: Path, rgb: np.ndarray) -> Path:
    path.parent.mkdir(parents=True, exist_ok=True)
    assert cv2.imwrite(str(path), np.ascontiguousarray(rgb[:, :, ::-1]))
    return path


@pytest.fixture(scope="module")
def folder(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """Four 8-bit panoramas (one in a subfolder), one linear .hdr, and a 4:3 image that is not a panorama."""
    root = tmp_path_factory.mktemp("panoramas")
    for k, name in enumerate(("a.jpg", "b.png", "sub/c.jpg", "d.jpg")):
        write_rgb(root / name, equirect(k))
    linear = equirect().astype(np.float32) / 255.0 * 0.2
    linear[: PH // 2] *= 40.0  # a sky 40 x brighter than the ground, far beyond 8 bits
    assert cv2.imwrite(str(root / "e.hdr"), np.ascontiguousarray(linear[:, :, ::-1]))
    write_rgb(root / "photo.jpg", np.zeros((60, 80, 3), np.uint8))
    return root


def gl_pose(yaw: float, pitch: float) -> np.ndarray:
    """Camera-to-world pose (OpenGL camera, world +Y up, yaw 0 looking along -Z, yaw growing to the right)."""
    forward = np.array([np.sin(yaw), 0.0, -np.cos(yaw)])
    right, up = np.array([np.cos(yaw), 0.0, np.sin(yaw)]), np.array([0.0, 1.0, 0.0])
    f2, u2 = forward * np.cos(pitch) + up * np.sin(pitch), up * np.cos(pitch) - forward * np.sin(pitch)
    pose = np.eye(4)
    pose[:3, :3] = np.stack([right, u2, -f2], axis=1)
    return pose


def test_listing_finds_2_to_1_images_recursively_sorted_and_refuses_a_named_photo(folder: Path) -> None:
    found = list_panoramas([folder])
    assert [p.relative_to(folder).as_posix() for p in found] == ["a.jpg", "b.png", "d.jpg", "e.hdr", "sub/c.jpg"]
    assert is_panorama(folder / "e.hdr") and not is_panorama(folder / "photo.jpg")
    with pytest.raises(ValueError, match="photo.jpg: not an equirectangular panorama"):
        list_panoramas([folder / "photo.jpg"])


def test_listing_skips_and_names_an_unreadable_file_in_a_folder_and_refuses_a_named_one(tmp_path: Path) -> None:
    good = write_rgb(tmp_path / "good.jpg", equirect())
    (tmp_path / "cut.jpg").write_bytes(good.read_bytes()[:2000])
    (tmp_path / "notes.png").write_text("not a panorama\n")
    problems: list = []
    assert list_panoramas([tmp_path], problems) == [good]
    assert sorted((Path(p.path).name, p.reason.split(" (")[0]) for p in problems) == [
        ("cut.jpg", "truncated JPEG"),
        ("notes.png", "not an image"),
    ]
    with pytest.raises(ValueError, match="cut.jpg: truncated JPEG"):
        list_panoramas([tmp_path / "cut.jpg"])


def test_the_horizon_row_is_where_the_pinhole_model_puts_it() -> None:
    w, h, yfov = 96, 80, np.radians(60)
    fy = render.intrinsics(yfov, w, h)[1, 1]
    for pitch_deg in (-20.0, -5.0, 0.0, 8.0):
        pitch = np.radians(pitch_deg)
        view, _ = render_view(equirect(), np.radians(30), pitch, yfov, w, h)
        v_h = h / 2 + fy * np.tan(pitch)  # the horizon's row coordinate (pixel i spans [i, i + 1))
        sky = np.all(np.abs(view.astype(int) - SKY) <= 3, axis=2).all(axis=1)
        rows = np.arange(h) + 0.5
        assert sky[rows < v_h - 1.5].all() and not sky[rows > v_h + 1.5].any()
        depth = ground_depth(w, h, yfov, pitch, 1.6, max_distance=np.inf)
        assert np.array_equal((depth > 0).all(axis=1), rows > v_h) and not depth[rows < v_h].any()


def test_ground_depth_is_the_z_depth_of_the_flat_ground_point() -> None:
    w, h, yfov, pitch, cam_h = 64, 48, np.radians(55), np.radians(-12), 2.3
    depth = ground_depth(w, h, yfov, pitch, cam_h)
    k, pose = render.intrinsics(yfov, w, h), gl_pose(0.0, pitch)
    for i, j in ((47, 0), (40, 31), (30, 63), (25, 10)):
        ray = pose[:3, :3] @ np.array([(j + 0.5 - k[0, 2]) / k[0, 0], -(i + 0.5 - k[1, 2]) / k[1, 1], -1.0])
        below = np.arcsin(-ray[1] / np.linalg.norm(ray))  # angle below the horizon
        assert below > 0
        ground = ray / np.hypot(ray[0], ray[2]) * cam_h / np.tan(below)  # horizontal distance h / tan(angle)
        ground[1] = -cam_h
        assert depth[i, j] == pytest.approx(render.project(ground[None], pose, k)[0, 2], rel=1e-3)
    assert (depth[: h // 2 - int(k[1, 1] * np.tan(-pitch))] == 0).all()  # sky rows
    near = ground_depth(w, h, yfov, pitch, cam_h, max_distance=5.0)
    assert (near <= depth).all() and 0 < (near > 0).sum() < (depth > 0).sum()


def test_a_marker_appears_where_the_pinhole_projection_puts_it() -> None:
    pano = np.zeros((PH, PW, 3), np.float32)
    yaw_m, elev_m = np.radians(100), np.radians(-10)
    s, t = yaw_m / (2 * np.pi) * PW, (0.5 - elev_m / np.pi) * PH  # its panorama coordinates
    yy, xx = np.mgrid[0:PH, 0:PW] + 0.5
    pano[..., 0] = np.exp(-((xx - s) ** 2 + (yy - t) ** 2) / (2 * 1.5**2))
    point = np.array([[np.cos(elev_m) * np.sin(yaw_m), np.sin(elev_m), -np.cos(elev_m) * np.cos(yaw_m)]]) * 50
    yfov, yaw, pitch = np.radians(70), np.radians(85), np.radians(-4)
    for w, h in ((120, 90), (320, 240)):  # sampled directly; sampled at the panorama's resolution and upscaled
        view, softness = render_view(pano, yaw, pitch, yfov, w, h)
        assert (softness < 1) == (w == 120)
        blob = view[..., 0]
        rows, cols = np.mgrid[0:h, 0:w] + 0.5
        got = np.array([(blob * cols).sum(), (blob * rows).sum()]) / blob.sum()
        want = render.project(point, gl_pose(yaw, pitch), render.intrinsics(yfov, w, h))[0, :2]
        assert np.abs(got - want).max() < 0.1 * softness


def test_views_are_seeded_and_byte_reproducible(folder: Path) -> None:
    paths = list_panoramas([folder])
    one, other = PanoramaBackgrounds(paths, 64, 48, seed=3), PanoramaBackgrounds(paths, 64, 48, seed=3)
    first = one.background(6)
    other.background(2)  # another panorama in memory first
    again = other.background(6)
    assert first[0].tobytes() == again[0].tobytes() and first[1].tobytes() == again[1].tobytes()
    assert first[2] == again[2] and first[2]["site"] is True and first[2]["panorama"] in {p.name for p in paths}
    assert first[0].dtype == np.uint8 and first[0].shape == (48, 64, 3) and first[1].dtype == np.float32
    assert PanoramaBackgrounds(paths, 64, 48, seed=4).background(6)[2] != first[2]


def test_every_panorama_is_used_before_any_repeats(folder: Path) -> None:
    paths = list_panoramas([folder])
    bg = PanoramaBackgrounds(paths, 32, 24, seed=11)
    names = [bg.background(v)[2]["panorama"] for v in range(2 * len(paths))]
    assert sorted(names[: len(paths)]) == sorted(p.name for p in paths) == sorted(names[len(paths) :])


def test_softness_says_when_a_view_asks_for_more_pixels_than_the_panorama_has(folder: Path) -> None:
    view, softness = render_view(equirect(), 0.0, 0.0, np.radians(60), 256, 256)  # 4.3 px/deg vs 1.4
    assert softness == pytest.approx((256 / 60) / (PW / 360), rel=1e-9) and softness > 1
    assert view.shape == (256, 256, 3)
    _, softness = render_view(equirect(), 0.0, 0.0, np.radians(60), 48, 48)
    assert softness < 1
    meta = PanoramaBackgrounds([folder / "a.jpg"], 300, 300, seed=0).background(0)[2]
    assert meta["softness"] == pytest.approx((300 / np.degrees(meta["camera"]["yfov"])) / (PW / 360), rel=1e-3)


def test_hdr_views_are_tone_mapped_to_uint8_with_a_sane_mean(folder: Path) -> None:
    pano = read_panorama(folder / "e.hdr")
    assert pano.dtype == np.float32 and pano.max() > 1.5
    bg = PanoramaBackgrounds([folder / "e.hdr"], 64, 48, seed=0)
    for v in range(4):
        rgb, depth, meta = bg.background(v)
        assert rgb.dtype == np.uint8 and 30 < rgb.mean() < 200 and "exposure" in meta and (depth > 0).mean() >= 0.15
    assert "exposure" not in PanoramaBackgrounds([folder / "a.jpg"], 64, 48, seed=0).background(0)[2]


def test_a_broken_hdr_is_named_with_its_reason(tmp_path: Path, folder: Path) -> None:
    header = b"#?RADIANCE\nFORMAT=32-bit_rle_rgbe\n\n-Y 256 +X 512\n"
    (tmp_path / "cut.hdr").write_bytes(header + b"\x02\x02\x02\x00" + bytes(300))
    (tmp_path / "fake.hdr").write_bytes(b"P6 not radiance at all")
    (tmp_path / "odd.hdr").write_bytes(b"#?RADIANCE\n\n+X 512 -Y 256\n" + bytes(8))
    with pytest.raises(ImageError, match=r"cut.hdr: Radiance HDR: cannot be decoded \(corrupt or truncated"):
        read_panorama(tmp_path / "cut.hdr")
    with pytest.raises(ImageError, match="fake.hdr: Radiance HDR: no '#\\?RADIANCE' signature"):
        is_panorama(tmp_path / "fake.hdr")
    with pytest.raises(ImageError, match="odd.hdr: Radiance HDR: resolution line"):
        is_panorama(tmp_path / "odd.hdr")
    (tmp_path / "x.exr").write_bytes(b"\x76\x2f\x31\x01" + bytes(100))  # this OpenCV may have no EXR decoder
    with pytest.raises(ImageError, match=r"x.exr: OpenEXR: cannot be decoded"):
        is_panorama(tmp_path / "x.exr")
    bg = PanoramaBackgrounds([tmp_path / "cut.hdr", folder / "a.jpg"], 32, 24, seed=0)
    assert all(bg.background(v)[2]["panorama"] == "a.jpg" for v in range(3))
    assert list(bg.problems) == [str(tmp_path / "cut.hdr")] and "Radiance HDR" in bg.problems[str(tmp_path / "cut.hdr")]


def test_sidecars_are_strict_and_apply_key_by_key(tmp_path: Path) -> None:
    pano = write_rgb(tmp_path / "site.jpg", equirect())
    (tmp_path / "site.yaml").write_text("pitchh: [-10, 0]\n")
    with pytest.raises(ValueError, match=r"site.yaml: pitchh: unknown key"):
        PanoramaBackgrounds([pano], 32, 24, seed=0)
    (tmp_path / "site.yaml").write_text("pitch: -10\n")
    with pytest.raises(ValueError, match=r"site.yaml: pitch: expected a list"):
        PanoramaBackgrounds([pano], 32, 24, seed=0)
    (tmp_path / "site.yaml").write_text("pitch: [5, -10]\n")
    with pytest.raises(ValueError, match=r"site.yaml: pitch must be \[lo, hi\] with lo <= hi"):
        PanoramaBackgrounds([pano], 32, 24, seed=0)
    (tmp_path / "panoramas.yaml").write_text("yaw: [90, 90]\ncamera_height: [2, 2]\n")
    (tmp_path / "site.yaml").write_text("pitch: [-10, -10]\nyfov: [60, 60]\n")
    meta = PanoramaBackgrounds([pano], 32, 24, seed=0).background(0)[2]
    assert (meta["yaw"], meta["pitch"], meta["camera_height"]) == (90, -10, 2)
    prints = panorama_fingerprints([tmp_path])
    assert list(prints[0]) == ["name", "sha256", "sidecar panoramas.yaml", "sidecar site.yaml"]


def test_a_sky_only_configuration_is_refused_naming_the_panorama(tmp_path: Path) -> None:
    pano = write_rgb(tmp_path / "roof.jpg", equirect())
    (tmp_path / "roof.yaml").write_text("pitch: [60, 60]\n")
    with pytest.raises(ValueError, match=r"roof.jpg: no view in 5 tries has ground within 40 m"):
        PanoramaBackgrounds([pano], 32, 24, seed=0, tries=5).background(0)


def test_fingerprints_are_by_content(tmp_path: Path) -> None:
    for sub in ("x", "y"):
        write_rgb(tmp_path / sub / "p.png", equirect())
    prints = panorama_fingerprints([tmp_path / "x"])
    assert prints == panorama_fingerprints([tmp_path / "y"]) and len(prints[0]["sha256"]) == 64


@pytest.mark.shared_data
def test_views_of_real_panoramas(shared_data: Path) -> None:
    names = ("autoshop_01.hdr", "esplanade.jpg", "IndoorEnvironmentHDRI003_4K-TONEMAPPED.jpg")
    bg = PanoramaBackgrounds([shared_data / "panoramas" / n for n in names], 416, 416, seed=0)
    seen = set()
    for v in range(3):
        rgb, depth, meta = bg.background(v)
        assert rgb.shape == (416, 416, 3) and rgb.dtype == np.uint8 and 20 < rgb.mean() < 235
        assert depth.shape == (416, 416) and depth.dtype == np.float32 and (depth > 0).mean() >= 0.15
        assert ("exposure" in meta) == meta["panorama"].endswith(".hdr") and 0.8 < meta["camera"]["yfov"] < 1.4
        seen.add(meta["panorama"])
    assert seen == set(names) and not bg.problems
