"""Environment files: sidecars, discovery, normalisation to metres / +Y up, textures kept, ground planes."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
import trimesh
from factories import write_textured_room

from synth.places.envfile import environment_file, find_environment_files, footprint, load_meshes, mesh_bounds


def test_a_centimetre_z_up_file_is_normalised_by_its_sidecar(tmp_path: Path) -> None:
    mesh = write_textured_room(tmp_path / "room.glb", up="+z", scale=0.01)
    (tmp_path / "room.yaml").write_text("scale: 0.01\nup: +z\ncamera: {height: [1.4, 1.8]}\n")
    spec = environment_file(mesh)
    assert (spec.scale, spec.up, spec.camera.height, spec.sidecar) == (0.01, "+z", (1.4, 1.8), tmp_path / "room.yaml")
    bounds = mesh_bounds(load_meshes(spec))
    assert np.allclose(bounds, [[-3, 0, -3], [3, 3, 3]], atol=1e-6)
    plain = mesh_bounds(load_meshes(environment_file(write_textured_room(tmp_path / "m" / "room.glb"))))
    assert np.allclose(plain, bounds, atol=1e-6)


def test_textures_and_materials_are_kept(tmp_path: Path) -> None:
    meshes = load_meshes(environment_file(write_textured_room(tmp_path / "room.glb")))
    materials = [m.visual.material for m, _ in meshes]
    assert len(meshes) == 3
    assert sum(getattr(mat, "baseColorTexture", None) is not None for mat in materials) == 1
    assert {tuple(np.asarray(mat.baseColorFactor)[:3]) for mat in materials if mat.baseColorFactor is not None} >= {
        (120, 70, 30)
    }


def test_a_sidecar_passed_in_place_of_its_mesh(tmp_path: Path) -> None:
    mesh = write_textured_room(tmp_path / "data" / "scene.glb")
    side = tmp_path / "mine" / "lounge.yaml"
    side.parent.mkdir()
    side.write_text("file: ../data/scene.glb\noutdoor: true\nlights: none\n")
    spec = environment_file(side)
    assert spec.file == mesh.resolve() and spec.outdoor and spec.lights == "none"
    assert spec.name == "data"  # generic stem: the folder names the scene
    found = find_environment_files([tmp_path])
    assert [f.file for f in found] == [mesh.resolve()] and found[0].outdoor  # the sidecar wins, counted once


def test_folders_are_searched_and_sorted(tmp_path: Path) -> None:
    write_textured_room(tmp_path / "b" / "hall.obj")
    write_textured_room(tmp_path / "a" / "den.glb")
    (tmp_path / "a" / "notes.yaml").write_text("title: not a sidecar\n")
    assert [f.name for f in find_environment_files([tmp_path])] == ["den", "hall"]


@pytest.mark.parametrize(
    ("text", "message"),
    [
        ("scale: 0\n", "scale must be > 0"),
        ("up: sideways\n", "up must be one of"),
        ("lights: disco\n", "lights must be auto or none"),
        ("colour: red\n", "unknown key"),
        ("camera: {fov: 3}\n", "unknown key"),
        ("- a list\n", "mapping"),
    ],
)
def test_bad_sidecars_are_named(tmp_path: Path, text: str, message: str) -> None:
    mesh = write_textured_room(tmp_path / "room.glb")
    (tmp_path / "room.yaml").write_text(text)
    with pytest.raises(ValueError, match=message):
        environment_file(mesh)


def test_missing_and_broken_files(tmp_path: Path) -> None:
    (tmp_path / "x.yaml").write_text("file: gone.glb\n")
    with pytest.raises(FileNotFoundError, match="gone.glb"):
        environment_file(tmp_path / "x.yaml")
    with pytest.raises(FileNotFoundError):
        find_environment_files([tmp_path / "nowhere"])
    (tmp_path / "empty").mkdir()
    with pytest.raises(ValueError, match="no mesh files"):
        find_environment_files([tmp_path / "empty"])
    (tmp_path / "bad.obj").write_text("this is not a mesh\n")
    with pytest.raises(ValueError, match="bad.obj"):
        load_meshes(environment_file(tmp_path / "bad.obj"))


def test_footprint_ignores_a_ground_plane(tmp_path: Path) -> None:
    meshes = load_meshes(environment_file(write_textured_room(tmp_path / "room.glb")))
    ground = trimesh.creation.box((200, 0.1, 200))
    assert np.allclose(mesh_bounds([*meshes, (ground, np.eye(4))])[:, 0], [-100, 100])
    box = footprint([*meshes, (ground, np.eye(4))])
    assert np.allclose(box[:, 0], [-3, 3]) and np.allclose(box[:, 2], [-3, 3])
    assert np.isclose(box[0, 1], -0.05)  # heights still span everything


def test_large_textures_are_scaled_down_once(tmp_path: Path) -> None:
    from PIL import Image

    from synth.places.envfile import MAX_TEXTURE

    big = Image.fromarray(np.random.default_rng(0).integers(0, 256, (1536, 3072, 3), dtype=np.uint8))
    material = trimesh.visual.material.PBRMaterial(baseColorTexture=big)
    scene = trimesh.Scene()
    for k in range(3):  # three meshes sharing one material, as exporters do
        quad = trimesh.Trimesh([[k, 0, 0], [k + 1, 0, 0], [k + 1, 1, 0]], [[0, 1, 2]], process=False)
        quad.visual = trimesh.visual.TextureVisuals(uv=[[0, 0], [1, 0], [1, 1]], material=material)
        scene.add_geometry(quad, f"q{k}")
    scene.export(tmp_path / "big.glb")
    meshes = load_meshes(environment_file(tmp_path / "big.glb"))
    textures = {id(m.visual.material.baseColorTexture): m.visual.material.baseColorTexture for m, _ in meshes}
    assert [t.size for t in textures.values()] == [(MAX_TEXTURE, MAX_TEXTURE // 2)]


def test_fingerprints_follow_content_not_location(tmp_path: Path) -> None:
    from synth.places.envfile import fingerprint

    glb = [write_textured_room(tmp_path / d / "room.glb") for d in ("a", "b")]
    a, b = (fingerprint(environment_file(p)) for p in glb)
    assert a == b and set(a["sha256"]) == {"room.glb"} and a["scale"] == 1.0 and "camera" in a
    obj = write_textured_room(tmp_path / "c" / "room.obj")
    resources = fingerprint(environment_file(obj))["sha256"]
    assert "room.obj" in resources and any(n.endswith((".mtl", ".png", ".jpg")) for n in resources if n != "room.obj")
    (obj.parent / "room.yaml").write_text("scale: 0.01\n")  # a sidecar beside it changes the settings
    assert fingerprint(environment_file(obj))["scale"] == 0.01
