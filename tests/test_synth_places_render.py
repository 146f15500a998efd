"""pyrender traps (see synth/places/render.py), each with a test; rendering runs on EGL (or OSMesa) on the CPU."""

from __future__ import annotations

import subprocess
import sys
import textwrap

import numpy as np
import pytest

from synth.places import render as R

W, H = 96, 72


@pytest.fixture(scope="module")
def renderer():
    with R.Renderer(W, H) as r:
        yield r


def _scene(pr, bg=(0.0, 0.0, 1.0, 1.0)):
    scene = pr.Scene(bg_color=bg, ambient_light=(0.2, 0.2, 0.2))
    cam_pose = R.look_at(np.array([0.0, 0.5, 2.0]), np.array([0.0, 0.5, 0.0]))
    scene.add(pr.PerspectiveCamera(yfov=np.pi / 3, aspectRatio=W / H), pose=cam_pose)
    return scene, cam_pose


def _quad(renderer, halves, size=(1.0, 1.0), bg=(0.0, 0.0, 1.0, 1.0)):
    """A quad of ``size`` (m) textured with the RGBA ``halves`` before the camera, rendered: (scene, pose, colour,
    depth)."""
    pr = renderer.pyrender
    scene, pose = _scene(pr, bg=bg)
    scene.add(R.textured_quad(pr, *size, R.rgba_material(pr, halves)))
    color, depth = renderer.color_depth(scene)
    return scene, pose, color, depth


def _halves(top, bottom, alpha_top=255, alpha_bottom=255, n=32):
    img = np.zeros((n, n, 4), np.uint8)
    img[: n // 2, :, :3], img[: n // 2, :, 3] = top, alpha_top
    img[n // 2 :, :, :3], img[n // 2 :, :, 3] = bottom, alpha_bottom
    return img


def test_select_platform_rejects_unknown_names():
    with pytest.raises(R.RenderError, match="unknown OpenGL platform"):
        R.select_platform("vulkan")


def test_ids_colors_round_trip():
    ids = np.array([0, 1, 255, 256, 65535, 70000, (1 << 24) - 1])
    assert np.array_equal(R.colors_to_ids(R.ids_to_colors(ids)[None]), ids[None])
    with pytest.raises(ValueError):
        R.ids_to_colors(np.array([1 << 24]))


def test_texture_appears_upright(renderer):
    """Trap 4: pyrender flips textures on upload; textured_quad shows image row 0 at the top."""
    _, _, color, depth = _quad(renderer, _halves((255, 0, 0), (0, 255, 0)))
    ys, xs = np.nonzero(depth > 0)
    top, bottom = color[ys.min() + 2, xs.mean().astype(int)], color[ys.max() - 2, xs.mean().astype(int)]
    assert top[0] > 200 and top[1] < 50, top
    assert bottom[1] > 200 and bottom[0] < 50, bottom


def test_rgba_texture_is_transparent(renderer):
    """Trap 3: the alpha of an RGBA texture shows the background through (base colour alpha < 1)."""
    scene, _, color, _ = _quad(renderer, _halves((255, 0, 0), (0, 255, 0), alpha_top=0, alpha_bottom=255))
    quad = R.project(R.quad_corners(1.0, 1.0), scene.get_pose(scene.main_camera_node), R.intrinsics(np.pi / 3, W, H))
    x0, x1 = quad[:, 0].min(), quad[:, 0].max()
    y0, y1 = quad[:, 1].min(), quad[:, 1].max()
    cx = int((x0 + x1) / 2)
    upper = color[int(y0 + 0.25 * (y1 - y0)), cx]
    lower = color[int(y0 + 0.75 * (y1 - y0)), cx]
    assert upper[2] > 200 and upper[0] < 30, f"transparent half must show the blue background, got {upper}"
    assert lower[1] > 200 and lower[2] < 30, lower


def test_projection_matches_rendered_silhouette(renderer):
    _, pose, _, depth = _quad(renderer, _halves((255, 255, 255), (255, 255, 255)), size=(0.8, 0.6))
    ys, xs = np.nonzero(depth > 0)
    uv = R.project(R.quad_corners(0.8, 0.6), pose, R.intrinsics(np.pi / 3, W, H))
    assert abs(xs.min() - uv[:, 0].min()) <= 1 and abs(xs.max() + 1 - uv[:, 0].max()) <= 1
    assert abs(ys.min() - uv[:, 1].min()) <= 1 and abs(ys.max() + 1 - uv[:, 1].max()) <= 1
    assert np.allclose(uv[:, 2], 2.0)
    assert np.allclose(depth[ys, xs], 2.0, atol=1e-3)


def test_segment_maps_unmapped_nodes_to_background(renderer):
    """Trap 5: SEG draws only mapped nodes; Renderer.segment lets unmapped geometry occlude."""
    pr = renderer.pyrender
    scene, _ = _scene(pr)
    plane = scene.add(R.textured_quad(pr, 1.0, 1.0, R.rgba_material(pr, _halves((9, 9, 9), (9, 9, 9)))))
    wall = pr.Mesh.from_trimesh(__import__("trimesh").creation.box((0.5, 2.0, 0.05)), smooth=False)
    scene.add(wall, pose=np.array([[1, 0, 0, 0], [0, 1, 0, 0.5], [0, 0, 1, 0.5], [0, 0, 0, 1.0]]))
    seg = renderer.segment(scene, {plane: 7})
    assert set(np.unique(seg)) == {0, 7}
    raw, _ = renderer._r.render(
        scene, flags=pr.RenderFlags.SEG, seg_node_map={plane: R.ids_to_colors(np.array([7]))[0]}
    )
    raw_ids = R.colors_to_ids(raw[..., :3])
    assert (raw_ids == 7).sum() > (seg == 7).sum() + 100, "the wall must hide part of the plane"


_RSS_SCRIPT = textwrap.dedent(
    """
    import numpy as np, trimesh
    from synth.places import render as R
    def rss():
        with open("/proc/self/statm") as f:
            return int(f.read().split()[1]) * 4096 / 1e6
    with R.Renderer(64, 48, platform="{platform}") as r:
        pr = r.pyrender
        scene = pr.Scene(bg_color=(0, 0, 0, 1))
        scene.add(pr.PerspectiveCamera(yfov=1.0), pose=R.look_at(np.array([0, 0, 3.0]), np.zeros(3)))
        scene.add(pr.Mesh.from_trimesh(trimesh.creation.box((1, 1, 1)), smooth=False))
        scene.add(pr.DirectionalLight(intensity=3.0))
        for _ in range(5):
            r.color_depth(scene)
        before = rss()
        for _ in range(50):
            r.color_depth(scene)
        print(rss() - before)
    """
)


@pytest.mark.parametrize("platform", R.PLATFORMS)
def test_rss_stays_flat_over_50_renders(platform):
    """Trap 2: under OSMesa pyrender's shader cache never hits; 50 renders must grow RSS by < 50 MB."""
    try:
        R.select_platform(platform)
    except R.RenderError as exc:
        pytest.skip(str(exc))
    env = {"PATH": "/usr/bin:/bin", "FUZZYFIRE_GL": platform}
    out = subprocess.run(
        [sys.executable, "-c", _RSS_SCRIPT.format(platform=platform)],
        capture_output=True,
        text=True,
        env=env,
        timeout=120,
        cwd=str(__import__("pathlib").Path(R.__file__).parents[1]),
    )
    assert out.returncode == 0, out.stderr
    assert float(out.stdout.strip().splitlines()[-1]) < 50.0


def test_odd_width_textures_are_not_sheared(renderer):
    """Trap 6: rgba_material uploads RGBA only; an odd-width texture shows its vertical stripes upright."""
    pr = renderer.pyrender
    scene, pose = _scene(pr, bg=(0.0, 0.0, 0.0, 1.0))
    img = np.zeros((33, 31, 4), np.uint8)
    img[..., 3] = 255
    img[:, :15, :3] = (255, 40, 0)  # left half orange, right half white
    img[:, 15:, :3] = 255
    scene.add(R.textured_quad(pr, 1.0, 1.0, R.rgba_material(pr, img)))
    color, depth = renderer.color_depth(scene)
    ys, xs = np.nonzero(depth > 0)
    left = color[ys.min() + 2 : ys.max() - 1, xs.min() + 2 : (xs.min() + xs.max()) // 2 - 2]
    right = color[ys.min() + 2 : ys.max() - 1, (xs.min() + xs.max()) // 2 + 2 : xs.max() - 1]
    assert left[..., 2].max() < 60 and right[..., 2].min() > 200


def test_unproject_inverts_project():
    pose = R.look_at(np.array([1.0, 2.0, 3.0]), np.array([0.0, 0.5, -1.0]))
    k = R.intrinsics(0.9, 160, 120)
    pts = np.random.default_rng(0).uniform(-2, 2, (20, 3)) + np.array([0.0, 0.5, -1.0])
    uvd = R.project(pts, pose, k)
    np.testing.assert_allclose(R.unproject(uvd[:, :2], uvd[:, 2], pose, k), pts, atol=1e-9)


def test_closing_one_renderer_keeps_the_others_working(renderer):
    """Trap 7: pyrender's EGL delete terminates the display shared by every renderer of the process."""
    pr = renderer.pyrender
    scene, _ = _scene(pr)
    scene.add(R.textured_quad(pr, 1.0, 1.0, R.rgba_material(pr, _halves((255, 0, 0), (0, 255, 0)))))
    before, _ = renderer.color_depth(scene)
    with R.Renderer(32, 24) as other:
        own, _ = _scene(pr)
        own.add(R.textured_quad(pr, 1.0, 1.0, R.rgba_material(pr, _halves((255, 0, 0), (0, 255, 0)))))
        assert other.color_depth(own)[0][9, 16, 0] > 200  # the red top half
    after, _ = renderer.color_depth(scene)
    assert np.array_equal(before, after)
