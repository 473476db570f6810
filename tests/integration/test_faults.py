"""Faults (issue 12 part 3, docs/faults.md): killed services restarted by ``pfusion run``,
late, duplicated and out-of-order input, a silent channel or base, a base whose clock
jumps, and an operator's subscriber that stops reading. Real processes on loopback."""

from __future__ import annotations

import os
import re
import signal
import subprocess
import sys
import threading
import time
import tomllib
from pathlib import Path
from typing import Any

import numpy as np
import pytest

from common.bus.transport import Publisher, free_port, open_session
from common.deploy.config import ZenohConfig, load
from common.radar.fusion.cycle import GlobalFusion
from common.radar.fusion.params import FusionParams
from common.sim.simulator import load_scenario
from common.wire import protocol
from common.wire.radar_messages import etracks_from
from common.wire.sim_messages import run_scenario
from tests.harness import ROOT, SCENARIOS, Deployment
from tests.integration.test_run import TWO_TARGETS, Collector, Run
from tests.radar.test_global_ekf import BASES, RX, TX, _Synth

SCAN_S = 1.0  # scan period of two_targets.toml
REMAINING = {"b2", "b3"}


def bases_of(track: dict[str, Any]) -> set[str]:
    return {b for b, _ in track["etracks"]}


def target_of(track: dict[str, Any], truth: dict[str, Any]) -> int:
    """The truth target nearest in plan position (x, y) to a global track."""
    d = np.hypot(np.asarray(truth["x"]) - track["x"][0], np.asarray(truth["y"]) - track["x"][2])
    assert d.min() < 2000.0, (track["id"], d)
    return int(truth["id"][int(np.argmin(d))])


@pytest.mark.slow
def test_killed_tracker_and_fusion_restarted_by_run(tmp_path: Path) -> None:
    """Kill -9 b1's elementary tracker, then global fusion, under ``pfusion run``
    (two_targets.toml lengthened to 300 scans, at 4x real time; the run is stopped once
    the restarted fusion has confirmed every target)."""
    scn = tmp_path / "two_targets.toml"
    scn.write_text(Path(TWO_TARGETS).read_text().replace("n_scans = 120", "n_scans = 300"))
    endpoint = f"tcp/127.0.0.1:{free_port()}"
    run = Run("--config", str(scn), "--connect", endpoint, "--with-router",
              "--with-simulator", str(scn), "--speed", "4", "--wait-alive", "test/collector")
    col = Collector(endpoint, ["radar/etracks/*", "radar/gtracks", "sim/truth/radar", "sim/status"])

    def newest(key: str) -> float:
        ms = col.of(key)
        return ms[-1]["t"] if ms else -1.0

    def restarted(key: str, t_from: float) -> float | None:
        """Time of the first message of a restarted publisher on `key`: the first after
        a gap in its times from t_from on (the collector may still receive the killed
        process's last messages after the kill, so the time seen at the kill is no bound)."""
        times = sorted(m["t"] for m in col.of(key) if m["t"] >= t_from)
        return next((b for a, b in zip(times, times[1:]) if b - a > SCAN_S + 1e-9), None)

    try:
        run.wait_for("confirmed global tracks", lambda: newest("radar/gtracks") >= 25)
        [tracker] = run.pids("elementary-tracker/b1")
        os.kill(tracker, signal.SIGKILL)
        t_kill = newest("radar/gtracks")
        run.wait_for("b1's restart", lambda: len(run.pids("elementary-tracker/b1")) == 2)
        t_restart = max(newest(f"radar/etracks/{b}") for b in REMAINING)
        run.wait_for("b1 back", lambda: restarted("radar/etracks/b1", t_kill) is not None)
        b1_first = restarted("radar/etracks/b1", t_kill)
        run.wait_for("5 more scans", lambda: newest("radar/gtracks") >= b1_first + 6)
        [fusion] = run.pids("global-fusion")
        os.kill(fusion, signal.SIGKILL)
        t_fkill = newest("radar/gtracks")
        run.wait_for("fusion's restart", lambda: len(run.pids("global-fusion")) == 2)
        t_frestart = max(newest(f"radar/etracks/{b}") for b in ("b1", *REMAINING))
        run.wait_for("20 cycles of the new fusion",
                     lambda: newest("radar/gtracks") >= (restarted("radar/gtracks", t_fkill)
                                                         or np.inf) + 20, timeout=120)
        assert not col.of("sim/status"), "the scenario ended too early"
    finally:
        col.close()
        assert run.stop() == 0, run.log()
    assert any(re.match(r"\[run\] global-fusion exited with code -9 ", line) for line in run.lines)
    truth = {m["t"]: m for m in col.of("sim/truth/radar")}
    gtracks = col.of("radar/gtracks")
    f_first = restarted("radar/gtracks", t_fkill)
    before = [m for m in gtracks if m["t"] < f_first]
    after = [m for m in gtracks if m["t"] >= f_first]
    t_fkill = before[-1]["t"]  # the killed process's last cycle
    # the old process's cycles are in order, none lost
    assert [m["t"] for m in before] == sorted({m["t"] for m in before})

    # 1. tracks seen by >= 2 remaining bases keep confirmed and their numbers
    at_kill = next(m for m in before if m["t"] == t_kill)
    kept = {k["id"]: target_of(k, truth[t_kill]) for k in at_kill["tracks"]
            if k["status"] == "confirmed" and len(bases_of(k) & REMAINING) >= 2}
    assert len(kept) == 2, at_kill["tracks"]
    for m in before:
        if m["t"] > t_kill:
            now = {k["id"]: k for k in m["tracks"]}
            for tid, target in kept.items():
                assert now[tid]["status"] == "confirmed", (m["t"], now.get(tid))
                assert target_of(now[tid], truth[m["t"]]) == target, m["t"]
    # 2. b1's contribution returns within 5 scans of its restarted tracker's first output:
    # every kept track has a member of b1 among b1's tracks of the same scan (the
    # memberships of a base that does not report are kept, so membership alone says little)
    b1 = {m["t"]: {e["id"] for e in m["tracks"]} for m in col.of("radar/etracks/b1")}

    def b1_in(m: dict[str, Any]) -> bool:
        now = {k["id"]: k for k in m["tracks"]}
        return all(any(b == "b1" and e in b1.get(m["t"], ()) for b, e in now[tid]["etracks"])
                   for tid in kept)

    b1_back = next((m["t"] for m in before if m["t"] >= b1_first and b1_in(m)), None)
    assert b1_back is not None, f"b1 not back in the global tracks by t={t_fkill}"
    lost = [t for t in sorted(truth) if t_kill < t < b1_first]
    print(f"tracker b1 killed after the cycle of t={t_kill}: {len(lost)} scans without b1, "
          f"restarted at t~{t_restart}, first etracks t={b1_first}, back in the global "
          f"tracks at t={b1_back} ({(b1_back - b1_first) / SCAN_S:.0f} scans)")
    assert b1_back - b1_first <= 5 * SCAN_S, "\n".join(  # e.g. b1's etracks fused late?
        [line for line in run.lines if "global-fusion" in line or "tracker/b1" in line][-60:])

    # 3. a restarted fusion confirms a track on every target within 10 scans
    def all_confirmed(m: dict[str, Any]) -> bool:
        found = {target_of(k, truth[m["t"]]) for k in m["tracks"] if k["status"] == "confirmed"}
        return found == set(truth[m["t"]]["id"])

    def seen(m: dict[str, Any]) -> str:
        return f"t={m['t']}: " + ", ".join(
            f"{k['id']} {k['status'][:4]} {sorted(bases_of(k))}" for k in m["tracks"])

    resumed = next((m for m in after if all_confirmed(m)), None)
    assert resumed is not None, ("the restarted fusion never confirmed every target:\n"
                                 + "\n".join(seen(m) for m in after) + "\n" + run.log())
    old = {target_of(k, truth[t_fkill]): k["id"] for k in before[-1]["tracks"]
           if k["status"] == "confirmed"}
    new = {target_of(k, truth[resumed["t"]]): k["id"] for k in resumed["tracks"]
           if k["status"] == "confirmed"}
    print(f"global fusion killed after the cycle of t={t_fkill}, restarted at t~{t_frestart}, "
          f"first cycle t={after[0]['t']}, every target confirmed at t={resumed['t']} "
          f"({(resumed['t'] - after[0]['t']) / SCAN_S:.0f} scans after its first cycle); "
          f"numbers (target: track) before {old}, after {new}")
    assert resumed["t"] - after[0]["t"] <= 10 * SCAN_S
    assert [m["t"] for m in after] == list(np.arange(after[0]["t"], after[-1]["t"] + 1))


def test_unit_a_duplicate_is_known_until_its_cycle_runs() -> None:
    syn = _Synth(np.random.default_rng(3))
    gf = GlobalFusion(BASES, FusionParams())
    m1, m2, m3 = syn.messages(0.0)
    assert not gf.is_duplicate("b1", 0.0)
    assert gf.push(*etracks_from(m1)) == [] and gf.is_duplicate("b1", 0.0) and not gf.is_duplicate("b2", 0.0)
    assert [o.t for o in gf.push(*etracks_from(m2)) + gf.push(*etracks_from(m3))] == [0.0]
    assert not gf.is_duplicate("b1", 0.0) and gf.is_late(0.0)  # once run: late


def latest_metrics(d: Deployment, service: str, instance: str) -> dict[str, Any]:
    ms = d.of(f"metrics/{service}/{instance}")
    return ms[-1] if ms else {"rejected": {}, "missed": {}}


GF_TOML = f"""
[zenoh]
root = "{ROOT}"
[radar.fusion]
max_wait = 1.0
max_lead = 20.0
""" + "".join(f"""
[[radar.base]]
id = "b{k + 1}"
tx = {TX[k].tolist()}
rx = {RX.tolist()}
channels = ["c1"]
""" for k in range(3))


def test_fusion_late_duplicate_out_of_order_silent_and_clock_jumps(tmp_path: Path) -> None:
    """Global fusion as a process, fed the etracks of three bases (two targets, real
    elementary trackers in this process) with faults; one cycle per scan, in order,
    whatever happens; each fault counted under its reason."""
    cfg = tmp_path / "fusion.toml"
    cfg.write_text(GF_TOML)
    syn = _Synth(np.random.default_rng(5))
    with Deployment(tmp_path) as d:
        d.collect("radar/gtracks")
        d.collect("metrics/global_fusion/main")
        d.start("fusion", "global-fusion", "--config", str(cfg))
        d.wait_alive(["global_fusion/main"])
        pubs = {b.id: Publisher(d.session, f"{ROOT}/radar/etracks/{b.id}") for b in BASES}
        msgs = {k: syn.messages(float(k)) for k in range(60)}

        def put(m: dict[str, Any], t: float | None = None) -> None:
            pubs[m["base"]].put(protocol.encode({**m, "t": m["t"] if t is None else t}))

        for k in range(60):
            m1, m2, m3 = msgs[k]
            if k == 10:
                put(m1)  # duplicate: twice before its cycle -> duplicate
            if k == 11:
                put(msgs[12][0])  # out of order: b1 sends 12 before 11 (both used)
            if k == 12:
                m1 = None  # (sent above)
            if k == 13:
                put(msgs[12][1])  # late: b2's 12 again, after its cycle -> time_backwards
            if 14 <= k < 19:
                m3 = None  # b3 silent 1.5 s (> max_wait): the cycles go on without it
                time.sleep(0.3)
            if 24 <= k < 34:
                m1 = {**m1, "t": k + 1000.0}  # b1's clock 1000 s ahead -> clock_ahead
            if 40 <= k < 45:
                m2 = {**m2, "t": k - 10.0}  # b2's clock 10 s back -> time_backwards
            for m in (m1, m2, m3):
                if m is not None:
                    put(m)
            time.sleep(0.05)

        def done() -> bool:
            r = latest_metrics(d, "global_fusion", "main")["rejected"]
            return bool(d.of("radar/gtracks")) and d.of("radar/gtracks")[-1]["t"] == 59.0 \
                and sum(r.values()) >= 17
        d.wait_for(done, timeout=60)
        assert all(c.alive() for c in d.children)
    out = d.of("radar/gtracks")
    assert [m["t"] for m in out] == [float(k) for k in range(60)]  # every cycle, in order
    rejected = latest_metrics(d, "global_fusion", "main")["rejected"]
    # time_backwards: b2's late 12, b2's five scans behind its clock, and b3's first scan
    # after its silence (19: sent after b1's and b2's, whose cycle ran while b3 was stale)
    assert rejected == {"duplicate": 1, "time_backwards": 7, "clock_ahead": 10}, rejected
    confirmed = [sorted(tr["id"] for tr in m["tracks"] if tr["status"] == "confirmed")
                 for m in out]
    assert all(ids == [1, 2] for ids in confirmed[5:]), confirmed  # no track lost or renumbered


def test_base_silent_channel_duplicates_out_of_order_and_clock_jumps(tmp_path: Path) -> None:
    """One base's channel plotter and elementary tracker as processes, fed the plots of
    two_targets.toml with faults on their way; every fault counted under its reason,
    every accepted scan fused and tracked, the tracker alive and tracking after the
    jumps of its clock."""
    cfg = load(TWO_TARGETS)
    scn = load_scenario(tomllib.loads(Path(TWO_TARGETS).read_text()))
    scans = [(t, [(k, m) for k, m in out if k.startswith("radar/plots/b1/")])
             for t, out in run_scenario(scn, [cfg.base("b1")], [], seed=1)]
    with Deployment(tmp_path) as d:
        d.collect("radar/fused/b1")
        d.collect("radar/etracks/b1")
        d.collect("metrics/**")
        d.start("plotter", "channel-plotter", "--config", TWO_TARGETS, "--base", "b1")
        d.start("tracker", "elementary-tracker", "--config", TWO_TARGETS, "--base", "b1")
        d.wait_alive(["channel_plotter/b1", "elementary_tracker/b1"])
        pubs = {k: Publisher(d.session, f"{ROOT}/{k}") for k, _ in scans[0][1]}
        sent: list[float] = []

        def put(key: str, msg: dict[str, Any], dt: float = 0.0) -> None:
            pubs[key].put(protocol.encode({**msg, "t": msg["t"] + dt}))

        for i, (t, out) in enumerate(scans):
            dt = 1000.0 if i >= 60 else 0.0  # the base's clock jumps 1000 s forward at 60
            if 90 <= i < 95:
                dt -= 5.0  # ... and 5 s back at 90: scans 90-94 behind its latest time
            for key, msg in out:
                ch = key.rsplit("/", 1)[-1]
                if 20 <= i < 30 and ch == "c3":
                    continue  # c3 silent for 10 scans
                if i == 41 and ch != "c1" or i == 42 and ch == "c1":
                    continue  # c2, c3 of 41 come after c1 of 42 (below)
                put(key, msg, dt)
                if i == 35 and ch == "c2":
                    put(key, msg, dt)  # duplicated
            if i == 41:
                put("radar/plots/b1/c1", scans[42][1][0][1])
                for key, msg in out[1:]:
                    put(key, msg)  # out of order: their scan already published
            if i == 50:
                put(*scans[45][1][0])  # a late copy of c1's scan 45
            sent.append(t + dt)
            time.sleep(0.02)

        def metric(service: str, field: str) -> dict[str, int]:
            return latest_metrics(d, service, "b1")[field]

        d.wait_for(lambda: bool(d.of("radar/etracks/b1"))
                   and d.of("radar/etracks/b1")[-1]["t"] == sent[-1]
                   and sum(metric("channel_plotter", "rejected").values()) >= 20, timeout=60)
        assert all(c.alive() for c in d.children)
    fused = [m["t"] for m in d.of("radar/fused/b1")]
    etracks = d.of("radar/etracks/b1")
    # every scan fused once, in time order, except the five behind the clock (90-94)
    want = [t for i, t in enumerate(sent) if not 90 <= i < 95]
    assert fused == want and [m["t"] for m in etracks] == want
    # the jump at 60: c1's first jumped plot is `ahead` (max_ahead 60 s), c2's takes it
    assert metric("channel_plotter", "rejected") == {"time_backwards": 1 + 1 + 15, "late_scan": 2,
                                                     "ahead": 1}
    assert metric("elementary_tracker", "rejected") == {}
    confirmed = [sum(tr["status"] == "confirmed" for tr in m["tracks"]) for m in etracks]
    print("confirmed elementary tracks per scan:", confirmed)
    assert confirmed[-1] >= 2  # tracking again after the clock jumps


STALLED = """
import sys, time, zenoh
from common.bus.transport import zenoh_config
with zenoh.open(zenoh_config([sys.argv[1]], [], "client")) as s:
    sub = s.declare_subscriber("pf/v1/**", zenoh.handlers.FifoChannel(1))  # never drained
    print("subscribed", flush=True)
    time.sleep(3600)
"""


def flood(session: Any, stop: threading.Event) -> None:
    """Ballast on root/test/ballast: 20 MB at once (below the 25-40 MB that a stalled
    session absorbed before the router blocked, measured here), then about 4 MB/s until
    ``stop``."""
    pub = Publisher(session, f"{ROOT}/test/ballast")
    n, t0 = 0, time.monotonic()
    while not stop.wait(0.0 if n < 1000 else 0.005):
        pub.put(b"x" * 20000)
        n += 1
    print(f"ballast: {n * 20e3 / 1e6:.0f} MB in {time.monotonic() - t0:.1f} s")


@pytest.mark.slow
def test_a_stalled_subscriber_stalls_no_service(tmp_path: Path) -> None:
    """An operator's tool subscribed to everything that stops reading, while this test
    sends it ballast on another key (so that its buffers fill while two_targets.toml
    runs at 5x real time): the chain still delivers every message of every
    stage to a normal collector, nothing missed (the router closes the stalled session:
    services/router/main.py)."""
    with Deployment(tmp_path) as d:
        stalled = subprocess.Popen([sys.executable, "-c", STALLED, d.endpoint],
                                   stdout=subprocess.PIPE, cwd=Path(__file__).parents[2])
        try:
            assert stalled.stdout is not None
            assert b"subscribed\n" in iter(stalled.stdout.readline, b"")  # after Zenoh's log, if any
            for key in ("radar/fused/*", "radar/etracks/*", "radar/gtracks", "sim/truth/radar"):
                d.collect(key)
            alive = d.start_services(SCENARIOS / "two_targets.toml",
                                     ("channel-plotter", "elementary-tracker", "global-fusion"))
            d.wait_alive(alive)
            d.announce()
            scn = str(SCENARIOS / "two_targets.toml")
            with open_session(ZenohConfig([d.endpoint], [], ROOT)) as ballast_session:
                stop = threading.Event()
                ballast = threading.Thread(target=flood, args=(ballast_session, stop))
                ballast.start()
                try:
                    sim = d.start("simulate", "simulate", "--config", scn, "--scenario", scn,
                                  "--speed", "5", "--wait-alive", "test/collector",
                                  *(a for name in alive for a in ("--wait-alive", name)))
                    while sim.alive():
                        d.drain()
                        time.sleep(0.05)
                    assert sim.proc.returncode == 0
                finally:
                    stop.set()
                    ballast.join()
            keys = [f"radar/{s}/b{k}" for s in ("fused", "etracks") for k in (1, 2, 3)]
            d.wait_for(lambda: all(len(d.of(k)) == 120 for k in keys)
                       and len(d.of("radar/gtracks")) == 120, timeout=60)
            assert all(c.alive() for c in d.children if c.name != "simulate")
        finally:
            stalled.kill()
            stalled.wait()
    assert not any(d.losses.missed.values()), d.losses.missed
    assert [m["t"] for m in d.of("radar/gtracks")] == [m["t"] for m in d.of("sim/truth/radar")]
