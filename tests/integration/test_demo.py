"""``pfusion demo`` end to end: exit code, summary table, and both pictures."""

from __future__ import annotations

import struct
import subprocess
import sys
from pathlib import Path

import pytest

from services.demo.pictures import DPI, SIZE_IN


def png_size(path: Path) -> tuple[int, int]:
    """(width, height) from a PNG's IHDR chunk; fails on anything that is not a PNG."""
    head = path.read_bytes()[:24]
    assert head[:8] == b"\x89PNG\r\n\x1a\n" and head[12:16] == b"IHDR", f"{path} is not a PNG"
    return struct.unpack(">II", head[16:24])


@pytest.mark.slow
def test_demo_runs_everything_and_draws(tmp_path: Path) -> None:
    r = subprocess.run([sys.executable, "-m", "common", "demo", "--out", str(tmp_path)],
                       capture_output=True, text=True, timeout=240)
    assert r.returncode == 0, r.stdout + r.stderr[-3000:]
    out = r.stdout
    assert ", lost 0," in out and "out of order 0" in out
    assert "radar (confirmed global tracks vs truth" in out and "mean GOSPA" in out
    assert "PCRLB m" in out and "NEES3 / NEES6" in out
    assert "confirmed bearing tracks" in out
    expected = (int(SIZE_IN[0] * DPI), int(SIZE_IN[1] * DPI))
    for name in ("radar.png", "sonar.png"):
        assert png_size(tmp_path / name) == expected
