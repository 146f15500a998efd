"""Load any YOLO-family detector exported to ONNX and run it with onnxruntime.

Output layouts (auto-detected from the output shape and class count, or chosen with ``fmt``):

- ``fuzzyfire`` / ``yolov5``: (B, N, 5 + C) rows ``[cx, cy, w, h, obj, p_1 .. p_C]``, score = obj * p_c.
- ``yolov8`` (also YOLO11): (B, 4 + C, N) columns ``[cx, cy, w, h, p_1 .. p_C]``, score = p_c.

Boxes are centre boxes in pixels of the letterboxed input; every value is already post-sigmoid.
Input: ``images`` (B, 3, H, W) float RGB in [0, 1], letterboxed with grey 114. Class names, input size and
(for our models) the layout come from the model's metadata (ours as written by ``train/export.py``,
YOLOv5's ``names``/``stride``, ultralytics' ``names``/``imgsz``) or from the caller. A layout named in the
metadata (``output_format``) is trusted; otherwise it is inferred from the output shape.
"""

from __future__ import annotations

import ast
import json
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Literal, get_args

import numpy as np
from numpy.typing import NDArray

from ground.run.device import onnx_providers

#: A model's output layout (module docstring), or ``auto``: read from its metadata, else inferred.
ModelFormat = Literal["auto", "fuzzyfire", "yolov5", "yolov8"]
FORMATS: tuple[str, ...] = get_args(ModelFormat)
LAYOUTS: tuple[str, ...] = FORMATS[1:]


class ModelError(ValueError):
    """A model that cannot be scored; ``str()`` is ``"<path>: <reason>"``."""

    def __init__(self, path: Path | str, reason: str) -> None:
        super().__init__(f"{path}: {reason}")
        self.path = str(path)
        self.reason = reason


@dataclass(frozen=True)
class ModelSpec:
    """What a detector expects and emits. ``batch`` is None when the batch axis is dynamic."""

    path: Path
    input_name: str
    input_width: int
    input_height: int
    batch: int | None
    class_names: tuple[str, ...]
    format: str
    pad_value: int = 114
    input_dtype: str = "float32"
    metadata: Mapping[str, str] = field(default_factory=dict)


def decode_yolov5(out: NDArray[np.floating]) -> tuple[NDArray[np.float32], NDArray[np.float32]]:
    """(B, N, 5 + C) -> centre boxes (B, N, 4) and class scores obj * p_c (B, N, C)."""
    out = out.astype(np.float32, copy=False)
    return out[..., :4], out[..., 4:5] * out[..., 5:]


def decode_yolov8(out: NDArray[np.floating]) -> tuple[NDArray[np.float32], NDArray[np.float32]]:
    """(B, 4 + C, N) -> centre boxes (B, N, 4) and class scores (B, N, C)."""
    rows = out.astype(np.float32, copy=False).transpose(0, 2, 1)
    return rows[..., :4], rows[..., 4:]


DECODERS: Mapping[str, Callable[[NDArray], tuple[NDArray[np.float32], NDArray[np.float32]]]] = {
    "fuzzyfire": decode_yolov5,
    "yolov5": decode_yolov5,
    "yolov8": decode_yolov8,
}


def parse_names(text: str) -> list[str]:
    """Class names from metadata text: a JSON/Python list, a ``{0: 'fire', ...}`` dict, or ``fire,smoke``."""
    value: object
    try:
        value = json.loads(text)
    except ValueError:
        try:
            value = ast.literal_eval(text)
        except (ValueError, SyntaxError):
            value = [n.strip() for n in text.split(",") if n.strip()]
    if isinstance(value, dict):
        return [str(value[k]) for k in sorted(value, key=lambda k: int(k))]
    if isinstance(value, (list, tuple)):
        return [str(v) for v in value]
    raise ValueError(f"cannot read class names from {text!r}")


def _parse_size(value: object) -> tuple[int, int] | None:
    """``640`` or ``[h, w]`` (ultralytics order) or a text of those -> ``(width, height)``."""
    if isinstance(value, str):
        try:
            value = ast.literal_eval(value)
        except (ValueError, SyntaxError):
            return None
    if isinstance(value, int):
        return value, value
    if isinstance(value, (list, tuple)) and len(value) == 2 and all(isinstance(v, int) for v in value):
        return int(value[1]), int(value[0])
    return None


def _json_object(text: str | None) -> dict:
    try:
        value = json.loads(text) if text else {}
    except ValueError:
        return {}
    return value if isinstance(value, dict) else {}


def read_metadata(meta: Mapping[str, str]) -> dict[str, object]:
    """Class names, input ``(width, height)``, pad value, output layout and whether the model is ours, from
    ONNX ``metadata_props``: our exporter's keys (``producer``, ``names``, ``imgsz``, ``output_format``,
    ``preprocessing``; see ``train/export.py``), YOLOv5's (``names``, ``stride``) or ultralytics'
    (``names``, ``imgsz``)."""
    names_text = meta.get("names") or meta.get("class_names")
    layout = meta.get("output_format")
    return {
        "ours": meta.get("producer") == "fuzzyfire",
        "names": parse_names(names_text) if names_text else None,
        "size": _parse_size(meta.get("imgsz") or meta.get("image_size") or ""),
        "pad_value": int(_json_object(meta.get("preprocessing")).get("pad_value", 114)),
        "layout": layout if layout in ("yolov5", "yolov8") else None,
    }


def infer_format(out_shape: Sequence[int], num_classes: int | None, path: Path | str = "<model>") -> str:
    """``yolov5`` for (B, N, 5 + C), ``yolov8`` for (B, 4 + C, N); raises :class:`ModelError` when the shape
    fits neither or both."""
    if len(out_shape) != 3:
        raise ModelError(path, f"output has shape {tuple(out_shape)}; expected (B, N, 5+C) or (B, 4+C, N)")
    a, b = int(out_shape[1]), int(out_shape[2])
    if num_classes is None:
        return "yolov8" if a < b else "yolov5"
    fits_v5, fits_v8 = b == 5 + num_classes, a == 4 + num_classes
    if fits_v5 and fits_v8:
        raise ModelError(path, f"output {tuple(out_shape)} fits both layouts; pass --format yolov5 or yolov8")
    if not (fits_v5 or fits_v8):
        raise ModelError(
            path,
            f"output {tuple(out_shape)} fits neither (B, N, 5+{num_classes}) nor (B, 4+{num_classes}, N) "
            f"for {num_classes} class names; check --names",
        )
    return "yolov5" if fits_v5 else "yolov8"


def _layout_mismatch(chosen: str, asked: str, out_shape: Sequence[int], class_names: Sequence[str]) -> str:
    """Why the output does not fit layout ``chosen`` with ``class_names``, and what would fit."""
    shape, c = tuple(int(d) for d in out_shape), len(class_names)
    expected = f"(B, N, 5+{c}) = (B, N, {5 + c})" if chosen != "yolov8" else f"(B, 4+{c}, N) = (B, {4 + c}, N)"
    how = "as asked with --format" if asked != "auto" else "from the model's metadata"
    fits = [
        name
        for name, ok in (("yolov5", shape[2] == 5 + c), ("yolov8", shape[1] == 4 + c))
        if ok and name != ("yolov5" if chosen == "fuzzyfire" else chosen)
    ]
    hint = f"; it fits --format {fits[0]}" if fits else f"; check --names (the model's has {c} classes?)"
    return (
        f"output shape {shape} does not fit the {chosen} layout {how}: for the {c} class names {list(class_names)} "
        f"it expects {expected}{hint}"
    )


def _static(dim: object) -> int | None:
    return dim if isinstance(dim, int) and dim > 0 else None


class OnnxDetector:
    """A detector ONNX file behind one call: letterboxed (B, 3, H, W) float batch -> boxes and scores.

    ``fmt`` is ``auto`` or one of :data:`LAYOUTS`; ``names`` overrides the metadata's class names;
    ``image_size`` ``(width, height)`` is needed only when the model's input size is dynamic and its
    metadata does not say. ``threads`` = 0 lets onnxruntime use every core. ``device`` picks onnxruntime's
    provider (:func:`ground.run.device.onnx_providers`); ``device_notice`` says when a GPU was asked for and the CPU is used.
    """

    def __init__(
        self,
        path: Path | str,
        fmt: str = "auto",
        names: Sequence[str] | None = None,
        image_size: tuple[int, int] | None = None,
        threads: int = 0,
        device: str = "cpu",
    ) -> None:
        if fmt not in FORMATS:
            raise ValueError(f"unknown model format {fmt!r}; choose one of {', '.join(FORMATS)}")
        self.path = Path(path)
        providers, self.device_notice = onnx_providers(device)
        self.session = _open_session(self.path, threads, providers)
        if providers[0] != "CPUExecutionProvider" and "CUDAExecutionProvider" not in self.session.get_providers():
            self.device_notice = (
                f"notice: onnxruntime could not start its CUDA provider for {self.path.name}; scoring on the CPU"
            )
        self._output = _detection_output(self.session, self.path)
        self.spec = self._build_spec(fmt, names, image_size)
        self._decode = DECODERS[self.spec.format]

    def _build_spec(self, fmt: str, names: Sequence[str] | None, image_size: tuple[int, int] | None) -> ModelSpec:
        inp = self.session.get_inputs()[0]
        meta = dict(self.session.get_modelmeta().custom_metadata_map)
        info = read_metadata(meta)
        if len(inp.shape) != 4:
            raise ModelError(self.path, f"input {inp.name!r} has shape {inp.shape}; expected (B, 3, H, W)")
        width, height = _input_size(self.path, inp.shape, image_size, info["size"])  # type: ignore[arg-type]
        class_names = list(names) if names else info["names"]
        out_shape = self._output_shape(inp.name, width, height)
        chosen = fmt
        if fmt == "auto":
            detected = info["layout"] or infer_format(out_shape, len(class_names) if class_names else None, self.path)
            chosen = "fuzzyfire" if info["ours"] and detected == "yolov5" else detected
        num_classes = out_shape[1] - 4 if chosen == "yolov8" else out_shape[2] - 5
        if not class_names:
            raise ModelError(self.path, "the model's metadata has no class names; pass --names fire,smoke")
        if len(class_names) != num_classes:
            raise ModelError(self.path, _layout_mismatch(chosen, fmt, out_shape, class_names))
        return ModelSpec(
            path=self.path,
            input_name=inp.name,
            input_width=width,
            input_height=height,
            batch=_static(inp.shape[0]),
            class_names=tuple(class_names),
            format=chosen,
            pad_value=int(info["pad_value"]),  # type: ignore[arg-type]
            input_dtype="float16" if inp.type == "tensor(float16)" else "float32",
            metadata=meta,
        )

    def _output_shape(self, input_name: str, width: int, height: int) -> list[int]:
        """The detection output's shape, from the graph when static, else by running one blank image."""
        shape = self.session.get_outputs()[self._output].shape
        if len(shape) == 3 and all(_static(d) for d in shape[1:]):
            return [1, int(shape[1]), int(shape[2])]
        dtype = np.float16 if self.session.get_inputs()[0].type == "tensor(float16)" else np.float32
        batch = _static(self.session.get_inputs()[0].shape[0]) or 1
        blank = np.zeros((batch, 3, height, width), dtype=dtype)
        return list(self.session.run(None, {input_name: blank})[self._output].shape)

    def raw(self, batch: NDArray[np.float32]) -> NDArray[np.floating]:
        """Run the graph on (B, 3, H, W) float32 in [0, 1]; returns the raw detection output for B images.
        A model with a fixed batch size is run in chunks of that size (the last one zero-padded)."""
        spec = self.spec
        if batch.shape[1:] != (3, spec.input_height, spec.input_width):
            raise ValueError(
                f"batch shape {batch.shape} does not match the model input 3x{spec.input_height}x{spec.input_width}"
            )
        x = batch.astype(np.float16) if spec.input_dtype == "float16" else batch
        step = spec.batch or len(x)
        outs = []
        for start in range(0, len(x), step):
            chunk = x[start : start + step]
            if len(chunk) < step:
                chunk = np.concatenate([chunk, np.zeros((step - len(chunk), *chunk.shape[1:]), chunk.dtype)])
            out = self.session.run(None, {spec.input_name: chunk})[self._output]
            outs.append(out[: len(x) - start])
        return np.concatenate(outs)

    def __call__(self, batch: NDArray[np.float32]) -> tuple[NDArray[np.float32], NDArray[np.float32]]:
        """(B, 3, H, W) -> centre boxes (B, N, 4) in input pixels and class scores (B, N, C) in [0, 1]."""
        return self._decode(self.raw(batch))


def _open_session(path: Path, threads: int, providers: Sequence):  # -> onnxruntime.InferenceSession
    import onnxruntime as ort

    if not path.is_file():
        raise ModelError(path, "file not found")
    opts = ort.SessionOptions()
    opts.intra_op_num_threads = max(0, int(threads))
    opts.inter_op_num_threads = 1
    opts.log_severity_level = 3
    opts.add_session_config_entry("session.intra_op.allow_spinning", "0")  # decoding threads need the cores
    try:
        return ort.InferenceSession(str(path), opts, providers=list(providers))
    except Exception as exc:  # noqa: BLE001 - onnxruntime raises its own exception types for bad files
        raise ModelError(path, f"onnxruntime cannot load it ({exc.__class__.__name__}: {exc})") from None


def _detection_output(session, path: Path) -> int:
    """Index of the first rank-3 output (YOLOv5 exports may add per-level outputs after it)."""
    for i, out in enumerate(session.get_outputs()):
        if len(out.shape) == 3:
            return i
    shapes = [o.shape for o in session.get_outputs()]
    raise ModelError(path, f"no output of rank 3 among {shapes}; models with NMS inside are not supported")


def _input_size(
    path: Path, shape: Sequence[object], given: tuple[int, int] | None, meta: tuple[int, int] | None
) -> tuple[int, int]:
    """``(width, height)`` of the model input: the graph's static size, else ``given``, else metadata."""
    static = (_static(shape[3]), _static(shape[2]))
    if static[0] and static[1]:
        if given and tuple(given) != static:
            raise ModelError(path, f"the model takes {static[0]}x{static[1]} inputs, not {given[0]}x{given[1]}")
        return static  # type: ignore[return-value]
    size = given or meta
    if not size:
        raise ModelError(path, "the input size is dynamic and not in the metadata; pass --imgsz")
    return int(size[0]), int(size[1])
