"""Real ONNX "oracle" detectors and a tiny matching test set, for the eval tests.

Each test image is a flat grey PNG with its own grey level; the model reads the centre pixel of its
letterboxed input and, for every row of a constant detection table, multiplies the row's score by
``exp(-K (pixel - grey_row)^2)``: rows of the image's own grey keep their score, all others drop to 0.
So the graph emits exactly the rows written for each image, in letterboxed input pixels, and nothing on
images whose grey level has no rows (negatives).
"""

from __future__ import annotations

import json
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import onnx
from onnx import TensorProto, helper, numpy_helper
from PIL import Image

from ground.data.dataset import DatasetBuilder

SIZE = 64
NAMES = ("fire", "smoke")
_K = 1e5


@dataclass(frozen=True)
class TestImage:
    name: str
    width: int
    height: int
    grey: int
    scale: tuple[float, float]  # letterboxed pixels per original pixel (x, y), computed by hand
    pad: tuple[int, int]  # letterbox offset (left, top), by hand
    boxes: tuple[tuple[str, tuple[float, float, float, float]], ...]  # (class, xywh original pixels)


# Letterbox geometry into 64x64 written out by hand (independent of ground.data.boxes).
IMAGES = (
    TestImage("wide", 64, 32, 40, (1.0, 1.0), (0, 16), (("fire", (4, 2, 20, 10)), ("smoke", (30, 8, 16, 16)))),
    TestImage("tall", 30, 60, 80, (32 / 30, 64 / 60), (16, 0), (("fire", (6, 12, 15, 30)),)),
    TestImage("big", 128, 128, 120, (0.5, 0.5), (0, 0), (("fire", (10, 10, 50, 40)), ("fire", (70, 72, 40, 40)))),
    TestImage("large", 200, 150, 240, (0.32, 0.32), (0, 8), (("fire", (40, 30, 120, 100)),)),
    TestImage("neg1", 48, 48, 160, (4 / 3, 4 / 3), (0, 0), ()),
    TestImage("neg2", 100, 50, 200, (0.64, 0.64), (0, 16), ()),
)


def write_test_set(root: Path, images: tuple[TestImage, ...] = IMAGES) -> Path:
    """The ``images`` (default :data:`IMAGES`) as PNGs plus ``annotations.json`` (COCO) in ``root``."""
    builder = DatasetBuilder(root, NAMES)
    for img in images:
        path = root / "images" / f"{img.name}.png"
        path.parent.mkdir(parents=True, exist_ok=True)
        Image.fromarray(np.full((img.height, img.width, 3), img.grey, dtype=np.uint8)).save(path)
        image_id = builder.add_image(f"images/{img.name}.png", img.width, img.height, "real:test", "test")
        for cls, box in img.boxes:
            builder.add_box(image_id, cls, box)
    (root / "annotations.json").write_text(json.dumps(builder.build().to_coco()))
    return root


def to_input_cxcywh(img: TestImage, xywh: tuple[float, ...], shift: float = 0.0) -> list[float]:
    """An original-pixel xywh box -> centre box in letterboxed input pixels, moved right by ``shift``."""
    x, y, w, h = xywh
    sx, sy = img.scale
    return [(x + w / 2) * sx + img.pad[0] + shift, (y + h / 2) * sy + img.pad[1], w * sx, h * sy]


def rows_for(images=IMAGES, shift: float = 0.0, duplicates: bool = True) -> list[tuple[int, list[float], int, float]]:
    """Detection rows ``(grey, cxcywh, class index, score)``: every ground-truth box with a distinct score
    and, with ``duplicates``, a slightly moved copy of the first box of each image (IoU > 0.6) scored above
    every other image's boxes, which only NMS removes."""
    rows = []
    score = 0.95
    for img in images:
        for j, (cls, box) in enumerate(img.boxes):
            rows.append((img.grey, to_input_cxcywh(img, box, shift), NAMES.index(cls), score))
            if j == 0 and duplicates:
                rows.append((img.grey, to_input_cxcywh(img, box, shift + 1.0), NAMES.index(cls), score - 0.001))
            score -= 0.05
    return rows


def _gate_nodes(rows, width: int) -> tuple[list, list]:
    """Nodes computing ``gate`` (B, N, 1) from the centre pixel of ``images``."""
    mid = SIZE // 2
    inits = [
        numpy_helper.from_array(np.array([0, 0, mid, mid], np.int64), "starts"),
        numpy_helper.from_array(np.array([2**31, 1, mid + 1, mid + 1], np.int64), "ends"),
        numpy_helper.from_array(np.array([-1, 1, 1], np.int64), "pshape"),
        numpy_helper.from_array(np.array([[[r[0] / 255.0] for r in rows]], np.float32), "greys"),
        numpy_helper.from_array(np.array(-_K, np.float32), "negk"),
    ]
    nodes = [
        helper.make_node("Slice", ["images", "starts", "ends"], ["pix4"]),
        helper.make_node("Reshape", ["pix4", "pshape"], ["pix"]),
        helper.make_node("Sub", ["pix", "greys"], ["diff"]),
        helper.make_node("Mul", ["diff", "diff"], ["sq"]),
        helper.make_node("Mul", ["sq", "negk"], ["arg"]),
        helper.make_node("Exp", ["arg"], ["gate"]),
    ]
    return nodes, inits


def oracle_model(
    path: Path,
    layout: str = "yolov5",
    rows=None,
    batch: int | str = "batch",
    metadata: dict[str, str] | None = None,
    dynamic_size: bool = False,
) -> Path:
    """Write an ONNX detector emitting ``rows`` (see :func:`rows_for`) in the ``yolov5`` (B, N, 5+C) or
    ``yolov8`` (B, 4+C, N) layout. ``metadata`` defaults to YOLOv5/ultralytics-style ``names``."""
    rows = rows_for() if rows is None else rows
    c = len(NAMES)
    v5 = layout == "yolov5"
    table = np.zeros((1, len(rows), (5 if v5 else 4) + c), np.float32)
    for i, (_, box, cls, score) in enumerate(rows):
        table[0, i, :4] = box
        if v5:
            table[0, i, 4], table[0, i, 5 + cls] = score, 1.0
        else:
            table[0, i, 4 + cls] = score
    gated = np.zeros((1, 1, table.shape[2]), np.float32)
    gated[0, 0, 4 if v5 else slice(4, None)] = 1.0
    nodes, inits = _gate_nodes(rows, table.shape[2])
    inits += [
        numpy_helper.from_array(table, "table"),
        numpy_helper.from_array(gated, "gated"),
        numpy_helper.from_array(1.0 - gated, "kept"),
    ]
    nodes += [
        helper.make_node("Mul", ["gate", "gated"], ["g1"]),
        helper.make_node("Add", ["g1", "kept"], ["mult"]),
        helper.make_node("Mul", ["table", "mult"], ["rows" if not v5 else "output0"]),
    ]
    if not v5:
        nodes.append(helper.make_node("Transpose", ["rows"], ["output0"], perm=[0, 2, 1]))
    hw = ["height", "width"] if dynamic_size else [SIZE, SIZE]
    out_shape = [batch, len(rows), table.shape[2]] if v5 else [batch, table.shape[2], len(rows)]
    graph = helper.make_graph(
        nodes,
        "oracle",
        [helper.make_tensor_value_info("images", TensorProto.FLOAT, [batch, 3, *hw])],
        [helper.make_tensor_value_info("output0", TensorProto.FLOAT, out_shape)],
        inits,
    )
    model = helper.make_model(graph, opset_imports=[helper.make_opsetid("", 17)])
    model.ir_version = 8
    meta = {"names": str(dict(enumerate(NAMES))), "stride": "32"} if metadata is None else metadata
    for key, value in meta.items():
        entry = model.metadata_props.add()
        entry.key, entry.value = key, value
    onnx.checker.check_model(model)
    path.parent.mkdir(parents=True, exist_ok=True)
    onnx.save(model, str(path))
    return path


def write_class_layout(root: Path, fire: tuple[int, ...], free: tuple[int, ...], fire_dir: str = "fire") -> Path:
    """A classification layout in ``root``: ``fire_dir/`` with one flat 64x64 grey PNG per grey level of
    ``fire`` and ``normal/`` with one per level of ``free`` (no label files)."""
    for folder, greys in ((fire_dir, fire), ("normal", free)):
        for grey in greys:
            path = root / folder / f"g{grey:03d}.png"
            path.parent.mkdir(parents=True, exist_ok=True)
            Image.fromarray(np.full((SIZE, SIZE, 3), grey, dtype=np.uint8)).save(path)
    return root


def image_rows(
    greys: tuple[int, ...], score: float = 0.9, cls: str = "fire"
) -> list[tuple[int, list[float], int, float]]:
    """Detection rows (:func:`rows_for`'s shape) of one centred 32x32 box of ``cls`` on each grey level of
    ``greys``, at ``score``: a detector that fires on exactly those images."""
    return [(grey, [32.0, 32.0, 32.0, 32.0], NAMES.index(cls), score) for grey in greys]


def layout_and_two_detectors(root: Path) -> dict[str, Path]:
    """A classification layout in ``root/layout`` (fire/: four grey levels, normal/: two) and two detectors: ``a``
    fires on half the fire photos only, ``b`` on three fire photos and one normal photo."""
    write_class_layout(root / "layout", (40, 80, 120, 160), (200, 240))
    return {
        "layout": root / "layout",
        "a": oracle_model(root / "a.onnx", rows=image_rows((40, 80))),
        "b": oracle_model(root / "b.onnx", rows=image_rows((40, 80, 120, 200))),
    }
