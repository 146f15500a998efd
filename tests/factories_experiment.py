"""A toy experiment config: stand-in data and synthetic pools of a dozen 64x48 images, 1 epoch at 64 px; a fake
``yolo`` as a command engine (tests/fake_trainer.py: trains in no time, its detector finds one box per image);
a folder of fire-free photos."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np
import yaml
from PIL import Image

from fuzzyfire.experiment_config import ExperimentConfig
from ground.config.loader import build_config

SIZE = {"width": 64, "height": 48}
FLAMES = {"sequences": 2, "frames": 48, "keep_every": 12}
FAKE = Path(__file__).with_name("fake_trainer.py")
TRAIN = f"{{python}} {FAKE} train data={{data_yaml}} seed={{seed}} project={{run_dir}}/train name=yolo"
EXPORT = f"{{python}} {FAKE} export model={{run_dir}}/train/yolo/weights/best.pt"


def command_engine(**engine: Any) -> dict[str, Any]:
    """The ``engine:`` section of the fake ``yolo`` (``engine`` overrides keys)."""
    return {"name": "command", "train": TRAIN, "export": EXPORT, "onnx": "train/yolo/weights/best.onnx", **engine}


def fire_free_photos(folder: Path, count: int, seed: int = 0) -> Path:
    """``count`` distinct noise photos (64x48 PNG) and no label file: a negatives-only set."""
    rng = np.random.default_rng(seed)
    folder.mkdir(parents=True, exist_ok=True)
    for i in range(count):
        Image.fromarray(rng.integers(0, 255, (48, 64, 3), dtype=np.uint8)).save(folder / f"photo{i:02d}.png")
    return folder


#: A named test set of the toy: six stand-in images without fire (a negatives-only set).
FIRE_FREE = {"fire-free": {"standin": {"splits": {"test": 6}, "seed": 2, "negatives": 1.0, **SIZE, **FLAMES}}}


def toy_dict(*, fire_free: bool = False, **grid: Any) -> dict[str, Any]:
    """Plain data of a toy config; ``grid`` overrides grid keys (default: R12_S0, R6_S6, Table 1 R0_S12, seed 0);
    ``fire_free`` adds the named test set :data:`FIRE_FREE`."""
    doc = {
        "classes": ["fire"],
        "real": {"standin": {"kind": "common", "splits": {"train": 12, "valid": 6, "test": 6}, **SIZE, **FLAMES}},
        "rare": {"standin": {"kind": "rare", "splits": {"test": 6}, "seed": 1, **SIZE, **FLAMES}},
        "synth": {
            "method1": {"n": 12, "scenes": 2, "images_per_view": 6, **SIZE, "flames": FLAMES},
            "method2": {"n": 12, "scenes": 2, **SIZE, "flames": FLAMES},
        },
        "grid": {"mixtures": ["R12_S0", "R6_S6"], "table1": ["R0_S12"], "seeds": [0], **grid},
        "train": {"epochs": 1, "imgsz": 64, "batch": 8, "optim": {"warmup_min_iters": 2, "nominal_batch": 16}},
        "executor": {"num_cpus": 2, "local_cpus": 2},
        "report": {"bootstrap": 20, "samples": True, "min_fire_images": 1},  # toy test sets: a few images
    }
    return {**doc, "tests": FIRE_FREE} if fire_free else doc


def toy_config(*, fire_free: bool = False, **grid: Any) -> ExperimentConfig:
    return build_config(toy_dict(fire_free=fire_free, **grid), ExperimentConfig)


def write_toy_config(path: Path, *, fire_free: bool = False, **grid: Any) -> Path:
    path.write_text(yaml.safe_dump(toy_dict(fire_free=fire_free, **grid), sort_keys=False), encoding="utf-8")
    return path


def run_local_and_ray(specs: list, folder: Path, num_cpus: float) -> list:
    """Run ``specs`` with the local executor into ``folder/local`` and on a local Ray (``num_cpus`` per run) into
    ``folder/ray``; asserts every run of both finished and each Ray run's results.json has the local run's bytes.
    Returns the Ray outcomes (for further checks)."""
    from dataclasses import replace

    from fuzzyfire.executors import LocalExecutor, build_executor
    from fuzzyfire.runs import RESULTS_FILE, execute_run

    local = [replace(s, root=folder / "local") for s in specs]
    remote = [replace(s, root=folder / "ray") for s in specs]
    assert [o.error for o in LocalExecutor().map(execute_run, local)] == [None] * len(specs)
    executor = build_executor("ray", num_cpus=num_cpus, local_cpus=2)
    try:
        outcomes = list(executor.map(execute_run, remote))
    finally:
        executor.close()
    assert all(o.error is None for o in outcomes), [o.error for o in outcomes]
    for a, b in zip(local, remote):
        assert (a.out / RESULTS_FILE).read_bytes() == (b.out / RESULTS_FILE).read_bytes()
    return outcomes
