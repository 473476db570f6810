"""docs/README.md indexes every file of docs/, and no link of docs/ is broken.

- every .md file under docs/ (recursively, decision records included) and every image
  is linked from docs/README.md;
- every relative link of every .md file under docs/ (and of the top README.md) points
  to a file that exists, and its #anchor, if any, to a heading of that file."""

from __future__ import annotations

import re
from pathlib import Path

import pytest

from tests.docs.blocks import DOCS, REPO

INDEX = DOCS / "README.md"
LINK = re.compile(r"\[[^\]]*\]\(([^)\s]+)\)")
PAGES = sorted(DOCS.rglob("*.md")) + [REPO / "README.md"]


def links(page: Path) -> list[str]:
    """Relative link targets of a page, outside code blocks and code spans."""
    text = re.sub(r"^```.*?^```", "", page.read_text(), flags=re.M | re.S)
    text = re.sub(r"`[^`\n]*`", "", text)
    return [t for t in LINK.findall(text) if not re.match(r"^[a-z]+:", t)]


def anchors(page: Path) -> set[str]:
    """GitHub's anchors of the headings of a page."""
    out = set()
    for h in re.findall(r"^#+ (.+)$", page.read_text(), re.M):
        slug = re.sub(r"[^\w\- ]", "", h.strip().lower()).replace(" ", "-")
        out.add(slug)
    return out


def test_every_file_of_docs_is_in_the_index() -> None:
    linked = {(INDEX.parent / t.split("#")[0]).resolve() for t in links(INDEX)}
    files = [p for p in DOCS.rglob("*") if p.is_file() and p != INDEX and not p.name.startswith(".")]
    assert len(files) > 20
    missing = sorted(str(p.relative_to(DOCS)) for p in files if p.resolve() not in linked)
    assert not missing, f"docs/README.md does not link: {missing}"


@pytest.mark.parametrize("page", PAGES, ids=lambda p: str(p.relative_to(REPO)))
def test_no_broken_link(page: Path) -> None:
    broken = []
    for target in links(page):
        path, _, anchor = target.partition("#")
        dest = (page.parent / path).resolve() if path else page
        if not dest.exists():
            broken.append(target)
        elif anchor and dest.suffix == ".md" and anchor not in anchors(dest):
            broken.append(target)
    assert not broken, f"{page.relative_to(REPO)}: broken links {broken}"


def test_the_link_check_catches_a_broken_link(tmp_path: Path) -> None:
    page = tmp_path / "p.md"
    page.write_text("# Title\n[ok](p.md) [gone](nothing.md) [here](#title) `[code](x.md)`\n")
    assert links(page) == ["p.md", "nothing.md", "#title"]
    assert "title" in anchors(page)
