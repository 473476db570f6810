"""Fenced code blocks of the docs, to run them as written: ``blocks(page, info)`` gives
the bodies of the blocks whose info string is exactly ``info`` (e.g. "python",
"python zenoh", "sh")."""

from __future__ import annotations

import re
from pathlib import Path

REPO = Path(__file__).resolve().parents[2]
DOCS = REPO / "docs"


def blocks(page: Path, info: str) -> list[str]:
    """Bodies of the ```<info> blocks of ``page``, in order."""
    return [m.group(2) for m in re.finditer(r"^```([^\n`]*)\n(.*?)^```\s*$", page.read_text(), re.M | re.S)
            if m.group(1).strip() == info]
