"""ONNX export and onnxruntime embeddings: parity with torch, caching by weight hash, user models."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
import torch
from curate_helpers import GRACE_HOPPER, scene

from curate.effnet import efficientnet_lite0
from curate.embed import (
    LITE0_PREPROCESS,
    OnnxEmbedder,
    Preprocess,
    builtin_model_path,
    l2_normalize,
    load_embedder,
)
from ground.image.imageio import read_image


def _batch() -> np.ndarray:
    images = [read_image(GRACE_HOPPER), *(scene(s) for s in range(3))]
    return np.stack([LITE0_PREPROCESS.resize(im) for im in images])


def test_onnxruntime_matches_torch(embedder: OnnxEmbedder) -> None:
    batch = _batch()
    with torch.no_grad():
        expected, _ = efficientnet_lite0(image_size=LITE0_PREPROCESS.size)(
            torch.from_numpy(LITE0_PREPROCESS.normalize(batch))
        )
    got = embedder.embed(batch)
    assert got.shape == (4, 320)
    np.testing.assert_allclose(got, expected.numpy(), rtol=1e-3, atol=1e-4)


def test_export_is_cached_by_weight_hash(embedder: OnnxEmbedder) -> None:
    path = builtin_model_path()
    assert path == embedder.path and "efficientnet-lite0-" in path.name
    mtime = path.stat().st_mtime_ns
    assert builtin_model_path() == path and path.stat().st_mtime_ns == mtime  # not exported again
    assert embedder.model_id.startswith(path.stem)


def test_batching_does_not_change_embeddings(embedder: OnnxEmbedder) -> None:
    batch = _batch()
    whole = embedder.embed(batch)
    single = np.concatenate([embedder.embed(batch[i : i + 1]) for i in range(len(batch))])
    np.testing.assert_allclose(whole, single, rtol=1e-4, atol=1e-5)


@pytest.mark.filterwarnings("ignore::DeprecationWarning", "ignore::UserWarning")
def test_user_model_with_preprocessing_flags(embedder: OnnxEmbedder, tmp_path: Path) -> None:
    """A user's ONNX file: NHWC input, BGR, its own mean/std; output picked by name and flattened."""

    class Tiny(torch.nn.Module):
        def forward(self, x: torch.Tensor) -> tuple[torch.Tensor, torch.Tensor]:
            return x.mean(dim=(1, 2)), x[:, :2, :2, :]

    path = tmp_path / "tiny.onnx"
    torch.onnx.export(
        Tiny(),
        (torch.zeros(1, 8, 8, 3),),
        str(path),
        input_names=["x"],
        output_names=["mean", "corner"],
        dynamic_axes={"x": {0: "n"}},
        opset_version=17,
        dynamo=False,
    )
    pre = Preprocess(size=8, mean=(10.0, 20.0, 30.0), std=(2.0, 2.0, 2.0), bgr=True, layout="nhwc")
    model = load_embedder(path, pre)
    img = np.zeros((16, 16, 3), np.uint8)
    img[..., 0] = 100  # red channel; BGR puts it last
    out = model.embed(np.stack([pre.resize(img)]))
    np.testing.assert_allclose(out, [[(0 - 10) / 2, (0 - 20) / 2, (100 - 30) / 2]])
    corner = load_embedder(path, pre, output="corner").embed(np.stack([pre.resize(img)]))
    assert corner.shape == (1, 12)
    with pytest.raises(ValueError, match="no output"):
        load_embedder(path, pre, output="nope")


def test_bad_inputs_are_rejected(tmp_path: Path) -> None:
    with pytest.raises(FileNotFoundError):
        load_embedder(tmp_path / "missing.onnx")
    with pytest.raises(ValueError):
        Preprocess(size=2)
    with pytest.raises(ValueError):
        Preprocess(std=(1.0, 0.0, 1.0))
    with pytest.raises(ValueError, match="fixed preprocessing"):
        load_embedder(None, Preprocess(size=128))


def test_views_are_whole_and_centre_blurred() -> None:
    img = np.zeros((100, 200, 3), np.uint8)
    img[:10] = 255  # a white band at the top: outside the centre 80 % view
    pre = Preprocess(size=32)
    views = pre.views(img)
    assert views.shape == (2, 32, 32, 3) and views[0].max() == 255 and views[1].max() == 0
    blurred = Preprocess(size=32, blur=2.0).resize(img)
    assert 0 < blurred[4, 16, 0] < 255 or blurred[:, 16, 0].std() < views[0][:, 16, 0].std()
    with pytest.raises(ValueError):
        Preprocess(blur=-1)


def test_l2_normalize_rows() -> None:
    x = np.array([[3.0, 4.0], [0.0, 0.0]])
    np.testing.assert_allclose(l2_normalize(x), [[0.6, 0.8], [0.0, 0.0]])
