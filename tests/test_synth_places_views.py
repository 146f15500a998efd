"""Camera views: reproducible per (seed, view index), unblocked, cached."""

from __future__ import annotations

import numpy as np
import pytest

from synth.places import camera as C
from synth.places import render as R
from synth.places.views import ViewCache


@pytest.fixture(scope="module")
def renderer():
    with R.Renderer(64, 48) as r:
        yield r


def test_views_are_reproducible_and_cycle_environments(renderer):
    a, b = ViewCache(3, 2, renderer), ViewCache(3, 2, renderer)
    v5 = a.view(5)
    assert v5 is a.view(5)  # the last view is cached
    a.view(0)
    assert np.array_equal(a.view(5).camera.pose, v5.camera.pose)  # remade identically
    assert np.array_equal(b.view(5).camera.pose, v5.camera.pose) and np.array_equal(b.view(5).depth, v5.depth)
    assert a.view(4).env.name != v5.env.name and a.view(3).env.name == v5.env.name  # environment = view % 2
    assert not C.view_blocked(v5.depth, v5.env.camera)
    assert not np.array_equal(ViewCache(4, 2, renderer).view(5).camera.pose, v5.camera.pose)


def test_background_matches_a_fresh_render(renderer):
    views = ViewCache(0, 1, renderer)
    rgb, depth, meta = views.background(2)
    v = views.view(2)
    again, _ = R.render_view(renderer, v.scene, v.camera.pose, v.camera.yfov)
    assert np.array_equal(rgb, again) and rgb.shape == (48, 64, 3)
    assert np.allclose(depth, v.depth, atol=1e-3)
    assert meta == v.meta() and {"environment", "family", "camera"} <= set(meta)
    with pytest.raises(ValueError):
        ViewCache(0, 0, renderer)


def test_file_environments_come_first_in_blocks_then_procedural(renderer, tmp_path):
    from factories import write_textured_room

    from synth.places.envfile import environment_file

    spec = environment_file(write_textured_room(tmp_path / "den.glb"))
    views = ViewCache(0, 2, renderer, [spec], views=6)  # 3 environments, 2 views each
    assert [views.environment_index(v) for v in range(6)] == [0, 0, 1, 1, 2, 2]
    assert views.view(0).env.family == "file" and views.view(1).env.name == "den"
    assert views.view(2).env.name == ViewCache(0, 2, renderer).view(0).env.name  # procedural 0 after the file
    assert views.view(5).env.name == ViewCache(0, 2, renderer).view(1).env.name
    two = ViewCache(0, 0, renderer, [spec, spec], views=4)
    two.view(0)
    two.view(3)
    assert list(two._scenes) == [1]  # the first file scene was released when the second was needed
    with pytest.raises(ValueError, match="at least one environment"):
        ViewCache(0, 0, renderer)
    with pytest.raises(ValueError, match="number of views"):
        ViewCache(0, 0, renderer, [spec])


def test_surfaces_keep_only_up_facing_ground_and_views_that_show_some(renderer):
    from synth.places.standing import standing_mask
    from synth.places.views import MIN_ZONE_SHARE

    views = ViewCache(0, 2, renderer, surfaces=True)
    for i in range(4):
        v = views.view(i)
        assert standing_mask(v.depth, v.camera.pose, v.camera.yfov).mean() >= MIN_ZONE_SHARE  # else redrawn
        full = R.render_view(renderer, v.scene, v.camera.pose, v.camera.yfov)[1]
        stand = standing_mask(full, v.camera.pose, v.camera.yfov)
        rgb, depth, meta = views.background(i)
        assert meta["site"] == "surfaces"
        assert np.all(depth[~stand] == 0) and np.any(depth[stand] > 0)  # flames may stand only on those pixels
    plain = ViewCache(0, 2, renderer).background(0)
    assert "site" not in plain[2] and plain[1].min() >= 0


def _photos(folder, n: int):
    from factories import write_image

    from synth.places.photos import PhotoBackgrounds

    paths = [write_image(folder / f"p{k:02d}.jpg", 80, 60, seed=k) for k in range(n)]
    return PhotoBackgrounds(paths, 64, 48, seed=0)


def test_each_image_on_photos_has_a_photo_of_its_own_until_every_photo_is_used(renderer, tmp_path):
    """N images on P >= N photos show N distinct photos, however many images a rendered view carries; with renders
    beside them, the images on photos go through every photo before any repeats."""
    photos = _photos(tmp_path, 14)
    only = ViewCache(0, 0, renderer, photos=photos)
    shown = [only.image_background(i, 8)[2]["photo"] for i in range(12)]
    assert len(set(shown)) == 12
    assert [only.image_background(i, 8)[2]["photo"] for i in range(12)] == shown  # seeded, remade alike
    mixed = ViewCache(0, 1, renderer, photos=photos, photo_share=0.5)
    metas = [mixed.image_background(i, 4)[2] for i in range(80)]
    on_photos = [m["photo"] for m in metas if m["kind"] == "photo"]
    assert len(on_photos) >= 28 and {m["kind"] for m in metas} == {"photo", "render"}
    assert len(set(on_photos[:14])) == 14 and on_photos[14:28] == on_photos[:14]  # all 14, then the same order
    renders = [m["camera"] for m in metas if m["kind"] == "render"]
    assert renders[0:4] == [renders[0]] * 4  # a rendered view still carries 4 images
