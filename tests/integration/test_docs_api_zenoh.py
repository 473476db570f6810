"""docs/api.md's ```python zenoh block as written: its own router on a free 127.0.0.1
port (multicast scouting off), a subscriber and a publisher, in one process."""

from __future__ import annotations

from tests.docs.blocks import DOCS
from tests.docs.test_api import blocks, run_block


def test_zenoh_block_runs_on_loopback() -> None:
    (code,) = blocks(DOCS / "api.md", "python zenoh")
    assert "127.0.0.1" in code and "zenoh_config" in code
    r = run_block(code)
    assert r.returncode == 0, f"{r.stdout}\n{r.stderr}"
    assert r.stdout.count("track 1 confirmed") == 3
