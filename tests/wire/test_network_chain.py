"""A range-Doppler network end to end in one process (issue 29): scenarios/network_rd.toml
(8 receivers, 22 range-Doppler bases with their own scan periods and phases, geodetic
sites, 20 aircraft at constant height) through common.wire.radar_chain, whose global
fusion is then the network core; confirmed global tracks against the simulator's truth."""

from __future__ import annotations

from pathlib import Path

import numpy as np
from scipy.stats import chi2

from common.deploy.config import load
from common.radar.fusion_core import Network
from common.sim.scenario import load_scenario
from common.wire import protocol
from common.wire.radar_chain import RadarChain
from common.wire.sim_messages import run_scenario
from tests.network_check import score

SCENARIO = Path(__file__).resolve().parents[2] / "scenarios" / "network_rd.toml"
WARMUP = 30.0  # s


def test_network_chain_holds_every_aircraft() -> None:
    cfg = load(SCENARIO)
    chain = RadarChain(cfg)
    assert isinstance(chain.fusion, Network)
    truth, out = {}, []
    for t, msgs in run_scenario(load_scenario(cfg.doc), cfg.bases, cfg.arrays, seed=1):
        truth[t] = next(m for k, m in msgs if k == "sim/truth/radar")
        out += chain.step(msgs)
    last = out[-1]["t"]
    out += chain.flush()  # the reports still in the reordering window
    assert out[-1]["t"] > last >= max(truth) - 3.0
    gtracks = [protocol.decode("gtracks", protocol.encode(g)) for g in out]
    s = score(gtracks, truth, WARMUP)
    assert s.reports >= 85, s.reports  # one per report_period (1 s) after the warm-up
    assert (s.missed, s.false, s.duplicates) == (0, 0, 0), s
    assert len(s.nees) == 20 * s.reports
    assert max(s.nees) <= chi2.ppf(0.9999, 3), max(s.nees)
    assert np.mean(s.nees) <= 6.0, np.mean(s.nees)
    track = next(k for k in gtracks[-1]["tracks"] if k["status"] == "confirmed")
    assert {"lat", "lon", "alt"} <= set(track) and len(track["etracks"]) >= 3
    assert track["score"] == 0.0 and track["ambiguous"] is False  # not filled by this core
