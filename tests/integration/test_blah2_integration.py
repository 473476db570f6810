"""blah2 nodes in (issue 30): fake blah2 nodes (tests/blah2_node.py, an aiohttp server on
loopback) serve the simulator's plots of scenarios/network_rd_blah2.toml (9 range-Doppler
bases on 7 receivers), one `pfusion ingest blah2` per node polls them, and the chain
(channel plotters, elementary trackers, global fusion: the network core) tracks the
aircraft from them. Bad feeds are served on four nodes; each is counted in its ingest's
metrics, and no process stops. Also: a node whose config disagrees with the deployment
is refused (exit 2, both values named), and `--file` / `ingest csv` replay."""

from __future__ import annotations

import json
import time
from pathlib import Path

import numpy as np

from tests.blah2_node import EPOCH_MS, Blah2Nodes, Fault
from tests.harness import ROOT, SCENARIOS, Deployment

SCENE = SCENARIOS / "network_rd_blah2.toml"
SPEED = 1.5
END = 40.0  # s of scenario
WARMUP = 25.0
HELD = 3000.0  # m
FAULTS = {
    "r1dvbt2": [Fault(5.0, "json"), Fault(8.0, "lengths"), Fault(11.0, "nan"), Fault(14.0, "negative")],
    "r2dvbt2": [Fault(6.0, "back"), Fault(12.0, "ahead")],
    "r3dvbt8": [Fault(10.0, "down", 3.0)],
    "r4dvbt8": [Fault(9.0, "slow")],
}
EXPECTED = {"r1dvbt2": {"json", "lengths", "nan", "negative_delay"}, "r2dvbt2": {"time_backwards", "ahead"},
            "r3dvbt8": {"unreachable"}, "r4dvbt8": {"timeout"}}


def ingest(d: Deployment, nodes: Blah2Nodes, base: str) -> None:
    d.start(f"ingest-{base}", "ingest", "blah2", "--config", str(SCENE), "--base", base,
            "--url", nodes.url(base), "--interval", "0.1")


def test_blah2_nodes_through_the_chain(tmp_path: Path) -> None:
    with Blah2Nodes(SCENE, speed=SPEED) as nodes, Deployment(tmp_path) as d:
        for base, faults in FAULTS.items():
            nodes.nodes[base].faults = list(faults)
        d.collect("radar/gtracks")
        d.collect("radar/plots/**")
        d.collect("metrics/ingest/*")
        alive = d.start_services(SCENE, ("channel-plotter", "elementary-tracker", "global-fusion"))
        for base in nodes.nodes:
            ingest(d, nodes, base)
        d.wait_alive(alive + [f"ingest/{b}" for b in nodes.nodes])
        nodes.start()
        d.wait_for(lambda: nodes.now() > END + 2.0, timeout=END / SPEED + 30)
        time.sleep(2.5)  # the last metrics (every 2 s)
        fusion = next(c for c in d.children if c.name == "global-fusion")
        assert fusion.stop(timeout=30.0) == 0
        d.drain()
        assert all(c.alive() for c in d.children if c.name != "global-fusion"), "a process stopped"
        metrics = {k.rsplit("/", 1)[-1]: m for k, m in d.messages if k.startswith(f"{ROOT}/metrics/ingest/")}
    for base, reasons in EXPECTED.items():
        assert reasons <= set(metrics[base]["rejected"]), (base, metrics[base]["rejected"])
    for base in nodes.nodes:
        if base not in EXPECTED:
            assert not metrics[base]["rejected"], (base, metrics[base]["rejected"])
        ts = [m["t"] for m in d.of(f"radar/plots/{base}/{nodes.cfg.base(base).channels[0]}")]
        assert ts == sorted(set(ts)), f"{base}: a frame published twice or out of order"
        sent = [EPOCH_MS / 1000 + t for t, f in nodes.nodes[base].frames if t <= END and f["delay"]]
        got = np.asarray(ts)
        missing = [t for t in sent if not np.any(np.abs(got - t) < 1e-3)]
        assert len(missing) <= (0 if base in ("r3dvbt8", "r4dvbt8") else 3), (base, missing)
    score(d.of("radar/gtracks"), nodes)


def score(gtracks: list[dict], nodes: Blah2Nodes) -> None:
    """After the warm-up every aircraft held by a confirmed track within HELD, no false
    confirmed track."""
    truth = {round(s.t, 6): s for s in nodes.truth}
    times = np.array(sorted(truth))
    reports = 0
    for g in gtracks:
        t = g["t"] - EPOCH_MS / 1000
        if t < WARMUP:
            continue
        s = truth[times[np.abs(times - t).argmin()]]
        x = np.array([k["x"] for k in g["tracks"] if k["status"] == "confirmed"]).reshape(-1, 6)[:, [0, 2, 4]]
        d = np.linalg.norm(s.pos[:, None] - x[None], axis=2).reshape(len(s.pos), len(x))
        assert (d <= HELD).any(axis=1).all(), f"t={t}: aircraft not held"
        assert (d <= HELD).any(axis=0).all(), f"t={t}: a false track"
        reports += 1
    assert reports >= 8, reports


def test_mismatch_file_and_csv(tmp_path: Path) -> None:
    with Blah2Nodes(SCENE) as nodes, Deployment(tmp_path) as d:
        node = nodes.nodes["r1dvbt2"]
        node.config["capture"]["fc"] = 601e6
        node.config["location"]["rx"]["latitude"] += 0.001  # 111 m north
        bad = d.start("ingest-bad", "ingest", "blah2", "--config", str(SCENE), "--base", "r1dvbt2",
                      "--url", nodes.url("r1dvbt2"))
        assert bad.wait(60) == 2
        log = (tmp_path / "ingest-bad.log").read_text()
        assert "fc: node 6.01e+08 Hz, deployment 6e+08 Hz" in log, log
        assert "rx: node [47.356500, 6.912100, 805.0], deployment [47.355500, 6.912100, 805.0]" in log, log
        d.collect("radar/plots/**")
        saved = tmp_path / "r2.json"
        frames = [f for _, f in nodes.nodes["r2dvbt2"].frames[:20]]
        saved.write_text(json.dumps(frames[:10] + [{"timestamp": 1, "delay": [1.0]}] + frames[10:]))
        rows = ["t,base,channel,rb_m,vb_mps,snr_db,srb_m,svb_mps",
                "1.0,r1dvbt2,dvbt3,50000,10,20,40,0.3", "1.0,r1dvbt2,dvbt3,60000,-10,20,40,0.3",
                "2.0,r1dvbt2,dvbt3,nan,-10,20,40,0.3", "0.5,r1dvbt2,dvbt3,50000,10,,40,0.3",
                "3.0,r1dvbt2,dvbt3,50000,10,,40,0.3"]
        (tmp_path / "p.csv").write_text("\n".join(rows) + "\n")
        d.announce()
        replay = d.start("ingest-file", "ingest", "blah2", "--config", str(SCENE), "--base", "r2dvbt2",
                         "--file", str(saved))
        csv = d.start("ingest-csv", "ingest", "csv", str(tmp_path / "p.csv"), "--config", str(SCENE))
        assert replay.wait(60) == 0 and csv.wait(60) == 0
        d.wait_for(lambda: len(d.of("radar/plots/r2dvbt2/dvbt2")) >= 20
                   and len(d.of("radar/plots/r1dvbt2/dvbt3")) >= 2)
        time.sleep(0.5)
        d.drain()
        assert len(d.of("radar/plots/r2dvbt2/dvbt2")) == 20
        got = d.of("radar/plots/r1dvbt2/dvbt3")
        assert [(m["t"], list(m["rb"])) for m in got] == [(1.0, [50000.0, 60000.0]), (3.0, [50000.0])]
        assert "'nan': 1" in (tmp_path / "ingest-csv.log").read_text()
        assert "'time_backwards': 1" in (tmp_path / "ingest-csv.log").read_text()
        assert "'fields': 1" in (tmp_path / "ingest-file.log").read_text()
