"""Router + simulator + subscriber as real processes on loopback: nothing is lost, and
what a router restart loses is counted."""

from __future__ import annotations

import time
from collections import defaultdict
from pathlib import Path

import pytest

from common.bus.procs import start_router
from common.deploy.config import load
from tests.harness import ROOT, SCENARIOS, Deployment

SCANS = 1000


@pytest.mark.slow
def test_dense_1000_scans_every_message_arrives_in_order(tmp_path: Path) -> None:
    with Deployment(tmp_path) as d:
        d.collect("**")
        d.simulate(SCENARIOS / "dense.toml", seed=3, scans=SCANS)
        d.wait_for(lambda: bool(d.of("sim/status")), timeout=60)
        status = d.of("sim/status")[0]
        data = [(k, m) for k, m in d.messages if "/sim/status" not in k and "/alive/" not in k]
        seqs: dict[str, list[int]] = defaultdict(list)
        for key, msg in data:
            if "seq" in msg:
                seqs[key].append(msg["seq"])
    assert status["scans"] == SCANS
    gaps = {k: sorted(set(range(SCANS)) - set(s)) for k, s in seqs.items() if len(s) != SCANS}
    truth_t = [m["t"] for k, m in data if k.endswith("sim/truth/radar")]
    arrived = {round(m["t"], 6) for k, m in data if "/radar/plots/" in k}
    missing_truth = sorted(arrived - {round(t, 6) for t in truth_t})
    assert len(data) == status["published"], (
        f"lost: {gaps}, truth missing at t={missing_truth}, stamps say {dict(d.losses.missed)}")
    assert not d.losses.missed
    # CI once lost the last 12-17 truth samples: the simulator undeclared its publishers
    # before closing its session (see common.bus.transport.Publisher); the times above name them
    plot_keys = [k for k in seqs if "/radar/plots/" in k]
    cfg = load(SCENARIOS / "dense.toml")
    assert len(cfg.bases) == 4
    assert len(plot_keys) == sum(len(b.channels) for b in cfg.bases)
    for key, s in seqs.items():
        assert s == list(range(len(s))), f"{key}: out of order or gaps"
    assert all(len(seqs[k]) == SCANS for k in plot_keys)
    truth = [m for k, m in data if k.endswith("sim/truth/radar")]
    assert len(truth) == SCANS and len(truth[0]["id"]) >= 100


@pytest.mark.slow
def test_router_killed_and_restarted_lost_plots_are_counted(tmp_path: Path) -> None:
    """The router is killed mid-stream and started again on its port: the plotter and
    the collector reconnect by themselves, and from the publishers' stamps the
    plotter's metrics account for every plot of base b1 that it did not get while the
    router was away: in + missed == published, exactly, and missed > 0."""
    scn = SCENARIOS / "two_targets.toml"
    cfg = load(scn)
    published = len(cfg.base("b1").channels) * 120  # two_targets: 120 scans
    with Deployment(tmp_path) as d:
        port = int(d.endpoint.rsplit(":", 1)[1])
        d.collect("metrics/channel_plotter/b1")
        d.start("plotter", "channel-plotter", "--config", str(scn), "--base", "b1")
        d.wait_alive(["channel_plotter/b1"])
        sim = d.start("simulate", "simulate", "--config", str(scn), "--scenario", str(scn),
                      "--speed", "6", "--wait-alive", "channel_plotter/b1")
        d.wait_for(lambda: any(m["in"] >= 30 for m in d.of("metrics/channel_plotter/b1")))
        d.router.proc.kill()
        d.router.proc.wait()
        time.sleep(1.0)
        d.router, _ = start_router(log=tmp_path / "router-restarted.log", port=port)
        assert sim.wait(60) == 0

        def accounted() -> bool:
            m = d.of("metrics/channel_plotter/b1")
            return bool(m) and m[-1]["in"] + sum(m[-1]["missed"].values()) == published

        d.wait_for(accounted, timeout=30)
        last = d.of("metrics/channel_plotter/b1")[-1]
        print(f"plotter: {last['in']} plots in, missed {last['missed']}")
        assert sum(last["missed"].values()) > 0
        keys = {f"{ROOT}/radar/plots/b1/{c}" for c in cfg.base("b1").channels}
        assert set(last["missed"]) <= keys
        assert all(c.alive() for c in d.children if c.name == "plotter")
