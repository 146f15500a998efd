"""eval's settings as frozen dataclasses (:mod:`ground.config.loader` builds them from YAML, ``--set`` and flags):
how a detector ONNX runs over images (:class:`InferenceConfig`: an experiment's ``score`` section too), which
model it is (:class:`OnnxModelConfig`), which test set it is scored on (:class:`TestSetConfig`), and one dataclass
per command: :class:`ScoreConfig`, :class:`CompareConfig` and :class:`PredictConfig` (whose boxes are drawn: its
:class:`DrawingInference` keeps them at an alarm's confidence). Every default is written here once; the commands'
flags are aliases of these keys (:mod:`eval.cli.options`)."""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path
from typing import Optional

from eval.errors import ALARM_CONF
from eval.onnx_model import ModelFormat, OnnxDetector
from eval.operating import ALARM_BUDGET
from ground.data.formats.registry import FORMATS as DATA_FORMATS
from ground.detect.detections import PostprocessConfig
from ground.detect.letterbox import ResizeMode
from ground.run.device import parse_device


@dataclass(frozen=True)
class OnnxModelConfig:
    """What a detector ONNX is, where its metadata does not say (or says otherwise)."""

    format: ModelFormat = "auto"  # output layout; auto = the metadata's, else inferred from the output shape
    names: Optional[tuple[str, ...]] = None  # class names in output order, e.g. [fire, smoke]; null = the metadata's
    imgsz: Optional[tuple[int, int]] = None  # [width, height] input size, for a model whose input size is dynamic
    # and not in its metadata; null = the model's

    def __post_init__(self) -> None:
        if self.imgsz is not None and (len(self.imgsz) != 2 or min(self.imgsz) < 1):
            raise ValueError(f"model.imgsz must be [width, height] in pixels, got {list(self.imgsz)}")
        if self.names is not None and not all(n.strip() for n in self.names):
            raise ValueError(f"model.names must not hold an empty name, got {list(self.names)}")


@dataclass(frozen=True)
class InferenceConfig:
    """How a detector ONNX runs over images: letterbox, batches, threads, device, and its post-processing. An
    experiment's ``score`` section; the ``inference`` of ``fuzzyfire score``, ``compare`` and ``predict``."""

    postprocess: PostprocessConfig = field(default_factory=PostprocessConfig)  # confidence threshold, NMS, boxes
    # per image (training's validation uses the same: train.postprocess)
    resize: ResizeMode = "area"  # letterbox resize: area when shrinking (ours and YOLOv5's) or always bilinear
    # (ultralytics 8.x's: use it to reproduce ultralytics' own numbers)
    batch: int = 16  # images per onnxruntime call
    workers: int = 2  # image decoding threads
    threads: int = 0  # onnxruntime threads; 0 = every core the run may use
    device: str = "auto"  # auto | cpu | cuda | cuda:N; auto = onnxruntime's CUDA provider when installed, else the CPU

    def __post_init__(self) -> None:
        if self.batch < 1 or self.workers < 0 or self.threads < 0:
            raise ValueError(
                f"batch must be >= 1, workers and threads >= 0; got {self.batch}, {self.workers}, {self.threads}"
            )
        parse_device(self.device)  # DeviceError (a ValueError) naming the choices

    def detector(self, path: Path | str, model: OnnxModelConfig | None = None) -> OnnxDetector:
        """The detector ONNX at ``path`` (as ``model`` describes it) on this config's device with its threads."""
        m = model or OnnxModelConfig()
        return OnnxDetector(path, m.format, m.names, m.imgsz, threads=self.threads, device=self.device)


@dataclass(frozen=True)
class TestSetConfig:
    """How ``--data`` is read: its format, the split scored, its classes, the images held out."""

    __test__ = False  # for pytest: not a test class

    format: str = "auto"  # auto (detect) | coco | yolo | voc | dfire | images | folders
    split: Optional[str] = None  # split scored (val and valid are one name); null = test, else val/valid, else the
    # whole set when it has no splits; all = every image
    label: Optional[str] = None  # every image of a folder without label files holds this class (e.g. fire): an
    # image-labelled set, judged by image recall; null = such a folder is negatives only (fire/ and normal/
    # sub-folders are read as image-labelled without it)
    holdout: float = 0.0  # score only the images held out by content at this share (0..1): the photos a Method 2
    # pool with background_holdout SHARE never composites on; 0 = every image
    aliases: dict[str, str] = field(default_factory=dict)  # a test-set class read as another, e.g. {Flame: fire}
    drop_class: tuple[str, ...] = ()  # test-set classes whose boxes are ignored

    def __post_init__(self) -> None:
        if self.format not in ("auto", *DATA_FORMATS):
            raise ValueError(f"data.format {self.format!r}: choose one of auto, {', '.join(DATA_FORMATS)}")
        if not 0.0 <= self.holdout <= 1.0:
            raise ValueError(f"data.holdout must be in [0, 1], got {self.holdout}")


@dataclass(frozen=True)
class ScoringConfig:
    """What ``score`` and ``compare`` share: the model, how it runs, the test set, the bootstrap's seed."""

    model: OnnxModelConfig = field(default_factory=OnnxModelConfig)  # the detector ONNX (layout, classes, input size)
    inference: InferenceConfig = field(default_factory=InferenceConfig)  # how it runs and its post-processing
    data: TestSetConfig = field(default_factory=TestSetConfig)  # the test set (--data) as read
    seed: int = 0  # seed of the bootstrap's image resamples


@dataclass(frozen=True)
class ScoreConfig(ScoringConfig):
    """``fuzzyfire score``'s settings."""

    ci: int = 0  # image resamples of the 95% bootstrap interval of AP; 0 = no interval
    alarm_conf: float = ALARM_CONF  # confidence of a false alarm and of a found box (--errors), and of an image
    # recall on an image-labelled set

    def __post_init__(self) -> None:
        if self.ci < 0 or not 0.0 <= self.alarm_conf < 1.0:
            raise ValueError(f"ci must be >= 0 and alarm_conf in [0, 1), got {self.ci}, {self.alarm_conf}")


@dataclass(frozen=True)
class CompareConfig(ScoringConfig):
    """``fuzzyfire compare``'s settings."""

    samples: int = 1000  # paired bootstrap resamples
    alarm_budget: float = ALARM_BUDGET  # false alarms per 100 images without fire at which each model is read
    # (with --negatives, or a test set's own images without fire)
    negatives_holdout: float = 0.0  # --negatives: only the photos held out by content at this share (0..1), those
    # a pool with background_holdout SHARE never composited on; 0 = every image
    paired_seeds: bool = False  # run i of each side was trained with seed i: each resample also draws the seeds, as
    # the study's comparisons do (two levels, eval.stats.seed_picks; at least 3 runs on each side, as many on both)

    def __post_init__(self) -> None:
        if self.alarm_budget <= 0 or self.samples < 1:
            raise ValueError(f"alarm_budget must be > 0 and samples >= 1, got {self.alarm_budget}, {self.samples}")
        if not 0.0 <= self.negatives_holdout <= 1.0:
            raise ValueError(f"negatives_holdout must be in [0, 1], got {self.negatives_holdout}")


@dataclass(frozen=True)
class AlarmPostprocess(PostprocessConfig):
    """Post-processing of boxes drawn for a person to look at: those that would raise an alarm."""

    conf: float = ALARM_CONF  # score threshold before NMS, [0, 1): an alarm's (scoring keeps lower scores: they
    # only add recall)


@dataclass(frozen=True)
class DrawingInference(InferenceConfig):
    """How ``fuzzyfire predict`` runs a detector: as score does, its boxes kept at an alarm's confidence."""

    postprocess: AlarmPostprocess = field(default_factory=AlarmPostprocess)  # confidence threshold, NMS, boxes per
    # image


@dataclass(frozen=True)
class PredictConfig:
    """``fuzzyfire predict``'s settings."""

    model: OnnxModelConfig = field(default_factory=OnnxModelConfig)  # the detector ONNX (layout, classes, input size)
    inference: DrawingInference = field(default_factory=DrawingInference)  # how it runs; its boxes are drawn, so
    # at an alarm's confidence, not scoring's
    classes: Optional[tuple[str, ...]] = None  # only these model classes, e.g. [fire]; null = every class
