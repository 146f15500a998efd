"""What a person looks at after a dedup: an HTML gallery of duplicate groups (keeper marked) and of the
top-ranked images, and a PNG histogram of nearest-neighbour distances with the threshold drawn in.

Thumbnails (at most 160 px) go to ``OUT/thumbs/<sha256[:16]>.jpg`` and are reused by later runs.
"""

from __future__ import annotations

import html
from collections.abc import Sequence
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path

import cv2
import numpy as np
from numpy.typing import NDArray

from ground.image.imageio import ImageError, read_image

THUMB = 160
_CSS = """body{font-family:sans-serif;margin:1em}figure{display:inline-block;margin:3px;text-align:center;
font-size:11px;width:168px;vertical-align:top}img{max-width:160px;max-height:160px;border:3px solid #ccc}
.keep img{border-color:#2a2}.group{border-bottom:1px solid #ddd;padding:4px 0}figcaption{word-break:break-all}"""


def write_histogram(nn_dist: NDArray[np.float32], threshold: float, path: Path, title: str = "") -> Path:
    """PNG histogram of each image's distance to its nearest other image (N,), threshold as a red line."""
    from matplotlib.figure import Figure

    fig = Figure(figsize=(7, 3.5), dpi=100)
    ax = fig.add_subplot()
    finite = nn_dist[np.isfinite(nn_dist)]
    ax.hist(finite, bins=np.linspace(0, max(1.5, float(finite.max(initial=0))), 76), color="#48c")
    ax.axvline(threshold, color="r", label=f"threshold {threshold:.3f}")
    ax.set_xlabel("distance to nearest other image (unit embeddings)")
    ax.set_ylabel("images")
    ax.set_title(title or f"{len(finite)} images")
    ax.legend()
    fig.tight_layout()
    fig.savefig(path)
    return path


def make_thumbs(items: Sequence[tuple[str, str]], folder: Path, workers: int = 3) -> dict[str, str]:
    """``(path, sha256)`` -> thumbnail file name relative to ``folder.parent`` (missing on decode errors)."""
    folder.mkdir(parents=True, exist_ok=True)

    def one(item: tuple[str, str]) -> tuple[str, str | None]:
        path, sha = item
        out = folder / f"{sha[:16]}.jpg"
        if not out.is_file():
            try:
                img = read_image(path, min_side=THUMB)  # a big JPEG decodes at 1/2..1/8
            except ImageError:
                return path, None
            scale = THUMB / max(img.shape[:2])
            if scale < 1:
                img = cv2.resize(img, None, fx=scale, fy=scale, interpolation=cv2.INTER_AREA)
            cv2.imwrite(str(out), img[:, :, ::-1], [cv2.IMWRITE_JPEG_QUALITY, 80])
        return path, f"{folder.name}/{out.name}"

    with ThreadPoolExecutor(workers) as pool:
        return {p: t for p, t in pool.map(one, list(dict.fromkeys(items))) if t is not None}


def _figure(path: str, thumb: str | None, caption: str, keep: bool) -> str:
    img = f'<img src="{html.escape(thumb)}" loading="lazy">' if thumb else "<div>(no preview)</div>"
    cls = ' class="keep"' if keep else ""
    return (
        f'<figure{cls}><a href="{html.escape(Path(path).as_uri())}">{img}</a>'
        f"<figcaption>{html.escape(caption)}</figcaption></figure>"
    )


GROUPS_NOTE = (
    "A group is the images linked by duplicate pairs. Near duplicates are not transitive (A like B and B like C "
    "while A is unlike C), so a group can keep several images: no two kept images are duplicates of each other, "
    "and every removed image is a duplicate of a kept one (named in dedup.json)."
)

#: A group as the page shows it: its heading (counts) and ``(path, caption, is_kept)`` per image shown.
ReportGroup = tuple[str, Sequence[tuple[str, str, bool]]]


def write_html(
    path: Path,
    title: str,
    summary: Sequence[str],
    groups: Sequence[ReportGroup],
    top: Sequence[tuple[str, str]],
    thumbs: dict[str, str],
    histogram: str | None,
    total_groups: int | None = None,
    unreadable: Sequence[tuple[str, str]] = (),
) -> Path:
    """The report page. ``groups``: the first groups (of ``total_groups``, default all shown), each with its
    heading and images, kept ones first; ``top``: ``(path, caption)`` best first; ``thumbs``: path ->
    thumbnail (relative to the page); ``unreadable``: ``(path, reason)`` of every file skipped, listed last."""
    parts = [f"<!doctype html><meta charset=utf-8><title>{html.escape(title)}</title><style>{_CSS}</style>"]
    parts.append(
        f"<h1>{html.escape(title)}</h1><ul>" + "".join(f"<li>{html.escape(s)}</li>" for s in summary) + "</ul>"
    )
    if histogram:
        parts.append(f'<img src="{html.escape(histogram)}" style="max-width:700px;max-height:none;border:0">')
    total = len(groups) if total_groups is None else total_groups
    parts.append(f"<h2>Duplicate groups (green = kept): {len(groups)} of {total}</h2><p>{html.escape(GROUPS_NOTE)}</p>")
    for heading, images in groups:
        figs = "".join(_figure(p, thumbs.get(p), c, k) for p, c, k in images)
        parts.append(f'<div class="group"><p>{html.escape(heading)}</p>{figs}</div>')
    parts.append(f"<h2>Most diverse kept images, top {len(top)}</h2><div>")
    parts.append("".join(_figure(p, thumbs.get(p), c, True) for p, c in top) + "</div>")
    if unreadable:
        items = "".join(f"<li>{html.escape(p)}: {html.escape(r)}</li>" for p, r in unreadable)
        parts.append(f"<h2>Unreadable files, skipped: {len(unreadable)}</h2><ul>{items}</ul>")
    path.write_text("\n".join(parts) + "\n", encoding="utf-8")
    return path
