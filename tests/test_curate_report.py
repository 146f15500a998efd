"""Report pieces: histogram PNG, thumbnails (reduced JPEG decode), escaped HTML."""

from __future__ import annotations

from pathlib import Path

import numpy as np
from curate_helpers import save, scene

from curate.report import make_thumbs, write_histogram, write_html


def test_histogram_png(tmp_path: Path) -> None:
    dist = np.random.default_rng(0).uniform(0, 1, 500).astype(np.float32)
    dist[0] = np.inf
    path = write_histogram(dist, 0.45, tmp_path / "h.png")
    assert path.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"


def test_thumbnails_small_and_cached(tmp_path: Path) -> None:
    big = save(np.ascontiguousarray(np.tile(scene(1), (8, 8, 1))), tmp_path / "big.jpg")  # 1280 x 960
    (tmp_path / "bad.jpg").write_bytes(b"not an image")
    thumbs = make_thumbs([(str(big), "ab" * 32), (str(tmp_path / "bad.jpg"), "cd" * 32)], tmp_path / "thumbs")
    assert list(thumbs) == [str(big)] and (tmp_path / thumbs[str(big)]).is_file()
    mtime = (tmp_path / thumbs[str(big)]).stat().st_mtime_ns
    make_thumbs([(str(big), "ab" * 32)], tmp_path / "thumbs")
    assert (tmp_path / thumbs[str(big)]).stat().st_mtime_ns == mtime


def test_html_escapes_names(tmp_path: Path) -> None:
    page = write_html(
        tmp_path / "r.html",
        "t",
        ["<b>summary</b>"],
        [
            (
                "2 images: 1 kept, 1 removed",
                [("/x/<a>.jpg", "KEPT <a>.jpg", True), ("/x/b.jpg", "near 0.1 b.jpg", False)],
            )
        ],
        [("/x/<a>.jpg", "0.5 <a>.jpg")],
        {},
        None,
    ).read_text()
    assert "<b>summary</b>" not in page and "&lt;a&gt;.jpg" in page and 'class="keep"' in page
