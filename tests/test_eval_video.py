"""Video in and out through OpenCV: batches of RGB frames in order, mp4v out at the source's rate and size."""

from __future__ import annotations

import cv2
import numpy as np
import pytest

from eval import video as V


def _frames(n: int) -> list[np.ndarray]:
    """n 64x48 RGB frames: red on the left half, a grey level on the right that grows with the index."""
    out = []
    for k in range(n):
        f = np.zeros((48, 64, 3), np.uint8)
        f[:, :32, 0] = 230
        f[:, 32:] = 30 + 40 * k
        out.append(f)
    return out


@pytest.fixture()
def clip(tmp_path):
    path = tmp_path / "clip.mp4"
    writer = V.VideoWriter(path, 12.0, 64, 48)
    for f in _frames(5):
        writer.write(f)
    writer.close()
    return path


def test_frames_come_back_in_order_as_rgb_in_batches(clip):
    info = V.video_info(clip)
    assert (info.fps, info.frames, info.width, info.height) == (12.0, 5, 64, 48)
    batches = list(V.read_batches(clip, 2))
    assert [len(b) for b in batches] == [2, 2, 1]
    frames = [f for b in batches for f in b]
    for got, want in zip(frames, _frames(5)):
        assert got.shape == (48, 64, 3) and got.dtype == np.uint8
        assert got[24, 8, 0] > 180 and got[24, 8, 2] < 60  # red stays red: RGB, not BGR
        assert abs(int(got[24, 48].mean()) - int(want[24, 48].mean())) <= 6  # mp4v is lossy, but barely here


def test_writer_refuses_a_frame_of_another_size(tmp_path):
    writer = V.VideoWriter(tmp_path / "x.mp4", 25.0, 64, 48)
    with pytest.raises(ValueError, match="frame of 32x32 in a 64x48 video"):
        writer.write(np.zeros((32, 32, 3), np.uint8))
    writer.close()


def test_unreadable_and_missing_videos_raise_video_error(tmp_path):
    bad = tmp_path / "bad.mp4"
    bad.write_bytes(b"not a video at all")
    for path in (bad, tmp_path / "missing.avi"):
        with pytest.raises(V.VideoError, match=path.name):
            list(V.read_batches(path, 4))
        with pytest.raises(V.VideoError, match=path.name):
            V.video_info(path)


def test_a_container_without_frame_rate_gets_the_default(tmp_path, monkeypatch):
    path = tmp_path / "c.avi"
    writer = cv2.VideoWriter(str(path), cv2.VideoWriter_fourcc(*"MJPG"), 7, (32, 32))
    writer.write(np.zeros((32, 32, 3), np.uint8))
    writer.release()
    assert V.video_info(path).fps == 7.0
    real_get = cv2.VideoCapture.get
    monkeypatch.setattr(
        cv2.VideoCapture, "get", lambda self, prop: 0.0 if prop == cv2.CAP_PROP_FPS else real_get(self, prop)
    )
    assert V.video_info(path).fps == V.DEFAULT_FPS


@pytest.mark.parametrize(
    ("name", "video"), [("a.MP4", True), ("b.avi", True), ("c.mkv", True), ("d.png", False), ("e", False)]
)
def test_video_suffixes(name, video):
    assert V.is_video_file(name) is video
