"""Stage cache (built once, reused, an interrupted stage rebuilt), folder references, synthetic pool identities."""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from fuzzyfire.datasets import DataRef
from fuzzyfire.stages import STAGE_FILE, cached_stage, digest, folder_ref


def test_digest_is_stable_and_order_free() -> None:
    assert digest({"a": 1, "b": [1, 2]}) == digest({"b": [1, 2], "a": 1})
    assert digest({"a": 1}) != digest({"a": 2}) and len(digest({})) == 12


def test_cached_stage_builds_once_and_rebuilds_an_interrupted_one(tmp_path: Path) -> None:
    built: list[Path] = []

    def build(folder: Path) -> None:
        built.append(folder)
        folder.mkdir(parents=True)
        (folder / "data.txt").write_text("x")

    first = cached_stage(tmp_path, "thing", {"n": 1}, build)
    again = cached_stage(tmp_path, "thing", {"n": 1}, build)
    assert not first.cached and again.cached and again.folder == first.folder and len(built) == 1
    assert (first.folder / STAGE_FILE).is_file() and first.folder.name == f"thing-{first.hash}"
    other = cached_stage(tmp_path, "thing", {"n": 2}, build)
    assert other.folder != first.folder and len(built) == 2

    (other.folder / STAGE_FILE).unlink()  # as if killed before the stage finished
    (other.folder / "partial.tmp").write_text("half")
    redone = cached_stage(tmp_path, "thing", {"n": 2}, build)
    assert not redone.cached and len(built) == 3 and not (redone.folder / "partial.tmp").exists()

    def fails(folder: Path) -> None:
        folder.mkdir()
        raise RuntimeError("boom")

    with pytest.raises(RuntimeError):
        cached_stage(tmp_path, "bad", {}, fails)
    assert not list(tmp_path.glob(f"bad-*/{STAGE_FILE}"))  # a failed stage is never marked done


def test_folder_ref_resolves_against_the_config_folder(split_folder: Path) -> None:
    ref = folder_ref(Path(split_folder.name), split_folder.parent, "coco", {"Fire": "fire"}, ("smoke",))
    assert ref.path == split_folder.resolve() and ref.identity["path"] == split_folder.resolve().as_posix()
    assert ref.key() == {"data": dict(ref.identity), "split": None}
    with pytest.raises(FileNotFoundError):
        folder_ref(Path("missing"), split_folder.parent, "auto", {}, ())
    assert isinstance(ref.with_split("test"), DataRef) and ref.with_split("test").split == "test"


def test_synth_stage_resolves_environments_by_content_and_every_key_counts(tmp_path: Path) -> None:
    from dataclasses import replace

    from factories import write_textured_room

    from fuzzyfire.stages import synth_stage
    from synth.flames.library import FlameLibraryConfig
    from synth.method2 import Method2Config
    from synth.smoke.placement import RULES_VERSION

    flames = FlameLibraryConfig(sequences=1, frames=60, keep_every=30)
    cfg = Method2Config(n=2, width=64, height=48, scenes=1, images_per_view=2, flames=flames)
    stage, _ = synth_stage(tmp_path / "data", cfg, tmp_path)
    identity = json.loads((stage.folder / "stage.json").read_text())["identity"]
    assert "environments" not in identity["config"]  # no files: nothing to fingerprint
    assert identity["config"]["flame_height_m"] == [0.3, 2.5]  # every key, at its default too
    assert "plume_rules" not in identity["config"]  # no plumes: a change of where plumes go keeps this pool
    taller, _ = synth_stage(tmp_path / "data", replace(cfg, flame_height_m=(0.9, 3.0)), tmp_path)
    assert taller.hash != stage.hash
    plumes = replace(cfg, n=1, smoke=replace(cfg.smoke, alone=1.0, sequences=1, frames=1))
    smoky, _ = synth_stage(tmp_path / "data", plumes, tmp_path)
    assert json.loads((smoky.folder / "stage.json").read_text())["identity"]["config"]["plume_rules"] == RULES_VERSION
    write_textured_room(tmp_path / "scenes" / "den.glb")
    files = replace(cfg, scenes=0, environments=(Path("scenes"),))
    stage, _ = synth_stage(tmp_path / "data", files, tmp_path)
    identity = json.loads((stage.folder / "stage.json").read_text())["identity"]
    (env,) = identity["config"]["environments"]  # by content, not by path
    assert env["file"] == "den.glb" and len(env["sha256"]["den.glb"]) == 64 and env["scale"] == 1.0


def test_pools_are_identified_by_the_content_of_their_environments_and_photos(tmp_path: Path) -> None:
    """A study moved elsewhere finds its pools: the same files in another folder give the same pool; an edited
    sidecar or another photo gives another."""
    import shutil
    from dataclasses import replace

    from factories import write_textured_room
    from factories_train import painted_dataset

    from fuzzyfire.stages import synth_stage
    from synth.flames.library import FlameLibraryConfig
    from synth.method2 import Method2Config

    for where in ("a", "b"):
        write_textured_room(tmp_path / where / "scenes" / "den.glb")
        painted_dataset(tmp_path / where / "photos", 2, seed=0)
    flames = FlameLibraryConfig(sequences=1, frames=60, keep_every=30)
    cfg = Method2Config(n=2, width=64, height=48, scenes=0, images_per_view=2, flames=flames,
                        environments=(Path("scenes"),), backgrounds=(Path("photos"),))  # fmt: skip
    first, _ = synth_stage(tmp_path / "data", cfg, tmp_path / "a")
    moved, _ = synth_stage(tmp_path / "data", cfg, tmp_path / "b")
    assert moved.hash == first.hash and moved.cached
    (tmp_path / "b" / "scenes" / "den.yaml").write_text("scale: 0.5\n")  # a sidecar beside the mesh
    shutil.copy(next((tmp_path / "b" / "photos").rglob("*.png")), tmp_path / "b" / "photos" / "extra.png")
    identity = json.loads((first.folder / STAGE_FILE).read_text())["identity"]["config"]
    assert [p["name"] for p in identity["backgrounds"]] == sorted(p["name"] for p in identity["backgrounds"])
    from fuzzyfire.stages import content_identity

    there = replace(cfg, environments=(tmp_path / "b" / "scenes",), backgrounds=(tmp_path / "b" / "photos",))
    changed = content_identity(there)
    assert (
        changed["environments"][0]["scale"] == 0.5 and len(changed["backgrounds"]) == len(identity["backgrounds"]) + 1
    )


def _dataset_builder(n: int, seeds: list[int]):
    """A build function writing a COCO dataset of ``n`` images whose pixels come from ``seeds`` (one per build)."""
    from dataclasses import replace

    from ground.data.writer import write_dataset
    from tests.factories import tiny_pool

    def build(folder: Path) -> None:
        src = folder.parent / f"src-{len(seeds)}"
        pool = tiny_pool(src, n, "real:x")
        if seeds.pop(0):  # another environment: the same config makes another picture
            from tests.factories import write_image

            write_image(src / "img000.png", 16, 12, seed=99)
        pool = replace(pool, images=tuple(replace(im, split="train") for im in pool.images))
        write_dataset(pool, folder, ("coco",), "copy")

    return build


def test_a_stage_records_its_contents_and_environment(tmp_path: Path) -> None:
    from ground.data.fingerprint import fingerprint
    from ground.data.formats.coco import read_coco

    stage = cached_stage(tmp_path, "data", {"n": 3}, _dataset_builder(3, [0]))
    doc = json.loads((stage.folder / STAGE_FILE).read_text())
    assert doc["contents"] == fingerprint(read_coco(stage.folder).dataset).to_dict()
    assert doc["contents"]["images"] == 3 and doc["contents"]["splits"] == {"train": 3}
    assert doc["environment"]["versions"]["numpy"] and doc["environment"]["lock"]


def test_a_verified_stage_with_other_contents_is_refused_in_one_line(tmp_path: Path) -> None:
    from fuzzyfire.stages import StageMismatch

    seeds = [0, 0, 1]  # first build, an identical rebuild, then a rebuild that differs
    build = _dataset_builder(3, seeds)
    first = cached_stage(tmp_path, "curated", {"n": 3}, build, verify=True)
    again = cached_stage(tmp_path, "curated", {"n": 3}, build, verify=True)
    assert again.cached and again.folder == first.folder and again.note is None
    with pytest.raises(StageMismatch) as err:
        cached_stage(tmp_path, "curated", {"n": 3}, build, verify=True)
    message = str(err.value)
    assert "\n" not in message and "would mix two datasets" in message
    assert message.count("3 images (train 3, fingerprint") == 2
    assert (first.folder / STAGE_FILE).is_file() and not list(tmp_path.glob(".*verify"))  # nothing lost or left


def test_a_stage_built_with_other_versions_says_so(tmp_path: Path) -> None:
    stage = cached_stage(tmp_path, "data", {"n": 2}, _dataset_builder(2, [0]))
    doc = json.loads((stage.folder / STAGE_FILE).read_text())
    doc["environment"]["versions"]["onnxruntime"] = "0.0.1"
    (stage.folder / STAGE_FILE).write_text(json.dumps(doc))
    again = cached_stage(tmp_path, "data", {"n": 2}, _dataset_builder(2, []))
    assert again.cached and again.note is not None
    assert again.note.startswith("built with onnxruntime 0.0.1 (now ") and again.note.endswith("a rebuild may differ")
