"""benchmarks/network_goals.py on a tiny scene (5 aircraft, 20 s, two base counts), so
the goals benchmark cannot rot: it runs, prints every column and the slopes, and
reports the goals' verdict by its exit code."""

from __future__ import annotations

import pytest

from benchmarks import network_goals


def test_goals_benchmark_runs(capsys: pytest.CaptureFixture[str]) -> None:
    code = network_goals.main(["--scenes", "5", "--seeds", "1", "--duration", "20", "--warm-up", "10",
                               "--scale-bases", "4", "8", "--scale-aircraft", "3",
                               "--scale-duration", "5"])
    out = capsys.readouterr().out
    assert code in (0, 1)
    assert "rmse/pcrlb" in out and "slope" in out
    row = next(line.split() for line in out.splitlines() if line.split()[:2] == ["5", "1"])
    assert len(row) == 11 and row[2] == "21"
    assert out.strip().endswith("met" if code == 0 else "FAILED")
