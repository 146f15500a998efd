import numpy as np
import pytest

from ground.data import boxes


def _random_xywh(n: int, seed: int = 0) -> np.ndarray:
    rng = np.random.default_rng(seed)
    xy = rng.uniform(0, 500, size=(n, 2))
    wh = rng.uniform(1, 200, size=(n, 2))
    return np.concatenate([xy, wh], axis=1)


def test_xywh_xyxy_round_trip():
    b = _random_xywh(100)
    np.testing.assert_allclose(boxes.xyxy_to_xywh(boxes.xywh_to_xyxy(b)), b, atol=1e-9)


def test_cxcywhn_round_trip():
    b = _random_xywh(100, seed=1)
    back = boxes.cxcywhn_to_xywh(boxes.xywh_to_cxcywhn(b, 640, 480), 640, 480)
    np.testing.assert_allclose(back, b, atol=1e-9)


def test_cxcywhn_known_value():
    np.testing.assert_allclose(boxes.cxcywhn_to_xywh([0.5, 0.5, 0.25, 0.5], 64, 48), [24, 12, 16, 24])


def test_voc_is_one_based_inclusive():
    # VOC pixels 1..10 cover [0, 10) in continuous coordinates.
    np.testing.assert_allclose(boxes.voc_to_xywh([1, 1, 10, 20]), [0, 0, 10, 20])
    b = _random_xywh(50, seed=2)
    voc = np.concatenate([b[:, :2] + 1.0, b[:, :2] + b[:, 2:]], axis=1)  # the inverse, written out
    np.testing.assert_allclose(boxes.voc_to_xywh(voc), b, atol=1e-9)


def test_functions_never_modify_input():
    b = _random_xywh(5)
    before = b.copy()
    for fn in (boxes.xywh_to_xyxy, boxes.xyxy_to_xywh, boxes.voc_to_xywh):
        fn(b)
    boxes.clip_xywh(b, 100, 100)
    boxes.xywh_to_cxcywhn(b, 100, 100)
    np.testing.assert_array_equal(b, before)


def test_clip_and_inside():
    b = np.array([[-10, -5, 30, 20], [90, 90, 20, 20], [10, 10, 5, 5]], dtype=float)
    np.testing.assert_allclose(boxes.clip_xywh(b, 100, 100), [[0, 0, 20, 15], [90, 90, 10, 10], [10, 10, 5, 5]])
    assert boxes.inside_xywh(b, 100, 100).tolist() == [False, False, True]


def test_iou_matches_hand_computed():
    a = [[0, 0, 10, 10]]
    b = [[5, 5, 15, 15], [20, 20, 30, 30], [0, 0, 10, 10]]
    np.testing.assert_allclose(boxes.box_iou_xyxy(a, b), [[25 / 175, 0.0, 1.0]])


def test_iou_degenerate_boxes_are_zero():
    assert boxes.box_iou_xyxy([[0, 0, 0, 0]], [[0, 0, 0, 0]])[0, 0] == 0.0


def test_bad_shape_raises():
    with pytest.raises(ValueError, match="shaped"):
        boxes.xywh_to_xyxy([1, 2, 3])


def test_cxcywh_to_xyxy():
    np.testing.assert_allclose(boxes.cxcywh_to_xyxy([[10, 20, 4, 6]]), [[8, 17, 12, 23]])


def test_letterbox_params_centre_the_image():
    assert boxes.letterbox_params(64, 32, 64, 64) == (64, 32, 0, 16)
    assert boxes.letterbox_params(30, 60, 64, 64) == (32, 64, 16, 0)
    assert boxes.letterbox_params(100, 100, 64, 64) == (64, 64, 0, 0)
    with pytest.raises(ValueError, match="positive"):
        boxes.letterbox_params(0, 10, 64, 64)


def test_letterbox_box_mapping_round_trip_and_hand_values():
    b = np.array([[0.0, 0.0, 64.0, 32.0], [10.0, 4.0, 20.0, 8.0]])
    lb = boxes.image_to_letterbox_xyxy(b, 128, 64, 64, 64)  # scale 0.5, pad_top 16
    np.testing.assert_allclose(lb, [[0, 16, 32, 32], [5, 18, 10, 20]])
    np.testing.assert_allclose(boxes.letterbox_to_image_xyxy(lb, 128, 64, 64, 64), b, atol=1e-9)


def test_mask_to_xywh_encloses_the_mask_exactly():
    from ground.data.boxes import mask_to_xywh

    mask = np.zeros((6, 8), bool)
    mask[2:5, 3] = True
    mask[4, 6] = True
    assert mask_to_xywh(mask).tolist() == [3.0, 2.0, 4.0, 3.0]
    assert mask_to_xywh(np.zeros((4, 4), np.uint8)).tolist() == [0.0, 0.0, 0.0, 0.0]
    full = np.ones((5, 7), np.uint8)
    assert mask_to_xywh(full).tolist() == [0.0, 0.0, 7.0, 5.0]
    with pytest.raises(ValueError):
        mask_to_xywh(np.ones(3))


def test_affine_xyxy_moves_corners_and_encloses():
    b = np.array([[10.0, 20.0, 30.0, 60.0]])
    shift_scale = np.array([[2.0, 0, 5], [0, 0.5, -10]])
    np.testing.assert_allclose(boxes.affine_xyxy(b, shift_scale), [[25, 0, 65, 20]])
    mirror = np.array([[-1.0, 0, 100], [0, 1, 0], [0, 0, 1]])  # x -> 100 - x keeps x_min < x_max
    np.testing.assert_allclose(boxes.affine_xyxy(b, mirror), [[70, 20, 90, 60]])
    rot90 = np.array([[0.0, -1, 0], [1, 0, 0]])  # (x, y) -> (-y, x)
    np.testing.assert_allclose(boxes.affine_xyxy(b, rot90), [[-60, 10, -20, 30]])
    assert boxes.affine_xyxy(np.zeros((0, 4)), mirror).shape == (0, 4)
    with pytest.raises(ValueError, match="2x3"):
        boxes.affine_xyxy(b, np.eye(2))


def test_points_to_xyxy_encloses_points():
    pts = np.array([[3.0, 9.0], [-2.5, 4.0], [7.0, 1.0], [0.0, 5.0]])
    np.testing.assert_allclose(boxes.points_to_xyxy(pts), [-2.5, 1.0, 7.0, 9.0])
    np.testing.assert_allclose(boxes.points_to_xyxy([[1.0, 2.0]]), [1, 2, 1, 2])
    with pytest.raises(ValueError, match="N, 2"):
        boxes.points_to_xyxy(np.zeros((0, 2)))


def test_xyxy_to_cxcywh_inverts_cxcywh_to_xyxy():
    b = np.array([[8.0, 17.0, 12.0, 23.0], [0.0, 0.0, 1.0, 3.0]])
    np.testing.assert_allclose(boxes.xyxy_to_cxcywh(b), [[10, 20, 4, 6], [0.5, 1.5, 1, 3]])
    np.testing.assert_allclose(boxes.cxcywh_to_xyxy(boxes.xyxy_to_cxcywh(b)), b)


def test_xywh_overlaps_any_agrees_with_a_positive_iou():
    b = _random_xywh(60, seed=3)
    for i in range(len(b)):
        others = np.delete(b, i, axis=0)
        iou = boxes.box_iou_xyxy(boxes.xywh_to_xyxy(b[i]), boxes.xywh_to_xyxy(others))
        assert boxes.xywh_overlaps_any(b[i], others) == bool((iou > 0).any())
    assert not boxes.xywh_overlaps_any([0, 0, 10, 10], [[10, 0, 5, 5]])  # touching edges share no area
    assert not boxes.xywh_overlaps_any([0, 0, 10, 10], [])
