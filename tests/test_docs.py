"""The user's guide and the reference pages: every relative link reaches a file, every anchor a heading, and the
README stays a guide (at most 300 lines)."""

from __future__ import annotations

import re
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
PAGES = [ROOT / "README.md", *sorted((ROOT / "docs").glob("*.md"))]


def anchors(text: str) -> set[str]:
    """GitHub's anchors of a Markdown page: each heading lower-cased, punctuation dropped, spaces as hyphens; and
    every explicit ``<a id="...">``."""
    out = set(re.findall(r'<a id="([^"]+)"', text))
    for heading in re.findall(r"^#+\s+(.*)$", text, re.M):
        plain = re.sub(r"<[^>]+>", "", heading).strip().lower()
        out.add(re.sub(r"[^\w\- ]", "", plain).replace(" ", "-"))
    return out


@pytest.mark.parametrize("page", PAGES, ids=lambda p: p.name)
def test_every_relative_link_reaches_its_file_and_heading(page: Path) -> None:
    text = page.read_text(encoding="utf-8")
    for target in re.findall(r"\]\(([^)\s]+)\)", text):
        if target.startswith(("http://", "https://", "mailto:")):
            continue
        path, _, fragment = target.partition("#")
        dest = (page.parent / path).resolve() if path else page
        assert dest.exists(), f"{page.name}: link to a missing file {target}"
        if fragment and dest.suffix == ".md":
            assert fragment in anchors(dest.read_text(encoding="utf-8")), f"{page.name}: no heading for {target}"


def test_the_readme_is_a_guide_not_a_log() -> None:
    text = (ROOT / "README.md").read_text(encoding="utf-8")
    assert len(text.splitlines()) <= 300
    assert not re.search(r"\bissue \d+|machine [A-Z0-9]\b|(second|third|fourth) machine", text)
