"""Stage cache (built once, reused, an interrupted stage rebuilt) and reading a dataset split with fixed classes."""

from __future__ import annotations

import json
from pathlib import Path

import pytest
from factories_train import painted_dataset

from curate.core.writer import write_dataset
from fuzzyfire.stages import STAGE_FILE, DataRef, cached_stage, digest, folder_ref, load_data


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


@pytest.fixture(scope="module")
def split_folder(tmp_path_factory: pytest.TempPathFactory) -> Path:
    root = tmp_path_factory.mktemp("split")
    ds = painted_dataset(root / "src", 10, seed=0)  # classes fire, smoke
    images = tuple(img.__class__(**{**img.__dict__, "split": "train" if img.id <= 6 else "test"}) for img in ds.images)
    write_dataset(ds.__class__(ds.root, images, ds.annotations, ds.categories), root / "ds", ("coco",))
    return root / "ds"


def test_load_data_picks_the_split_and_fixes_classes(split_folder: Path) -> None:
    ref = folder_ref(split_folder, Path("/"), "auto", {}, ())
    train = load_data(ref.with_split("train"), ["fire"])
    assert len(train.images) == 6 and train.category_names == ["fire"]
    full = load_data(ref, ["fire", "smoke"])
    assert len(full.images) == 10 and len(full.annotations) > len(train.annotations)
    assert load_data(ref, ["smoke", "fire"]).category_names == ["smoke", "fire"]
    with pytest.raises(ValueError, match="no split 'valid'.*curate"):
        load_data(ref.with_split("valid"), ["fire"])


def test_folder_ref_resolves_against_the_config_folder(split_folder: Path) -> None:
    ref = folder_ref(Path(split_folder.name), split_folder.parent, "coco", {"Fire": "fire"}, ("smoke",))
    assert ref.path == split_folder.resolve() and ref.identity["path"] == split_folder.resolve().as_posix()
    assert ref.key() == {"data": dict(ref.identity), "split": None}
    with pytest.raises(FileNotFoundError):
        folder_ref(Path("missing"), split_folder.parent, "auto", {}, ())
    assert isinstance(ref.with_split("test"), DataRef) and ref.with_split("test").split == "test"


def test_synth_stage_resolves_environments_and_keeps_old_identities(tmp_path: Path) -> None:
    from dataclasses import replace

    from factories import write_textured_room

    from fuzzyfire.stages import synth_stage
    from synth.library import FlameLibraryConfig
    from synth.method2 import Method2Config

    flames = FlameLibraryConfig(sequences=1, frames=60, keep_every=30)
    cfg = Method2Config(n=2, width=64, height=48, scenes=1, images_per_view=2, flames=flames)
    stage, _ = synth_stage(tmp_path / "data", "method2", cfg, tmp_path)
    identity = json.loads((stage.folder / "stage.json").read_text())["identity"]
    assert "environments" not in identity["config"]  # pools made before environments existed are still found
    assert "flame_opacity" not in identity["config"]  # nor flame_opacity, while it holds its default
    opaque, _ = synth_stage(tmp_path / "data", "method2", replace(cfg, flame_opacity=(0.9, 1.0)), tmp_path)
    assert opaque.hash != stage.hash
    write_textured_room(tmp_path / "scenes" / "den.glb")
    files = replace(cfg, scenes=0, environments=(Path("scenes"),))
    stage, _ = synth_stage(tmp_path / "data", "method2", files, tmp_path)
    identity = json.loads((stage.folder / "stage.json").read_text())["identity"]
    assert identity["config"]["environments"] == [(tmp_path / "scenes").resolve().as_posix()]
