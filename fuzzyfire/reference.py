"""Write the files generated from the config dataclasses: ``docs/config.md`` (every key of every command's
settings: type, default, meaning) and ``configs/synth-method1.yaml`` / ``configs/synth-method2.yaml`` (the
defaults, commented). ``python -m fuzzyfire.reference [ROOT]`` (``make reference``) rewrites them;
``tests/test_fuzzyfire_reference.py`` fails when a file differs from what the code generates."""

from __future__ import annotations

import sys
from pathlib import Path


def sections() -> list[tuple[str, str, type]]:
    """(heading, one paragraph, dataclass) of each settings section, in the order docs/config.md lists them."""
    from curate.curation import CurateConfig
    from curate.mix import MixConfig
    from curate.settings import DedupJobConfig, LeakageJobConfig
    from curate.sources import MergeConfig
    from eval.config import CompareConfig, PredictConfig, ScoreConfig
    from fuzzyfire.experiment_config import ExperimentConfig
    from synth.flames.cutouts import CutoutConfig
    from synth.flames.library import FlameLibraryConfig
    from synth.gap import GapConfig
    from synth.method1 import Method1Config
    from synth.method2 import Method2Config
    from synth.places.scenes import ScenesConfig
    from train.config import TrainConfig

    return [
        ("experiment", "`fuzzyfire experiment CONFIG.yaml [--set KEY=VALUE]` and `make experiment CONFIG=... "
         "SET=\"KEY=VALUE ...\"`. Its `synth.method1`, `synth.method2` and `train` sections are the tables below.",
         ExperimentConfig),
        ("synth method2", "`fuzzyfire synth method2 [CONFIG.yaml] [--set KEY=VALUE]` and an experiment's "
         "`synth.method2` (configs/synth-method2.yaml lists every key at its default).", Method2Config),
        ("synth method1", "`fuzzyfire synth method1 [CONFIG.yaml] [--set KEY=VALUE]` and an experiment's "
         "`synth.method1` (configs/synth-method1.yaml).", Method1Config),
        ("flame library", "`fuzzyfire synth flames [CONFIG.yaml]` and the `flames` section of Method 1 and 2.",
         FlameLibraryConfig),
        ("synth cutouts", "`fuzzyfire synth cutouts SRC --out OUT [--config CONFIG.yaml] [--set KEY=VALUE]` and "
         "`fuzzyfire synth colour SYNTHETIC REAL [--config CONFIG.yaml]` (its flame pixels are these cut-outs'); an "
         "experiment's own cut-out pools (`synth.method2.flames.source: cutouts`) cut at these defaults.", CutoutConfig),
        ("synth scenes", "`fuzzyfire synth scenes [CONFIG.yaml] --out OUT [--set KEY=VALUE]`.", ScenesConfig),
        ("synth gap", "`fuzzyfire synth gap SYNTHETIC REAL [--config CONFIG.yaml] [--set KEY=VALUE]`; its `model` "
         "section is dedup's. An experiment's report measures each pool's image gap over `report.gap_draws`.",
         GapConfig),
        ("train", "`fuzzyfire train [CONFIG.yaml] --train DATASET --val VAL [--set KEY=VALUE]` and an experiment's `train`.",
         TrainConfig),
        ("curate", "`fuzzyfire curate CONFIG.yaml --out OUT [--set KEY=VALUE]` and an experiment's `real.curate`.",
         CurateConfig),
        ("score", "`fuzzyfire score MODEL.onnx --data DATA [--config CONFIG.yaml] [--set KEY=VALUE]`. Its "
         "`inference` section is an experiment's `score` (the post-processing is also training's: "
         "`train.postprocess`).", ScoreConfig),
        ("compare", "`fuzzyfire compare A.onnx B.onnx --data DATA [--config CONFIG.yaml] [--set KEY=VALUE]`.",
         CompareConfig),
        ("predict", "`fuzzyfire predict MODEL.onnx IMAGES|VIDEO --out DIR [--config CONFIG.yaml] [--set "
         "KEY=VALUE]`: its confidence threshold is an alarm's, higher than scoring's.", PredictConfig),
        ("merge", "`fuzzyfire merge CONFIG.yaml --out OUT [--set KEY=VALUE]`.", MergeConfig),
        ("dedup", "`fuzzyfire dedup DIR... --out OUT [--config CONFIG.yaml] [--set KEY=VALUE]`; its `dedup`, `rank`, "
         "`model` and `executor` sections are curate's.", DedupJobConfig),
        ("leakage", "`fuzzyfire leakage A B [--config CONFIG.yaml] [--set KEY=VALUE]`.", LeakageJobConfig),
        ("mix", "`fuzzyfire mix [CONFIG.yaml] --real R --synth S --out OUT [--set KEY=VALUE]`.", MixConfig),
    ]  # fmt: skip


INTRO = """Generated from the config dataclasses by `python -m fuzzyfire.reference` (`make reference`); a test fails
when this page and the code differ. Every command that builds something takes a YAML file of its section and
`--set KEY=VALUE` (dotted keys, values in YAML: `--set flames.exposed=true`, `--set 'flame_height_m=[0.5, 2]'`);
its flags are short aliases of the keys below, with the same defaults. Unknown keys, wrong types and values out
of range are refused before any work, naming the key and the file."""

METHOD_HEADERS = {
    "synth-method1.yaml": """Method 1 (the paper's first method): flame planes placed in the 3D scenes and rendered with them;
boxes from the visible flame (or the paper's projected plane corners). Every key at its default, generated from
synth.method1.Method1Config (python -m fuzzyfire.reference); docs/config.md has the same table.
  fuzzyfire synth method1 configs/synth-method1.yaml --set n=200 --out out/m1
  fuzzyfire synth audit out/m1""",
    "synth-method2.yaml": """Method 2 (the paper's second method): render each camera view once, composite flame sprites onto it;
boxes from each flame's final visible mask (audit mean IoU = 1.0). Every key at its default, generated from
synth.method2.Method2Config (python -m fuzzyfire.reference); docs/config.md has the same table.
  fuzzyfire synth method2 configs/synth-method2.yaml --set n=200 --set 'backgrounds=[my/photos]' --out out/m2
  fuzzyfire synth audit out/m2""",
}


def generated() -> dict[str, str]:
    """{path relative to the repository: text} of every generated file."""
    from ground.config.reference import commented_yaml, markdown
    from synth.method1 import Method1Config
    from synth.method2 import Method2Config

    schemas = {"synth-method1.yaml": Method1Config, "synth-method2.yaml": Method2Config}
    out = {"docs/config.md": markdown("Configuration reference", INTRO, sections())}
    for name, header in METHOD_HEADERS.items():
        out[f"configs/{name}"] = commented_yaml(schemas[name], header)
    return out


def main(argv: list[str] | None = None) -> int:
    root = Path((argv if argv is not None else sys.argv[1:])[0] if (argv or sys.argv[1:]) else ".")
    for rel, text in generated().items():
        (root / rel).parent.mkdir(parents=True, exist_ok=True)
        (root / rel).write_text(text, encoding="utf-8")
        print(f"wrote {root / rel}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
