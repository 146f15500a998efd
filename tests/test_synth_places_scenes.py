import numpy as np
import pytest
import trimesh
from factories import write_textured_room

from synth.places import camera as C
from synth.places import render as R
from synth.places import scenes as S
from synth.places.envfile import environment_file


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


def test_file_environment_is_normalised_lit_and_viewable(tmp_path, renderer):
    mesh = write_textured_room(tmp_path / "room.glb", up="+z", scale=0.01)
    (tmp_path / "room.yaml").write_text("scale: 0.01\nup: +z\n")
    env, scene = S.file_environment(environment_file(mesh), renderer)
    assert env.family == "file" and env.name == "room" and env.camera.positions and env.camera.cell > 0
    assert [light.kind for light in env.lights] == ["point", "directional"]  # ~23 m2 of free floor: one lamp
    lowest = min(trimesh.transform_points(m.vertices, pose)[:, 1].min() for m, pose in env.meshes)
    assert lowest == pytest.approx(-0.01, abs=0.012)  # the floor quad (1 cm up in the file) is now at y = 0
    views = [
        C.find_view(
            env.camera, np.random.default_rng(k), lambda v: R.render_view(renderer, scene, v.pose, v.yfov, True)[1]
        )
        for k in range(3)
    ]
    for view in views:
        eye = view.pose[:3, 3]
        assert 1.3 <= eye[1] <= 2.2 and (np.abs(eye[[0, 2]]) < 3).all()
        rgb, depth = R.render_view(renderer, scene, view.pose, view.yfov)
        assert (depth > 0).all() and rgb.std() > 10  # inside the walls, textured, lit
    (tmp_path / "room.yaml").write_text("scale: 0.01\nup: +z\nlights: none\ncamera: {area: [-1, 1, -1, 1]}\n")
    bare, _ = S.file_environment(environment_file(mesh), renderer)
    assert not bare.lights and bare.camera.area == (-1, 1, -1, 1) and not bare.camera.positions


def test_textures_tile_and_reject_unknown():
    from synth.places.textures import TEXTURES, make_texture

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
    from synth.places.textures import plaster

    for seed in range(30):
        r, g, b = plaster(np.random.default_rng(seed), 32).reshape(-1, 3).mean(axis=0)
        assert r - g < 30 and not (r - g > 12 and b - g > 12), (seed, r, g, b)  # never pink or purple
    warm = S.white_balanced(2500.0)
    assert warm.max() == 1.0 and warm[0] > warm[1] > warm[2] > 0.3


def test_a_file_mesh_placed_twice_is_one_pyrender_mesh(renderer):
    box = trimesh.creation.box(extents=(1, 1, 1))
    env = S.Environment("twice", "file", C.CameraRule((0, 0, 0, 0)))
    env.meshes = [(box, S.translate(0, 0.5, -3)), (box, S.translate(2, 0.5, -3))]
    scene = S.to_pyrender(env, renderer.pyrender)
    nodes = list(scene.mesh_nodes)
    assert len(nodes) == 2 and nodes[0].mesh is nodes[1].mesh
    assert sorted(n.translation[0] for n in nodes) == [0.0, 2.0]
