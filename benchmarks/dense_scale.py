"""Radar at scale (issue 14): the in-process chain on the dense scenes, one table row per
target density; exit code 1 when a quality goal of the issue fails.

Run: .venv/bin/python benchmarks/dense_scale.py [--scenes dense dense300 dense1000]
     [--scans N] [--seed N] [--profile]

Each scene (scenarios/<name>.toml, written by benchmarks/dense_scene.py) goes through
common.wire.radar_chain's cores in one process: simulator, channel plotter and
elementary tracker of every base, global fusion, with the wall time of each service per
scan (CPU of this process; the services are separate processes in a deployment, so these
are the per-service costs). Quality of the confirmed global tracks against the truth
after a 30 s warm-up (GOSPA assignment, cut-off 2 km): missed targets and false tracks
per scan (as % of the targets present), number switches and breaks per 100 targets over
the run, RMSE / PCRLB (median over targets) and mean position NEES (3 dof). The log-log
slope of each service's cost against the number of targets is printed when several
scenes run.

Goals (issue 14, checked for scenes of >= 300 targets): missed < 2 % and false < 1 % per
scan, switches < 1 per 100 targets, RMSE/PCRLB <= 1.5, mean NEES within a factor 1.5 of
the dimension (2-4.5 for the 3-D position).

Measured 2026-11-23 (seed 1, 120 s, 2 shared cores at load 10-27; CPU ms per scan):

  scene      targets plotter tracker fusion x real  missed       false        switch breaks RMSE/PCRLB NEES
  before (the fusion of 0cd7502):
  dense          120     6.3    12.7   73.7   10.8  0.6 (0.5%)   1.6 (1.4%)    1.67   5.00   0.92     3.08
  dense300       300     9.3    22.1  167.2    5.0  2.6 (0.9%)   4.4 (1.6%)    6.33   4.00   0.97     3.82
  dense1000     1000    23.9    72.2  867.5    1.0 76.5 (8.2%) 113.2 (12.2%)  58.20  22.20   2.36    66.91
  after (typed arrays, closed-form SLR, 004 on confirmed tracks, duplicate merge):
  dense          120     6.7    13.8   57.0   12.9  0.6 (0.5%)   1.0 (0.9%)    0.00   5.00   0.92     3.07
  dense300       300     8.9    21.6  116.8    6.8  1.5 (0.5%)   2.1 (0.8%)    1.00   3.00   0.92     3.77
  dense1000     1000    23.0    69.8  442.4    1.9 11.3 (1.2%)  29.6 (3.2%)    9.00   4.80   1.01     7.71
  log-log slope of the cost per scan, 120 -> 1000 targets: plotter 0.59, tracker 0.77,
  fusion 0.97. Failing goals: dense300 switches 1.00 (< 1 asked); dense1000 false
  3.2 %, switches 9 per 100 targets, NEES 7.7 (its false tracks: 80 % hold one target's
  elementary tracks with the altitude 2-3 km off at sigma_z ~ 165 m).

Measured 2026-11-26 (seed 1, 120 s, 2 shared cores at load 1.5-8; CPU ms per scan; two
interleaved runs each, the faster; every gtracks message of both scenes is identical bit
for bit before and after, hence the same quality columns):

  scene      targets plotter tracker fusion x real  missed       false        switch breaks RMSE/PCRLB NEES
  before (a5ff39b):
  dense          120     2.1     3.9   18.3   41.0  0.6 (0.5%)   1.0 (0.9%)    0.00   5.00   0.92     3.07
  dense300       300     3.0     6.7   44.2   18.5  1.5 (0.5%)   2.1 (0.8%)    1.00   3.00   0.92     3.77
  after (block pruning by Taylor bounds over the leaf centres, children tested per
  parent; one call over all bases for the decorrelation, the gate [48] and the v_b
  rows; the gate by the heaviest component first; norm3; IMM mixing and band moments
  of live bands only; connected components of the plotter in numpy; gtracks by tolist):
  dense          120     1.4     3.8   12.3   57.2  0.6 (0.5%)   1.0 (0.9%)    0.00   5.00   0.92     3.07
  dense300       300     2.4     6.8   27.0   27.6  1.5 (0.5%)   2.1 (0.8%)    1.00   3.00   0.92     3.77
  This machine runs the chain about 3.2x faster than the one of 2026-11-23 (dense
  before: 41.0x real here, 12.9x there). End to end 1.40x on dense (fusion -33 %),
  1.49x on dense300 (fusion -39 %): about 18x real on the 2026-11-23 machine, short of
  issue 14's 20x there; 57x here.

Measured 2026-11-26, ghost tracks (seed 1, 120 s, 2 shared cores, two scenes at a time;
CPU ms per scan):

  scene      targets plotter tracker fusion x real  missed       false        switch breaks RMSE/PCRLB NEES
  before (304645d):
  dense          120     1.8     4.7   14.6   47.6  0.6 (0.5%)   1.0 (0.9%)    0.00   5.00   0.92     3.07
  dense300       300     3.0     8.4   31.9   23.1  1.5 (0.5%)   2.1 (0.8%)    1.00   3.00   0.92     3.77
  dense1000     1000     9.1    27.3  110.3    6.8 11.3 (1.2%)  29.6 (3.2%)    9.00   4.80   1.01     7.71
  after b1fc412 (duplicates in measurement space: a track whose elementary tracks another
  track explains, common.radar.global_merge):
  dense          120     1.6     4.3   13.8   50.9  0.6 (0.5%)   1.0 (0.9%)    0.00   5.00   0.92     3.07
  dense300       300     2.8     7.4   29.2   25.3  1.5 (0.5%)   2.1 (0.8%)    1.00   3.00   0.92     3.77
  dense1000     1000     8.2    24.3  105.2    7.3 11.3 (1.2%)  13.4 (1.4%)    7.40   5.20   0.98     7.53
  after (and a track of two targets' elementary tracks, each explained by another track,
  deleted: global_merge.explained):
  dense          120     1.5     3.9   12.8   55.1  0.6 (0.5%)   1.0 (0.9%)    0.00   5.00   0.92     3.07
  dense300       300     2.3     6.5   27.5   27.5  1.5 (0.5%)   2.1 (0.8%)    0.67   3.00   0.92     3.77
  dense1000     1000     7.9    23.5   99.6    7.6  8.7 (0.9%)   8.0 (0.9%)    7.70   5.20   0.99     6.02
  The false tracks of dense1000 (global_merge's module doc): pairs of two targets'
  elementary tracks at one azimuth, located at a fictitious altitude with sigma_z
  50-250 m, then holding one or both targets' bases there. Goals now met: dense300
  switches (0.67), dense1000 missed 0.9 % and false 0.9 %. Still failing: dense1000
  switches 7.7 per 100 targets and NEES 6.0; its breaks went 4.8 -> 5.2. Tried and
  not kept: a joint coherence test (ranges, azimuths and bistatic velocities of all
  members) of module 62's step 5: dense1000 false 3.1 -> 2.4 % over 60 s, but
  dense300 RMSE/PCRLB 0.92 -> 0.93 and NEES 3.77 -> 3.78.

Measured 2026-11-26, number switches of dense1000 (seed 1, 120 s, 2 shared cores; the
elementary tracks labelled with the truth projected into their base, each switch with
the fusion events before it). Of the 77 switches (35 in the 30 s warm-up, which the
switch count includes): 41 are flip-flops of 7 pairs of tracks on two aircraft 0.2-1 km
apart in plan, each track holding its own target's elementary tracks with 20-100 m plan
error but 0.2-1.3 km altitude error, so the 3-D GOSPA assignment crosses over and back
(one pair: 16); 8 a target first scored on a neighbour's or a mixed track, then on its
own new track (t = 6-17 s, one at 61 s); 16 the track matched to the target removed by
global_merge.explained (8 dissolved two-target tracks, 8 merged, 7 of them into the
target's new track); 3 a track deleted after coasting and replaced; 9 after breaks or
other swaps. 73 of the 77 had another aircraft within 2 km in plan. Fix of the merged
ones (global_merge.number_kept): a tentative track that explains a confirmed one takes
its number:

  scene      targets plotter tracker fusion x real  missed       false        switch breaks RMSE/PCRLB NEES
  after:
  dense          120     1.4     3.6    12.5   57.2  0.6 (0.5%)   1.0 (0.9%)    0.00   5.00   0.92     3.07
  dense300       300     2.3     6.7    27.5   27.4  1.5 (0.5%)   2.1 (0.8%)    0.67   3.00   0.92     3.77
  dense1000     1000     7.8    22.9    98.6    7.7  8.7 (0.9%)   8.0 (0.9%)    7.10   5.20   0.99     6.02
  Every other quality column equal to full precision (dense, dense300: the same
  gtracks); dense1000 switches 7.7 -> 7.1 (2 of the 16 left). Moving the confirmation
  with the number (the track reported at once): switches 7.1 and breaks 4.6, but false
  7.967 -> 7.978 per scan and NEES 6.0245 -> 6.0261; not kept. The flip-flops of close
  pairs (more than half) come from the altitude error of one receiver's geometry.

Measured 2026-11-26, ambiguous memberships (seed 1 unless said, 120 s, 2 shared cores; CPU
ms per scan). Traced first (every elementary track against the truths): two aircraft
540 m apart in plan, 1.7 km in altitude; at t = 5 s base b2's elementary tracks swapped
and both global tracks, 2 s old, took the other aircraft's (range-rate 8-10 sigma off
the truth, inside [48] of a young track); the bands collapsed to one 0.6-1.1 km off with
sigma_z 190-340 m, which the other three bases (ranges within 1 sigma of the truth at
both altitudes) never corrected: NEES 10-170, then 28 switches of that pair. Fix
(common.radar.global_assoc.ambiguous_members): a base whose elementary tracks of two
tracks pass [48] against each other's track is used by neither this scan.

  scene      targets plotter tracker fusion x real  missed       false        switch breaks RMSE/PCRLB NEES
  before (62f13e8):
  dense1000     1000     8.2    24.5    98.4    7.6   8.7 (0.9%)   8.0 (0.9%)    7.10   5.20   0.99     6.02
  dense1000 s2  1000     7.9    23.5    97.2    7.8  14.3 (1.5%)  16.0 (1.7%)    7.10   5.60   1.01     4.72
  after:
  dense          120     1.6     4.3    15.5   46.7   0.6 (0.5%)   1.0 (0.9%)    0.00   5.00   0.92     3.09
  dense300       300     2.6     7.3    32.2   23.8   1.5 (0.5%)   2.1 (0.8%)    0.67   3.00   0.92     3.23
  dense1000     1000     8.2    24.6   113.8    6.8   8.4 (0.9%)   7.5 (0.8%)    4.70   4.90   0.99     3.36
  dense1000 s2  1000     8.0    24.1   110.2    7.0  12.4 (1.3%)  13.5 (1.4%)    3.80   4.10   1.01     3.25
  (dense and dense300 before: NEES 3.07 and 3.77, every other quality column equal.)
  The 47 switches left (seed 1): 35 trade two truths between two live tracks, 19 of
  them by t = 15 s; in 10 of those the track that lost the truth is still consistent
  with it (position NEES <= 11.3, chi-square 3 dof at 0.99): two aircraft under 1 km
  apart in plan whose honest altitude sigma is 0.5-1.1 km, which the Euclidean 3-D
  assignment of the scoring trades (e.g. t = 9 s: truth 67 at NEES 0.6 from its track,
  moved to a track at NEES 254 because the pair's summed squared errors were smaller).
  The rest: a target first scored on a neighbour's track and then on its own (young)
  track, and 8 track replacements (a track lost, a new one started).
  Then a scan counts towards confirmation only when the track was located (module 64's
  chi-square test passed; a track of two targets' elementary tracks fails it):
  dense1000     1000     7.7    23.1   108.9    7.2   8.4 (0.9%)   7.4 (0.8%)    4.40   4.70   0.99     3.36
  dense1000 s2  1000     7.6    22.7   104.6    7.4  12.4 (1.3%)  12.5 (1.3%)    3.60   3.90   1.01     3.25
  (dense and dense300: every quality column unchanged.)
  Tried and not kept (measured before this fix): q_z 0.1 and 0.01 m^2/s^3 (more altitude integration): switches
  7.1 -> 7.7, 8.3; stricter confirmation (confirm_cycles 5, 8; confirm_bases 3):
  switches 5.4, 5.0, 5.5 but missed 1.2, 1.6, 1.1 %.
"""

from __future__ import annotations

import argparse
import cProfile
import pstats
import sys
import time
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from common.deploy.config import parse, section
from common.evaluation.pcrlb import Evaluation, score_targets
from common.radar.global_fusion import FusionParams
from common.sim.simulator import load_scenario, run_scenario
from common.wire.radar_chain import RadarChain
from common.wire.radar_messages import gtracks_message, plots_of

REPO = Path(__file__).resolve().parents[1]
WARMUP = 30.0
GATE_C = 2000.0


@dataclass
class Row:
    """One scene's measurements."""

    name: str
    targets: int
    scans: int
    ms: dict[str, float]
    missed: float
    false: float
    switches: float
    breaks: float
    rmse_ratio: float
    nees: float
    present: float

    def goals(self) -> list[str]:
        """The issue's quality goals this row fails (empty: all met)."""
        bad = []
        if self.missed >= 0.02 * self.present:
            bad.append(f"missed {self.missed:.1f} per scan >= 2 % of {self.present:.0f}")
        if self.false >= 0.01 * self.present:
            bad.append(f"false {self.false:.1f} per scan >= 1 % of {self.present:.0f}")
        if self.switches >= 1.0:
            bad.append(f"switches {self.switches:.2f} per 100 targets >= 1")
        if self.rmse_ratio > 1.5:
            bad.append(f"RMSE/PCRLB {self.rmse_ratio:.2f} > 1.5")
        if not 3 / 1.5 <= self.nees <= 3 * 1.5:
            bad.append(f"mean position NEES {self.nees:.2f} outside [2, 4.5]")
        return bad


def run(name: str, seed: int, scans: int | None, fusion: dict[str, Any] | None = None) -> Row:
    """The chain on scenarios/<name>.toml, scored; `fusion`: keys of [radar.fusion] set
    over the file's (benchmarks/seed_vs_mixture.py)."""
    import tomllib

    from common.evaluation.pcrlb import base_information
    from common.sim.scenario import radar_scene
    from common.wire.sim_messages import truth_state

    path = Path(name) if name.endswith(".toml") else REPO / "scenarios" / f"{name}.toml"
    name = path.stem
    doc = tomllib.loads(path.read_text())
    doc.setdefault("radar", {}).setdefault("fusion", {}).update(fusion or {})
    cfg = parse(doc, path)
    scn = load_scenario(doc)
    chain = RadarChain(cfg)
    cost = {"plotter": 0.0, "tracker": 0.0, "fusion": 0.0}
    ev = Evaluation(c=GATE_C, gamma=GATE_C)
    missed, false, present, n_scans = [], [], [], 0
    for t, msgs in run_scenario(scn, cfg.bases, [], seed, scans):
        n_scans += 1
        truth = next(m for k, m in msgs if k == "sim/truth/radar")
        out = []
        for key, msg in msgs:
            if not key.startswith("radar/plots/"):
                continue
            base = msg["base"]
            t0 = time.process_time()
            fused = chain.plotters[base].push(msg["channel"], msg["t"], plots_of(msg))
            t1 = time.process_time()
            cost["plotter"] += t1 - t0
            for tf, f in fused:
                tracks = chain.trackers[base].step(tf, f)
                t2 = time.process_time()
                cost["tracker"] += t2 - t1
                out += [gtracks_message(g) for g in chain.fusion.push(base, tracks)]
                t1 = time.process_time()
                cost["fusion"] += t1 - t2
        g = next((m for m in out if m["t"] == t), {"tracks": []})
        conf = [k for k in g["tracks"] if k["status"] == "confirmed"]
        ev.add(t, np.asarray(truth["id"]), truth_state(truth),
                     np.array([k["id"] for k in conf], dtype=np.int64),
                     np.array([k["x"] for k in conf]).reshape(-1, 6),
                     np.array([k["P"] for k in conf]).reshape(-1, 6, 6))
        res = ev.metrics.gospa_series[-1]
        if t >= WARMUP:
            n_truth = len(truth["id"])
            present.append(n_truth)
            missed.append(n_truth - res.rows.size)
            false.append(len(conf) - res.rows.size)
    p = section(cfg, "radar.fusion", FusionParams)
    sc = score_targets(ev, np.array([b.tx for b in cfg.bases]), np.array([b.rx for b in cfg.bases]),
                       base_information(radar_scene(cfg), cfg.bases), p.q, p.q_z, np.diag([1e6, 1e4, 1e6, 1e4, 1e6, 1e2]), WARMUP)
    s = ev.metrics.summary()
    n_t = len(ev.truth)
    ratio = np.array([v.rmse / v.bound for v in sc.values()])
    nees = np.array([v.nees_pos for v in sc.values()])
    return Row(name, n_t, n_scans, {k: 1e3 * v / n_scans for k, v in cost.items()},
               float(np.mean(missed)), float(np.mean(false)), 100.0 * s.switches / n_t,
               100.0 * s.breaks / n_t, float(np.median(ratio)), float(np.mean(nees)),
               float(np.mean(present)))


def table(rows: list[Row]) -> list[str]:
    """The per-density table of issue 14 (costs: ms of CPU per scan, all bases)."""
    out = [f"{'scene':<10} {'targets':>7} {'plotter':>8} {'tracker':>8} {'fusion':>8} {'x real':>7} "
           f"{'missed':>12} {'false':>12} {'switch':>7} {'breaks':>7} {'RMSE/PCRLB':>10} {'NEES':>6}",
           f"{'':<10} {'':>7} {'ms/scan':>8} {'ms/scan':>8} {'ms/scan':>8} {'':>7} "
           f"{'per scan':>12} {'per scan':>12} {'/100 tg':>7} {'/100 tg':>7} {'median':>10} {'pos':>6}"]
    for r in rows:
        total = sum(r.ms.values())
        out.append(f"{r.name:<10} {r.targets:>7} {r.ms['plotter']:>8.1f} {r.ms['tracker']:>8.1f} "
                   f"{r.ms['fusion']:>8.1f} {1e3 / total:>7.1f} "
                   f"{r.missed:>5.1f} ({100 * r.missed / r.present:4.1f}%) "
                   f"{r.false:>5.1f} ({100 * r.false / r.present:4.1f}%) {r.switches:>7.2f} "
                   f"{r.breaks:>7.2f} {r.rmse_ratio:>10.2f} {r.nees:>6.2f}")
    if len(rows) >= 2:
        n = np.log([r.targets for r in rows])
        slopes = {k: np.polyfit(n, np.log([r.ms[k] for r in rows]), 1)[0] for k in rows[0].ms}
        out.append("log-log slope of the cost per scan against targets: "
                   + ", ".join(f"{k} {v:.2f}" for k, v in slopes.items()))
    return out


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--scenes", nargs="+", default=["dense", "dense300", "dense1000"],
                    help="names in scenarios/ or paths of .toml files")
    ap.add_argument("--scans", type=int, default=None, help="default: the whole scenario")
    ap.add_argument("--seed", type=int, default=1)
    ap.add_argument("--profile", action="store_true", help="cProfile of the run, by cumulative time")
    args = ap.parse_args()
    rows = []
    for name in args.scenes:
        if args.profile:
            prof = cProfile.Profile()
            rows.append(prof.runcall(run, name, args.seed, args.scans))
            pstats.Stats(prof).sort_stats("tottime").print_stats(25)
        else:
            rows.append(run(name, args.seed, args.scans))
        print("\n".join(table(rows[-1:])[2:]), flush=True)
    print("\n".join(table(rows)))
    fail = [f"{r.name}: {g}" for r in rows if r.targets >= 300 for g in r.goals()]
    for f in fail:
        print(f"FAIL {f}")
    return 1 if fail else 0


if __name__ == "__main__":
    sys.exit(main())
