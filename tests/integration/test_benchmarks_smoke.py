"""Smoke check of the soak benchmark (``benchmarks/soak.py``) on a few hundred scans, so
that the script cannot rot: real router and services, its tables, exit code 0 (no process
grew by 10 % after the warm-up, nothing lost). The full 100,000-scan soak and the load
benchmark (``benchmarks/load.py``) are run by hand."""

from __future__ import annotations

import re
import subprocess
import sys
from pathlib import Path

SOAK = Path(__file__).resolve().parents[2] / "benchmarks" / "soak.py"
PROCESSES = ("channel-plotter-b1", "channel-plotter-b2", "elementary-tracker-b1",
             "elementary-tracker-b2", "global-fusion", "router")


def test_soak_short_run_passes_and_prints_its_tables() -> None:
    r = subprocess.run([sys.executable, str(SOAK), "--scans", "200"],
                       capture_output=True, text=True, timeout=240)
    assert r.returncode == 0, r.stdout + r.stderr[-3000:]
    out = r.stdout
    assert re.search(r"^soak: 200 scans of soak\.toml .* scans/s", out, re.M), out
    for name in PROCESSES:
        row = re.search(rf"^{name}\s+\d+\s+([\d.]+)\s+([\d.]+)\s+[\d.]+\s+(-?[\d.]+)$", out, re.M)
        assert row is not None, f"no RSS row for {name}:\n{out}"
        assert float(row.group(1)) > 10.0 and abs(float(row.group(3))) < 10.0
    for svc in ("channel_plotter/b1", "elementary_tracker/b2", "global_fusion/main"):
        assert re.search(rf"^{svc}\s+\d+", out, re.M), f"no counters of {svc}:\n{out}"
    assert "lost scans 0, missed samples 0, rejected inputs 0" in out
