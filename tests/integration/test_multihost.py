"""Issue 12: the radar chain across hosts, each host a network namespace (tests/netns.py).

The hosts, their routers' endpoints, their configuration files and their services are
those of deploy/multisite/hosts.toml (docs/deployment.md); only the fusion host's
address is replaced (192.0.2.10 -> tests.netns.HUB_ADDRESS). Two receiver sites, site1
(bases b1, b2) and site2 (b3), each run a router connected to the fusion host's router,
the channel plotters and elementary trackers of their bases, and a simulator as their
sensor feed: ``pfusion simulate --config <site file>`` publishes the plots of the
site's bases only, and since each key draws from its own seeded generator
(common.sim.simulator) they are the plots a single simulator of all bases publishes.
The fusion host runs its router and global fusion. A collector on each host
(tests/remote_collector.py) receives what the test checks, with receive times on the
kernel's monotonic clock shared by all namespaces.

Three runs of scenarios/two_targets.toml, seed 1, 120 scans at SPEED x real time:
clean links; impaired site links (50 ms delay, 10 ms jitter, 1 % loss both ways);
site2's link cut for 10 s. Global fusion's stale-base rule runs on wall time
(``max_wait`` = 3 s, deploy/multisite/fusion.toml): the tracks equal the single-host
chain's as long as no base's stream pauses for 3 s, which the impaired link does not
cause (its worst pause is a few TCP retransmission timeouts, 0.2-0.8 s) and the cut
does, on purpose.
"""

from __future__ import annotations

import json
import subprocess
import sys
import threading
import time
import tomllib
from collections.abc import Callable, Iterator
from dataclasses import dataclass
from functools import cache
from pathlib import Path
from types import TracebackType
from typing import Any

import msgpack
import numpy as np
import pytest

from common.bus.procs import pfusion_argv
from common.bus.transport import Publisher
from common.cli import COMMANDS
from common.deploy.config import load
from common.deploy.deployment import ChildSpec, plan
from common.deploy.sections import check_all
from common.radar.geometry.bistatic import POS
from common.sim.simulator import load_scenario
from common.wire import protocol
from common.wire.radar_chain import RadarChain
from common.wire.radar_messages import etracks_message, plots_of
from common.wire.sim_messages import run_scenario
from tests.harness import REPO, SCENARIOS, Deployment
from tests.netns import HUB_ADDRESS, NsProcess, Topology, require

ROOT = "pf/v1"
SCENARIO = SCENARIOS / "two_targets.toml"
MULTISITE = REPO / "deploy" / "multisite"
EXAMPLE_HUB = "192.0.2.10"  # the fusion host's address in deploy/multisite (RFC 5737)
SEED = 1
SPEED = 4.0  # times real time: 120 scans of 1 s in 30 s
CUT_AT, CUT_FOR = 6.0, 10.0  # s of wall time after site2's first plots; length of the cut
RESUME_WITHIN = 5.0  # s after the restore
NEAR = 2000.0  # m: a confirmed global track this close to a target is its track
SIM = tomllib.loads(SCENARIO.read_text())["sim"]
MAX_WAIT = tomllib.loads((MULTISITE / "fusion.toml").read_text())["radar"]["fusion"]["max_wait"]
SCANS = SIM["n_scans"]
T_LAST = (SCANS - 1) * SIM["scan_period"]  # the last scan's time


@dataclass(frozen=True)
class Host:
    """One host of deploy/multisite/hosts.toml."""

    name: str
    config: str  # path relative to the repository, as in docs/deployment.md
    router_listen: list[str]
    router_connect: list[str]
    services: tuple[str, ...]

    def router_argv(self) -> list[str]:
        argv = ["router"]
        for ep in self.router_listen:
            argv += ["--listen", ep]
        for ep in self.router_connect:
            argv += ["--connect", ep]
        return argv

    def service_specs(self) -> list[ChildSpec]:
        """The services of the host: common.deploy.deployment.plan of its config file,
        restricted to the commands hosts.toml gives it."""
        return plan(load(REPO / self.config), self.config, self.services)

    def commands(self) -> list[str]:
        """The command lines docs/deployment.md gives for this host."""
        return [" ".join(["pfusion", *self.router_argv()])] + [
            " ".join(["pfusion", *s.argv]) for s in self.service_specs()]


def hosts(hub_address: str = EXAMPLE_HUB) -> dict[str, Host]:
    """The hosts of deploy/multisite/hosts.toml, the fusion host's address replaced."""
    doc = tomllib.loads((MULTISITE / "hosts.toml").read_text())

    def sub(eps: list[str]) -> list[str]:
        return [ep.replace(EXAMPLE_HUB, hub_address) for ep in eps]

    return {name: Host(name, str((MULTISITE / h["config"]).relative_to(REPO)),
                       sub(h["router_listen"]), sub(h["router_connect"]), tuple(h["services"]))
            for name, h in doc["host"].items()}


@cache
def reference() -> tuple[list[dict[str, Any]], dict[float, dict[str, Any]]]:
    """The single-host chain (common.wire.radar_chain, shown equal to the single-host
    processes by tests/integration/test_global_integration.py) on SCENARIO, seed SEED: gtracks
    messages and truth by scan time."""
    cfg = load(SCENARIO)
    scn = load_scenario(tomllib.loads(SCENARIO.read_text()))
    rc = RadarChain(cfg)
    steps = list(run_scenario(scn, cfg.bases, cfg.arrays, SEED))
    truth = {m["t"]: m for _, msgs in steps for k, m in msgs if k == "sim/truth/radar"}
    return [g for _, msgs in steps for g in rc.step(msgs)], truth


@dataclass
class Received:
    """One sample a collector received: receive time, the time its first router put on
    it (tests/remote_collector.py), key, decoded message."""

    at: float
    ts: float
    key: str
    msg: dict[str, Any]


class Collector:
    """Reads a tests/remote_collector.py process's stdout on a thread."""

    def __init__(self, proc: NsProcess) -> None:
        self.proc = proc
        self.items: list[Received] = []
        self.errors: list[str] = []
        threading.Thread(target=self._read, daemon=True).start()

    def _read(self) -> None:
        unpacker = msgpack.Unpacker(raw=False)
        stream = self.proc.proc.stdout
        assert stream is not None
        while chunk := stream.read1(1 << 16):
            unpacker.feed(chunk)
            for at, ts, key, payload in unpacker:
                kind = protocol.kind_of(key, ROOT)
                try:
                    msg = protocol.decode(kind, payload) if kind else protocol.unpack(payload)
                except protocol.DecodeError as e:
                    self.errors.append(f"{key}: {e}")
                    continue
                self.items.append(Received(at, ts, key, msg))

    def of(self, suffix: str) -> list[Received]:
        full = f"{ROOT}/{suffix}"
        return [r for r in list(self.items) if r.key == full]

    def like(self, prefix: str) -> list[Received]:
        full = f"{ROOT}/{prefix}"
        return [r for r in list(self.items) if r.key.startswith(full)]


class MultiSite:
    """The hosts of deploy/multisite/hosts.toml in namespaces, with their routers and
    services, a collector per host, and a simulator per site."""

    def __init__(self, logdir: Path, impaired: bool = False) -> None:
        self.logdir = logdir
        self.net = Topology(logdir)
        self.hosts = hosts(HUB_ADDRESS)
        self.sites = [h for h in self.hosts if h != "fusion"]
        for i, site in enumerate(self.sites, start=1):
            self.net.add_site(site, i, impaired)
        self.collectors: dict[str, Collector] = {}
        self.sims: list[NsProcess] = []

    def __enter__(self) -> "MultiSite":
        return self

    def __exit__(self, exc_type: type | None, exc: BaseException | None,
                 tb: TracebackType | None) -> None:
        self.net.close()
        if exc is not None:
            for log in sorted(self.logdir.glob("*.log")):
                print(f"==== {log.name} (last 30 lines) ====")
                print("\n".join(log.read_text(errors="replace").splitlines()[-30:]))

    def start(self) -> None:
        """Routers, services and collectors of every host, then the sites' simulators
        (which wait for every service and collector to be alive)."""
        routers = [self.net.start(h.name, pfusion_argv(*h.router_argv()), f"{h.name}-router")
                   for h in self.hosts.values()]
        logs = [self.logdir / f"{r.name}.log" for r in routers]
        self.wait(lambda: all("router listening" in log.read_text() for log in logs),
                  "routers not listening", 120.0)  # clients give up after 10 s without one
        alive = []
        for h in self.hosts.values():
            for spec in h.service_specs():
                self.net.start(h.name, pfusion_argv(*spec.argv),
                               f"{h.name}-{spec.name.replace('/', '-')}")
                alive.append(spec.alive)
        keys = {"fusion": ["radar/gtracks", "radar/etracks/*", "metrics/global_fusion/*"]}
        for site in self.sites:
            bases = [b.id for b in load(REPO / self.hosts[site].config).bases]
            keys[site] = [k for b in bases for k in (f"radar/plots/{b}/*", f"radar/etracks/{b}")]
        for host, keyexprs in keys.items():
            proc = self.net.start(host, [sys.executable, "-m", "tests.remote_collector",
                                         "--connect", "tcp/127.0.0.1:7447", "--name", host,
                                         *keyexprs], f"{host}-collector", stdout=subprocess.PIPE)
            self.collectors[host] = Collector(proc)
            alive.append(f"test/{host}")
        for site in self.sites:
            argv = ["simulate", "--config", self.hosts[site].config, "--scenario", str(SCENARIO),
                    "--seed", str(SEED), "--speed", str(SPEED), "--wait-timeout", "150"]
            for name in alive:
                argv += ["--wait-alive", name]
            self.sims.append(self.net.start(site, pfusion_argv(*argv), f"{site}-simulate"))

    def check(self) -> None:
        """Raise if a service, router or collector exited, or a simulator failed."""
        for p in self.net.processes:
            if not p.alive() and (p not in self.sims or p.proc.returncode != 0):
                raise RuntimeError(f"{p.name} exited with {p.proc.returncode}; see {self.logdir}")

    def wait(self, predicate: Callable[[], bool], what: str, timeout: float) -> None:
        deadline = time.time() + timeout
        while not predicate():
            self.check()
            if time.time() > deadline:
                raise TimeoutError(f"{what} after {timeout} s; see logs in {self.logdir}")
            time.sleep(0.05)

    def finish(self, timeout: float = 240.0) -> None:
        """Wait for the simulators to end and the global tracks of the last scan."""
        self.wait(lambda: not any(s.alive() for s in self.sims), "simulators not done", timeout)
        self.wait(lambda: any(r.msg["t"] == T_LAST for r in self.gtracks()),
                  f"no gtracks of t={T_LAST}", 60.0)

    def gtracks(self) -> list[Received]:
        return self.collectors["fusion"].of("radar/gtracks")

    def fusion_metrics(self, until: Callable[[dict[str, Any]], bool], timeout: float = 30.0
                       ) -> dict[str, Any]:
        """The first metrics message of global fusion for which ``until`` holds."""
        found: list[dict[str, Any]] = []

        def ready() -> bool:
            found[:] = [r.msg for r in self.collectors["fusion"].like("metrics/global_fusion/")
                        if until(r.msg)]
            return bool(found)

        self.wait(ready, "no global fusion metrics as expected", timeout)
        return found[0]


def assert_same_tracks(ours: list[dict[str, Any]], theirs: list[dict[str, Any]]) -> None:
    """Same cycles, same track numbers, states and covariances to 1e-9."""
    by_t = {g["t"]: g for g in theirs}
    assert [g["t"] for g in ours] == sorted(by_t)
    for g in ours:
        h = by_t[g["t"]]["tracks"]
        assert [k["id"] for k in g["tracks"]] == [k["id"] for k in h], g["t"]
        for a, b in zip(g["tracks"], h):
            np.testing.assert_allclose(a["x"], b["x"], rtol=1e-9, atol=1e-9)
            np.testing.assert_allclose(np.ravel(a["P"]), b["P"], rtol=1e-9, atol=1e-9)


def percentiles(seconds: list[float]) -> dict[str, float]:
    ms = np.asarray(seconds) * 1e3
    return {"n": int(ms.size), "p50_ms": round(float(np.percentile(ms, 50)), 1),
            "p99_ms": round(float(np.percentile(ms, 99)), 1),
            "min_ms": round(float(ms.min()), 1), "max_ms": round(float(ms.max()), 1)}


def latency(ms: MultiSite) -> dict[str, dict[str, float]]:
    """End to end, plot -> global track, per scan: the time the fusion host's router put
    on the scan's global tracks minus the latest time a site router put on one of the
    scan's plots (the cycle needs them all); both are taken as the samples enter the
    network, so the collectors' own delays do not count. Link crossing: an elementary
    tracks message's arrival at the fusion host's collector minus its site router's
    time."""
    last_plot: dict[float, float] = {}
    crossing = []
    for site in ms.sites:
        for r in ms.collectors[site].like("radar/plots/"):
            last_plot[r.msg["t"]] = max(last_plot.get(r.msg["t"], 0.0), r.ts)
    for r in ms.collectors["fusion"].like("radar/etracks/"):
        crossing.append(r.at - r.ts)
    return {"plot_to_gtrack": percentiles([r.ts - last_plot[r.msg["t"]] for r in ms.gtracks()]),
            "etracks_link_crossing": percentiles(crossing)}


def report(case: str, numbers: dict[str, Any]) -> None:
    """Print the numbers (pytest -s shows them) and keep them in out/multihost.json."""
    print(f"\n[multihost] {case}: {json.dumps(numbers)}")
    out = REPO / "out" / "multihost.json"
    out.parent.mkdir(exist_ok=True)
    doc = json.loads(out.read_text()) if out.exists() else {}
    doc[case] = numbers
    out.write_text(json.dumps(doc, indent=2) + "\n")


@pytest.fixture
def multisite(tmp_path: Path) -> Iterator[Callable[[bool], MultiSite]]:
    """Factory of MultiSite runs; skips (with the reason printed) where namespaces
    cannot be made, fails there under CI (tests.netns.require); every namespace is
    deleted at the end, even on failure."""
    require()
    made: list[MultiSite] = []

    def make(impaired: bool) -> MultiSite:
        made.append(MultiSite(tmp_path / f"run{len(made)}", impaired))
        return made[-1]

    yield make
    for ms in made:
        ms.net.close()


def run_whole(ms: MultiSite) -> list[dict[str, Any]]:
    """Run the scenario through the hosts; the gtracks messages received."""
    ms.start()
    reference()  # while the processes start
    ms.finish()
    return [r.msg for r in ms.gtracks()]


def check_accounting(ms: MultiSite, missed_b3: int = 0) -> dict[str, Any]:
    """Global fusion's metrics account for every etracks message of the three bases:
    in + missed = 3 x scans, and only b3's key misses samples (``missed_b3``)."""
    n = 3 * SCANS
    m = ms.fusion_metrics(lambda m: m["in"] + sum(m["missed"].values()) >= n)
    assert m["in"] + sum(m["missed"].values()) == n, m
    assert m["missed"] == ({f"{ROOT}/radar/etracks/b3": missed_b3} if missed_b3 else {}), m
    assert not any(c.errors for c in ms.collectors.values())
    return m


def test_deploy_files_are_the_tested_topology() -> None:
    """deploy/multisite: every file is a valid deployment; the sites' bases split the
    fusion host's bases (same geometry as the scenario the tests run); the sites'
    routers connect to the fusion router's listening endpoint; docs/deployment.md gives
    every host's command lines as the tests run them."""
    hs = hosts()
    assert set(hs) == {"fusion", "site1", "site2"}
    for h in hs.values():
        check_all(load(REPO / h.config))
        assert set(h.services) <= set(COMMANDS), h
    scenario = {b.id: b for b in load(SCENARIO).bases}
    fusion = load(REPO / hs["fusion"].config)
    assert [b.id for b in fusion.bases] == list(scenario)
    site_bases = [b for s in ("site1", "site2") for b in load(REPO / hs[s].config).bases]
    assert sorted(b.id for b in site_bases) == sorted(scenario)
    for b in [*fusion.bases, *site_bases]:
        ref = scenario[b.id]
        assert np.array_equal(b.tx, ref.tx) and np.array_equal(b.rx, ref.rx), b.id
        assert (b.channels, b.p) == (ref.channels, ref.p), b.id
    hub = [ep for ep in hs["fusion"].router_listen if EXAMPLE_HUB in ep]
    assert hub and all(hs[s].router_connect == hub for s in ("site1", "site2"))
    assert [s.argv[0] for s in hs["fusion"].service_specs()] == ["global-fusion"]
    docs = (REPO / "docs" / "deployment.md").read_text()
    for h in hs.values():
        for line in h.commands():
            assert line in docs, line


@pytest.mark.timeout(600)  # 14 processes start: slow on a loaded 2-core machine
@pytest.mark.slow
def test_clean_links_give_the_single_host_tracks(multisite: Callable[[bool], MultiSite]
                                                 ) -> None:
    """Three hosts on clean links: the global tracks of the single-host chain (numbers,
    states to 1e-9), no sample missed; the latency plot -> global track is reported."""
    t0 = time.monotonic()
    with multisite(False) as ms:
        ours = run_whole(ms)
        assert_same_tracks(ours, reference()[0])
        m = check_accounting(ms)
        lat = latency(ms)
    assert lat["plot_to_gtrack"]["p99_ms"] < 5000.0, lat  # sanity only
    report("clean", {**lat, "fusion_in": m["in"], "runtime_s": round(time.monotonic() - t0, 1)})


@pytest.mark.timeout(600)  # 14 processes start: slow on a loaded 2-core machine
@pytest.mark.slow
def test_impaired_links_give_the_same_tracks(multisite: Callable[[bool], MultiSite]) -> None:
    """Site links with 50 ms delay, 10 ms jitter and 1 % loss each way: reliable
    transport, so the same global tracks and no sample missed; every global track
    arrives at least the link's minimum delay after its last plot."""
    t0 = time.monotonic()
    with multisite(True) as ms:
        ours = run_whole(ms)
        assert_same_tracks(ours, reference()[0])
        m = check_accounting(ms)
        lat = latency(ms)
        impairment = ms.net.impairment
    assert lat["etracks_link_crossing"]["min_ms"] >= 40.0, lat  # 50 ms +- 10 ms one way
    assert lat["plot_to_gtrack"]["p99_ms"] < 5000.0, lat  # sanity only
    frames = userspace_netem_counts(ms.logdir)
    if frames:  # the userspace netem dropped frames (~1 %), and TCP made up for them
        assert sum(c["dropped"] for c in frames) > 0, frames
    report("impaired", {**lat, "impairment": impairment, "netem_frames": frames,
                        "fusion_in": m["in"], "runtime_s": round(time.monotonic() - t0, 1)})


def userspace_netem_counts(logdir: Path) -> list[dict[str, int]]:
    """The frame counts tests/netem.py printed when it stopped (none: kernel netem)."""
    return [json.loads(line.split(": ", 1)[1]) for log in sorted(logdir.glob("netem*.log"))
            for line in log.read_text().splitlines() if line.startswith("netem ")]


def confirmed_near(g: dict[str, Any], truth: dict[str, Any], tid: int) -> list[int]:
    """Ids of the confirmed tracks of gtracks ``g`` within NEAR of target ``tid``."""
    k = truth["id"].index(tid)
    p = np.array([truth["x"][k], truth["y"][k], truth["z"][k]])
    return [t["id"] for t in g["tracks"] if t["status"] == "confirmed"
            and np.linalg.norm(np.asarray(t["x"])[POS] - p) < NEAR]


@pytest.mark.timeout(600)  # 14 processes start: slow on a loaded 2-core machine
@pytest.mark.slow
def test_cut_site_link_reconnects_and_counts_what_it_missed(
        multisite: Callable[[bool], MultiSite]) -> None:
    """site2's link down for 10 s, then up: the routers reconnect by themselves (no
    process restarts); b3's elementary tracks reach the fusion host again and a global
    cycle fuses them within 5 s of the restore (the first ones back may come after their
    cycle ran: rejected as late, they make b3 live again); the tracks keep their numbers (those of
    the single-host chain) throughout; every b3 etracks message lost meanwhile is counted
    in global fusion's `missed`; before the first lost one the tracks are the single-
    host chain's."""
    t_start = time.monotonic()
    with multisite(False) as ms:
        ms.start()
        site2 = ms.collectors["site2"]
        ms.wait(lambda: bool(site2.like("radar/plots/")), "no plots at site2", 180.0)
        t_plots = site2.like("radar/plots/")[0].at
        time.sleep(max(0.0, t_plots + CUT_AT - time.time()))
        ms.net.set_link("site2", up=False)
        t_cut = time.time()
        time.sleep(CUT_FOR)
        ms.net.set_link("site2", up=True)
        t_restore = time.time()
        ms.finish()
        ours = [r.msg for r in ms.gtracks()]
        published = {r.msg["t"]: r.at for r in site2.of("radar/etracks/b3")}
        arrived = {r.msg["t"]: r.at for r in ms.collectors["fusion"].of("radar/etracks/b3")}
        lost = sorted(set(published) - set(arrived))
        m = check_accounting(ms, missed_b3=len(lost))
        gt_at = {r.msg["t"]: r.at for r in ms.gtracks()}
    ref, truth = reference()
    assert len(published) == len(ref) and set(arrived) <= set(published)
    assert lost, "the cut lost no etracks message"
    assert all(t_cut - 3.0 <= published[t] <= t_restore + RESUME_WITHIN for t in lost), \
        (t_cut, t_restore, [(t, published[t]) for t in lost])
    # resumed: b3's reports whose cycle had already run are rejected (time_backwards),
    # and rejoin b3 (services/global_fusion): the next ones are fused. They are the first
    # b3 reports back, at most one per scan b3 lags behind (max_wait of message time).
    late = m["rejected"].get("time_backwards", 0)
    assert late <= MAX_WAIT / SIM["scan_period"] + 1, m["rejected"]
    back = [t for t in sorted(arrived) if arrived[t] > t_restore]
    assert len(back) > late, "b3 never contributed again"
    resume = gt_at[back[late]] - t_restore
    assert resume <= RESUME_WITHIN, (resume, back[:late + 1])
    # before the first lost message: the single-host chain's tracks exactly
    before = [g for g in ours if g["t"] < lost[0]]
    assert_same_tracks(before, [g for g in ref if g["t"] < lost[0]])
    # numbers kept: from its confirmation in the single-host chain to the end, each
    # target has one confirmed track nearby, with the single-host chain's number
    by_t = {g["t"]: g for g in ours}
    assert sorted(by_t) == [g["t"] for g in ref]
    for tid in (1, 2):
        for g in ref:
            want = confirmed_near(g, truth[g["t"]], tid)
            if want:
                assert confirmed_near(by_t[g["t"]], truth[g["t"]], tid) == want, (tid, g["t"])
    report("cut", {"cut_s": round(t_restore - t_cut, 2), "lost_b3_etracks": len(lost),
                   "lost_scan_times": [lost[0], lost[-1]], "fusion_missed": m["missed"],
                   "fusion_in": m["in"], "rejected": m["rejected"],
                   "resume_s": round(resume, 3), "b3_late_after_restore": late,
                   "b3_back_at_fusion_s": round(arrived[back[0]] - t_restore, 3),
                   "runtime_s": round(time.monotonic() - t_start, 1)})


def etracks_per_scan(scans: int) -> list[dict[str, dict[str, Any]]]:
    """The etracks message of every base at each of the first ``scans`` scans of SCENARIO
    (the plotters and trackers of the in-process chain)."""
    cfg = load(SCENARIO)
    scn = load_scenario(tomllib.loads(SCENARIO.read_text()))
    rc = RadarChain(cfg)
    out = []
    for _, msgs in run_scenario(scn, cfg.bases, cfg.arrays, SEED, scans):
        scan = {}
        for key, msg in msgs:
            if key.startswith("radar/plots/"):
                b = msg["base"]
                for t, fused in rc.plotters[b].push(msg["channel"], msg["t"], plots_of(msg)):
                    scan[b] = etracks_message(b, rc.trackers[b].step(t, fused))
        out.append(scan)
    return out


def test_a_stale_base_back_behind_the_others_is_fused_again(tmp_path: Path) -> None:
    """services/global_fusion on loopback: b3 silent for more than max_wait (the cycles
    go on with b1, b2), then back one scan behind: its report of t=6 comes after the
    cycle of t=6 ran and is rejected as late, but makes b3 live again, so the cycle of
    t=7 waits for b3's report (what brings a site back after a cut link)."""
    scans = etracks_per_scan(8)
    with Deployment(tmp_path) as d:
        d.collect("radar/gtracks")
        d.start("global-fusion", "global-fusion", "--config", str(SCENARIO))
        d.wait_alive(["global_fusion/main"])
        pubs = {b: Publisher(d.session, f"{ROOT}/radar/etracks/{b}") for b in ("b1", "b2", "b3")}

        def send(t: int, *bases: str) -> None:
            for b in bases:
                pubs[b].put(protocol.encode(scans[t][b]))

        def cycles() -> list[float]:
            d.drain()
            return [m["t"] for m in d.of("radar/gtracks")]

        for t in range(5):
            send(t, "b1", "b2", "b3")
        send(5, "b1", "b2")
        d.wait_for(lambda: cycles() == [0.0, 1.0, 2.0, 3.0, 4.0])
        time.sleep(MAX_WAIT + 0.5)  # b3 is stale from now on
        send(6, "b1", "b2")
        d.wait_for(lambda: cycles()[-1:] == [6.0])  # 5 and 6 without b3
        send(6, "b3")  # late: rejected, b3 live again
        send(7, "b1", "b2")
        time.sleep(1.0)
        assert cycles()[-1] == 6.0, "the cycle of t=7 ran without waiting for b3"
        send(7, "b3")
        d.wait_for(lambda: cycles()[-1:] == [7.0])
