"""Safe image reading: every image comes out as (H, W, 3) uint8 RGB, upright, or as an :class:`ImageError`.

- EXIF orientation is applied (sizes are reported after it, as a viewer shows the image).
- 16-bit and float images are scaled to 8-bit; grey is expanded to RGB; an alpha channel is dropped.
- Paths may be any unicode; files are read as bytes, never through a locale-dependent C path.
- Corrupt, truncated, empty and non-image files raise :class:`ImageError` naming the file and the reason.
"""

from __future__ import annotations

import io
import warnings
from pathlib import Path

import cv2
import numpy as np
from numpy.typing import NDArray
from PIL import Image, UnidentifiedImageError

#: File suffixes treated as images when scanning folders (lower case).
IMAGE_SUFFIXES: frozenset[str] = frozenset(
    {".jpg", ".jpeg", ".png", ".bmp", ".tif", ".tiff", ".webp", ".gif", ".jfif", ".jpe", ".dib", ".pbm", ".pgm", ".ppm"}
)

_EXIF_ORIENTATION = 274
_SWAPS_AXES = frozenset({5, 6, 7, 8})


class ImageError(Exception):
    """An image that cannot be used; ``str()`` is ``"<path>: <reason>"``."""

    def __init__(self, path: Path | str, reason: str) -> None:
        super().__init__(f"{path}: {reason}")
        self.path = str(path)
        self.reason = reason


def is_image_file(path: Path) -> bool:
    return path.suffix.lower() in IMAGE_SUFFIXES


def image_size(path: Path | str) -> tuple[int, int]:
    """``(width, height)`` as displayed (after EXIF orientation), read from the header without decoding.

    Also rejects JPEG/PNG files whose end marker is missing (truncated), which costs nothing more.
    """
    path = Path(path)
    data = _read_bytes(path)
    _check_complete(data, path)
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            with Image.open(io.BytesIO(data)) as im:
                width, height = im.size
                orientation = _orientation(im)
    except (UnidentifiedImageError, OSError, ValueError, SyntaxError) as exc:
        raise ImageError(path, f"not a readable image ({exc.__class__.__name__}: {exc})") from None
    if width <= 0 or height <= 0:
        raise ImageError(path, f"invalid image size {width}x{height}")
    return (height, width) if orientation in _SWAPS_AXES else (width, height)


def read_image(path: Path | str) -> NDArray[np.uint8]:
    """Decode ``path`` to an upright (H, W, 3) uint8 RGB array, or raise :class:`ImageError`."""
    path = Path(path)
    return decode_image(_read_bytes(path), path)


def decode_image(data: bytes, path: Path | str = "<bytes>") -> NDArray[np.uint8]:
    """Decode encoded image bytes (any format OpenCV or Pillow reads) to upright (H, W, 3) uint8 RGB."""
    _check_complete(data, path)
    buf = np.frombuffer(data, dtype=np.uint8)
    # ANYDEPTH|ANYCOLOR: keeps 16-bit, drops alpha, applies EXIF orientation.
    img = cv2.imdecode(buf, cv2.IMREAD_ANYDEPTH | cv2.IMREAD_ANYCOLOR)
    if img is None:
        return _decode_with_pillow(data, path)
    return _to_rgb8(_to_uint8(img), bgr=True)


def _read_bytes(path: Path) -> bytes:
    try:
        data = path.read_bytes()
    except FileNotFoundError:
        raise ImageError(path, "file not found") from None
    except IsADirectoryError:
        raise ImageError(path, "is a directory") from None
    except OSError as exc:
        raise ImageError(path, f"cannot read ({exc.strerror or exc})") from None
    if not data:
        raise ImageError(path, "empty file (0 bytes)")
    return data


def _check_complete(data: bytes, path: Path | str) -> None:
    """Reject JPEG/PNG files whose end marker is missing (truncated downloads decode as grey garbage)."""
    tail = data[-4096:].rstrip(b"\x00\r\n\t ")
    if data[:3] == b"\xff\xd8\xff" and b"\xff\xd9" not in tail[-256:]:
        raise ImageError(path, "truncated JPEG (no end-of-image marker)")
    if data[:8] == b"\x89PNG\r\n\x1a\n" and b"IEND" not in tail[-64:]:
        raise ImageError(path, "truncated PNG (no IEND chunk)")


def _orientation(im: Image.Image) -> int:
    try:
        return int(im.getexif().get(_EXIF_ORIENTATION, 1))
    except Exception:  # noqa: BLE001 - a broken EXIF block must not make a good image unreadable
        return 1


def _decode_with_pillow(data: bytes, path: Path | str) -> NDArray[np.uint8]:
    from PIL import ImageOps

    try:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            with Image.open(io.BytesIO(data)) as im:
                im.load()
                im = ImageOps.exif_transpose(im)
                arr = np.asarray(im.convert("RGB") if im.mode not in ("I;16", "I", "F") else im)
    except (UnidentifiedImageError, OSError, ValueError, SyntaxError) as exc:
        reason = "not an image" if isinstance(exc, UnidentifiedImageError) else f"corrupt image ({exc})"
        raise ImageError(path, reason) from None
    return _to_rgb8(_to_uint8(arr), bgr=False)


def _to_uint8(img: NDArray) -> NDArray[np.uint8]:
    if img.dtype == np.uint8:
        return img
    if img.dtype == np.uint16:
        return (img.astype(np.uint32) * 255 // 65535).astype(np.uint8)
    if np.issubdtype(img.dtype, np.floating):
        finite = np.nan_to_num(img.astype(np.float64), nan=0.0, posinf=0.0, neginf=0.0)
        scale = 255.0 if finite.max(initial=0.0) <= 1.0 else 1.0
        return np.clip(finite * scale + 0.5, 0, 255).astype(np.uint8)
    info = np.iinfo(img.dtype)
    span = float(info.max) - float(max(info.min, 0))
    return np.clip(img.astype(np.float64) / span * 255.0 + 0.5, 0, 255).astype(np.uint8)


def _to_rgb8(img: NDArray[np.uint8], bgr: bool) -> NDArray[np.uint8]:
    if img.ndim == 2:
        return np.ascontiguousarray(np.repeat(img[:, :, None], 3, axis=2))
    channels = img.shape[2]
    if channels == 1:
        return np.ascontiguousarray(np.repeat(img, 3, axis=2))
    rgb = img[:, :, :3]
    if bgr:
        rgb = rgb[:, :, ::-1]
    return np.ascontiguousarray(rgb)
