"""Measured history lives in docs/decisions/NNN-*.md, not in the code's docstrings.

1. Every command a decision record names (a line of a ```sh block starting with
   `.venv/bin/python benchmarks/...` or `.venv/bin/pfusion ...`) exists and runs with
   `--help` (exit 0).
2. No module docstring in common/ carries measured history. The patterns (FORBIDDEN):
   a date YYYY-MM-DD; "session N"; and a measured figure, which is any of
   - "measured" or "Measured" introducing a measurement: followed by on, over, in, here,
     with, through, at, "(", "," or ":" (not "the measured bearing" or "measured
     components", which are terms of the equations);
   - a before/after pair of numbers: "3.67 -> 5.40";
   - a seed range: "seeds 1-40";
   - a run count: "7 to 11 swap runs of 20", "5 of the 7", "14 runs of 20";
   - a NEES figure: "mean NEES 4.0", "NEES 3.2".
   The rule and the equations' citations (001 [48], Bar-Shalom et al. 2001) stay in the
   docstring, with a pointer to the record that holds the figures.
"""

from __future__ import annotations

import ast
import re
import shlex
import subprocess
import sys

import pytest

from tests.docs.blocks import DOCS, REPO, blocks

DECISIONS = sorted((DOCS / "decisions").glob("*.md"))
FORBIDDEN = {
    "date": re.compile(r"\b\d{4}-\d{2}-\d{2}\b"),
    "session": re.compile(r"\bsession \d+", re.I),
    "measured": re.compile(r"\b[Mm]easured\b\s*(?:on|over|in|here|with|through|at|\(|,|:)"),
    "before -> after": re.compile(r"\d(?:\.\d+)?\s*->\s*\d"),
    "seed range": re.compile(r"\bseeds \d+\s*-\s*\d+"),
    "run count": re.compile(r"\b\d+ (?:to \d+ )?(?:\w+ )?runs? of \d+|\b\d+ of the \d+\b"),
    "NEES figure": re.compile(r"\bNEES \d"),
}


def commands() -> list[tuple[str, list[str]]]:
    out = []
    for page in DECISIONS:
        for block in blocks(page, "sh"):
            for line in block.splitlines():
                if line.startswith((".venv/bin/python benchmarks/", ".venv/bin/pfusion ")):
                    out.append((page.name, shlex.split(line)))
    return out


def module_docstrings() -> list[tuple[str, str]]:
    return [(str(p.relative_to(REPO)), ast.get_docstring(ast.parse(p.read_text()), clean=False) or "")
            for p in sorted((REPO / "common").rglob("*.py"))]


def test_records_are_numbered_and_have_their_parts() -> None:
    assert DECISIONS, "docs/decisions/ has no record"
    for page in DECISIONS:
        assert re.match(r"^\d{3}-[a-z0-9-]+\.md$", page.name), page.name
        text = page.read_text()
        for part in ("## Context", "## Decision", "## Measured", "## Regenerate"):
            assert part in text, f"{page.name} has no '{part}' section"
        assert any(name == page.name for name, _ in commands()), f"{page.name} names no command"


@pytest.mark.parametrize("page,argv", commands(), ids=lambda v: v if isinstance(v, str) else " ".join(v[:2]))
def test_named_command_exists_and_answers_help(page: str, argv: list[str]) -> None:
    if argv[0] == ".venv/bin/pfusion":
        run = [sys.executable, "-m", "common", argv[1], "--help"]
    else:
        script = REPO / argv[1]
        assert script.is_file(), f"{page}: {argv[1]} does not exist"
        run = [sys.executable, str(script), "--help"]
    r = subprocess.run(run, cwd=REPO, capture_output=True, text=True, timeout=120)
    assert r.returncode == 0, f"{page}: {' '.join(run)}\n{r.stderr}"


def test_no_module_docstring_carries_measured_history() -> None:
    found = [f"{path}: {name} {m.group(0)!r}" for path, doc in module_docstrings()
             for name, pat in FORBIDDEN.items() for m in pat.finditer(doc)]
    assert not found, "measured history in module docstrings (move it to docs/decisions/):\n" + "\n".join(found)


@pytest.mark.parametrize("text", ["until 2026-11-26", "since session 16", "Measured on dense1000.toml",
                                  "mean NEES 3.67 -> 5.40", "seeds 1-40", "7 to 11 swap runs of 20",
                                  "5 of the 7", "(29 measured on crossing.toml)", "mean NEES 4.0"])
def test_the_patterns_catch_history(text: str) -> None:
    assert any(p.search(text) for p in FORBIDDEN.values())


@pytest.mark.parametrize("text", ["the measured bearing and amplitude", "measured components",
                                  "001 [48]", "modules 31-34", "(N, 3) -> (N, 6)", "seed 004's memory mode"])
def test_the_patterns_spare_the_equations(text: str) -> None:
    assert not any(p.search(text) for p in FORBIDDEN.values())
