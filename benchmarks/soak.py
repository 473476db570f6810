"""Soak benchmark: the radar chain for N scans (default 100,000) of a small scene, as fast
as it goes; the resident memory of every process must not grow by 10 % or more after the
warm-up, and no scan may be lost.

Real processes: a ``pfusion router`` and the radar services of ``scenarios/soak.toml``
(2 bases x 2 channels, 2 aircraft flying circles for ever: 2 channel plotters, 2 elementary
trackers, global fusion), each a child process on a free loopback port
(``common.bus.local_run.Deployment``). The scene's plots come from the simulator core
(``common.wire.sim_messages.run_scenario``, the same messages as ``pfusion simulate``),
published by this process with stamped reliable BLOCK publishers.

Pacing (deviation from ``pfusion simulate --speed 0``): BLOCK congestion control only
stops a publisher when the network buffers are full, and a service's inbox is an unbounded
queue, so an open-loop simulator faster than the chain would fill the services' inboxes and
the soak would measure that queue, not the services. Here scan k is published only once
the global tracks of scan k - WINDOW arrived: the chain runs as fast as its slowest service.

Resident memory: VmRSS of /proc/<pid>/status of every process, sampled every second, at
the end of the warm-up (the global tracks of the first 10 % of the scans received) and at
the end (after the last scan's global tracks and the services' next counters). Growth =
end / warm-up - 1. Lost: scans whose global tracks never arrived, samples missed by the
stamps (the services' ``missed`` counters and this collector's) and rejected inputs.
Exit code 1 if any process grows by >= 10 % or anything was lost or rejected.

Run: .venv/bin/python benchmarks/soak.py [--scans N] [--window W] [--seed S]
"""

from __future__ import annotations

import argparse
import dataclasses
import logging
import queue
import sys
import tempfile
import time
import tomllib
from pathlib import Path
from typing import Any

import zenoh

from common.bus.local_run import ROOT, Deployment
from common.bus.transport import LossCount, Publisher, attachment_of
from common.deploy.config import load
from common.sim.simulator import load_scenario
from common.wire import protocol
from common.wire.sim_messages import run_scenario

REPO = Path(__file__).resolve().parents[1]

SCENE = REPO / "scenarios" / "soak.toml"
RADAR = ("channel-plotter", "elementary-tracker", "global-fusion")
MAX_GROWTH = 0.10
STALL_S = 10.0
METRICS_WAIT_S = 6.0


def rss_kib(pid: int) -> int:
    """VmRSS of a process in KiB (/proc/<pid>/status)."""
    for line in Path(f"/proc/{pid}/status").read_text().splitlines():
        if line.startswith("VmRSS:"):
            return int(line.split()[1])
    raise ValueError(f"no VmRSS for pid {pid}")


class Observer:
    """A collector on the chain: arrival wall time (stamped on reception) of every message
    on the watched keys per scan time, the stamps' losses, and the latest counters of
    every service."""

    def __init__(self, d: Deployment, keys: list[str]) -> None:
        self._q: queue.SimpleQueue[tuple[float, str, bytes, bytes | None]] = queue.SimpleQueue()
        self.losses = LossCount(logging.getLogger("observer"))
        self.metrics: dict[str, dict[str, Any]] = {}
        self.metrics_at: dict[str, float] = {}
        self.arrivals: dict[str, dict[float, list[float]]] = {}
        self.t_max: dict[str, float] = {}
        self._subs = [d.session.declare_subscriber(f"{ROOT}/{k}", self._on_sample)
                      for k in [*keys, "metrics/**"]]
        d.announce()

    def _on_sample(self, sample: zenoh.Sample) -> None:
        self._q.put((time.monotonic(), str(sample.key_expr), sample.payload.to_bytes(),
                     attachment_of(sample)))

    def drain(self, timeout: float = 0.0) -> int:
        """Take everything received (waiting up to ``timeout`` for the first); returns the
        number of messages taken."""
        n = 0
        while True:
            try:
                at, key, payload, attachment = self._q.get(timeout=timeout) if n == 0 and timeout > 0 \
                    else self._q.get_nowait()
            except queue.Empty:
                return n
            n += 1
            self.losses.check(key, attachment)
            m = protocol.unpack(payload)
            suffix = key[len(ROOT) + 1:]
            if suffix.startswith("metrics/"):
                name = f"{m['service']}/{m['instance']}"
                self.metrics[name], self.metrics_at[name] = m, at
            else:
                t = float(m["t"])
                self.arrivals.setdefault(suffix, {}).setdefault(t, []).append(at)
                self.t_max[suffix] = max(t, self.t_max.get(suffix, t))

    def scans(self, suffix: str) -> set[float]:
        """Scan times seen on root/suffix."""
        return set(self.arrivals.get(suffix, {}))

    def close(self) -> None:
        for s in self._subs:
            s.undeclare()


def start_chain(d: Deployment, config: Path) -> dict[str, int]:
    """The router and the radar services of ``config``; returns {name: pid} once every
    service is alive."""
    alive = d.start_services(config, RADAR)
    d.wait_alive(alive)
    return {c.name: c.proc.pid for c in d.children} | {"router": d.router.proc.pid}


def wait_counters(obs: Observer, services: int, since: float) -> None:
    """Wait until every service published counters after ``since`` (metrics come every
    2 s), so that the final table counts everything."""
    deadline = time.monotonic() + METRICS_WAIT_S
    while time.monotonic() < deadline:
        obs.drain(0.1)
        if sum(at >= since for at in obs.metrics_at.values()) >= services:
            return
    raise TimeoutError(f"counters of {services} services not all received in {METRICS_WAIT_S} s")


def failures(obs: Observer, expected: list[float], out_key: str) -> tuple[int, int, int]:
    """(scans lost on out_key, samples missed by any stamp check, inputs rejected)."""
    lost = len(set(expected) - obs.scans(out_key))
    missed = sum(sum(m["missed"].values()) for m in obs.metrics.values()) + sum(obs.losses.missed.values())
    rejected = sum(sum(m["rejected"].values()) for m in obs.metrics.values())
    return lost, missed, rejected


def counters_table(obs: Observer) -> list[str]:
    """One line of counters per service (as ``pfusion status``)."""
    lines = [f"{'service':<30} {'in':>9} {'out':>9} {'rejected':>8} {'missed':>6} "
             f"{'p50 ms':>7} {'p99 ms':>7} {'queue':>5}"]
    for name, m in sorted(obs.metrics.items()):
        lines.append(f"{name:<30} {m['in']:>9} {m['out']:>9} {sum(m['rejected'].values()):>8} "
                     f"{sum(m['missed'].values()):>6} {m['p50_ms']:>7.2f} {m['p99_ms']:>7.2f} "
                     f"{m['queue']:>5}")
    return lines


def soak(scans: int, window: int, seed: int) -> int:
    """Run the soak; print the tables; return the exit code."""
    cfg = load(SCENE)
    scn = load_scenario(tomllib.loads(SCENE.read_text()))
    scn = dataclasses.replace(scn, duration=max(scn.duration, scans * scn.radar.scan_period))
    warm = max(1, scans // 10)
    period = scn.radar.scan_period
    with tempfile.TemporaryDirectory() as tmp, Deployment(Path(tmp)) as d:
        pids = start_chain(d, SCENE)
        obs = Observer(d, ["radar/gtracks"])
        time.sleep(0.3)  # let the subscriptions reach the router (as wait_alive does)
        pubs: dict[str, Publisher] = {}
        rss_warm: dict[str, int] = {}
        peak = {n: 0 for n in pids}
        expected: list[float] = []
        t0 = next_sample = last_progress = time.monotonic()
        t_warm, next_report, done, stalls = t0, warm, 0, 0

        def sample() -> dict[str, int]:
            """RSS of every process now; the peak counts samples after the warm-up."""
            now = {n: rss_kib(p) for n, p in pids.items()}
            if rss_warm:
                peak.update({n: max(peak[n], v) for n, v in now.items()})
            return now

        def pump(timeout: float) -> bool:
            """Take what arrived, sample RSS; True while the chain makes progress (global
            tracks of a later scan within STALL_S)."""
            nonlocal next_sample, next_report, last_progress, t_warm, rss_warm, done
            obs.drain(timeout)
            latest = obs.t_max.get("radar/gtracks")
            if latest is not None and round(latest / period) + 1 > done:
                done, last_progress = round(latest / period) + 1, time.monotonic()
            if not rss_warm and done >= warm:
                rss_warm, t_warm = sample(), time.monotonic()
                peak.update(rss_warm)
            if time.monotonic() >= next_sample:
                rss = sample()
                next_sample = time.monotonic() + 1.0
                if done >= next_report:
                    print(f"{done} scans, {time.monotonic() - t0:.0f} s, RSS MiB "
                          f"{ {n: round(v / 1024, 1) for n, v in rss.items()} }", file=sys.stderr)
                    next_report += warm
            for c in d.children:
                if not c.alive():
                    raise RuntimeError(f"{c.name} exited with {c.proc.returncode}")
            return time.monotonic() - last_progress <= STALL_S

        for k, (t, messages) in enumerate(run_scenario(scn, cfg.bases, cfg.arrays, seed, scans)):
            while k - done >= window:
                if not pump(0.05):  # an output lost on the way: counted at the end, go on
                    stalls, last_progress = stalls + 1, time.monotonic()
                    print(f"no global tracks for {STALL_S:.0f} s after scan {done}: "
                          f"publishing on", file=sys.stderr)
                    break
            for suffix, msg in messages:
                if suffix.startswith("radar/plots/"):
                    if suffix not in pubs:
                        pubs[suffix] = Publisher(d.session, f"{ROOT}/{suffix}")
                    pubs[suffix].put(protocol.encode(msg))
            expected.append(float(t))
            pump(0.0)
        while done < scans and pump(0.05):
            pass
        t_end = time.monotonic()
        wait_counters(obs, len(pids) - 1, time.monotonic())
        rss_end = sample()
        lost, missed, rejected = failures(obs, expected, "radar/gtracks")
        obs.close()

    growth = {n: rss_end[n] / rss_warm[n] - 1.0 for n in pids}
    wall = t_end - t0
    rate_after = (scans - warm) / (t_end - t_warm) if scans > warm else float("nan")
    print(f"soak: {scans} scans of {SCENE.name} (seed {seed}, window {window}) in {wall:.0f} s wall "
          f"= {scans / wall:.1f} scans/s ({rate_after:.1f} after warm-up); warm-up = first {warm} scans")
    print(f"{'process':<30} {'pid':>7} {'RSS warm-up MiB':>15} {'RSS end MiB':>11} "
          f"{'peak MiB':>8} {'growth %':>8}")
    for n in pids:
        print(f"{n:<30} {pids[n]:>7} {rss_warm[n] / 1024:>15.1f} {rss_end[n] / 1024:>11.1f} "
              f"{peak[n] / 1024:>8.1f} {100 * growth[n]:>8.2f}")
    print("\n".join(counters_table(obs)))
    print("(out counts the counters published every 2 s too; p50/p99: handling time per input)")
    print(f"lost scans {lost}, missed samples {missed}, rejected inputs {rejected}, "
          f"stalls {stalls} (no global tracks for {STALL_S:.0f} s)")
    grown = [n for n, g in growth.items() if g >= MAX_GROWTH]
    if grown:
        print(f"FAIL: resident memory grew by >= {100 * MAX_GROWTH:.0f} % in {', '.join(grown)}")
    if lost or missed or rejected:
        print("FAIL: scans lost, samples missed or inputs rejected")
    return 1 if grown or lost or missed or rejected else 0


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--scans", type=int, default=100_000)
    ap.add_argument("--window", type=int, default=4,
                    help="scans published ahead of the last global tracks received")
    ap.add_argument("--seed", type=int, default=1)
    args = ap.parse_args()
    zenoh.init_log_from_env_or("warn")  # this process's Zenoh warnings (link closed, lease)
    if args.scans < 10 or args.window < 1:
        ap.error("--scans must be >= 10 and --window >= 1")
    return soak(args.scans, args.window, args.seed)


if __name__ == "__main__":
    sys.exit(main())
