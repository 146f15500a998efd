"""Batched inference over a dataset: boxes back in original pixels, batching invariance, bad images."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest
from detector_factories import IMAGES, oracle_model, write_test_set

from eval.config import InferenceConfig
from eval.onnx_model import OnnxDetector
from eval.predict import _loader, detect_images, predict_dataset
from ground.data.boxes import xyxy_to_xywh
from ground.data.formats.registry import read_dataset
from ground.detect.detections import PostprocessConfig
from ground.image.imageio import read_image


@pytest.fixture(scope="module")
def setup(tmp_path_factory):
    root = tmp_path_factory.mktemp("predict")
    ds = read_dataset(write_test_set(root / "test")).dataset
    return ds, OnnxDetector(oracle_model(root / "m.onnx"))


@pytest.mark.parametrize("batch", [1, 2, 4, 16])
def test_boxes_come_back_in_original_pixels(setup, batch):
    ds, det = setup
    preds = predict_dataset(det, ds, InferenceConfig(batch=batch))
    assert preds.problems == [] and set(preds.by_image) == {img.id for img in ds.images}
    by_name = {img.file_name.split("/")[-1][:-4]: img.id for img in ds.images}
    for img in IMAGES:
        got = preds.by_image[by_name[img.name]]
        want = sorted((("fire", "smoke").index(c), *b) for c, b in img.boxes)
        have = sorted((int(lab), *box) for lab, box in zip(got.labels, xyxy_to_xywh(got.boxes)))
        assert len(have) == len(want)
        np.testing.assert_allclose(np.array(have), np.array(want, float), atol=1e-3)


def test_unreadable_image_is_reported_and_skipped(setup, tmp_path):
    ds, det = setup
    bad = tmp_path / "broken.png"
    bad.write_bytes(b"\x89PNG\r\n\x1a\n garbage")
    first = ds.images[0]
    images = (dataclasses.replace(first, file_name=str(bad)), *ds.images[1:])
    preds = predict_dataset(det, dataclasses.replace(ds, images=images))
    assert first.id not in preds.by_image and len(preds.by_image) == len(ds.images) - 1
    assert len(preds.problems) == 1 and "broken.png" in str(preds.problems[0])


def test_size_mismatch_is_a_warning(setup):
    ds, det = setup
    images = (dataclasses.replace(ds.images[0], width=999), *ds.images[1:])
    preds = predict_dataset(det, dataclasses.replace(ds, images=images))
    assert [p.level for p in preds.problems] == ["warning"] and "999x" in preds.problems[0].reason


@pytest.mark.parametrize("batch", [1, 4])
def test_decoded_images_get_the_detections_their_files_get(setup, batch):
    ds, det = setup
    opt = InferenceConfig(PostprocessConfig(conf=0.2), batch=batch)
    from_files = predict_dataset(det, ds, opt)
    found = detect_images(det, [read_image(ds.image_path(img)) for img in ds.images], opt)
    assert len(found) == len(ds.images)
    for img, got in zip(ds.images, found):
        want = from_files.by_image[img.id]
        assert np.array_equal(got.boxes, want.boxes) and np.array_equal(got.scores, want.scores)
        assert np.array_equal(got.labels, want.labels)
    assert sum(len(d) for d in found) == sum(len(i.boxes) for i in IMAGES)  # NMS and conf applied alike


def test_decoding_threads_fill_the_batch_exactly_as_to_nchw_float(setup):
    from ground.detect.letterbox import letterbox_image, to_nchw_float

    ds, det = setup
    spec = det.spec
    paths = [str(ds.image_path(img)) for img in ds.images[:3]]
    batch = np.full((len(paths), 3, spec.input_height, spec.input_width), np.nan, dtype=np.float32)
    load = _loader(spec.input_width, spec.input_height, spec.pad_value, "area")
    sizes = [load(p, batch, j) for j, p in enumerate(reversed(paths))]
    boxed = [letterbox_image(read_image(p), spec.input_width, spec.input_height, spec.pad_value) for p in paths]
    np.testing.assert_array_equal(batch[::-1], to_nchw_float(boxed))
    assert sizes[::-1] == [(img.width, img.height) for img in ds.images[:3]]
