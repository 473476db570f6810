"""Multi-process test of a range-Doppler network (issue 29): router + simulator + a
channel-plotter and an elementary-tracker per base (22 bases on 8 receivers, each base
with its own scan period and phase) + global-fusion, each a real process, on the first
60 s of scenarios/network_rd.toml; global fusion runs the network core
(common.radar.fusion_core). Its published radar/gtracks are scored against the truth as
the in-process chain's are (tests/wire/test_network_chain.py).

The simulator runs at 1.5 x real time: the network core orders reports by message time
in a 2 s window and rejects (too_late) a report older than what it processed, so a base
whose processes lag the others by more than the window in message time would lose
reports; as fast as possible, the 44 base processes on 2 cores lag by many seconds."""

from __future__ import annotations

from pathlib import Path

import numpy as np
from scipy.stats import chi2

from common.deploy.config import load
from tests.harness import ROOT, SCENARIOS, Deployment
from tests.network_check import score

WARMUP = 30.0  # s
SCANS = 60  # s of scenario
SPEED = 1.5  # times real time


def short_scene(tmp_path: Path) -> Path:
    """network_rd.toml cut to SCANS s."""
    text = (SCENARIOS / "network_rd.toml").read_text()
    assert "n_scans = 120" in text
    path = tmp_path / "network_rd.toml"
    path.write_text(text.replace("n_scans = 120", f"n_scans = {SCANS}"))
    return path


def test_network_through_processes(tmp_path: Path) -> None:
    scn = short_scene(tmp_path)
    cfg = load(scn)
    with Deployment(tmp_path) as d:
        d.collect("radar/gtracks")
        d.collect("sim/truth/radar")
        d.collect("metrics/global_fusion/main")
        alive = d.start_services(scn, ("channel-plotter", "elementary-tracker", "global-fusion"))
        assert len(alive) == 2 * len(cfg.bases) + 1 == 45
        d.wait_alive(alive)
        d.simulate(scn, seed=1, wait_alive=alive, speed=SPEED)
        truth = {m["t"]: m for m in d.of("sim/truth/radar")}
        t_last = max(truth)
        window = 2.0  # NetworkParams.window: the reports behind the newest stay buffered
        d.wait_for(lambda: any(m["t"] >= t_last - window - 1.0 for m in d.of("radar/gtracks")))
        fusion = next(c for c in d.children if c.name == "global-fusion")
        assert fusion.stop(timeout=30.0) == 0  # SIGTERM: the service flushes its core
        d.wait_for(lambda: any(m["t"] >= t_last - 1.0 for m in d.of("radar/gtracks")))
        metrics = [m for k, m in d.messages if k == f"{ROOT}/metrics/global_fusion/main"]
    gtracks = sorted(d.of("radar/gtracks"), key=lambda m: m["t"])
    s = score(gtracks, truth, WARMUP)
    assert s.reports >= 25, s.reports
    assert (s.missed, s.false, s.duplicates) == (0, 0, 0), s
    assert max(s.nees) <= chi2.ppf(0.9999, 3), max(s.nees)
    assert np.mean(s.nees) <= 6.0, np.mean(s.nees)
    assert metrics and metrics[-1]["rejected"].get("too_late", 0) <= 5, metrics[-1]["rejected"]
