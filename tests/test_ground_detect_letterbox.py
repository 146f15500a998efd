"""Inference letterbox: size, placement, padding and the float NCHW batch."""

from __future__ import annotations

import cv2
import numpy as np
import pytest

from ground.detect.letterbox import letterbox_image, to_nchw_float


def test_wide_image_is_centred_with_grey_bands():
    img = np.full((32, 64, 3), 7, np.uint8)
    out = letterbox_image(img, 64, 64)
    assert out.shape == (64, 64, 3) and out.dtype == np.uint8
    assert (out[16:48] == 7).all() and (out[:16] == 114).all() and (out[48:] == 114).all()


def test_shrinks_and_keeps_channel_order():
    img = np.zeros((100, 50, 3), np.uint8)
    img[..., 0] = 200
    out = letterbox_image(img, 32, 32, pad_value=0)
    assert (out[:, 8:24, 0] == 200).all() and (out[:, 8:24, 1:] == 0).all() and (out[:, :8] == 0).all()


def test_to_nchw_float():
    batch = to_nchw_float([np.full((4, 5, 3), 255, np.uint8), np.zeros((4, 5, 3), np.uint8)])
    assert batch.shape == (2, 3, 4, 5) and batch.dtype == np.float32
    assert batch[0].min() == 1.0 and batch[1].max() == 0.0 and batch.flags["C_CONTIGUOUS"]


@pytest.mark.parametrize("resize,interp", [("linear", cv2.INTER_LINEAR), ("area", cv2.INTER_AREA)])
def test_resize_modes_match_a_reference_resize(resize, interp):
    image = np.random.default_rng(0).integers(0, 255, (300, 400, 3), dtype=np.uint8)
    out = letterbox_image(image, 64, 64, resize=resize)
    # by hand: 400 x 300 into 64 x 64 -> 64 x 48, centred with 8 rows of grey above and below
    reference = cv2.resize(image, (64, 48), interpolation=interp)
    np.testing.assert_array_equal(out[8:56], reference)
    assert (out[:8] == 114).all() and (out[56:] == 114).all()
    if resize == "linear":
        assert not np.array_equal(out, letterbox_image(image, 64, 64, resize="area"))
    with pytest.raises(ValueError, match="unknown resize"):
        letterbox_image(image, 64, 64, resize="cubic")
