"""ONNX export of a trained detector (``RUN/best.onnx``).

Contract (what a scorer may rely on; the YOLOv5 layout, which ``fuzzyfire score`` auto-detects):

- Input ``images``: float32 (N, 3, H, W), RGB, values in [0, 1], the image letterboxed to H x W (one
  aspect-preserving resize, centred, padding grey 114/255). N is dynamic; H and W are fixed to the
  training size (``imgsz`` in the metadata).
- Output ``output``: float32 (N, A, 5 + C), A = 3 * (H/8 * W/8 + H/16 * W/16 + H/32 * W/32) candidate boxes.
  Per row: ``cx, cy, w, h`` (box centre and size in *letterboxed input pixels*), ``obj`` (objectness
  probability), then C class probabilities, all after the sigmoid. The detection score of class c is
  ``obj * p_c``. With a single class ``p_0`` is exactly 1 (the score is the objectness). No NMS is applied.
- Metadata (``metadata_props``, strings): ``names`` (JSON list, class index -> name), ``imgsz`` (JSON
  ``[H, W]``), ``output_format`` (``"yolov5"``), ``box_format`` (``"cxcywh"``), ``scores``
  (``"obj*cls"``), ``preprocessing`` (JSON: letterbox, pad value, RGB, scale, layout), ``stride`` (``32``),
  ``producer`` (``"fuzzyfire"``).
"""

from __future__ import annotations

import io
import json
import warnings
from collections.abc import Sequence
from pathlib import Path

import onnx
import torch
from torch import nn

from train.model import Detector

OPSET = 17
PREPROCESSING = {
    "resize": "letterbox",
    "pad_value": 114,
    "color": "RGB",
    "scale": "1/255",
    "layout": "NCHW",
    "dtype": "float32",
}


class _Decoded(nn.Module):
    """Wraps a detector so its forward returns the decoded (N, A, 5 + C) tensor."""

    def __init__(self, model: Detector) -> None:
        super().__init__()
        self.model = model

    def forward(self, images: torch.Tensor) -> torch.Tensor:
        return self.model.predict(images)


def onnx_metadata(class_names: Sequence[str], imgsz: int) -> dict[str, str]:
    return {
        "names": json.dumps(list(class_names)),
        "imgsz": json.dumps([imgsz, imgsz]),
        "output_format": "yolov5",
        "box_format": "cxcywh",
        "scores": "obj*cls",
        "preprocessing": json.dumps(PREPROCESSING),
        "stride": "32",
        "producer": "fuzzyfire",
    }


def torch_to_onnx(module: nn.Module, imgsz: int, target: str | io.BytesIO, output_names: Sequence[str] = ()) -> None:
    """Trace ``module`` on one (1, 3, imgsz, imgsz) input named ``images`` into ``target`` (a file path or a
    buffer): the batch dimension of the input and of each of ``output_names`` dynamic, opset :data:`OPSET`, the
    TorchScript exporter (deprecated, but it needs no onnxscript; its warning silenced)."""
    with warnings.catch_warnings(), torch.no_grad():
        warnings.simplefilter("ignore")
        torch.onnx.export(
            module,
            (torch.zeros(1, 3, imgsz, imgsz),),
            target,
            input_names=["images"],
            output_names=list(output_names) or None,
            dynamic_axes={name: {0: "batch"} for name in ("images", *output_names)},
            opset_version=OPSET,
            do_constant_folding=True,
            dynamo=False,
        )


def export_onnx(model: Detector, path: Path | str, imgsz: int, class_names: Sequence[str]) -> Path:
    """Write ``model`` (eval mode, CPU) to ``path`` following the contract above; returns the path."""
    if len(class_names) != model.num_classes:
        raise ValueError(f"{len(class_names)} class names for a model of {model.num_classes} classes")
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    tmp = path.with_suffix(".onnx.tmp")
    torch_to_onnx(_Decoded(model).eval(), imgsz, str(tmp), ["output"])
    proto = onnx.load(str(tmp))
    for key, value in onnx_metadata(class_names, imgsz).items():
        entry = proto.metadata_props.add()
        entry.key, entry.value = key, value
    onnx.checker.check_model(proto)
    onnx.save(proto, str(tmp))
    tmp.replace(path)
    return path
