"""Data stages of an experiment, each cached in a folder named by a hash of its resolved config.

A stage writes ``OUT/data/<name>-<hash>/`` and, last, ``stage.json`` (its identity, the fingerprint of the
dataset it holds and the versions that built it): a folder with ``stage.json`` is reused (a curation after
checking that this environment curates the same contents; any stage with a note when it was built with other
versions); a folder without it is an interrupted stage of ours and is rebuilt (synthetic
generators resume from their own staging folders beside it). Stages: the real data (a user folder read in
place, a curation of sources, or a generated stand-in), the rare test set, and the Method 1 / Method 2 pools.
"""

from __future__ import annotations

import hashlib
import json
import os
import shutil
from collections.abc import Callable, Mapping
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import TYPE_CHECKING, Any

from fuzzyfire import __version__
from fuzzyfire.datasets import DataRef
from ground.config.loader import to_dict

if TYPE_CHECKING:
    from synth.method_config import MethodConfig

STAGE_FILE = "stage.json"
STANDIN_LABEL = " (stand-in)"


#: The version of what stages and runs mean, in every identity :func:`digest` hashes. Bump it when a config key
#: is removed or changes meaning (every stage and run then rebuilds), instead of keeping old keys for old hashes.
#: 2: the options measured not to help were deleted (docs/findings.md, "Retired designs").
#: 3: post-processing is one section, train.postprocess and score.postprocess (was train.val_conf, val_iou,
#: max_det and score.conf, iou, max_det); score gained resize.
IDENTITY = 3


def digest(identity: Mapping[str, Any]) -> str:
    """12 hex digits of the SHA-256 of ``identity`` and :data:`IDENTITY` as canonical JSON."""
    text = json.dumps({"identity": identity, "version": IDENTITY}, sort_keys=True, separators=(",", ":"), default=str)
    return hashlib.sha256(text.encode("utf-8")).hexdigest()[:12]


@dataclass(frozen=True)
class Stage:
    folder: Path
    hash: str
    cached: bool
    note: str | None = None  # one line for the user about a reused stage (built on another environment)


class StageMismatch(ValueError):
    """A finished stage holds other contents than its config gives in this environment."""


def contents(folder: Path) -> dict[str, Any] | None:
    """The :class:`ground.data.fingerprint.Fingerprint` of the dataset in ``folder`` (None: not a dataset)."""
    from ground.data.fingerprint import fingerprint
    from ground.data.formats.coco import read_coco

    if not (folder / "annotations.json").is_file():
        return None
    return fingerprint(read_coco(folder).dataset).to_dict()


def environment() -> dict[str, Any]:
    """What a stage was built with: the versions that shape outputs and the lock file's hash."""
    from ground.data.manifest import versions
    from ground.run.lock import lock_status

    return {"versions": versions(), "lock": lock_status().get("sha256")}


def cached_stage(
    root: Path,
    name: str,
    identity: Mapping[str, Any],
    build: Callable[[Path], Any],
    verify: bool = False,
) -> Stage:
    """Run ``build(folder)`` unless ``root/<name>-<hash>/stage.json`` exists; write ``stage.json`` last, with
    the :func:`contents` of what was built and the :func:`environment` that built it.
    ``verify`` (for cheap stages, e.g. a curation whose embeddings are cached): a reused stage is rebuilt aside
    and compared by contents; other contents raise :class:`StageMismatch` instead of mixing two datasets."""
    identity = {**identity, "fuzzyfire": __version__}
    h = digest(identity)
    folder = Path(root) / f"{name}-{h}"
    if (folder / STAGE_FILE).is_file():
        return reused_stage(folder, h, build if verify else None)
    if folder.exists():
        shutil.rmtree(folder)  # our own interrupted stage (no stage.json): rebuild it
    build(folder)
    doc = {"stage": name, "hash": h, "identity": identity, "contents": contents(folder), "environment": environment()}
    (folder / STAGE_FILE).write_text(json.dumps(doc, indent=1, sort_keys=True, default=str) + "\n", encoding="utf-8")
    return Stage(folder, h, False)


def reused_stage(folder: Path, h: str, rebuild: Callable[[Path], Any] | None) -> Stage:
    """A finished stage, checked: with ``rebuild``, against a fresh build of it (:class:`StageMismatch` when the
    contents differ); otherwise its environment against this one (a note when they differ)."""
    doc = json.loads((folder / STAGE_FILE).read_text(encoding="utf-8"))
    if rebuild is not None:
        recorded = doc.get("contents") or contents(folder)
        fresh = _rebuilt_contents(folder, rebuild)
        if fresh != recorded:
            raise StageMismatch(
                f"{folder}: holds {_describe(recorded)}, but its config now gives {_describe(fresh)} "
                "(another environment or fuzzyfire version): its runs would mix two datasets; move the folder "
                "away to rebuild it, or use another --out"
            )
    return Stage(folder, h, True, _environment_note(doc.get("environment")))


def _rebuilt_contents(folder: Path, rebuild: Callable[[Path], Any]) -> dict[str, Any] | None:
    aside = folder.parent / f".{folder.name}.verify"
    shutil.rmtree(aside, ignore_errors=True)
    try:
        rebuild(aside)
        return contents(aside)
    finally:
        shutil.rmtree(aside, ignore_errors=True)


def _describe(fp: Mapping[str, Any] | None) -> str:
    if fp is None:
        return "no dataset"
    splits = ", ".join(f"{k or '(none)'} {v}" for k, v in fp["splits"].items())
    return f"{fp['images']} images ({splits}, fingerprint {fp['fingerprint']})"


def _environment_note(built: Mapping[str, Any] | None) -> str | None:
    """One line naming the versions that differ from the ones a stage was built with (None: same, or unknown)."""
    if not built:
        return None
    now = environment()
    changed = {k: (v, now["versions"].get(k)) for k, v in built["versions"].items() if now["versions"].get(k) != v}
    if not changed:
        return None
    shown = ", ".join(f"{k} {old} (now {new})" for k, (old, new) in sorted(changed.items()))
    return f"built with {shown}: a rebuild may differ"


def _absolute(path: Path, base: Path) -> Path:
    return (path if path.is_absolute() else base / path).resolve()


def folder_ref(
    path: Path,
    base: Path,
    fmt: str,
    aliases,
    drop,
    split: str | None = None,
    holdout: float = 0.0,
    negatives=(),
    key: str = "path",
    label: str | None = None,
) -> DataRef:
    """A user's dataset read in place (identity = its resolved path and reading options; ``holdout``, the share
    of held-out photos it is cut to, and ``label``, the class every image of a folder without labels holds, only
    when set). ``key``: the config key that gave ``path``, for the error when it names nothing."""
    where = _absolute(path, base)
    if not where.exists():
        raise FileNotFoundError(f"{key}: {str(path)!r}: dataset not found (no {where})")
    identity = {"kind": "folder", "path": where.as_posix(), "format": fmt, "aliases": dict(aliases)}
    if holdout:
        identity["holdout"] = holdout
    if label:
        identity["label"] = label
    ref = DataRef(where, identity, fmt, split, dict(aliases), holdout=holdout, label=label)
    return with_class_rules(ref, drop, negatives)


def with_class_rules(ref: DataRef, drop, negatives) -> DataRef:
    """``ref`` with the classes ``drop`` and ``negatives`` removed, images left without boxes leaving it unless
    their boxes were all of ``negatives`` (:func:`ground.data.load.with_classes`), both in its identity."""
    identity = {**ref.identity, "drop": list(drop), "negative_classes": list(negatives)}
    return replace(ref, identity=identity, drop=tuple(drop), negatives=tuple(negatives))


def standin_stage(root: Path, name: str, cfg: Any) -> tuple[Stage, DataRef]:
    """A generated stand-in set (:func:`synth.standin.run_standin`)."""
    from synth.standin import run_standin

    stage = cached_stage(root, name, {"kind": "standin", "config": to_dict(cfg)}, lambda out: run_standin(cfg, out))
    return stage, DataRef(stage.folder, {"kind": "standin", "hash": stage.hash}, "coco", standin=True)


def synth_stage(root: Path, cfg: MethodConfig, base: Path, cutouts: Stage | None = None) -> tuple[Stage, DataRef]:
    """A Method 1 or Method 2 pool of ``cfg``, its flame library built from ``cfg.flames``; its places (every key
    of :meth:`~synth.method_config.MethodConfig.place_keys`: environments, and Method 2's backgrounds and
    labelled frames) resolve against ``base``. They enter the pool's identity by content
    (:func:`content_identity`), not by path, so a study moved to another folder or machine finds its pools (and
    runs) again. ``cutouts``: a stage of real flame cut-outs (:mod:`fuzzyfire.cutout_pools`) for a ``flames.source:
    cutouts`` pool, named ``<method>-cutouts-<hash>``; its hash enters the pool's identity. The pool is made in one
    process per core."""
    from synth.flames.sprites import load_library
    from synth.generate import generate, run_library

    method = cfg.method
    cfg = cfg.with_paths(lambda p: _absolute(p, base))
    config = {k: v for k, v in to_dict(cfg).items() if k not in cfg.place_keys()}
    files = content_identity(cfg)
    flames = {"cutouts": cutouts.hash} if cutouts is not None else {}
    flames |= _plume_rules(cfg)
    frames = "-frames" if cfg.places().labelled_frames else ""
    stage = cached_stage(
        root,
        f"{method}-cutouts" if cutouts is not None else f"{method}{frames}",
        {"kind": method, "config": {**config, **files, **flames}},
        lambda out: generate(
            cfg,
            run_library(cfg, load_library([cutouts.folder]) if cutouts else ()),
            out,
            workers=os.cpu_count() or 1,  # the same bytes from any number of processes
        ),
    )
    return stage, DataRef(stage.folder, {"kind": method, "hash": stage.hash}, "coco")


def _plume_rules(cfg: MethodConfig) -> dict[str, int]:
    """``{"plume_rules": version}`` for a pool that lays plumes (:data:`synth.smoke.placement.RULES_VERSION`), else
    nothing: a change of where plumes go rebuilds those pools only."""
    from synth.method2 import Method2Config
    from synth.smoke.placement import RULES_VERSION

    return {"plume_rules": RULES_VERSION} if isinstance(cfg, Method2Config) and cfg.smoke.plumes else {}


def content_identity(cfg: MethodConfig) -> dict[str, Any]:
    """The places of ``cfg`` by content, under the kind of each (only the kinds it has): ``environments`` (mesh
    files), ``panoramas``, ``backgrounds`` (the photos a pool composites on, its held-out share left out) and
    ``frames`` (labelled frames, :mod:`synth.places.frames`)."""
    from synth.places.envfile import find_environment_files, fingerprint
    from synth.places.panorama import panorama_fingerprints
    from synth.places.photos import photo_fingerprints

    out: dict[str, Any] = {}
    given = cfg.places()
    places = given.split()
    if places.meshes:
        out["environments"] = [fingerprint(spec) for spec in find_environment_files(places.meshes)]
    if places.panoramas:
        out["panoramas"] = panorama_fingerprints(places.panoramas)
    if given.backgrounds:
        out["backgrounds"] = photo_fingerprints(given.backgrounds, given.background_holdout)
    if given.labelled_frames:
        from synth.places.frames import frame_classes, frame_fingerprints

        out["frames"] = frame_fingerprints(given.labelled_frames, frame_classes(cfg.smoke_class))
    return out


def curate_stage(root: Path, cfg: Any, base: Path) -> tuple[Stage, DataRef]:
    """``fuzzyfire curate`` of ``cfg`` (a :class:`curate.curation.CurateConfig`; sources relative to ``base``)
    with the user's embedding cache (on ``cfg.executor``, a Ray cluster if so configured). A finished curation is
    verified on reuse (a few seconds with the cache): its contents must be what this environment curates."""
    config = to_dict(cfg)
    del config["executor"], config["model"]["device"]  # where it runs, not what it makes: the same dataset
    for i, source in enumerate(config["sources"]):
        where = _absolute(Path(source["path"]), base)
        if not where.exists():
            raise FileNotFoundError(
                f"real.curate.sources[{i}].path: {source['path']!r}: dataset to curate not found (no {where})"
            )
        source["path"] = where.as_posix()
    stage = cached_stage(
        root, "curated", {"kind": "curate", "config": config}, lambda out: _curate(cfg, base, out), verify=True
    )
    return stage, DataRef(stage.folder, {"kind": "curate", "hash": stage.hash}, "coco")


def _curate(cfg: Any, base: Path, out: Path) -> None:
    from curate.curation import curate_dataset
    from curate.embed import embedding_cache_path

    curate_dataset(
        cfg, base, out, embedding_cache_path(), {"command": "experiment curate", "args": {"config": to_dict(cfg)}}
    )


@dataclass(frozen=True)
class Prepared:
    """The experiment's data: the real set (with splits), the rare test set, the synthetic pools, the named
    test sets (``tests:``) by label and, by test-set label, the check of each against the training data
    (:class:`fuzzyfire.leakage.TestLeaks`; its leaked images leave the set when ``leakage.action`` is drop)."""

    real: DataRef
    rare: DataRef | None
    pools: dict[str, DataRef]
    tests: dict[str, DataRef] = field(default_factory=dict)
    leaks: dict[str, Any] = field(default_factory=dict)

    @property
    def standin(self) -> bool:
        return self.real.standin or bool(self.rare and self.rare.standin)


def label(name: str, standin: bool) -> str:
    """A test-set label; stand-in data says so in every table column and figure legend."""
    return f"{name}{STANDIN_LABEL}" if standin and "stand-in" not in name else name
