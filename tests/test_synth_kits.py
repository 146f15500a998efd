"""Building kits (synth/kits.py): kits found by their files' names, parts in metres with facades to +Z, tints,
credits and content fingerprints."""

from __future__ import annotations

import shutil
from pathlib import Path

import numpy as np
import pytest
import trimesh
from factories import write_tiny_kits

from synth import kits as K


@pytest.fixture(scope="module")
def root(tmp_path_factory) -> Path:
    return write_tiny_kits(tmp_path_factory.mktemp("kits"))


def test_kits_are_found_in_a_folder_of_kits_or_given_one_by_one(root) -> None:
    both = K.find_kits([root])
    assert [p.name for p in both] == ["kenney_city_kit_suburban", "kenney_retro_urban"]
    assert K.find_kits([root / "kenney_retro_urban", root]) == [root / "kenney_retro_urban", both[0]]
    assert [K.profile_of(p).name for p in both] == ["suburban", "retro_urban"]


def test_a_folder_missing_a_required_part_is_no_kit(root, tmp_path) -> None:
    kit = shutil.copytree(root / "kenney_retro_urban", tmp_path / "retro")
    (kit / "glb" / "wall-a-door.glb").unlink()  # a retro street needs doors
    assert K.profile_of(kit) is None
    with pytest.raises(ValueError, match=r"retro: not a building kit .*wall-\[ab\]-door.glb"):
        K.find_kits([kit])


def test_parts_are_in_metres_with_their_facade_to_plus_z(root) -> None:
    retro, suburban = K.load_kit(root / "kenney_retro_urban"), K.load_kit(root / "kenney_city_kit_suburban")
    wall = retro.parts["wall"][0]
    assert np.allclose(wall.size, 4.5, atol=1e-6)  # a 1-unit block at 4.5 m per unit
    assert np.isclose(retro.parts["bin"][0].size[1], 1.5)  # props to their real height
    assert np.isclose(suburban.parts["house"][0].size[1], 0.83 * 8.0)
    for part in (retro.parts["door"][0], suburban.parts["house"][0]):  # the door slab: on +Z after loading
        mesh, pose = part.meshes[0]
        points = trimesh.transform_points(mesh.vertices, pose)
        assert points[:, 2].max() > -points[:, 2].min() + 0.05
    assert {p.name for p in suburban.parts["road"]} == {"roads/road-straight.glb"}


def test_a_tint_multiplies_the_base_colour_of_a_copy(root) -> None:
    part = K.load_kit(root / "kenney_retro_urban").parts["wall"][0]
    mesh = part.meshes[0][0]
    assert K.tinted(part, (0.5, 1.0, 1.0)).meshes[0][0] is mesh  # vertex colours: nothing to tint
    box = trimesh.creation.box()
    box.visual = trimesh.visual.TextureVisuals(
        uv=np.zeros((len(box.vertices), 2)), material=trimesh.visual.material.PBRMaterial(baseColorFactor=[200] * 4)
    )
    textured = K.Part("box.glb", "kit", ((box, np.eye(4)),), part.bounds)
    tinted = K.tinted(textured, (0.5, 1.0, 1.0)).meshes[0][0]
    assert tinted.visual.material.baseColorFactor.tolist() == [100, 200, 200, 200]
    assert box.visual.material.baseColorFactor.tolist() == [200, 200, 200, 200]  # the original is untouched


def test_credits_licences_and_fingerprints(root, tmp_path) -> None:
    folders = K.find_kits([root])
    assert {c["credit"] for c in K.credits(folders)} == {K.CC0_KENNEY}
    assert [p.name for p in K.licence_files(folders[0])] == ["LICENSE.txt"]
    copy = shutil.copytree(folders[1], tmp_path / "elsewhere" / folders[1].name)
    assert K.kit_fingerprint(copy) == K.kit_fingerprint(folders[1])  # by content, wherever it lies
    (copy / "glb" / "wall-a.glb").write_bytes(b"edited")
    assert K.kit_fingerprint(copy) != K.kit_fingerprint(folders[1])
