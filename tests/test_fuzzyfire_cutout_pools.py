"""Own Method 2 pools per (mixture's real training subset, seed): flames (and own frames) only from that subset
(no leakage), one pool per subset content, R0 mixtures on the shared simulated pool, byte-identical rebuilds, and
the identities of configs without ``flames.source`` or ``own_frames`` unchanged."""

from __future__ import annotations

import contextlib
import hashlib
import io
import json
from pathlib import Path
from typing import Any

import pytest
from factories import tiny_pool
from factories_experiment import toy_dict

import fuzzyfire.stages as stages
from fuzzyfire.cutout_pools import cutout_pools, cutout_stage, simulated
from fuzzyfire.datasets import Datasets
from fuzzyfire.experiment import (
    grid_entries,
    needed_methods,
    prepare_data,
    run_experiment,
    shared_methods,
    write_mixtures,
)
from fuzzyfire.experiment_config import ExperimentConfig
from ground.config.loader import build_config
from ground.data.formats.coco import read_coco

CONFIGS = Path(__file__).resolve().parents[1] / "configs"
SEEDS = [0, 1]


def _config(source: str | None, own_frames: float = 0.0, **grid: Any) -> ExperimentConfig:
    """The toy config with 160x120 real images (flames large enough to cut), no Method 1, Method 2 flames from
    ``source`` (None: the key left out), ``own_frames`` when > 0."""
    d = toy_dict(**{"mixtures": ["R6_S6", "R6_S3", "R0_S6"], "table1": [], "seeds": SEEDS, **grid})
    d["real"]["standin"].update(width=160, height=120, flame_height=[0.3, 0.6], negatives=0.0)
    d["synth"]["method1"] = None
    if source is not None:
        d["synth"]["method2"]["flames"] = {**d["synth"]["method2"]["flames"], "source": source}
    if own_frames:
        d["synth"]["method2"]["own_frames"] = own_frames
    d["report"] = {"bootstrap": 0, "samples": False, "gap_draws": 0}
    return build_config(d, ExperimentConfig)


def _prepare(cfg: ExperimentConfig, out: Path) -> tuple[Any, dict, dict, str]:
    """(data, own pools, mixture refs, what was printed) of ``cfg`` in ``out``, nothing trained."""
    printed = io.StringIO()
    with contextlib.redirect_stdout(printed):
        grid = grid_entries(cfg)
        data = prepare_data(cfg, out, out, needed_methods(grid))
        datasets = Datasets(cfg.classes)
        drawn = [e.mixture for e in grid if e.method == "method2"]
        own = cutout_pools(cfg, drawn, data.real.with_split(cfg.real.train_split), datasets, out, out)
        refs = write_mixtures(cfg, grid, data, datasets, out, own)
    return data, own, refs, printed.getvalue()


@pytest.fixture(scope="module")
def built(tmp_path_factory: pytest.TempPathFactory) -> tuple[Path, Any, dict, dict, str]:
    out = tmp_path_factory.mktemp("cutout-pools")
    return (out, *_prepare(_config("cutouts"), out))


def _cut_stage(out: Path, pool: Path) -> Path:
    identity = json.loads((pool / "stage.json").read_text())["identity"]
    return out / "data" / f"cutouts-{identity['config']['cutouts']}"


def _files(root: Path, names: list[str]) -> set[str]:
    return {(root / n).resolve().as_posix() for n in names}


def test_every_cutout_comes_from_its_mixtures_own_real_training_images(built) -> None:
    out, data, own, refs, _ = built
    real = read_coco(data.real.path).dataset
    held_out = {real.image_path(i).resolve().as_posix() for i in real.images if i.split != "train"}
    assert sorted(own) == sorted((m, "method2", s) for s in SEEDS for m in ("R6_S6", "R6_S3"))
    for (name, method, seed), pool in own.items():
        record = json.loads((refs[(name, method, seed)].path / "mixture.json").read_text())
        trained = {e["from"] for e in record["images"] if e["source"].startswith("real:")}
        synthetic = {e["from"] for e in record["images"] if e["source"].startswith("synth:")}
        index = json.loads((_cut_stage(out, pool.path) / "cutouts.json").read_text())
        cut_from = _files(data.real.path, [e["file"] for e in index])
        assert index and cut_from <= trained and not cut_from & held_out  # no validation or test flame
        assert synthetic <= _files(pool.path, [i.file_name for i in read_coco(pool.path).dataset.images])
        assert refs[(name, method, seed)].identity["synth"] == pool.key()


def test_one_pool_per_subset_content_and_seed(built) -> None:
    out, _, own, _, _ = built
    for seed in SEEDS:  # R6_S6 and R6_S3 train on the same 6 real images: one cut-out set, one pool
        assert own[("R6_S6", "method2", seed)] == own[("R6_S3", "method2", seed)]
    assert own[("R6_S6", "method2", 0)] != own[("R6_S6", "method2", 1)]  # another draw, other flames
    pools = sorted(p.name for p in (out / "data").iterdir() if p.name.startswith("method2-cutouts-"))
    assert len(pools) == 2 and len(list((out / "data").glob("cutouts-*"))) == 2
    identity = json.loads((own[("R6_S6", "method2", 0)].path / "stage.json").read_text())["identity"]["config"]
    assert identity["flames"]["source"] == "cutouts"  # a non-default key is in the identity


def test_r0_mixtures_keep_the_shared_simulated_pool_and_say_so(built) -> None:
    _, data, _, refs, printed = built
    for seed in SEEDS:
        assert refs[("R0_S6", "method2", seed)].identity["synth"] == data.pools["method2"].with_split(None).key()
    assert "R0_S6 have no real images of their own: the shared simulated pool" in printed


def test_a_study_of_own_pools_only_builds_no_shared_simulated_pool(tmp_path: Path) -> None:
    """The shared Method 2 pool is built only when a run draws it: an R0 mixture, or flames.source simulated."""
    own_only = _config("cutouts", mixtures=["R6_S6"], seeds=[0])
    assert shared_methods(own_only, grid_entries(own_only)) == []
    assert needed_methods(grid_entries(own_only)) == ["method2"]  # its photos are still checked for leakage
    for cfg in (_config("cutouts"), _config(None, mixtures=["R6_S6"])):  # R0_S6 draws it; simulated flames share it
        assert shared_methods(cfg, grid_entries(cfg)) == ["method2"]
    with contextlib.redirect_stdout(io.StringIO()):
        result = run_experiment(own_only, tmp_path, tmp_path / "study")  # no executor: builds data, trains nothing
    pools = sorted(p.name for p in (tmp_path / "study" / "data").glob("method2-*"))
    assert pools and all(name.startswith("method2-cutouts-") for name in pools), pools
    assert result.report.is_file()


def test_configs_without_the_key_keep_their_pools_and_mixtures(built) -> None:
    out, data, _, refs, _ = built
    for source in (None, "simulated"):
        plain_data, plain_own, plain_refs, printed = _prepare(_config(source), out)
        assert plain_own == {} and plain_data.pools == data.pools  # the shared pool: the same stage, reused
        assert f"{data.pools['method2'].path}  (cached)" in printed
        for seed in SEEDS:
            key = ("R0_S6", "method2", seed)
            assert plain_refs[key].identity == refs[key].identity and plain_refs[key].path == refs[key].path


def _identity_digest(cfg: Any, base: Path, monkeypatch: pytest.MonkeyPatch) -> str:
    """The digest of the identity :func:`fuzzyfire.stages.synth_stage` gives a pool (fuzzyfire's version left out),
    captured before anything is built."""

    class Captured(Exception):
        pass

    def capture(root, name, identity, build, legacy=None, verify=False):
        raise Captured(stages.digest(identity))

    monkeypatch.setattr(stages, "cached_stage", capture)
    with pytest.raises(Captured) as got:
        stages.synth_stage(Path("unused"), cfg, base)
    return str(got.value)


def _hashes(folder: Path) -> dict[str, str]:
    return {
        p.relative_to(folder).as_posix(): hashlib.sha256(p.read_bytes()).hexdigest()
        for p in sorted(folder.rglob("*"))
        if p.is_file() and p.suffix in (".png", ".jpg")
    }


def test_a_rebuild_elsewhere_gives_the_same_stages_byte_for_byte(built, tmp_path: Path) -> None:
    out, _, own, _, _ = built
    _, again, _, _ = _prepare(_config("cutouts", seeds=[0]), tmp_path)
    first, second = own[("R6_S6", "method2", 0)], again[("R6_S6", "method2", 0)]
    assert first.identity == second.identity
    assert _hashes(first.path) == _hashes(second.path) and _hashes(first.path)
    cut_a, cut_b = _cut_stage(out, first.path), _cut_stage(tmp_path, second.path)
    assert (
        _hashes(cut_a) == _hashes(cut_b)
        and (cut_a / "cutouts.json").read_bytes() == (cut_b / "cutouts.json").read_bytes()
    )


def test_a_subset_without_cutouts_or_a_grid_without_fire_is_refused_in_one_line(tmp_path: Path) -> None:
    with pytest.raises(
        ValueError, match=r"fire cut-outs: the 4 real images of a mixture give none \(fire boxes of at least 16 px"
    ):
        cutout_stage(tmp_path / "data", tiny_pool(tmp_path / "tiny", 4, "real:tiny"))  # 16x12 images, 4-8 px boxes
    d = toy_dict(mixtures=["R6_S6"], table1=[], seeds=[0])
    d["classes"], d["synth"]["method1"] = ["smoke"], None
    d["synth"]["method2"]["flames"] = {**d["synth"]["method2"]["flames"], "source": "cutouts"}
    cfg = build_config(d, ExperimentConfig)
    with pytest.raises(ValueError, match=r"own Method 2 pools cut 'fire' boxes, but classes are \['smoke'\]"):
        cutout_pools(cfg, ["R6_S6"], None, Datasets(cfg.classes), tmp_path, tmp_path)


def test_smoke_cutouts_carry_the_matte_rule_and_fire_cutouts_keep_their_identity(tmp_path: Path) -> None:
    import json

    from synth.smoke.matte import CENTRE_HAZE

    identity = {}
    for cls in ("fire", "smoke"):
        with pytest.raises(ValueError, match=f"{cls} cut-outs: the 4 real images of a mixture give none"):
            cutout_stage(tmp_path / cls, tiny_pool(tmp_path / f"tiny-{cls}", 4, "real:tiny", cls), (cls,))
        (stage,) = (tmp_path / cls).glob("cutouts-*/stage.json")
        identity[cls] = json.loads(stage.read_text())["identity"]
    assert "centre_haze" not in identity["fire"] and identity["smoke"]["centre_haze"] == CENTRE_HAZE


def test_own_frames_composite_on_the_mixtures_own_training_images_only(tmp_path: Path) -> None:
    """``own_frames``: each (subset, seed) pool composites simulated flames on that subset's images, which keep
    their fire boxes; R0 mixtures keep the shared pool, which is the pool of the config without the key."""
    cfg = _config(None, own_frames=1.0)
    data, own, refs, printed = _prepare(cfg, tmp_path)
    assert sorted(own) == sorted((m, "method2", s) for s in SEEDS for m in ("R6_S6", "R6_S3"))
    assert simulated(cfg.synth.method2) == _config(None).synth.method2
    real = read_coco(data.real.path).dataset
    boxes = real.annotations_by_image()
    real_boxes = {real.image_path(i).resolve().as_posix(): len(boxes[i.id]) for i in real.images}
    for (name, method, seed), pool in own.items():
        assert pool.path.name.startswith("method2-frames-") and "flames of" not in printed
        record = json.loads((refs[(name, method, seed)].path / "mixture.json").read_text())
        trained = {e["from"] for e in record["images"] if e["source"].startswith("real:")}
        per_image = json.loads((pool.path / "manifest.json").read_text())["args"]["per_image"]
        shown = {Path(m["photo"]).resolve().as_posix() for m in per_image}
        assert shown <= trained  # only the mixture's own training images, never validation or test ones
        assert all(len(m["frame_boxes"]) <= real_boxes[Path(m["photo"]).resolve().as_posix()] for m in per_image)
        assert sum(len(m["frame_boxes"]) for m in per_image) > 0
    for seed in SEEDS:
        assert refs[("R0_S6", "method2", seed)].identity["synth"] == data.pools["method2"].with_split(None).key()
