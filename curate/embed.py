"""Image embeddings with onnxruntime: the built-in EfficientNet-Lite0 or a user's own ONNX CNN.

The built-in model is built in torch (:mod:`curate.effnet`) and exported to ONNX once, into the user cache
folder under a name holding its weights' hash; later runs load the ``.onnx`` file directly.

A user model (``--model x.onnx``, e.g. a VGG16 export as the paper used) takes one float input of shape
(N, 3, S, S) (or (N, S, S, 3) with ``layout="nhwc"``); the image is resized to S x S (stretched), blurred by
a Gaussian of ``blur`` pixels (0 = none), converted to RGB (or BGR) and scaled as ``(pixel - mean) / std`` per
channel, pixel in 0..255. The embedding is the output named ``output`` (default: the first), flattened.

Every image is embedded in two views: the whole image and its central 80 % (:data:`CROP_VIEW`), so that a
cropped copy matches the centre view of its original (see :func:`curate.search.duplicate_pairs`).
The built-in model runs at S = 160 with blur 1.5: on ``experiments/dedup_quality.py`` this two-view setup
reaches pair F1 0.98, against 0.82 for one 224-pixel view of the 1280-d head, at the same compute.
"""

from __future__ import annotations

import hashlib
import math
import os
import tempfile
import warnings
from dataclasses import dataclass
from pathlib import Path
from typing import Literal

import cv2
import numpy as np
from numpy.typing import NDArray

DEFAULT_MODEL = "efficientnet-lite0"
CROP_VIEW = 0.8  # side of the centre view, as a fraction of the image side
#: A JPEG is decoded at 1/2, 1/4 or 1/8 of its size only while its short side stays >= this many times S: a
#: 416-px frame is decoded whole for S = 160 (its sharpness and embedding are those of the full picture), a
#: 6.6 MP photo at 1/4. Part of every embedding's identity (:meth:`Preprocess.key`): the embedding cache never
#: mixes vectors decoded under another rule.
DECODE_MIN_SIDE = 2.0


@dataclass(frozen=True)
class Preprocess:
    """How an (H, W, 3) uint8 RGB image becomes one model input (see the module docstring)."""

    size: int = 224  # square input side S in pixels
    mean: tuple[float, float, float] = (127.0, 127.0, 127.0)  # per channel, on 0..255 values
    std: tuple[float, float, float] = (128.0, 128.0, 128.0)
    bgr: bool = False  # channel order the model expects
    layout: Literal["nchw", "nhwc"] = "nchw"
    blur: float = 0.0  # Gaussian sigma in model-input pixels, applied after resizing (0 = none)

    def __post_init__(self) -> None:
        if self.size < 8:
            raise ValueError(f"input size must be >= 8 pixels, got {self.size}")
        if len(self.mean) != 3 or len(self.std) != 3 or min(self.std) <= 0:
            raise ValueError(f"mean and std need 3 values each, std > 0; got {self.mean}, {self.std}")
        if self.layout not in ("nchw", "nhwc"):
            raise ValueError(f"layout must be nchw or nhwc, got {self.layout!r}")
        if self.blur < 0:
            raise ValueError(f"blur must be >= 0, got {self.blur}")

    def resize(self, image: NDArray[np.uint8]) -> NDArray[np.uint8]:
        """(H, W, 3) uint8 RGB -> (S, S, 3) uint8 in the model's channel order."""
        h, w = image.shape[:2]
        interp = cv2.INTER_AREA if h > self.size or w > self.size else cv2.INTER_LINEAR
        small = cv2.resize(image, (self.size, self.size), interpolation=interp)
        if self.blur > 0:
            small = cv2.GaussianBlur(small, (0, 0), self.blur)
        return np.ascontiguousarray(small[:, :, ::-1]) if self.bgr else small

    def views(self, image: NDArray[np.uint8]) -> NDArray[np.uint8]:
        """(2, S, S, 3): :meth:`resize` of the whole image and of its central :data:`CROP_VIEW` part."""
        h, w = image.shape[:2]
        dy, dx = round(h * (1 - CROP_VIEW) / 2), round(w * (1 - CROP_VIEW) / 2)
        centre = image[dy : max(h - dy, dy + 1), dx : max(w - dx, dx + 1)]
        return np.stack([self.resize(image), self.resize(centre)])

    def normalize(self, batch: NDArray[np.uint8]) -> NDArray[np.float32]:
        """(N, S, S, 3) uint8 from :meth:`resize` -> float32 model input (N, 3, S, S) or (N, S, S, 3)."""
        mean = np.asarray(self.mean, np.float32)
        inv_std = 1.0 / np.asarray(self.std, np.float32)
        x = (batch.astype(np.float32) - mean) * inv_std
        return np.ascontiguousarray(x.transpose(0, 3, 1, 2)) if self.layout == "nchw" else x

    def decode_min_side(self) -> int:
        """Smallest short side, in pixels, a JPEG may be decoded down to for these inputs (:data:`DECODE_MIN_SIDE`)."""
        return math.ceil(DECODE_MIN_SIDE * self.size)

    def key(self) -> str:
        return f"r{DECODE_MIN_SIDE:g}-b{self.blur:g}-v{CROP_VIEW:g}-s{self.size}-m{','.join(f'{v:g}' for v in self.mean)}-d{','.join(f'{v:g}' for v in self.std)}-{'bgr' if self.bgr else 'rgb'}-{self.layout}"


LITE0_PREPROCESS = Preprocess(size=160, blur=1.5)


def cache_dir() -> Path:
    """Per-user cache folder (``FUZZYFIRE_CACHE`` overrides), created on first use."""
    from platformdirs import user_cache_dir

    path = Path(os.environ.get("FUZZYFIRE_CACHE") or user_cache_dir("fuzzyfire"))
    path.mkdir(parents=True, exist_ok=True)
    return path


def embedding_cache_path() -> Path:
    """The user's embedding cache (:class:`curate.embedcache.EmbeddingCache`), shared by every command."""
    return cache_dir() / "embeddings.sqlite"


def builtin_model_path(folder: Path | None = None) -> Path:
    """The EfficientNet-Lite0 ONNX file, exported on first use (named by the weights' sha256)."""
    from curate.lite0_weights import lite0_weights_path
    from ground.data.manifest import file_sha256

    folder = folder or cache_dir() / "models"
    size = LITE0_PREPROCESS.size
    path = folder / f"efficientnet-lite0-{file_sha256(lite0_weights_path())[:16]}-s{size}.onnx"
    if not path.is_file():
        export_lite0(path, size)
    return path


def export_lite0(path: Path, size: int) -> Path:
    """Export EfficientNet-Lite0 to ``path``: input ``input`` (N, 3, size, size), outputs ``embedding``
    (N, 320) and ``logits`` (N, 1000). Written atomically (a crash leaves no half file)."""
    import torch

    from curate.effnet import efficientnet_lite0

    net = efficientnet_lite0(image_size=size)
    path.parent.mkdir(parents=True, exist_ok=True)
    fd, tmp = tempfile.mkstemp(suffix=".onnx", dir=path.parent)
    os.close(fd)
    try:
        with warnings.catch_warnings(), torch.no_grad():
            warnings.simplefilter("ignore")
            torch.onnx.export(
                net,
                (torch.zeros(1, 3, size, size),),
                tmp,
                input_names=["input"],
                output_names=["embedding", "logits"],
                dynamic_axes={"input": {0: "batch"}, "embedding": {0: "batch"}, "logits": {0: "batch"}},
                opset_version=17,
                dynamo=False,
            )
        os.replace(tmp, path)
    finally:
        Path(tmp).unlink(missing_ok=True)
    return path


class OnnxEmbedder:
    """Runs an ONNX CNN on batches: ``embed(batch uint8 (N, S, S, 3)) -> (N, D) float32``.

    ``device`` (``auto | cpu | cuda | cuda:N``) picks onnxruntime's CUDA provider when it is installed (``auto``:
    when present; ``notice`` says when a GPU was asked for and the CPU is used). The model's identity
    (``model_id``: file name, content hash, output, preprocessing) does not depend on the device."""

    def __init__(
        self,
        model: Path | str,
        preprocess: Preprocess,
        output: str | None = None,
        threads: int = 1,
        device: str = "cpu",
        model_bytes: bytes | None = None,
        model_id: str | None = None,
    ) -> None:
        """``model_bytes`` (with the ``model_id`` computed where the file was read): the model's content, on a
        machine that does not have the file (a Ray worker)."""
        import onnxruntime as ort

        from ground.run.device import onnx_providers

        self.path = Path(model)
        if model_bytes is None and not self.path.is_file():
            raise FileNotFoundError(f"{self.path}: ONNX model not found")
        opts = ort.SessionOptions()
        opts.intra_op_num_threads = threads  # 1: parallelism comes from concurrent run() calls (see scan.py)
        opts.inter_op_num_threads = 1
        opts.add_session_config_entry("session.intra_op.allow_spinning", "0")
        providers, self.notice = onnx_providers(device)
        source = model_bytes if model_bytes is not None else str(self.path)
        self.session = ort.InferenceSession(source, opts, providers=providers)
        if providers[0] != "CPUExecutionProvider" and not self.on_gpu():  # CUDA or cuDNN libraries failed to load
            self.notice = (
                f"notice: onnxruntime could not start its CUDA provider for {self.path.name}; embedding on the CPU"
            )
        self.device = device
        self.preprocess = preprocess
        self.input_name = self.session.get_inputs()[0].name
        names = [o.name for o in self.session.get_outputs()]
        if output is not None and output not in names:
            raise ValueError(f"{self.path}: no output {output!r}; outputs are {names}")
        self.output = output or names[0]
        self.model_id = model_id or _model_id(self.path, preprocess, self.output)

    def on_gpu(self) -> bool:
        """Whether onnxruntime runs this model with its CUDA provider."""
        return "CUDAExecutionProvider" in self.session.get_providers()

    def embed(self, batch: NDArray[np.uint8]) -> NDArray[np.float32]:
        """(N, S, S, 3) uint8 images from ``preprocess.resize`` (or views) -> (N, D) float32 raw embeddings."""
        x = self.preprocess.normalize(batch)
        (out,) = self.session.run([self.output], {self.input_name: x})
        return np.asarray(out, np.float32).reshape(len(batch), -1)


def load_embedder(model: Path | str | None = None, preprocess: Preprocess | None = None, **kwargs) -> OnnxEmbedder:
    """The built-in EfficientNet-Lite0 (``model`` None) or a user ONNX model with its ``preprocess``."""
    if model is None or str(model) == DEFAULT_MODEL:
        if preprocess not in (None, LITE0_PREPROCESS):
            raise ValueError("the built-in model has a fixed preprocessing; preprocessing flags need --model")
        return OnnxEmbedder(builtin_model_path(), LITE0_PREPROCESS, output="embedding", **kwargs)
    return OnnxEmbedder(model, preprocess or Preprocess(), **kwargs)


def l2_normalize(x: NDArray[np.floating]) -> NDArray[np.float32]:
    """Rows scaled to unit length ((N, D) -> (N, D) float32); zero rows stay zero."""
    x = np.asarray(x, np.float32)
    norms = np.linalg.norm(x, axis=1, keepdims=True)
    return x / np.maximum(norms, 1e-12)


def _model_id(path: Path, preprocess: Preprocess, output: str) -> str:
    digest = hashlib.sha256()
    with open(path, "rb") as fh:
        while block := fh.read(1 << 20):
            digest.update(block)
    return f"{path.stem}:{digest.hexdigest()[:16]}:{output}:{preprocess.key()}"
