"""benchmarks/network_goals.py on a tiny scene (5 aircraft, 20 s, two base counts), so
the goals benchmark cannot rot: it runs, prints every column and the slopes, and
reports the goals' verdict by its exit code."""

from __future__ import annotations

import numpy as np
import pytest

from benchmarks import network_goals
from benchmarks.network_scene import scene_doc
from common.deploy.config import parse
from common.sim.scenario import load_scenario


def test_goals_benchmark_runs(capsys: pytest.CaptureFixture[str]) -> None:
    code = network_goals.main(["--scenes", "5", "--seeds", "1", "--duration", "20", "--warm-up", "10",
                               "--scale-bases", "4", "8", "--scale-aircraft", "3",
                               "--scale-duration", "5", "--per-aircraft", "2"])
    out = capsys.readouterr().out
    assert code in (0, 1)
    assert "rmse/pcrlb" in out and "slope" in out
    row = next(line.split() for line in out.splitlines() if line.split()[:2] == ["5", "1"])
    assert len(row) == 11 and row[2] == "21"
    lines = out.splitlines()
    head = next(k for k, line in enumerate(lines) if line.split()[:2] == ["share", "id"])
    assert len(lines[head + 1].split()) == 11 and len(lines[head + 2].split()) == 11
    assert out.strip().endswith("met" if code == 0 else "FAILED")


def test_scans_between_reports() -> None:
    """A base's scans in each (t_k-1, t_k] of the report times, all before t_0 in the first."""
    base = np.array([0.1, 0.6, 1.1, 1.6, 2.1, 2.6])
    assert network_goals.scans(base, np.array([1.0, 2.0, 3.0])).tolist() == [2.0, 2.0, 2.0]
    assert network_goals.scans(base, np.array([0.6, 1.0, 2.5])).tolist() == [2.0, 0.0, 3.0]


def test_bound_counts_every_scan(monkeypatch: pytest.MonkeyPatch) -> None:
    """The goal scenes' bases scan every 0.5-1 s and the bound steps once per 1 s report:
    with one scan per report (the bound before decision 024) the bound is looser, so
    RMSE / PCRLB lower, by about sqrt(1.33)."""
    doc = scene_doc(5, seed=1, duration=15.0)
    cfg, radar = parse(doc), load_scenario(doc).radar
    assert radar is not None
    run = network_goals.run_chain(cfg, doc, 1, 5.0)
    counted = network_goals.bound_ratio(run, cfg, radar)
    monkeypatch.setattr(network_goals, "scans", lambda base, times: np.ones(times.size))
    one = network_goals.bound_ratio(run, cfg, radar)
    assert 1.08 < counted / one < 1.3
