"""Safe image reading: every image comes out as (H, W, 3) uint8 RGB, upright, or as an :class:`ImageError`.

- EXIF orientation is applied (sizes are reported after it, as a viewer shows the image).
- 16-bit and float images are scaled to 8-bit; grey is expanded to RGB; an alpha channel is dropped.
- Paths may be any unicode; files are read as bytes, never through a locale-dependent C path.
- Corrupt, truncated, empty and non-image files raise :class:`ImageError` naming the file and the reason.
  Completeness is decided by the file's own structure, the way the decoders decide it: a JPEG is complete when
  its end-of-image marker follows the start of its scan anywhere in the file, a PNG when it has its ``IEND``
  chunk; zero padding and trailing bytes after the marker (phone exports, metadata tools) are fine. A JPEG whose
  scan data holds a stray marker (garbled bytes: libjpeg warns "Corrupt JPEG data: premature end of data
  segment" on stderr and OpenCV returns a mostly grey image) is refused as ``corrupt JPEG data``.
- Bytes between a JPEG's header segments, which libjpeg skips with a nameless "Corrupt JPEG data: 1 extraneous
  bytes before marker 0xdb" on stderr, are removed before decoding (the same pixels, no libjpeg line) and logged
  as a warning naming the file (:func:`jpeg_repaired`; ``fuzzyfire validate`` lists them). Decoding threads stay
  independent: nothing redirects the process's stderr. libjpeg's warnings that only its entropy decoder can
  see (e.g. "bad Huffman code") still reach stderr unnamed.
- Where only a small image is needed (embeddings, thumbnails), ``min_side`` decodes a JPEG at 1/2, 1/4 or 1/8
  of its size in the DCT domain (libjpeg scaling: 3-10x faster, a fraction of the memory).
- Images over :data:`MAX_PIXELS` decoded pixels are refused with a clear error instead of decoding gigabytes.
"""

from __future__ import annotations

import io
import logging
import os
import re
import warnings
from dataclasses import dataclass
from pathlib import Path

import cv2
import numpy as np
from numpy.typing import NDArray
from PIL import Image, UnidentifiedImageError

#: File suffixes treated as images when scanning folders (lower case).
IMAGE_SUFFIXES: frozenset[str] = frozenset(
    {".jpg", ".jpeg", ".png", ".bmp", ".tif", ".tiff", ".webp", ".gif", ".jfif", ".jpe", ".dib", ".pbm", ".pgm", ".ppm"}
)

#: Largest decoded image, in pixels (100 MP = 300 MB as RGB); a JPEG decoded at reduced size counts reduced.
MAX_PIXELS = 100_000_000
_REDUCED_FLAGS = {2: cv2.IMREAD_REDUCED_COLOR_2, 4: cv2.IMREAD_REDUCED_COLOR_4, 8: cv2.IMREAD_REDUCED_COLOR_8}
_JPEG_STANDALONE = frozenset({0x01, *range(0xD0, 0xD9)})  # markers without a length field (TEM, RSTn, SOI)
# segments that may stand between two scans: DHT, DAC, DQT, DNL, DRI, APPn, COM (JPEG standard B.2.4)
_BETWEEN_SCANS = frozenset({0xC4, 0xCC, 0xDB, 0xDC, 0xDD, *range(0xE0, 0xF0), 0xFE})
_DCT_FRAMES = frozenset({*range(0xC0, 0xC4), *range(0xC5, 0xC8), *range(0xC9, 0xCC), *range(0xCD, 0xD0)})  # SOFn
_SCAN_MARKER = re.compile(rb"\xff[^\x00\xff]")  # a marker inside scan data (FF 00 is stuffing, FF FF fill)
_EXIF_ORIENTATION = 274
_LOG = logging.getLogger(__name__)
_SWAPS_AXES = frozenset({5, 6, 7, 8})


#: The reason of a file no decoder recognises (a text file named .jpg, an HTML error page saved as an image).
NOT_AN_IMAGE = "not an image (no image format recognised in its bytes)"
_BUFFER_REPR = re.compile(r"<_io\.BytesIO object at 0x[0-9a-fA-F]+>")


class ImageError(Exception):
    """An image that cannot be used; ``str()`` is ``"<path>: <reason>"``."""

    def __init__(self, path: Path | str, reason: str) -> None:
        super().__init__(f"{path}: {reason}")
        self.path = str(path)
        self.reason = reason


def is_image_file(path: Path | str) -> bool:
    """Whether the file name's suffix is an image suffix (:data:`IMAGE_SUFFIXES`, any case)."""
    return os.path.splitext(str(path))[1].lower() in IMAGE_SUFFIXES


def image_size(path: Path | str) -> tuple[int, int]:
    """``(width, height)`` as displayed (after EXIF orientation), read from the header without decoding.

    Also rejects JPEG/PNG files whose end marker is missing (truncated), which costs nothing more.
    """
    path = Path(path)
    data = read_bytes(path)
    check_complete(data, path)
    return header_size(data, path)


def header_size(data: bytes, path: Path | str = "<bytes>") -> tuple[int, int]:
    """``(width, height)`` of encoded image bytes as displayed (after EXIF orientation), from the header only."""
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            with Image.open(io.BytesIO(data)) as im:
                width, height = im.size
                orientation = _orientation(im)
    except Image.DecompressionBombError as exc:  # Pillow's own limit (2 x 89 MP), met before ours
        raise ImageError(path, f"over the {MAX_PIXELS / 1e6:g} MP decoding budget ({exc})") from None
    except UnidentifiedImageError:  # its message names the in-memory buffer, not the file
        raise ImageError(path, NOT_AN_IMAGE) from None
    except (OSError, ValueError, SyntaxError) as exc:
        raise ImageError(path, f"not a readable image ({exc.__class__.__name__}: {_without_buffer(exc)})") from None
    if width <= 0 or height <= 0:
        raise ImageError(path, f"invalid image size {width}x{height}")
    return (height, width) if orientation in _SWAPS_AXES else (width, height)


def read_image(path: Path | str, min_side: int = 0) -> NDArray[np.uint8]:
    """Decode ``path`` to an upright (H, W, 3) uint8 RGB array, or raise :class:`ImageError`.

    ``min_side`` > 0 allows a smaller decode (see :func:`decode_image`)."""
    path = Path(path)
    return decode_image(read_bytes(path), path, min_side)


def reduction(data: bytes, size: tuple[int, int], min_side: int) -> int:
    """The JPEG DCT scaling (1, 2, 4 or 8) that keeps the short side of a ``size`` (width, height) image at least
    ``min_side`` pixels; 1 for other formats or ``min_side`` <= 0 (no reduced decoding)."""
    if min_side <= 0 or data[:3] != b"\xff\xd8\xff":
        return 1
    short = min(size)
    return max([1, *(r for r in _REDUCED_FLAGS if short // r >= min_side)])


def decode_image(data: bytes, path: Path | str = "<bytes>", min_side: int = 0) -> NDArray[np.uint8]:
    """Decode encoded image bytes (any format OpenCV or Pillow reads) to upright (H, W, 3) uint8 RGB.

    With ``min_side`` > 0 a JPEG may come out at 1/2, 1/4 or 1/8 of its size (DCT-domain scaling, rounded up),
    its short side still >= ``min_side``; use it where the image is only shrunk afterwards. Raises
    :class:`ImageError` for bad files and for images over :data:`MAX_PIXELS` decoded pixels."""
    return decode_sized(data, path, min_side)[0]


def decode_sized(
    data: bytes, path: Path | str = "<bytes>", min_side: int = 0
) -> tuple[NDArray[np.uint8], tuple[int, int]]:
    """:func:`decode_image` and the image's full ``(width, height)`` as displayed (the decode may be smaller).

    A JPEG with bytes libjpeg skips between its header segments (:func:`jpeg_repaired`) is decoded without them,
    the same pixels, and each is a warning on the ``ground.image.imageio`` logger naming the file (stderr unless
    logging is configured) instead of libjpeg's nameless line."""
    data, notes = jpeg_repaired(data)
    for note in notes:
        _LOG.warning("%s: %s", path, note)
    check_complete(data, path)
    size = header_size(data, path)
    r = reduction(data, size, min_side)
    if (size[0] // r) * (size[1] // r) > MAX_PIXELS:
        raise ImageError(
            path,
            f"{size[0]}x{size[1]} image ({size[0] * size[1] / 1e6:.0f} MP) is over the {MAX_PIXELS / 1e6:g} MP "
            "decoding budget (it would take gigabytes): resize it, or tile it into smaller images",
        )
    buf = np.frombuffer(data, dtype=np.uint8)
    # REDUCED_COLOR_r: 8-bit BGR at 1/r; ANYDEPTH|ANYCOLOR: keeps 16-bit, drops alpha. Both apply EXIF orientation.
    img = cv2.imdecode(buf, _REDUCED_FLAGS[r] if r > 1 else cv2.IMREAD_ANYDEPTH | cv2.IMREAD_ANYCOLOR)
    if img is None:
        return _decode_with_pillow(data, path), size
    return _to_rgb8(_to_uint8(img), bgr=True), size


def read_bytes(path: Path | str) -> bytes:
    """The bytes of the image file ``path``; :class:`ImageError` when it cannot be read or is empty."""
    path = Path(path)
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


def check_complete(data: bytes, path: Path | str) -> None:
    """Reject JPEG/PNG files that end before their image data does (truncated downloads decode as grey garbage)
    or whose JPEG scan data is garbled, with :class:`ImageError`; no decoding (a pass over the bytes).

    JPEG: the end-of-image marker (FF D9) must follow the first start-of-scan anywhere in the file (inside the
    entropy-coded data FF is always stuffed, so FF D9 there is the real end; an EXIF thumbnail's own end marker
    sits before the scan and does not count), and no marker may stand inside the scan data
    (:func:`_check_scan_data`). PNG: the ``IEND`` chunk must be present. Bytes after either (zero padding,
    appended data) are allowed: every decoder and viewer ignores them."""
    if data[:3] == b"\xff\xd8\xff":
        head = _jpeg_headers(data)
        if head.scan is None:
            raise ImageError(path, "truncated JPEG (ends inside its headers)")
        if data.rfind(b"\xff\xd9") < head.scan:
            raise ImageError(path, "truncated JPEG (no end-of-image marker)")
        if head.scan and head.frame:  # a DCT JPEG (not JPEG-LS, whose scan data stuffs FF differently)
            _check_scan_data(data, head.scan, head.interval, path)
    elif data[:8] == b"\x89PNG\r\n\x1a\n":
        end = data.rfind(b"IEND")
        if end < 12 or data[end - 4 : end] != b"\x00\x00\x00\x00":
            raise ImageError(path, "truncated PNG (no IEND chunk)")


@dataclass(frozen=True)
class _JpegHeaders:
    """What a walk of a JPEG's marker segments up to its first scan found (:func:`_jpeg_headers`)."""

    scan: int | None  # offset of the first start-of-scan marker; 0: the walk got lost; None: ends inside headers
    frame: int = 0  # the start-of-frame marker (0: none seen)
    interval: int = 0  # the restart interval in MCUs (0: no DRI segment sets one)
    extraneous: tuple[tuple[int, int, int, int], ...] = ()  # (start, end, bytes as libjpeg counts them, marker)


def _jpeg_headers(data: bytes) -> _JpegHeaders:
    """Walk the marker segments from the start to the first start-of-scan marker (FF DA) as libjpeg reads them:
    bytes where a marker should be are skipped up to the next marker (libjpeg warns "Corrupt JPEG data: N
    extraneous bytes before marker 0xXX" on stderr and decodes the image all the same). The walk gets lost (scan
    0: an end marker anywhere will do, and the decoder judges) when no marker follows such bytes."""
    pos, n, frame, interval, junk = 2, len(data), 0, 0, []
    while pos + 2 <= n:
        if data[pos] != 0xFF or data[pos + 1] == 0x00:  # FF 00 is no marker either
            found = _next_marker(data, pos)
            if found is None:
                return _JpegHeaders(0, frame, interval, tuple(junk))
            junk.append((pos, found[0], found[1], data[found[0] + 1]))
            pos = found[0]
            continue
        marker = data[pos + 1]
        if marker == 0xFF:  # fill byte
            pos += 1
        elif marker in (0xDA, 0xD9):  # the first scan; or the end of the image before one: lost
            return _JpegHeaders(pos if marker == 0xDA else 0, frame, interval, tuple(junk))
        elif marker in _JPEG_STANDALONE:
            pos += 2
        elif pos + 4 > n:
            break
        else:
            if marker in _DCT_FRAMES:
                frame = marker
            elif marker == 0xDD and pos + 6 <= n:
                interval = int.from_bytes(data[pos + 4 : pos + 6], "big")
            pos += 2 + int.from_bytes(data[pos + 2 : pos + 4], "big")
    return _JpegHeaders(None, frame, interval, tuple(junk))


def _next_marker(data: bytes, pos: int) -> tuple[int, int] | None:
    """libjpeg's ``next_marker`` from ``pos``: (offset of the FF just before the next marker's code, the bytes
    it discards on the way as it counts them: each non-FF byte, 2 per FF 00 pair); None when no marker follows."""
    counted, n = 0, len(data)
    while True:
        ff = data.find(b"\xff", pos)
        if ff < 0:
            return None
        counted += ff - pos
        code = ff + 1
        while code < n and data[code] == 0xFF:
            code += 1
        if code >= n:
            return None
        if data[code] != 0x00:
            return code - 1, counted
        counted += 2
        pos = code + 1


def jpeg_repaired(data: bytes) -> tuple[bytes, list[str]]:
    """``data`` without the bytes libjpeg would skip with a warning between the segments of a JPEG's headers (when
    a walk of its segments reaches its first scan), and those warnings (``corrupt JPEG data (1 extraneous bytes before marker 0xdb)``, libjpeg's words); ``data`` and
    [] for anything else. libjpeg decodes both the same, but prints its warning on stderr without the file's
    name: decoding the repaired bytes keeps it quiet and lets the caller name the file."""
    if data[:3] != b"\xff\xd8\xff":
        return data, []
    head = _jpeg_headers(data)
    junk = head.extraneous
    if not junk or not head.scan:  # no such bytes, or a walk that got lost: the decoder judges the file as it is
        return data, []
    parts, last = [], 0
    for start, end, _, _ in junk:
        parts += [data[last:start]]
        last = end
    notes = [
        f"corrupt JPEG data ({counted} extraneous bytes before marker 0x{marker:02x})" for *_, counted, marker in junk
    ]
    return b"".join([*parts, data[last:]]), notes


def _check_scan_data(data: bytes, pos: int, interval: int, path: Path | str) -> None:
    """Reject a JPEG whose entropy-coded (scan) data holds a marker that cannot be there: libjpeg stops decoding at
    it with a "Corrupt JPEG data: premature end of data segment" warning (which neither OpenCV nor Pillow lets a
    caller see) and fills the rest of the image with flat grey.

    Walks every scan from the first start-of-scan to the end-of-image marker: inside scan data a 0xFF byte is
    stuffed (FF 00), fill (FF FF) or a restart marker RSTn in sequence 0..7 when a restart interval is set; a scan
    ends at the end-of-image marker or at a segment that may stand between scans (tables, restart interval,
    comment, application data) before the next scan of a progressive (or non-interleaved) JPEG. Garbled data that holds no such byte
    (e.g. a run of zeros) decodes to shifted blocks instead and is not seen here: finding it needs the entropy
    decoder itself. ``pos``: the offset of the first start-of-scan marker; ``interval``: the restart interval
    the headers set (0: none)."""
    n = len(data)
    while True:  # pos: at a marker, FF xx
        marker = data[pos + 1]
        if marker == 0xD9:
            return
        if marker in _BETWEEN_SCANS or marker == 0xDA:
            if pos + 4 > n:
                raise ImageError(path, "corrupt JPEG data (ends inside a segment)")
            length = int.from_bytes(data[pos + 2 : pos + 4], "big")
            if marker == 0xDD and length >= 4:
                interval = int.from_bytes(data[pos + 4 : pos + 6], "big")
            pos += 2 + length
            if marker == 0xDA:
                pos = _end_of_scan(data, pos, interval, path)
            elif data[pos : pos + 1] != b"\xff":
                raise ImageError(path, f"corrupt JPEG data (no marker after the 0x{marker:02x} segment at byte {pos})")
            while data[pos + 1 : pos + 2] == b"\xff":  # fill bytes before a marker
                pos += 1
            if pos + 2 > n:
                raise ImageError(path, "corrupt JPEG data (ends inside its image data)")
            continue
        raise ImageError(path, f"corrupt JPEG data (stray marker 0x{marker:02x} at byte {pos} of its image data)")


def _end_of_scan(data: bytes, pos: int, interval: int, path: Path | str) -> int:
    """Offset of the marker that ends the scan whose entropy-coded data starts at ``pos`` (restart markers checked
    against the restart ``interval``: allowed only when it is set, in sequence RST0..RST7)."""
    expected = 0
    for match in _SCAN_MARKER.finditer(data, pos):
        marker = data[match.start() + 1]
        if not 0xD0 <= marker <= 0xD7:
            return match.start()
        if not interval or marker != 0xD0 + expected:
            why = "no restart interval is set" if not interval else f"RST{expected} expected"
            raise ImageError(
                path, f"corrupt JPEG data (restart marker RST{marker - 0xD0} at byte {match.start()}: {why})"
            )
        expected = (expected + 1) % 8
    raise ImageError(path, "corrupt JPEG data (no end-of-image marker after its image data)")


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
        reason = NOT_AN_IMAGE if isinstance(exc, UnidentifiedImageError) else f"corrupt image ({_without_buffer(exc)})"
        raise ImageError(path, reason) from None
    return _to_rgb8(_to_uint8(arr), bgr=False)


def _without_buffer(exc: Exception) -> str:
    """``str(exc)`` without the ``<_io.BytesIO object at 0x...>`` a Pillow message may name (the error names the
    file already)."""
    return _BUFFER_REPR.sub("the file", str(exc))


def unit_to_u8(values: NDArray[np.floating]) -> NDArray[np.uint8]:
    """Values in [0, 1] (any shape; outside it clipped) as uint8 0..255, rounded to the nearest (half to even):
    the one float -> 8-bit step of every synthesised image and alpha layer."""
    return np.round(np.clip(values, 0.0, 1.0) * 255.0).astype(np.uint8)


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
