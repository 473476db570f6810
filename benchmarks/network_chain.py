"""The whole network chain through its processes (issue 29 section 3, docs/networks.md
"Through the processes").

Run: PYTHONPATH=. .venv/bin/python benchmarks/network_chain.py [--aircraft 300] [--seed 1]
     [--duration 120] [--speed 1] [--max-lag 60]

A real router, every base's channel plotter and elementary tracker (21 bases of the goal
scene, benchmarks/network_scene.py), global fusion and the simulator at --speed times
real time, each its own process on this machine (common.bus.local_run), unpinned.
Measured: per kind of service, the CPU seconds (all threads, /proc/<pid>/stat) per scene
second; the wall time from the simulator's first scan until global fusion has taken in
the last elementary-track report (its control queryable, common.bus.control, answered
from its loop after every sample queued before the query), and the lag: that wall time
less the simulator's (a chain that keeps up lags by its latency and the fusion's
reordering window, one that does not by a growing backlog); the host's load. Nothing lost, from the services'
counters (their control replies) and the simulator's own count (sim/status
`published`, less its truth messages, counted here by key): the plotters took in every
plot message the simulator published, each elementary tracker one report per plot
message of its base, global fusion every tracker's report, and no service missed a
sample (publisher stamps) or rejected one (too_late included). Exit 1 when a report is
lost or the chain lags by more than --max-lag s (it does not keep up with real time:
at 0.95 x real time a 120 s scene lags by 6 s); global fusion's progress is then printed.
"""

from __future__ import annotations

import argparse
import sys
import tempfile
import threading
import time
from collections import Counter
from pathlib import Path
from typing import Any

REPO = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(REPO))

from benchmarks.network_scene import scene_toml  # noqa: E402
from benchmarks.procstat import cpu_seconds, host_load  # noqa: E402
from common.bus import control  # noqa: E402
from common.bus.local_run import ROOT, Deployment  # noqa: E402
from common.deploy.config import load  # noqa: E402
from common.wire import protocol  # noqa: E402

KINDS = ("channel-plotter", "elementary-tracker", "global-fusion")
SERVICE = {"channel-plotter": "channel_plotter", "elementary-tracker": "elementary_tracker",
           "global-fusion": "global_fusion"}


class SimCount:
    """Samples of root/sim/** counted by key in a tiny callback (no decoding), and the
    simulator's sim/status payload."""

    def __init__(self) -> None:
        self.n: Counter[str] = Counter()
        self.status: bytes | None = None
        self.lock = threading.Lock()

    def on_sample(self, sample: Any) -> None:
        key = str(sample.key_expr)
        with self.lock:
            self.n[key] += 1
        if key.endswith("/sim/status"):
            self.status = sample.payload.to_bytes()


class CpuWatch:
    """The last CPU seconds read of each child (a finished one keeps its last reading)."""

    def __init__(self, children: dict[str, int]) -> None:
        self.pids = children
        self.start = {n: cpu_seconds(p) for n, p in children.items()}
        self.last = dict(self.start)

    def poll(self) -> None:
        for name, pid in self.pids.items():
            try:
                self.last[name] = cpu_seconds(pid)
            except (FileNotFoundError, ProcessLookupError):
                continue

    def used(self, prefix: str) -> float:
        return sum(self.last[n] - self.start[n] for n in self.pids if n.startswith(prefix))


def losses(states: dict[tuple[str, str], dict[str, Any]], plots: int, bases: list[str]) -> list[str]:
    """What the counters say was lost (module doc); empty: nothing."""
    out = []
    for (svc, inst), m in sorted(states.items()):
        out += [f"{svc}/{inst} missed {k}: {v}" for k, v in m["missed"].items() if v]
        out += [f"{svc}/{inst} rejected {k}: {v}" for k, v in m["rejected"].items() if v]
    plotter = {b: states.get(("channel_plotter", b), {}).get("in", 0) for b in bases}
    tracker = {b: states.get(("elementary_tracker", b), {}).get("in", 0) for b in bases}
    if sum(plotter.values()) != plots:
        out.append(f"plotters took in {sum(plotter.values())} of {plots} plot messages")
    out += [f"tracker {b}: {tracker[b]} reports of {plotter[b]} plot messages" for b in bases
            if tracker[b] != plotter[b]]
    fused = states.get(("global_fusion", "main"), {}).get("in")
    if fused is not None and fused != sum(tracker.values()):
        out.append(f"global fusion took in {fused} of {sum(tracker.values())} etracks reports")
    return out


def run(args: argparse.Namespace, tmp: Path) -> tuple[list[str], list[str]]:
    """One run (module doc); returns (table lines, what was lost or why it failed)."""
    scene = tmp / f"network_goals_{args.aircraft}.toml"
    scene.write_text(scene_toml(args.aircraft, seed=args.seed, duration=args.duration))
    cfg = load(scene)
    bases = [b.id for b in cfg.bases]
    fail: list[str] = []
    with Deployment(tmp) as d:
        sim_count = SimCount()
        sub = d.session.declare_subscriber(f"{ROOT}/sim/**", sim_count.on_sample)
        alive = d.start_services(scene, KINDS)
        d.wait_alive(alive, timeout=120.0)
        d.announce()
        watch = CpuWatch({"router": d.router.proc.pid} | {c.name: c.proc.pid for c in d.children})
        load0 = host_load()
        sim = d.start("simulate", "simulate", "--config", str(scene), "--scenario", str(scene),
                      "--seed", str(args.seed), "--wait-alive", "test/collector", "--speed",
                      repr(args.speed), *[a for n in alive for a in ("--wait-alive", n)])
        watch.pids["simulate"] = sim.proc.pid
        watch.start["simulate"] = watch.last["simulate"] = cpu_seconds(sim.proc.pid)
        wall0 = time.monotonic()
        while sim.alive():
            watch.poll()
            time.sleep(0.5)
        sim_wall = time.monotonic() - wall0
        if sim.proc.returncode != 0 or sim_count.status is None:
            raise RuntimeError(f"simulator exited with {sim.proc.returncode} (logs: {tmp})")
        status = protocol.unpack(sim_count.status)
        truth = sum(n for k, n in sim_count.n.items() if "/sim/truth/" in k)
        plots = int(status["published"]) - truth
        deadline = time.monotonic() + args.max_lag
        states: dict[tuple[str, str], dict[str, Any]] = {}
        done = False
        while True:
            watch.poll()
            # one query at a time, alive until the deadline: it waits in global fusion's
            # queue behind the reports, and a reply to an expired query counts as its error
            states |= control.states(d.session, ROOT, timeout=max(deadline - time.monotonic(), 1.0))
            want = sum(states.get(("elementary_tracker", b), {}).get("in", -1) for b in bases)
            plot_in = sum(states.get(("channel_plotter", b), {}).get("in", -1) for b in bases)
            done = plot_in == plots and states.get(("global_fusion", "main"), {}).get("in") == want
            if done:
                break
            if time.monotonic() > deadline:
                fusion = states.get(("global_fusion", "main"), {})
                fail.append(f"not done {args.max_lag:g} s after the scene's end: global fusion took in "
                            + (f"{fusion['in']} of {want} reports, at t = {fusion['t']:.1f} s" if fusion
                               else "an unknown part of the reports (no control reply: its queue)"))
                break
            time.sleep(0.5)
        wall = time.monotonic() - wall0
        watch.poll()
        if wall - sim_wall > args.max_lag and not fail:
            fail.append(f"global fusion took in the last report {wall - sim_wall:.1f} s after the simulator's end")
        load1 = host_load()
        fail += losses(states, plots, bases)
        sub.undeclare()
    scene_s = args.duration
    cpu = {k: watch.used(k) for k in (*KINDS, "simulate", "router")}
    total = sum(cpu.values())
    lines = [f"{args.aircraft} aircraft, {len(bases)} bases, {scene_s:g} s scene at {args.speed:g} x real "
             f"time, seed {args.seed}: {plots} plot messages, simulator {sim_wall:.1f} s wall",
             f"{'process':>19} {'n':>3} {'cpu s':>8} {'cpu s / scene s':>15}"]
    for k in (*KINDS, "simulate", "router"):
        n = sum(1 for name in watch.pids if name.startswith(k))
        lines.append(f"{k:>19} {n:>3} {cpu[k]:>8.1f} {cpu[k] / scene_s:>15.3f}")
    lines += [f"{'all':>19} {len(watch.pids):>3} {total:>8.1f} {total / scene_s:>15.3f}",
              f"cores busy: {total / scene_s:.2f} of 2 (CPU s per scene s at 1 x real time)",
              (f"wall until global fusion took in the last report: {wall:.1f} s, "
               f"{wall - sim_wall:.1f} s after the simulator's end (its lag)" if done else
               f"global fusion not done {wall - sim_wall:.1f} s after the simulator's end"),
              f"before: {load0}; after: {load1}"]
    return lines, fail


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser()
    ap.add_argument("--aircraft", type=int, default=300)
    ap.add_argument("--seed", type=int, default=1)
    ap.add_argument("--duration", type=float, default=120.0, help="scene seconds")
    ap.add_argument("--speed", type=float, default=1.0, help="simulator pace, times real time")
    ap.add_argument("--max-lag", type=float, default=5.0,
                    help="s after the simulator's end by which global fusion must have every report")
    a = ap.parse_args(argv)
    logs = Path(tempfile.mkdtemp(prefix="network-chain-"))
    lines, fail = run(a, logs)
    print("\n".join(lines))
    print(f"logs of every process: {logs}")
    print("lost or late:", "; ".join(fail) if fail else "nothing")
    print("goal: >= 1 x real time, nothing lost:", "FAILED" if fail else "met")
    return 1 if fail else 0


if __name__ == "__main__":
    sys.exit(main())
