"""The schema of ``fuzzyfire experiment CONFIG``: frozen dataclasses built once from commented YAML by
:func:`ground.config.loader.load_config` (``docs/config.md`` lists every key with its type, default and meaning: it
is generated from these classes by :mod:`fuzzyfire.reference`).

Component configs are the packages' own: :class:`curate.curation.CurateConfig`, :class:`synth.method1.
Method1Config`, :class:`synth.method2.Method2Config`, :class:`synth.standin.StandInConfig`,
:class:`train.config.TrainConfig`, :class:`eval.config.InferenceConfig`. Relative paths resolve against the config
file's folder.
"""

from __future__ import annotations

from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import Literal, Optional

from curate.curation import CurateConfig
from curate.dedup import DEFAULT_THRESHOLD
from curate.frechet import DRAWS
from curate.sources import SourceConfig
from eval.config import InferenceConfig
from eval.tables import MIN_AP_IMAGES
from fuzzyfire.engine import EngineConfig, EngineError
from synth.method1 import Method1Config
from synth.method2 import Method2Config
from synth.method_config import MethodConfig
from synth.standin import StandInConfig
from train.config import TrainConfig

METHODS: tuple[str, ...] = ("method1", "method2")


class ExperimentConfigError(ValueError):
    """A config whose parts do not fit together (e.g. no source for the real data)."""


@dataclass(frozen=True)
class RealConfig:
    """The real data: a labelled folder (``path``), optionally curated first (``curate``; its sources default to
    ``path``), or a generated stand-in (``standin``, the offline demo). The result must have the three splits."""

    path: Optional[Path] = None  # dataset folder (any format the toolkit reads) or COCO .json
    format: Literal["auto", "coco", "yolo", "voc", "dfire"] = "auto"  # the folder's layout; auto: detected
    aliases: dict[str, str] = field(default_factory=dict)  # source class -> class, e.g. {flame: fire}
    drop_classes: tuple[str, ...] = ()  # classes whose boxes are removed (an image left without boxes leaves)
    negative_classes: tuple[str, ...] = ()  # classes whose boxes mark images without the studied classes (e.g.
    # 'default', a near-full-frame box on frames without fire): removed, their images stay as negatives. An image
    # whose every box was removed otherwise (drop_classes, a class not studied) leaves every split, counted
    curate: Optional[CurateConfig] = None  # `fuzzyfire curate` settings; sources: [] = curate ``path``
    standin: Optional[StandInConfig] = None  # a generated stand-in instead of real photos (configs/demo.yaml)
    train_split: str = "train"  # mixtures draw their real images from this split
    val_split: str = "valid"  # every run selects its best epoch on this split
    test_split: str = "test"  # the common test set
    name: str = "common"  # test-set label in tables and figures

    def source(self) -> str:
        """``"path"``, ``"curate"`` or ``"standin"``; raises when the keys contradict each other."""
        if self.standin is not None:
            if self.path is not None or self.curate is not None:
                raise ExperimentConfigError("real: standin excludes path and curate")
            return "standin"
        if self.curate is not None:
            if bool(self.curate.sources) == (self.path is not None):
                raise ExperimentConfigError("real: give curate.sources or path (the folder to curate), not both")
            return "curate"
        if self.path is None:
            raise ExperimentConfigError("real: give path (a labelled folder), curate or standin")
        return "path"

    def curate_config(self) -> CurateConfig:
        """``curate`` with its sources filled in from ``path`` when it lists none (``drop_classes`` apply to the
        curated set, as for a folder read in place: :func:`ground.data.load.with_classes`)."""
        assert self.curate is not None, "curate_config() without real.curate"
        if self.curate.sources:
            return self.curate
        return replace(self.curate, sources=(SourceConfig(self.path, self.format, aliases=self.aliases),))


@dataclass(frozen=True)
class EvalSetConfig:
    """A test set: a dataset folder (``path``, optionally one ``split``) or a generated stand-in (``standin``).
    A folder of images without labels is a negatives-only set (no AP: its false alarms per 100 images are
    reported) unless ``label`` declares the class every image holds: an image-labelled set, judged by image recall
    (no AP), as is a classification layout (``format: folders``: ``fire/`` and ``normal/`` sub-folders).
    ``holdout`` keeps only the images :func:`ground.data.holdout.held_out` picks at that share; when ``path`` is a
    folder of ``synth.method2.backgrounds``, the Method 2 pool never composites on them
    (:meth:`ExperimentConfig.resolved`)."""

    path: Optional[Path] = None  # dataset folder (any format) or a folder of unlabelled images
    format: Literal["auto", "coco", "yolo", "voc", "dfire", "images", "folders"] = "auto"  # images: unlabelled
    # (negatives only, or every image `label`); folders: fire/ + normal/ sub-folders (image-labelled); auto: detected
    split: Optional[str] = None  # null = every image of the folder
    aliases: dict[str, str] = field(default_factory=dict)  # source class -> class, e.g. {Fire: fire}
    drop_classes: tuple[str, ...] = ()  # classes whose boxes are removed (an image left without boxes leaves)
    negative_classes: tuple[str, ...] = ()  # classes whose boxes mark images without the studied classes:
    # removed, their images stay as negatives (any other image left without boxes leaves the set, counted)
    standin: Optional[StandInConfig] = None  # a generated stand-in set instead of a folder
    label: Optional[str] = None  # the class every image of a folder without label files holds (e.g. fire): an
    # image-labelled set, judged by image recall, no AP (null = such a folder is negatives only); on a stand-in,
    # its images are judged at the image level (those with a box of the class hold it, the others are negatives)
    holdout: float = 0.0  # 0 = every image; 0 < share <= 1 = only the held-out share (chosen by content hash); on
    # a folder of synth.method2.backgrounds, the photos the pool never composites on
    name: Optional[str] = None  # label in tables and figures; null = the key under ``tests:``

    def source(self, where: str = "test set") -> str:
        """``"path"`` or ``"standin"``; raises when the keys contradict each other (``where`` names the set)."""
        given = [k for k in ("path", "standin") if getattr(self, k) is not None]
        if len(given) != 1:
            raise ExperimentConfigError(f"{where}: give exactly one of path, standin (got {given or 'none'})")
        if not 0.0 <= self.holdout <= 1.0:
            raise ExperimentConfigError(f"{where}: holdout must be in 0..1, got {self.holdout:g}")
        if self.holdout and given[0] != "path":
            raise ExperimentConfigError(f"{where}: holdout picks photos of a folder (path), not of a stand-in")
        return given[0]


@dataclass(frozen=True)
class RareConfig(EvalSetConfig):
    """The rare test set (:class:`EvalSetConfig` labelled ``rare``)."""

    name: str = "rare"  # type: ignore[assignment]  # always labelled

    def source(self, where: str = "rare") -> str:
        return super().source(where)


@dataclass(frozen=True)
class SynthConfig:
    """The two synthetic pools; ``null`` leaves a method out (Table 1 then has one method)."""

    method1: Optional[Method1Config] = field(default_factory=Method1Config)  # flame planes in 3D scenes; null = none
    method2: Optional[Method2Config] = field(default_factory=Method2Config)  # flames composited; null = none

    def section(self, method: str) -> MethodConfig | None:
        """The settings of the pool of ``method`` (None: left out); ValueError for a name not in :data:`METHODS`."""
        sections: dict[str, MethodConfig | None] = {"method1": self.method1, "method2": self.method2}
        if method not in sections:
            raise ValueError(f"unknown synthesis method {method!r}; choose one of {', '.join(METHODS)}")
        return sections[method]


@dataclass(frozen=True)
class GridConfig:
    """The runs: every mixture x seed. ``mixtures`` make Table 2 (their synthetic images from ``synthetic``);
    ``table1`` mixtures (synthetic only) are trained with every method for Table 1. ``control``: each Table 2
    mixture with real and synthetic images is also trained with its synthetic images replaced by flame-free
    copies of its own real images (:mod:`fuzzyfire.controls`), and compared with that run."""

    mixtures: tuple[str, ...] = (
        "R250_S0", "R500_S0", "R750_S0", "R1000_S0",
        "R750_S250", "R500_S500", "R250_S750",
        "R0_S250", "R0_S500", "R0_S750", "R0_S1000",
    )  # fmt: skip
    # the Table 2 mixtures: R<m>_S<n> = m real + n synthetic training images
    synthetic: Literal["method1", "method2"] = "method2"  # the pool of Table 2's mixtures: method1 | method2
    table1: tuple[str, ...] = ("R0_S1000",)  # synthetic-only mixtures trained with every method (Table 1)
    seeds: tuple[int, ...] = (0, 1, 2, 3, 4)  # every mixture is trained once per seed
    control: bool = False  # also train each real + synthetic mixture on flame-free copies of its own real images


@dataclass(frozen=True)
class RunExecutorConfig:
    """Where an experiment's runs train (:mod:`fuzzyfire.executors`)."""

    name: Literal["local", "ray"] = "local"  # local (one run at a time, all cores) | ray (one task per run)
    address: Optional[str] = None  # ray: address of a running cluster (e.g. ray://head:10001); null = start one here
    num_cpus: float = 2  # CPUs per run (ray task resources; also the torch threads when train.threads is 0)
    num_gpus: float = 0  # GPUs per run (ray task resources)
    local_cpus: Optional[int] = None  # ray without address: CPUs the local Ray may use (null = all)


@dataclass(frozen=True)
class LeakageConfig:
    """Every test set is checked against the real training data before anything is trained
    (:mod:`fuzzyfire.leakage`): its copies and near duplicates of training images are dropped or refuse the study."""

    action: Literal["drop", "refuse"] = "drop"  # drop: leaked test images leave their set (listed in leakage.json
    # and the report) | refuse: the study stops before training and names them
    threshold: float = DEFAULT_THRESHOLD  # Euclidean distance of unit embeddings, 0..2, under which two images
    # are duplicates (the dedup's default)


@dataclass(frozen=True)
class ReportConfig:
    title: str = "fuzzyfire study"  # the report's title
    bootstrap: int = 1000  # paired image-level bootstrap resamples per comparison (0 = no comparisons)
    baseline: Optional[str] = None  # mixture the others are compared with (default: largest real-only one)
    samples: bool = True  # sample thumbnails with boxes (8 per dataset) in report.html
    gap_draws: int = DRAWS  # realism gap of each synthetic pool (synth gap) over this many draws; 0 = none
    min_fire_images: int = MIN_AP_IMAGES  # a test set with fewer fire images gets no AP or AP50 (their interval
    # is too wide to tell mixtures apart): its AP25 and image recall, with intervals, instead
    attributes: dict[str, Path] = field(default_factory=dict)  # test-set label -> CSV image,attribute,value of your
    # own attributes of its images (e.g. {common: cameras.csv}): slices beside the computed ones


@dataclass(frozen=True)
class ExperimentConfig:
    real: RealConfig  # the real data: a folder read as is, a folder curated first, or a stand-in
    rare: Optional[RareConfig] = None  # the rare test set (never trained on); null = none
    tests: dict[str, EvalSetConfig] = field(default_factory=dict)  # more test sets, by name (scored, not trained on)
    classes: Optional[tuple[str, ...]] = None  # trained and scored classes; null = every class the real data
    # boxes (synonyms mapped: Fire/flame -> fire), less real.drop_classes and real.negative_classes; other
    # classes' boxes are removed
    synth: SynthConfig = field(default_factory=SynthConfig)  # the synthetic pools
    grid: GridConfig = field(default_factory=GridConfig)  # which mixtures and seeds are trained
    train: TrainConfig = field(default_factory=TrainConfig)  # each run's detector training (fuzzyfire train's settings)
    engine: EngineConfig = field(default_factory=EngineConfig)  # who trains: fuzzyfire or a command (engine.py)
    score: InferenceConfig = field(default_factory=InferenceConfig)  # how each run's model is scored (the inference
    # settings of fuzzyfire score)
    executor: RunExecutorConfig = field(default_factory=RunExecutorConfig)  # where runs run: here, or on a Ray cluster
    leakage: LeakageConfig = field(default_factory=LeakageConfig)  # test images that are training images: dropped
    report: ReportConfig = field(default_factory=ReportConfig)  # tables, comparisons and report.html
    images: Literal["symlink", "hardlink", "copy"] = "symlink"  # how images reach the mixture folders

    def check(self) -> None:
        """Raise :class:`ExperimentConfigError` when the parts do not fit together."""
        self.real.source()
        if self.rare is not None:
            self.rare.source()
        self.check_test_names()
        if self.synth.section(self.grid.synthetic) is None:
            raise ExperimentConfigError(
                f"grid.synthetic is {self.grid.synthetic} but synth.{self.grid.synthetic} is null"
            )
        if not self.grid.seeds:
            raise ExperimentConfigError("grid.seeds is empty")
        if self.grid.control and self.synth.method2 is None:
            raise ExperimentConfigError(
                "grid.control makes its copies of the real images with Method 2, but synth.method2 is null"
            )
        if not self.grid.mixtures and not self.grid.table1:
            raise ExperimentConfigError("grid.mixtures and grid.table1 are both empty: nothing to train")
        if self.classes is not None and not self.classes:
            raise ExperimentConfigError("classes is empty (null: the classes of the real data)")
        if not 0.0 <= self.leakage.threshold <= 2.0:
            raise ExperimentConfigError(f"leakage.threshold must be in 0..2, got {self.leakage.threshold:g}")
        try:
            self.engine.check()
        except EngineError as exc:
            raise ExperimentConfigError(str(exc)) from None
        if self.engine.name == "command" and self.train.real_finetune:
            raise ExperimentConfigError(
                "train.real_finetune is fuzzyfire's trainer's; engine command trains with its own recipe (set it to 0)"
            )

    def resolved(self, base: Path) -> ExperimentConfig:
        """This config :meth:`check`-ed, with what follows from its parts filled in (``base``: the folder its relative
        paths resolve against): ``report.attributes`` as absolute paths, and ``synth.method2.background_holdout``
        from the test sets on its backgrounds (:meth:`background_holdout`)."""
        self.check()
        given = {k: p if Path(p).is_absolute() else base / p for k, p in self.report.attributes.items()}
        cfg = replace(self, report=replace(self.report, attributes=given))
        m2 = self.synth.method2
        share = self.background_holdout(base)
        if m2 is None or share == m2.background_holdout:
            return cfg
        return replace(cfg, synth=replace(self.synth, method2=replace(m2, background_holdout=share)))

    def background_holdout(self, base: Path) -> float:
        """The share of ``synth.method2.backgrounds`` photos the pool holds out: in an experiment, the ``holdout`` of
        the test sets (rare and named) whose ``path`` is one of those folders (the largest, when several: a share's
        held-out photos are among those of any larger share), so each stays disjoint from the pool; with no such
        test set, ``background_holdout`` as given. A different ``background_holdout`` given beside such a test set
        raises :class:`ExperimentConfigError`: the test set's ``holdout`` is the one key."""
        m2 = self.synth.method2
        if m2 is None or not m2.backgrounds:
            return m2.background_holdout if m2 is not None else 0.0
        folders = {_resolved(Path(p), base) for p in m2.backgrounds}
        sets = {
            **({"rare": self.rare} if self.rare is not None else {}),
            **{f"tests.{k}": t for k, t in self.tests.items()},
        }
        on = {
            key: t.holdout
            for key, t in sets.items()
            if t.path is not None and t.holdout and _resolved(t.path, base) in folders
        }
        if not on:
            return m2.background_holdout
        key, share = max(on.items(), key=lambda item: item[1])
        if share >= 1.0:
            raise ExperimentConfigError(
                f"{key}.holdout {share:g} holds out every photo of synth.method2.backgrounds: nothing is left for the "
                "pool to composite on"
            )
        if m2.background_holdout and m2.background_holdout != share:
            raise ExperimentConfigError(
                f"synth.method2.background_holdout {m2.background_holdout:g} and {key}.holdout {share:g} cut the same "
                f"photos ({key}.path is a folder of synth.method2.backgrounds): the test set's holdout is the one key, "
                "the pool holds out that share; remove synth.method2.background_holdout"
            )
        return share

    def test_names(self) -> dict[str, str]:
        """The label of every named test set (``tests:``), by key."""
        return {key: t.name or key for key, t in self.tests.items()}

    def check_test_names(self) -> None:
        """Every named test set has a source; no two test sets (common, rare, named) share a label or the folder
        name of their scores (:func:`fuzzyfire.runs.slug`)."""
        from fuzzyfire.runs import slug

        seen = [slug(self.real.name), *([slug(self.rare.name)] if self.rare is not None else [])]
        for key, name in self.test_names().items():
            self.tests[key].source(f"tests.{key}")
            if slug(name) in seen:
                raise ExperimentConfigError(f"tests.{key}: the label {name!r} is taken by another test set")
            seen.append(slug(name))


def _resolved(path: Path, base: Path) -> Path:
    """``path`` (relative to ``base``) as an absolute path, links resolved."""
    return (path if path.is_absolute() else base / path).resolve()
