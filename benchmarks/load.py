"""Load benchmark: the dense scenario's radar chain at 10x its real-time rate for 60 s of
wall time; no scan may be lost; end-to-end and per-service latencies.

Real processes: a ``pfusion router``, the radar services of ``scenarios/dense.toml`` (120
aircraft, 4 bases with 15 channels in all: 4 channel plotters, 4 elementary trackers,
global fusion) and ``pfusion simulate --speed X``, each a child process on a free loopback
port (``common.bus.local_run.Deployment``). 60 s at 10x are 600 scans of 1 s: the scenario's 120 s
back to back five times (``--repeat 5``, seeds 1-5), so the air picture stays dense.

Lost: a scan time of the input missing from any base's fused plots or elementary tracks
or from the global tracks, a sample missed by the stamps (the services' ``missed``
counters and this collector's) or an input rejected. Latency, from this collector's
reception wall times (one clock): plots -> global tracks = arrival of a scan's global
tracks - arrival of its first channel plots (the simulator publishes a scan's plots at
once); per stage, the plotter (first plots -> fused plots of its base), the elementary
tracker (fused -> elementary tracks) and global fusion (last base's elementary tracks ->
global tracks); and the services' own handling time per input (their p50/p99 counters).
Kept up: the last scan's global tracks arrived within 1 s + 5 % of the input's wall
duration after its first plots (no backlog piled up).
Exit code 1 if anything was lost or the chain did not keep up.

Measured 2026-11-23 (2 shared cores): 10x: nothing lost but global fusion fell behind (last
scan 59.6 s late, end to end p50 48 s); 6x (idle machine) and 4x (load ~6) kept up, nothing
lost, end to end p50 / p99 135 / 900 ms and 186 / 1675 ms.
After global fusion on typed arrays (etracks parsed in 1.1 ms instead of 9.0 ms, a steady
dense.toml cycle 74 -> 48 ms of CPU in-process, benchmarks/dense_scale.py): 10x, nothing
lost, but still behind while other work shared the 2 cores: last scan 13 s late at load
average 6.5-9 (fusion handling p99 196 ms), 35 s late at load 13-16 (p99 235 ms); at
load 4.5-5 it kept up: 0 lost, last scan 0.08 s after its plots, end to end p50 / p99
80 / 1316 ms (the p99: the cycles that initialise a run's 120 tracks, ~3 s of module 62
block localisation each), fusion handling p99 100 ms. At load ~14 another run lost
samples at this collector (blocked over the router's 1 s limit while CPU-starved).
On an otherwise idle machine (2026-11-23, session 6, after the tracker and fusion work of
session 5): 10x, 600 scans in 59.9 s, 0 lost, 0 missed, 0 rejected, last scan's global
tracks 0.06 s after its plots (kept up), end to end p50 / p99 77 / 960 ms (plotter 16 / 36,
tracker 12 / 26, fusion 46 / 904 ms; the p99 again the cycles that initialise a run's
tracks), fusion handling p50 / p99 1.3 / 85 ms.

2026-11-26 (session 9, after the fusion speed-ups of benchmarks/dense_scale.py; 30 s at
each rate, load average 5-7 from other work; this machine ran the in-process chain ~3x
faster than the one above): 20x: 600 scans, kept up (last gtracks 0.03 s after its
plots), 0 lost, 0 missed, 0 rejected, end to end p50 / p99 33 / 335 ms; 30x: 960 scans,
kept up, 0 lost, 130 / 542 ms; 40x: 1200 scans, 0 lost, the last scan 2.3 s after its
plots (end to end p50 2.8 s: the ceiling is between 30x and 40x).
dense1000 (--scene dense1000, 1000 targets, 120 scans, idle machine, after the ghost
clean-up of common.radar.fusion.merge): 2x, 4x and 6x kept up (last gtracks 0.15-0.17 s
after its plots), 0 lost, 0 missed, 0 rejected; end to end p50 / p99 138 / 2740 ms,
136 / 3633 ms, 986 / 3830 ms (the p99: the cycles that initialise 1000 tracks; global
fusion handling p50 / p99 5 / 133 ms at 2x).
dense1000 at 2x again on 2026-11-26 (session 12: number succession in global fusion;
idle machine): kept up (last gtracks 0.12 s after its plots), 0 lost, 0 missed, 0
rejected; end to end p50 / p99 147 / 3111 ms; global fusion handling p50 / p99 5.3 / 148 ms.
Session 13 (the rebuild of contradicted tracks, common.radar.fusion.reopen; idle machine):
kept up (0.13 s), 0 lost, 0 missed, 0 rejected; end to end p50 / p99 173 / 3286 ms; global
fusion handling p50 / p99 7.4 / 188 ms.

Run: .venv/bin/python benchmarks/load.py [--speed X] [--seconds S] [--seed N] [--scene NAME]
"""

from __future__ import annotations

import argparse
import sys
import tempfile
import time
from pathlib import Path

import numpy as np
from soak import REPO, Observer, counters_table, failures, start_chain, wait_counters

from common.bus.local_run import Deployment
from common.deploy.config import load as load_config

RUN_SCANS = 120  # the dense scenes (dense, dense300, dense1000): 120 x 1 s
STALL_S = 30.0  # after the input: wait for the last global tracks while any arrive


def pct(x: list[float]) -> str:
    """'p50 / p99' in ms."""
    a = 1e3 * np.asarray(x)
    return f"{np.percentile(a, 50):8.1f} / {np.percentile(a, 99):8.1f}" if a.size else "       - /        -"


def load(speed: float, seconds: float, seed: int, scene: str = "dense") -> int:
    """Run the chain of scenarios/<scene>.toml at ``speed`` x real time for ``seconds`` of
    wall time; print the tables; return the exit code."""
    scene_path = REPO / "scenarios" / f"{scene}.toml"
    scans = int(round(speed * seconds))
    repeat = -(-scans // RUN_SCANS)  # whole runs of the scenario: seconds rounded up
    with tempfile.TemporaryDirectory() as tmp, Deployment(Path(tmp)) as d:
        pids = start_chain(d, scene_path)
        services = len(pids) - 1
        obs = Observer(d, ["radar/plots/**", "radar/fused/*", "radar/etracks/*", "radar/gtracks"])
        sim = d.start("simulate", "simulate", "--config", str(scene_path), "--scenario", str(scene_path),
                      "--seed", str(seed), "--speed", repr(speed), "--scans", str(min(scans, RUN_SCANS)),
                      "--repeat", str(repeat), "--wait-alive", "test/collector")
        while sim.alive():
            obs.drain(0.1)
        if sim.proc.returncode != 0:
            raise RuntimeError(f"simulator exited with {sim.proc.returncode}")
        plots = {}
        for suffix, by_t in obs.arrivals.items():
            if suffix.startswith("radar/plots/"):
                for t, at in by_t.items():
                    plots[t] = min(plots.get(t, np.inf), *at)
        expected = [float(k) for k in range(repeat * min(scans, RUN_SCANS))]  # dense: 1 s scans
        t_last = expected[-1]
        progress = (obs.t_max.get("radar/gtracks"), time.monotonic())
        while t_last not in obs.scans("radar/gtracks") and time.monotonic() - progress[1] < STALL_S:
            obs.drain(0.1)
            if obs.t_max.get("radar/gtracks") != progress[0]:
                progress = (obs.t_max.get("radar/gtracks"), time.monotonic())
        time.sleep(2.0)  # a late message of another key
        obs.drain()
        wait_counters(obs, services, time.monotonic())
        bases = [b.id for b in load_config(scene_path).bases]
        lost, missed, rejected = failures(obs, expected, "radar/gtracks")
        lost += len(set(expected) - set(plots))
        for stage in ("fused", "etracks"):
            for b in bases:
                lost += len(set(expected) - obs.scans(f"radar/{stage}/{b}"))
        obs.close()

    gt = {t: min(a) for t, a in obs.arrivals["radar/gtracks"].items() if t in plots}
    end_to_end = [gt[t] - plots[t] for t in expected if t in gt]
    plotter = [min(obs.arrivals[f"radar/fused/{b}"][t]) - plots[t] for b in bases for t in expected
               if t in plots and t in obs.arrivals.get(f"radar/fused/{b}", {})]
    tracker = [min(obs.arrivals[f"radar/etracks/{b}"][t]) - min(obs.arrivals[f"radar/fused/{b}"][t])
               for b in bases for t in expected
               if t in obs.arrivals.get(f"radar/etracks/{b}", {}) and t in obs.arrivals.get(f"radar/fused/{b}", {})]
    fusion = [gt[t] - max(min(obs.arrivals[f"radar/etracks/{b}"][t]) for b in bases) for t in expected
              if t in gt and all(t in obs.arrivals.get(f"radar/etracks/{b}", {}) for b in bases)]
    wall_in = max(plots.values()) - min(plots.values())
    backlog = gt.get(t_last, np.inf) - plots.get(t_last, np.inf)
    kept_up = backlog <= 1.0 + 0.05 * wall_in
    print(f"load: {scene_path.name} at {speed:g}x real time: {len(expected)} scans published in {wall_in:.1f} s "
          f"wall = {(len(plots) - 1) / wall_in:.1f} scans/s (seed {seed}, {repeat} runs of the scenario)")
    print(f"{'latency, ms':<44} {'p50 /      p99':>19}")
    print(f"{'plots -> global tracks (end to end)':<44} {pct(end_to_end)}")
    print(f"{'  channel plotter: plots -> fused':<44} {pct(plotter)}")
    print(f"{'  elementary tracker: fused -> etracks':<44} {pct(tracker)}")
    print(f"{'  global fusion: last etracks -> gtracks':<44} {pct(fusion)}")
    print("\n".join(counters_table(obs)))
    print("(out counts the counters published every 2 s too; p50/p99: handling time per input)")
    print(f"last scan's global tracks {backlog:.2f} s after its plots: "
          f"{'kept up' if kept_up else 'DID NOT KEEP UP (backlog)'}")
    print(f"lost scans {lost}, missed samples {missed}, rejected inputs {rejected}")
    if lost or missed or rejected:
        print("FAIL: scans lost, samples missed or inputs rejected")
    if not kept_up:
        print(f"FAIL: the chain did not keep up with {speed:g}x")
    return 1 if lost or missed or rejected or not kept_up else 0


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--speed", type=float, default=10.0, help="times the scenario's real-time rate")
    ap.add_argument("--seconds", type=float, default=60.0, help="wall time of the input")
    ap.add_argument("--seed", type=int, default=1)
    ap.add_argument("--scene", default="dense", help="scenarios/<scene>.toml: dense, dense300, dense1000")
    args = ap.parse_args()
    if args.speed <= 0 or args.speed * args.seconds < 2:
        ap.error("--speed must be > 0 and --speed x --seconds >= 2 scans")
    return load(args.speed, args.seconds, args.seed, args.scene)


if __name__ == "__main__":
    sys.exit(main())
