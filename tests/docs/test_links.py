"""Every relative link in the project's Markdown (README, docs/, studies/, measurements/) reaches a file or folder
of the checkout, so that a moved file shows up here rather than as a dead link. The study pages' report.html files
are written by the study scripts and kept out of git (.gitignore), so links to them are left out."""

from __future__ import annotations

import re
from pathlib import Path

REPO = Path(__file__).resolve().parents[2]
PAGES = sorted([REPO / "README.md", *(REPO / "docs").glob("*.md"), *(REPO / "studies").rglob("*.md"),
                *(REPO / "measurements").rglob("*.md")])
#: Files the study scripts write and git ignores (studies/**/report.html).
GENERATED = {"report.html"}
LINK = re.compile(r"\]\((?P<target>[^)#\s]+)(?:#[^)\s]*)?\)")


def relative_links(page: Path) -> list[str]:
    return [m["target"] for m in LINK.finditer(page.read_text())
            if not m["target"].startswith(("http://", "https://", "mailto:"))]


def test_the_pages_have_links():
    assert len(PAGES) >= 15 and sum(len(relative_links(page)) for page in PAGES) >= 30


def test_every_relative_link_reaches_a_file():
    dead = [(str(page.relative_to(REPO)), target) for page in PAGES for target in relative_links(page)
            if Path(target).name not in GENERATED and not (page.parent / target).exists()]
    assert not dead, dead
