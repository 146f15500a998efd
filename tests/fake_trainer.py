"""A stand-in for ``yolo detect train`` / ``yolo export`` in the engine tests (no ultralytics in CI).

``python fake_trainer.py train data=D.yaml seed=S project=P name=N [fail=1]`` checks the dataset file, writes
``P/N/weights/best.pt`` (a text file) and prints a few lines; ``python fake_trainer.py export model=M`` writes
``best.onnx`` beside it: a real ONNX detector in the YOLOv5 layout (B, 1, 6) that always finds one centred box
of half the input size, with ultralytics-style metadata (names, imgsz). ``fail=1`` exits 3 after printing.
"""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np
import onnx
import yaml
from onnx import TensorProto, helper, numpy_helper

SIZE = 64


def detector_onnx(path: Path, seed: int) -> None:
    box = np.array([[[SIZE / 2, SIZE / 2, SIZE / 2, SIZE / 2, 0.5 + 0.01 * seed, 1.0]]], np.float32)
    nodes = [
        helper.make_node("ReduceMean", ["images"], ["m"], axes=[1, 2, 3], keepdims=1),
        helper.make_node("Reshape", ["m", "shape"], ["r"]),
        helper.make_node("Mul", ["r", "zero"], ["z"]),
        helper.make_node("Add", ["z", "box"], ["output0"]),
    ]
    graph = helper.make_graph(
        nodes,
        "fake",
        [helper.make_tensor_value_info("images", TensorProto.FLOAT, ["batch", 3, SIZE, SIZE])],
        [helper.make_tensor_value_info("output0", TensorProto.FLOAT, ["batch", 1, 6])],
        [
            numpy_helper.from_array(np.array([-1, 1, 1], np.int64), "shape"),
            numpy_helper.from_array(np.zeros((1, 1, 1), np.float32), "zero"),
            numpy_helper.from_array(box, "box"),
        ],
    )
    model = helper.make_model(graph, opset_imports=[helper.make_opsetid("", 13)])
    model.ir_version = 8
    for key, value in {"names": "{0: 'fire'}", "imgsz": f"[{SIZE}, {SIZE}]"}.items():
        model.metadata_props.add(key=key, value=value)
    onnx.save(model, str(path))


def main(argv: list[str]) -> int:
    step, args = argv[0], dict(a.split("=", 1) for a in argv[1:])
    if step == "train":
        doc = yaml.safe_load(Path(args["data"]).read_text(encoding="utf-8"))
        print(f"training on {doc['train']} with classes {doc['names']}, seed {args['seed']}")
        if args.get("fail"):
            print("CUDA out of memory (pretend)", file=sys.stderr)
            return 3
        weights = Path(args["project"]) / args["name"] / "weights"
        weights.mkdir(parents=True, exist_ok=True)
        (weights / "best.pt").write_text(f"seed {args['seed']}\n", encoding="utf-8")
        return 0
    if step == "export":
        pt = Path(args["model"])
        detector_onnx(pt.with_suffix(".onnx"), int(pt.read_text(encoding="utf-8").split()[1]))
        print(f"exported {pt.with_suffix('.onnx')}")
        return 0
    return 2


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
