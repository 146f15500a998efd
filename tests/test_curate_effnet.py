"""EfficientNet-Lite0 port: the packaged weights load into our torch net and classify real photos right."""

from __future__ import annotations

import numpy as np
import pytest
import torch
from curate_helpers import GRACE_HOPPER

from curate.effnet import EMBED_DIM, EfficientNetLite0, SameConv, efficientnet_lite0
from curate.embed import Preprocess
from ground.image.imageio import read_image

IMAGENET = Preprocess(size=224)  # the resolution the weights were trained at, no blur


@pytest.fixture(scope="module")
def net() -> EfficientNetLite0:
    return efficientnet_lite0()


def _predict(net: EfficientNetLite0, image: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    x = IMAGENET.normalize(IMAGENET.resize(image)[None])
    with torch.no_grad():
        emb, logits = net(torch.from_numpy(x))
    return emb.numpy(), torch.softmax(logits, 1).numpy()


@pytest.mark.parametrize("view", ["full", "hflip", "crop"])
def test_grace_hopper_is_a_military_uniform(net: EfficientNetLite0, view: str) -> None:
    """A real photo (shipped with matplotlib) and two views of it: top-1 = ImageNet 652 'military uniform'."""
    img = read_image(GRACE_HOPPER)
    if view == "hflip":
        img = np.ascontiguousarray(img[:, ::-1])
    elif view == "crop":
        img = img[40:520, 40:480]
    emb, probs = _predict(net, img)
    assert emb.shape == (1, EMBED_DIM)
    assert int(probs[0].argmax()) == 652
    assert probs[0, 652] > 0.2


def test_noise_is_not_confidently_a_uniform(net: EfficientNetLite0) -> None:
    noise = np.random.default_rng(0).integers(0, 256, (224, 224, 3), dtype=np.uint8)
    _, probs = _predict(net, noise)
    assert probs[0, 652] < 0.05


def test_same_padding_matches_tensorflow_rule() -> None:
    """TF 'same': output = ceil(in / stride); the odd pixel of padding goes bottom/right."""
    conv = SameConv(3, 4, 3, 2, in_size=224)
    assert conv.out_size == 112 and conv.pad == (0, 1, 0, 1)
    out = conv(torch.zeros(1, 3, 224, 224))
    assert out.shape == (1, 4, 112, 112)
    conv5 = SameConv(4, 4, 5, 2, in_size=28, groups=4)
    assert conv5(torch.zeros(1, 4, 28, 28)).shape == (1, 4, 14, 14)
    assert SameConv(4, 4, 5, 1, in_size=14).padding == (2, 2)


def test_wrong_weights_are_rejected(tmp_path) -> None:
    bad = tmp_path / "bad.pth"
    torch.save({"_conv_stem.weight": torch.zeros(32, 3, 3, 3)}, bad)
    with pytest.raises(ValueError, match="do not fit"):
        efficientnet_lite0(bad)
