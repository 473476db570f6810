"""The fusion centre's update path with every aircraft held (issue 29 section 3,
docs/networks.md "Through the processes").

Run: PYTHONPATH=. .venv/bin/python benchmarks/network_update.py [--scenes 100 300 1000]
     [--seed 1] [--duration 120] [--cache DIR] [--profile N]

At 300 and 1000 aircraft initiation holds few aircraft (docs/networks.md, "Why 300
aircraft fail"), so the cost of the update path at those loads (steps 1-5 and 7 of
common.radar.network.fusion: decorrelation, clocks, prediction, gating, assignment, the
EKF update, bookkeeping, reports) cannot be read from the goals benchmark. Here one
tentative track per aircraft is opened from the truth (straight flights: the first
scan's states moved on at constant velocity; position sigma 100 m, velocity 5 m/s)
when the core has processed OPEN_AT s of reports (the elementary tracks confirmed),
and initiation and the merge are off (init_period 1e9 s, merge_distance 0): the tracks
take their members by the gate and GNN of step 3 and are confirmed by step 5. Fed the
recorded elementary tracks of benchmarks/network_centre.py (same cache) in this
process; prints per scene the core's CPU per report (mean, p99), x real time (scene s
per CPU s), the wire's CPU per report (decoding the etracks payloads, encoding the
radar/gtracks messages: what the service adds, less Zenoh) and x real time with it, and
the confirmed tracks and members at the end; with --profile N,
cProfile's N costliest functions (own time). Exit 1 when fewer than 95 % of the
aircraft are held by a confirmed track at the end (the path is broken).
"""

from __future__ import annotations

import argparse
import cProfile
import pstats
import sys
import tempfile
import time
from dataclasses import replace
from pathlib import Path

import numpy as np

REPO = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(REPO))

from benchmarks.network_centre import cached  # noqa: E402
from common.bus.recording import RecordReader  # noqa: E402
from common.core.track_table import Status  # noqa: E402
from common.deploy.config import load, section  # noqa: E402
from common.radar.elementary.tracker import ElementaryParams  # noqa: E402
from common.radar.fusion_core import Network  # noqa: E402
from common.radar.network.fusion import NetworkFusion  # noqa: E402
from common.radar.network.params import NetworkParams  # noqa: E402
from common.sim.scenario import load_scenario  # noqa: E402
from common.wire import protocol  # noqa: E402
from common.wire.radar_messages import etracks_of, gtracks_message  # noqa: E402
from common.wire.sim_messages import run_scenario, truth_state  # noqa: E402

P0 = np.diag([100.0**2, 5.0**2] * 3)
OPEN_AT = 5.0  # s after the first report


def first_truth(scene: Path, seed: int) -> tuple[float, np.ndarray]:
    """(t, states (n, 6)) of the scene's first truth message."""
    cfg = load(scene)
    for t, msgs in run_scenario(load_scenario(cfg.doc), cfg.bases, cfg.arrays, seed):
        for key, msg in msgs:
            if key == "sim/truth/radar":
                return t, truth_state(msg)
    raise ValueError(f"{scene}: no truth")


def run(scene: Path, rec: Path, seed: int, prof: cProfile.Profile | None
        ) -> tuple[NetworkFusion, list[float], float, int]:
    """The core on the recording with tracks opened from truth (module doc); returns it,
    its CPU s per report, the CPU s of the wire (decoding every etracks payload,
    encoding every radar/gtracks message) and the number of aircraft."""
    cfg = load(scene)
    params = replace(section(cfg, "radar.network", NetworkParams), init_period=1e9, merge_distance=0.0)
    shell = Network(cfg.bases, params, section(cfg, "radar.tracker", ElementaryParams))
    core = shell.core
    t0, X = first_truth(scene, seed)
    with rec.open("rb") as f:
        payloads = [r.payload for r in RecordReader(f)]
    c0 = time.process_time()
    reports = [etracks_of(p) for p in payloads]
    wire = time.process_time() - c0
    cost = []
    t_open: float | None = reports[0][1].t + OPEN_AT
    for base, tracks in reports:
        if t_open is not None and core.done >= t_open:
            for x in X:
                moved = x.copy()
                moved[0::2] += (core.done - t0) * x[1::2]
                core.tracks.open(core.done, moved, P0, [])
            t_open = None
        c0 = time.process_time()
        if prof is not None:
            prof.enable()
        out = shell.push(base, tracks, 0.0)
        if prof is not None:
            prof.disable()
        c1 = time.process_time()
        for g in out:
            protocol.encode(gtracks_message(g, cfg.origin))
        wire += time.process_time() - c1
        cost.append(c1 - c0)
    c0 = time.process_time()
    shell.flush()
    cost[-1] += time.process_time() - c0
    return core, cost, wire, len(X)


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser()
    ap.add_argument("--scenes", type=int, nargs="+", default=[100, 300, 1000])
    ap.add_argument("--seed", type=int, default=1)
    ap.add_argument("--duration", type=float, default=120.0)
    ap.add_argument("--cache", type=Path, default=Path(tempfile.gettempdir()) / "pfusion-network-centre")
    ap.add_argument("--profile", type=int, default=0, help="print the N costliest functions")
    a = ap.parse_args(argv)
    print(f"{'aircraft':>8} {'reports':>7} {'ms/report':>9} {'p99 ms':>7} {'x rt':>6} "
          f"{'wire ms':>7} {'x rt+wire':>9} {'confirmed':>9} {'members':>7}")
    ok = True
    for n in a.scenes:
        scene, rec, _, _ = cached(n, a.seed, a.duration, a.cache)
        prof = cProfile.Profile() if a.profile else None
        core, cost, wire, aircraft = run(scene, rec, a.seed, prof)
        c = np.array(cost) * 1e3
        conf = int(np.sum(core.tracks.status == Status.CONFIRMED))
        members = int(core.tracks.n_bases().sum())
        print(f"{n:>8} {c.size:>7} {c.mean():>9.2f} {np.percentile(c, 99):>7.1f} "
              f"{a.duration / max(c.sum() / 1e3, 1e-9):>6.1f} {1e3 * wire / c.size:>7.2f} "
              f"{a.duration / max(c.sum() / 1e3 + wire, 1e-9):>9.1f} {conf:>9} {members:>7}", flush=True)
        ok &= conf >= 0.95 * aircraft
        if prof is not None:
            pstats.Stats(prof).sort_stats("tottime").print_stats(a.profile)
    print("update path:", "holds the aircraft" if ok else "FAILED (aircraft not held)")
    return 0 if ok else 1


if __name__ == "__main__":
    sys.exit(main())
