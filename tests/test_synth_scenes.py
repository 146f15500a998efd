import numpy as np
import pytest
import trimesh

from synth import camera as C
from synth import render as R
from synth import scenes as S


def test_48_distinct_environments_from_7_families():
    envs = [S.build_environment(i, seed=0) for i in range(49)]
    assert len({e.family for e in envs}) == len(S.FAMILIES) >= 6

    def signature(e):
        return (e.family, tuple(round(p.width, 4) for p in e.panels), tuple(round(s.pose[2, 3], 4) for s in e.solids))

    signatures = {signature(e) for e in envs}
    assert len(signatures) == 49
    again = S.build_environment(5, seed=0)
    assert [s.pose.tolist() for s in again.solids] == [s.pose.tolist() for s in envs[5].solids]


@pytest.fixture(scope="module")
def renderer():
    with R.Renderer(80, 60) as r:
        yield r


@pytest.mark.parametrize("family", range(len(S.FAMILIES)))
def test_every_family_renders_an_unblocked_horizontal_view(renderer, family):
    env = S.build_environment(family, seed=1)
    scene = S.to_pyrender(env, renderer.pyrender, texture_size=32)
    rng = np.random.default_rng(family)
    view = C.find_view(env.camera, rng, lambda v: R.render_view(renderer, scene, v.pose, v.yfov, True)[1])
    rgb, depth = R.render_view(renderer, scene, view.pose, view.yfov)
    pitch, roll = C.pitch_roll_deg(view.pose)
    assert abs(roll) < 1e-6 and abs(pitch) <= env.camera.max_pitch_deg + 1e-6
    assert rgb.std() > 5 and not C.view_blocked(depth, env.camera)


def test_wall_in_front_blocks_the_view(renderer):
    env = S.Environment("wall", "test", C.CameraRule((0, 0, 0, 0), (1.5, 1.5), ((0, 1.5, -5),)))
    S.add_box(env, (4, 3, 0.1), (0, 0, -0.3), (0.5, 0.5, 0.5))
    scene = S.to_pyrender(env, renderer.pyrender)
    with pytest.raises(C.NoViewError):
        C.find_view(
            env.camera,
            np.random.default_rng(0),
            lambda v: R.render_view(renderer, scene, v.pose, v.yfov, True)[1],
            tries=3,
        )


def test_user_mesh_environment(tmp_path, renderer):
    room = trimesh.creation.box((6, 3, 6))
    room.invert()
    room.apply_translation((0, 1.5, 0))
    room.export(tmp_path / "room.ply")
    env = S.load_user_environment(tmp_path / "room.ply")
    scene = S.to_pyrender(env, renderer.pyrender)
    view = C.find_view(
        env.camera, np.random.default_rng(0), lambda v: R.render_view(renderer, scene, v.pose, v.yfov, True)[1]
    )
    assert (R.render_view(renderer, scene, view.pose, view.yfov)[1] > 0).all()
    (tmp_path / "bad.obj").write_text("not a mesh")
    with pytest.raises(ValueError, match="bad.obj"):
        S.load_user_environment(tmp_path / "bad.obj")


def test_textures_tile_and_reject_unknown():
    from synth.textures import TEXTURES, make_texture

    for name in TEXTURES:
        img = make_texture(name, np.random.default_rng(0), 32)
        assert img.shape == (32, 32, 3) and img.dtype == np.uint8 and img.std() > 1
    with pytest.raises(ValueError):
        make_texture("marble", np.random.default_rng(0))


def test_camera_pose_looks_at_its_target():
    rule = C.CameraRule((0, 0, 0, 0), (1.0, 1.0), ((0, 1.0, -5.0),), yaw_jitter_deg=0)
    view = C.sample_view(rule, np.random.default_rng(0))
    fwd = -view.pose[:3, 2]
    assert np.allclose(fwd, [0, 0, -1], atol=1e-9)


def test_walls_are_plausible_paints_and_lamps_are_white_balanced():
    from synth.textures import plaster

    for seed in range(30):
        r, g, b = plaster(np.random.default_rng(seed), 32).reshape(-1, 3).mean(axis=0)
        assert r - g < 30 and not (r - g > 12 and b - g > 12), (seed, r, g, b)  # never pink or purple
    warm = S.white_balanced(2500.0)
    assert warm.max() == 1.0 and warm[0] > warm[1] > warm[2] > 0.3
