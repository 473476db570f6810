"""docs/api.md as written: each ```python block runs alone in a fresh interpreter (from
the repository root, as a reader runs it) and exits 0; its own asserts check the tracks.
The ```python zenoh block opens loopback sockets: tests/integration/test_docs_api_zenoh.py."""

from __future__ import annotations

import os
import subprocess
import sys

import pytest

from tests.docs.blocks import DOCS, REPO, blocks

API = DOCS / "api.md"
PYTHON = blocks(API, "python")


def run_block(code: str) -> subprocess.CompletedProcess[str]:
    env = {**os.environ, "PYTHONPATH": str(REPO)}
    return subprocess.run([sys.executable, "-c", code], cwd=REPO, env=env, capture_output=True,
                          text=True, timeout=120)


def test_the_page_has_its_examples() -> None:
    assert len(PYTHON) == 3 and len(blocks(API, "python zenoh")) == 1


@pytest.mark.parametrize("i", range(len(PYTHON)))
def test_python_block_runs(i: int) -> None:
    r = run_block(PYTHON[i])
    assert r.returncode == 0, f"docs/api.md python block {i + 1}:\n{r.stdout}\n{r.stderr}"
    assert r.stdout.strip(), "each example prints what it found"
