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


def export_onnx(model: Detector, path: Path | str, imgsz: int, class_names: Sequence[str]) -> Path:
    """Write ``model`` (eval mode, CPU) to ``path`` following the contract above; returns the path."""
    if len(class_names) != model.num_classes:
        raise ValueError(f"{len(class_names)} class names for a model of {model.num_classes} classes")
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    wrapper = _Decoded(model).eval()
    dummy = torch.zeros(1, 3, imgsz, imgsz)
    tmp = path.with_suffix(".onnx.tmp")
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # the TorchScript exporter is deprecated but needs no onnxscript
        torch.onnx.export(
            wrapper,
            (dummy,),
            str(tmp),
            input_names=["images"],
            output_names=["output"],
            dynamic_axes={"images": {0: "batch"}, "output": {0: "batch"}},
            opset_version=OPSET,
            do_constant_folding=True,
            dynamo=False,
        )
    proto = onnx.load(str(tmp))
    for key, value in onnx_metadata(class_names, imgsz).items():
        entry = proto.metadata_props.add()
        entry.key, entry.value = key, value
    onnx.checker.check_model(proto)
    onnx.save(proto, str(tmp))
    tmp.replace(path)
    return path
