"""Issue 29: global fusion partitioned by region across hosts (docs/networks.md,
"Partitions"), each host a network namespace (tests/netns.py).

The hosts, routers and configuration files are those of deploy/partitioned/hosts.toml,
the hub's address replaced (192.0.2.10 -> tests.netns.HUB_ADDRESS): fusion host
fusion-west (the hub's router, `global-fusion --partition west`), fusion host
fusion-east (`global-fusion --partition east`, its router connected to the hub), and
receiver sites site1 and site2 whose routers connect to the hub. On fusion-west a third
global fusion runs the same file without its partitions (one partition: the whole
plane, publishing radar/gtracks), so both ways fuse the same stream.

Feeds: each site replays (`pfusion replay --speed SPEED`) the elementary tracks of its
bases on scenarios/network_partition.toml, seed 1 (6 aircraft, 50 s; three cross the
border x = 0), computed beforehand by the channel plotters and elementary trackers of
the in-process chain (common.wire.radar_chain.RadarChain, the services' cores): the
per-base services as processes would cost 18 more processes on 2 cores, and are not
what this test is about (tests/integration/test_network_integration.py runs them).

Checked after a 15 s warm-up, on the two partitions' latest radar/gtracks/<p> of each
time against the one-partition radar/gtracks of that time: every aircraft held, no
false and no duplicate track, in both; the same number of confirmed tracks; each
aircraft's track within POS_TOL of the one-partition track's position; each aircraft
held by one number throughout (the handed-over tracks keep theirs); three handovers
sent, adopted and acked (metrics and keys), none timed out; no report rejected; and
`pfusion evaluate` of the partitioned file (site1 replays the truth too) scores the union
of the partitions at every time, with no number switch. About 37-41 s on 2 cores.
"""

from __future__ import annotations

import re
import subprocess
import sys
import time
import tomllib
from collections.abc import Iterator
from functools import cache
from pathlib import Path
from typing import Any

import numpy as np
import pytest

from common.bus.procs import pfusion_argv
from common.bus.recording import RecordWriter
from common.deploy.config import load
from common.sim.simulator import load_scenario
from common.wire import protocol
from common.wire.radar_chain import RadarChain
from common.wire.radar_messages import etracks_message, plots_of
from common.wire.sim_messages import run_scenario
from tests.harness import REPO, SCENARIOS
from tests.integration.test_multihost import Collector
from tests.netns import HUB_ADDRESS, Topology, require
from tests.network_check import XYZ, score

ROOT = "pf/v1"
SCENARIO = SCENARIOS / "network_partition.toml"
DEPLOY = REPO / "deploy" / "partitioned"
EXAMPLE_HUB = "192.0.2.10"
SEED = 1
SPEED = 5.0  # times real time: 50 s of scene in 10 s
WARMUP = 15.0  # s of scene
POS_TOL = 300.0  # m between a partition's track and the one-partition track of an aircraft
CROSSING = 3  # aircraft crossing x = 0 far enough to be handed over (the scenario's 1-3)
HOSTS = tomllib.loads((DEPLOY / "hosts.toml").read_text())["host"]


@cache
def feed() -> tuple[dict[str, list[tuple[float, str, bytes]]], dict[float, dict[str, Any]]]:
    """The etracks messages of every base (time, base, payload) of the in-process chain,
    and the truth by time."""
    cfg = load(SCENARIO)
    rc = RadarChain(cfg)
    out: dict[str, list[tuple[float, str, bytes]]] = {b.id: [] for b in cfg.bases}
    truth = {}
    for _, msgs in run_scenario(load_scenario(tomllib.loads(SCENARIO.read_text())), cfg.bases,
                                cfg.arrays, SEED):
        for key, msg in msgs:
            if key == "sim/truth/radar":
                truth[msg["t"]] = msg
            if key.startswith("radar/plots/"):
                b = msg["base"]
                for t, fused in rc.plotters[b].push(msg["channel"], msg["t"],
                                                    plots_of(msg, rc.azimuth[b])):
                    tracks = rc.trackers[b].step(t, fused)
                    out[b].append((t, b, protocol.encode(etracks_message(b, tracks))))
    return out, truth


def recording(path: Path, site: str, truth: bool) -> Path:
    """The site's bases' etracks as a .pfrec file (record times: scene time); with
    `truth` also the simulator's truth."""
    bases = [b.id for b in load(DEPLOY / HOSTS[site]["config"]).bases]
    records = sorted((t, f"radar/etracks/{b}", p) for b in bases for t, _, p in feed()[0][b])
    if truth:
        records = sorted(records + [(t, "sim/truth/radar", protocol.encode(m))
                                    for t, m in feed()[1].items()])
    with path.open("wb") as f:
        w = RecordWriter(f, ROOT, 0.0)
        for t, key, payload in records:
            w.write(f"{ROOT}/{key}", t, payload)
    return path


def router_argv(h: dict[str, Any]) -> list[str]:
    argv = ["router"]
    for ep in h["router_listen"]:
        argv += ["--listen", ep.replace(EXAMPLE_HUB, HUB_ADDRESS)]
    for ep in h["router_connect"]:
        argv += ["--connect", ep.replace(EXAMPLE_HUB, HUB_ADDRESS)]
    return argv


@pytest.fixture
def net(tmp_path: Path) -> Iterator[Topology]:
    require()
    topo = Topology(tmp_path / "logs", hub="fusion-west")
    for i, name in enumerate(("fusion-east", "site1", "site2"), start=1):
        topo.add_site(name, i)
    try:
        yield topo
    finally:
        topo.close()


def wait(topo: Topology, ok: Any, what: str, timeout: float) -> None:
    deadline = time.time() + timeout
    while not ok():
        if time.time() > deadline:
            raise TimeoutError(f"{what} after {timeout} s; logs in {topo.logdir}")
        time.sleep(0.05)


def connected(topo: Topology, host: str, pid: int) -> bool:
    """Whether process pid has a TCP connection to its host's router (its session)."""
    out = subprocess.run(["ip", "netns", "exec", topo.ns[host], "ss", "-Htnp", "state",
                          "established", "( dport = :7447 )"], capture_output=True, text=True)
    return f"pid={pid}," in out.stdout


def union_at(msgs: dict[str, list[dict[str, Any]]], t: float) -> dict[str, Any]:
    """The tracks of every partition's latest message at or before t, as one message."""
    tracks = []
    for ms in msgs.values():
        before = [m for m in ms if m["t"] <= t]
        tracks += before[-1]["tracks"] if before else []
    return {"t": t, "tracks": tracks}


def holders(g: dict[str, Any], truth: dict[str, Any]) -> list[tuple[int, np.ndarray]]:
    """Per aircraft, the number and position of its nearest confirmed track."""
    out = []
    conf = [k for k in g["tracks"] if k["status"] == "confirmed"]
    x = np.array([k["x"] for k in conf]).reshape(-1, 6)[:, XYZ]
    for i in range(len(truth["id"])):
        p = np.array([truth["x"][i], truth["y"][i], truth["z"][i]])
        j = int(np.linalg.norm(x - p, axis=1).argmin())
        out.append((conf[j]["id"], x[j]))
    return out


@pytest.mark.timeout(300)
@pytest.mark.slow
def test_two_partitions_give_the_tracks_of_one(net: Topology, tmp_path: Path) -> None:
    t0 = time.monotonic()
    routers = [net.start(name, pfusion_argv(*router_argv(h)), f"{name}-router")
               for name, h in HOSTS.items()]
    logs = [net.logdir / f"{r.name}.log" for r in routers]
    wait(net, lambda: all("router listening" in log.read_text() for log in logs),
         "routers not listening", 60.0)
    fusion = str(DEPLOY / "fusion.toml")
    single = tmp_path / "single.toml"  # the same file without its partitions
    single.write_text("".join(line for line in (DEPLOY / "fusion.toml").read_text()
                              .splitlines(keepends=True) if not line.startswith("partition")))
    fusions = [net.start(name, pfusion_argv("global-fusion", "--config", fusion, "--partition",
                                            HOSTS[name]["partition"]), f"{name}-fusion")
               for name in ("fusion-west", "fusion-east")]
    fusions.append(net.start("fusion-west", pfusion_argv("global-fusion", "--config", str(single)),
                             "fusion-west-single"))
    collector = Collector(net.start(
        "fusion-west", [sys.executable, "-m", "tests.remote_collector", "--connect",
                        "tcp/127.0.0.1:7447", "--name", "fusion-west", "radar/gtracks",
                        "radar/gtracks/*", "radar/handover/*", "radar/handover_ack/*",
                        "metrics/global_fusion/*"], "collector", stdout=subprocess.PIPE))
    evaluate = net.start("fusion-west", pfusion_argv("evaluate", "--config", fusion),
                         "fusion-west-evaluate", stdout=subprocess.PIPE)
    alive = ["global_fusion/west", "global_fusion/east", "global_fusion/main", "test/fusion-west",
             "evaluate/main"]
    replays = []
    for site in ("site1", "site2"):
        rec = recording(tmp_path / f"{site}.pfrec", site, truth=site == "site1")
        argv = ["replay", str(rec), "--connect",
                "tcp/127.0.0.1:7447", "--speed", str(SPEED), "--wait-timeout", "120"]
        for name in alive:
            argv += ["--wait-alive", name]
        replays.append(net.start(site, pfusion_argv(*argv, "--wait-alive", "test/go"),
                                 f"{site}-replay"))
    # Both replays start together: a replay refuses to start into services that already
    # processed its first time (pfusion replay, exit 3), which a site starting a window
    # (1 s of wall time here) after the other would meet.
    wait(net, lambda: all(connected(net, site, r.proc.pid) for site, r in zip(("site1", "site2"),
                                                                            replays)),
         "replays not connected", 60.0)
    net.start("fusion-west", [sys.executable, "-m", "tests.remote_collector", "--connect",
                              "tcp/127.0.0.1:7447", "--name", "go", "test/go"], "go")
    wait(net, lambda: not any(r.alive() for r in replays), "replays not done", 150.0)
    assert [r.proc.returncode for r in replays] == [0, 0]
    time.sleep(1.0)  # the last etracks reach the fusions
    for f in fusions:
        assert f.stop(10.0) == 0, f.name

    def finished() -> dict[str, dict[str, Any]]:
        return {r.msg["instance"]: r.msg for r in collector.like("metrics/global_fusion/")
                if r.msg.get("state") == "finished"}

    wait(net, lambda: len(finished()) == 3, "no final metrics of the fusions", 20.0)
    metrics = finished()
    assert evaluate.stop(30.0) == 0  # it prints its table on SIGTERM
    assert evaluate.proc.stdout is not None
    table = evaluate.proc.stdout.read().decode()
    runtime = time.monotonic() - t0
    _, truth = feed()
    one = [r.msg for r in collector.of("radar/gtracks")]
    parts = {p: [r.msg for r in collector.of(f"radar/gtracks/{p}")] for p in ("west", "east")}
    assert not collector.errors
    two = [union_at(parts, g["t"]) for g in one]

    s1, s2 = score(one, truth, WARMUP), score(two, truth, WARMUP)
    assert s1.reports == s2.reports >= 25
    assert (s1.missed, s1.false, s1.duplicates) == (0, 0, 0), s1
    assert (s2.missed, s2.false, s2.duplicates) == (0, 0, 0), s2
    numbers: dict[int, set[int]] = {}
    worst = 0.0
    for g, h in zip(one, two):
        if g["t"] < WARMUP:
            continue
        assert sum(k["status"] == "confirmed" for k in g["tracks"]) == \
            sum(k["status"] == "confirmed" for k in h["tracks"]), g["t"]
        for i, ((_, x1), (n2, x2)) in enumerate(zip(holders(g, truth[g["t"]]),
                                                   holders(h, truth[g["t"]]))):
            worst = max(worst, float(np.linalg.norm(x1 - x2)))
            numbers.setdefault(i, set()).add(n2)
    assert worst <= POS_TOL, worst
    assert all(len(n) == 1 for n in numbers.values()), numbers

    handed = {p: metrics[p]["handover"] for p in ("west", "east")}
    total = {k: sum(h.get(k, 0) for h in handed.values()) for k in
             ("handed", "adopted", "acked", "timeouts", "conflicts")}
    assert total == {"handed": CROSSING, "adopted": CROSSING, "acked": CROSSING,
                     "timeouts": 0, "conflicts": 0}, handed
    assert len(collector.like("radar/handover/")) == CROSSING
    assert len(collector.like("radar/handover_ack/")) == CROSSING
    assert all(m["rejected"] == {} and m["missed"] == {} for m in metrics.values()), metrics
    # pfusion evaluate on the partitioned deployment scores the union of radar/gtracks/*
    steps = re.search(r"^steps (\d+) .* switches (\d+) ", table, re.M)
    assert steps and int(steps[1]) == len(one) and int(steps[2]) == 0, table
    print(f"\n[partition multihost] reports {s2.reports}, worst position difference "
          f"{worst:.1f} m, handovers {handed}, runtime {runtime:.1f} s")
