"""Video in and out through OpenCV: frames read in batches as RGB (``cv2.VideoCapture``), frames written as an
MPEG-4 Part 2 ``.mp4`` (``cv2.VideoWriter``, FourCC ``mp4v``, which every OpenCV build can encode)."""

from __future__ import annotations

import os
from collections.abc import Iterator
from dataclasses import dataclass
from pathlib import Path

import cv2
import numpy as np
from numpy.typing import NDArray

#: File suffixes read as videos (lower case).
VIDEO_SUFFIXES: frozenset[str] = frozenset(
    {".mp4", ".m4v", ".mov", ".avi", ".mkv", ".webm", ".mpg", ".mpeg", ".wmv", ".flv", ".3gp"}
)
DEFAULT_FPS = 25.0  # frame rate written when the container does not state one


class VideoError(ValueError):
    """A video that cannot be read or written; ``str()`` is ``"<path>: <reason>"``."""

    def __init__(self, path: Path | str, reason: str) -> None:
        super().__init__(f"{path}: {reason}")


def is_video_file(path: Path | str) -> bool:
    """Whether the file name's suffix is a video suffix (:data:`VIDEO_SUFFIXES`, any case)."""
    return os.path.splitext(str(path))[1].lower() in VIDEO_SUFFIXES


@dataclass(frozen=True)
class VideoInfo:
    """``fps`` frames per second (:data:`DEFAULT_FPS` when unstated), ``frames`` the container's frame count
    (an estimate for some formats; 0 when unknown), frame ``width`` x ``height`` in pixels."""

    fps: float
    frames: int
    width: int
    height: int


def _open(path: Path) -> cv2.VideoCapture:
    if not path.is_file():
        raise VideoError(path, "file not found")
    cap = cv2.VideoCapture(str(path))
    if not cap.isOpened():
        cap.release()
        raise VideoError(path, "OpenCV cannot open it as a video")
    return cap


def video_info(path: Path) -> VideoInfo:
    """The :class:`VideoInfo` of ``path``; raises :class:`VideoError` when OpenCV cannot open it."""
    cap = _open(path)
    try:
        fps = float(cap.get(cv2.CAP_PROP_FPS) or 0.0)
        return VideoInfo(
            fps if fps > 0 else DEFAULT_FPS,
            max(int(cap.get(cv2.CAP_PROP_FRAME_COUNT) or 0), 0),
            int(cap.get(cv2.CAP_PROP_FRAME_WIDTH)),
            int(cap.get(cv2.CAP_PROP_FRAME_HEIGHT)),
        )
    finally:
        cap.release()


def read_batches(path: Path, batch: int) -> Iterator[list[NDArray[np.uint8]]]:
    """Consecutive frames of ``path`` as lists of up to ``batch`` (H, W, 3) uint8 RGB arrays, from frame 0 until
    the decoder stops; raises :class:`VideoError` when not even one frame can be decoded."""
    cap = _open(path)
    frames: list[NDArray[np.uint8]] = []
    count = 0
    try:
        while True:
            ok, bgr = cap.read()
            if not ok:
                break
            frames.append(cv2.cvtColor(bgr, cv2.COLOR_BGR2RGB))
            count += 1
            if len(frames) >= max(1, batch):
                yield frames
                frames = []
    finally:
        cap.release()
    if frames:
        yield frames
    if count == 0:
        raise VideoError(path, "no frame could be decoded")


class VideoWriter:
    """Write (height, width, 3) uint8 RGB frames to an ``mp4v`` ``.mp4`` at ``fps``; :meth:`close` finishes the file."""

    def __init__(self, path: Path, fps: float, width: int, height: int) -> None:
        self.path, self.size = path, (width, height)
        self._writer = cv2.VideoWriter(str(path), cv2.VideoWriter_fourcc(*"mp4v"), fps, (width, height))
        if not self._writer.isOpened():
            raise VideoError(path, f"OpenCV cannot write an mp4v video of {width}x{height} at {fps:g} fps here")

    def write(self, frame: NDArray[np.uint8]) -> None:
        """Append one RGB frame of the writer's size."""
        if (frame.shape[1], frame.shape[0]) != self.size:
            raise ValueError(f"frame of {frame.shape[1]}x{frame.shape[0]} in a {self.size[0]}x{self.size[1]} video")
        self._writer.write(cv2.cvtColor(frame, cv2.COLOR_RGB2BGR))

    def close(self) -> None:
        self._writer.release()
