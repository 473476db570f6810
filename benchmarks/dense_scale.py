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
the run, counted on the trajectory GOSPA assignment minimised over the whole run
(common.evaluation.trajectory_gospa, gamma = 2 km: a truth changes track only when the
exchange pays for its switches), RMSE / PCRLB (median over targets) and mean position
NEES (3 dof), both over the pairs of that trajectory assignment (each truth against the
track that follows it; since session 13: before, the per-step GOSPA pairs, under which a
truth whose own track is a kilometre off in altitude, within its sigma, was scored
against a neighbour's track that one scan happened to bring nearer: seed 14's aircraft
833, position NEES 3249 against 2-5 on its own track; kept as the diagnostic column
"NEES step"). The log-log slope of each service's cost against the number of targets is
printed when several scenes run. Diagnostic columns (not goals): "step", the switches per
100 targets of the per-step GOSPA assignments (the upper bound used before 2026-11-26,
session 12: it crosses two correctly fed tracks whenever their honest altitude errors
bring each nearer the other aircraft for one scan); "origin" (benchmarks/origin_switches.py),
the number switches per 100 targets of the tracks labelled by the truth their elementary
tracks follow (association errors and track replacements); "cross", the switches per 100
targets at which the truth keeps that track (the scoring crossing correctly fed tracks);
">30 s" (since session 14), the switches per 100 targets of the same joint assignment at
scans after the warm-up only (the goal counts them over the whole run).

Goals (issue 14, checked for scenes of >= 300 targets): missed < 2 % and false < 1 % per
scan, switches < 1 per 100 targets, RMSE/PCRLB <= 1.5, mean NEES within a factor 1.5 of
the dimension (2-4.5 for the 3-D position).

Current (2026-11-26, session 16: as session 15 (trajectory GOSPA scoring and pairing; the
number succession of common.radar.fusion.succession; the rebuild and the vertical floor
of common.radar.fusion.reopen; the confirmation of FusionParams.confirm_cycles /
confirm_bases), and since session 16 the track segment association of
common.radar.fusion.segments, a published number never replaced
(common.radar.fusion.succession) and the rebuild's test on every confirmed track
(FusionParams.reopen_watch); 120 s; CPU ms per scan on 2 cores shared with other runs).
dense and dense300, seeds 1 and 2, then dense1000:

  scene      targets plotter tracker fusion x real  missed       false        switch breaks RMSE/PCRLB NEES  origin cross  step  NEES  >30 s
  dense          120      1.8      4.6     23.4    33.4   0.6 ( 0.6%)   0.2 ( 0.2%)    0.00    1.67       0.94   3.16    0.00   0.00   0.00   3.16   0.00
  dense300       300      3.2      8.4     49.7    16.3   1.6 ( 0.6%)   0.6 ( 0.2%)    0.00    1.33       0.92   3.17    0.00   0.00   0.67   3.18   0.00
  dense          120      1.7      4.4     22.5    35.0   0.7 ( 0.7%)   0.3 ( 0.2%)    0.83    1.67       0.94   2.87    0.83   0.00   0.83   2.87   0.83
  dense300       300      3.0      8.0     49.2    16.6   1.6 ( 0.6%)   0.5 ( 0.2%)    0.00    0.67       0.95   2.90    0.00   0.00   1.33   3.16   0.00
  dense1000, seeds 1-14 (the scene's aircraft, other noise):
  seed 1        1000      8.1     24.3    157.8     5.3   7.5 ( 0.8%)   1.9 ( 0.2%)    0.20    1.90       0.98   3.04    0.00   0.10   1.70   3.04   0.00
  seed 2        1000      8.1     24.1    152.9     5.4  11.4 ( 1.2%)   4.9 ( 0.5%)    0.00    2.00       1.00   3.07    0.00   0.00   2.30   3.08   0.00
  seed 3        1000      8.5     25.6    165.6     5.0   7.5 ( 0.8%)   2.2 ( 0.2%)    0.30    1.40       1.00   3.05    0.00   0.20   3.60   3.70   0.00
  seed 4        1000      8.5     25.6    157.9     5.2   8.0 ( 0.9%)   2.3 ( 0.2%)    0.20    3.20       1.00   3.04    0.30   0.10   3.60   3.28   0.10
  seed 5        1000      8.9     27.0    166.9     4.9   8.0 ( 0.9%)   2.6 ( 0.3%)    0.70    2.00       1.01   3.07    0.20   0.50   5.40   3.31   0.10
  seed 6        1000      8.8     26.8    164.4     5.0   9.1 ( 1.0%)   3.2 ( 0.3%)    0.10    2.30       0.98   3.32    0.10   0.00   4.30   3.82   0.00
  seed 7        1000      8.4     25.3    154.8     5.3  10.2 ( 1.1%)   5.5 ( 0.6%)    0.30    1.70       1.00   2.99    0.10   0.10   4.90   3.26   0.10
  seed 8        1000      8.2     24.5    161.9     5.1   7.9 ( 0.9%)   2.6 ( 0.3%)    0.50    2.30       0.98   3.97    0.50   0.10   6.90   4.38   0.30
  seed 9        1000      8.5     25.6    161.1     5.1   9.9 ( 1.1%)   3.9 ( 0.4%)    0.90    2.40       0.98   3.10    0.30   0.20   6.30   3.21   0.20
  seed 10       1000      8.2     24.6    155.0     5.3  10.1 ( 1.1%)   4.5 ( 0.5%)    0.30    2.20       0.99   2.99    0.10   0.00   5.60   3.16   0.00
  seed 11       1000      8.2     24.7    156.5     5.3   7.3 ( 0.8%)   1.7 ( 0.2%)    0.70    2.40       1.00   3.61    0.10   0.40   7.70   5.40   0.20
  seed 12       1000      7.6     22.6    145.3     5.7   7.8 ( 0.8%)   2.5 ( 0.3%)    0.10    1.80       0.99   3.07    0.20   0.10   2.30   3.17   0.00
  seed 13       1000      7.9     23.5    149.0     5.5   9.4 ( 1.0%)   3.9 ( 0.4%)    0.00    2.40       1.00   2.98    0.00   0.00   4.20   3.12   0.00
  seed 14       1000      7.8     23.5    150.8     5.5  10.2 ( 1.1%)   4.0 ( 0.4%)    0.10    1.60       1.06   2.96    0.00   0.00   4.20   6.27   0.00
  dense1000, seeds 15-24 (first run in session 16; 16, 17, 20, 23 then traced):
  seed 15       1000      7.7     22.9    141.1     5.8   9.4 ( 1.0%)   2.8 ( 0.3%)    0.70    1.80       0.97   3.02    0.10   0.30   3.00   3.09   0.30
  seed 16       1000      7.8     23.6    154.9     5.4   8.7 ( 0.9%)   2.3 ( 0.2%)    0.70    3.40       1.03   2.79    0.50   0.00   3.10   2.85   0.60
  seed 17       1000      7.9     23.9    150.7     5.5  11.1 ( 1.2%)   4.2 ( 0.5%)    0.50    2.60       1.01   3.22    0.00   0.50   5.30   3.65   0.40
  seed 18       1000      7.9     24.0    154.6     5.4   9.8 ( 1.1%)   4.5 ( 0.5%)    0.30    3.20       1.00   3.02    0.30   0.00   5.00   3.24   0.20
  seed 19       1000      8.0     24.1    149.3     5.5   7.7 ( 0.8%)   2.2 ( 0.2%)    0.80    2.30       0.98   3.03    0.40   0.50   2.20   3.69   0.40
  seed 20       1000      8.0     24.1    150.9     5.5  11.3 ( 1.2%)   5.6 ( 0.6%)    0.10    2.40       0.99   3.17    0.00   0.00   4.20   3.41   0.00
  seed 21       1000      7.9     23.6    145.6     5.6   7.5 ( 0.8%)   2.0 ( 0.2%)    0.10    2.00       0.98   3.03    0.00   0.00   4.40   3.26   0.00
  seed 22       1000      7.9     23.8    151.6     5.5  10.9 ( 1.2%)   5.9 ( 0.6%)    0.30    2.70       0.99   3.28    0.10   0.10   4.90   7.07   0.10
  seed 23       1000      7.9     23.7    150.6     5.5   7.8 ( 0.8%)   1.5 ( 0.2%)    0.00    1.60       1.03   3.02    0.00   0.00   4.10   3.35   0.00
  seed 24       1000      8.2     24.7    159.0     5.2  11.4 ( 1.2%)   5.8 ( 0.6%)    0.50    2.40       1.04   3.11    0.10   0.10   4.20   3.43   0.10
  dense1000, seeds 25-34 (first run in session 16 before the watch; 34 then traced):
  seed 25       1000      8.2     24.5    156.4     5.3   8.7 ( 0.9%)   3.2 ( 0.3%)    0.40    2.20       0.98   2.98    0.30   0.20   4.60   2.98   0.00
  seed 26       1000      8.4     25.5    160.7     5.1  11.2 ( 1.2%)   4.3 ( 0.5%)    0.40    2.10       0.97   3.00    0.40   0.10   3.60   3.07   0.10
  seed 27       1000      8.3     25.0    160.0     5.2   7.8 ( 0.8%)   2.2 ( 0.2%)    0.30    1.80       1.03   3.03    0.00   0.00   4.40   3.04   0.00
  seed 28       1000      8.7     26.4    166.2     5.0   9.6 ( 1.0%)   2.9 ( 0.3%)    0.40    2.40       1.04   3.07    0.30   0.20   4.80   3.40   0.20
  seed 29       1000      8.7     26.4    158.9     5.2  10.9 ( 1.2%)   5.5 ( 0.6%)    0.60    3.30       1.01   3.06    0.50   0.00   2.10   3.42   0.40
  seed 30       1000      8.7     26.2    161.3     5.1   8.1 ( 0.9%)   2.5 ( 0.3%)    0.40    2.30       0.99   2.97    0.20   0.20   2.30   2.98   0.10
  seed 31       1000      8.7     26.2    159.2     5.2   9.9 ( 1.1%)   4.2 ( 0.5%)    0.40    3.40       0.97   3.06    0.00   0.20   3.90   3.15   0.20
  seed 32       1000      8.1     24.4    153.6     5.4   8.9 ( 1.0%)   3.6 ( 0.4%)    0.50    2.70       0.99   3.33    0.10   0.10   2.70   3.40   0.10
  seed 33       1000      8.1     24.3    155.0     5.3   9.6 ( 1.0%)   2.7 ( 0.3%)    0.60    2.70       1.04   3.24    0.20   0.10   3.40   3.24   0.20
  seed 34       1000      8.6     26.2    161.8     5.1   8.4 ( 0.9%)   3.2 ( 0.3%)    0.70    1.80       0.98   3.05    0.10   0.40   4.90   4.46   0.30
  dense1000, seeds 35-40 (first run with the watch, not looked at before):
  seed 35       1000      8.4     25.1    155.4     5.3  10.8 ( 1.2%)   4.9 ( 0.5%)    0.60    2.10       0.99   3.13    0.40   0.10   4.10   3.28   0.40
  seed 36       1000      8.4     25.4    159.6     5.2   7.9 ( 0.9%)   2.4 ( 0.3%)    0.60    2.70       1.01   3.12    0.30   0.40   4.00   3.26   0.30
  seed 37       1000      8.0     24.0    152.3     5.4  11.0 ( 1.2%)   3.9 ( 0.4%)    0.30    2.60       1.03   2.98    0.30   0.10   2.40   3.16   0.20
  seed 38       1000      8.3     24.9    151.3     5.4   7.7 ( 0.8%)   2.1 ( 0.2%)    0.40    1.70       1.02   3.02    0.20   0.10   5.30   3.10   0.30
  seed 39       1000      8.6     25.9    158.6     5.2   8.2 ( 0.9%)   2.3 ( 0.2%)    0.40    2.60       1.00   3.13    0.40   0.00   4.80   3.22   0.30
  seed 40       1000      8.6     26.1    159.6     5.1  10.9 ( 1.2%)   4.0 ( 0.4%)    0.40    2.30       0.98   3.09    0.40   0.00   3.70   5.21   0.10
  log-log slope of the cost per scan, 120 -> 1000 targets: plotter 0.7-0.9, tracker
  0.7-0.9, fusion 0.8-1.0 (session 13; noisy: other work shared the cores; the watch
  adds 35-45 % to fusion at 1000 targets). Every goal met on every row: switches 0.0-0.9
  per 100 targets (mean 0.40; seed 9 0.90, seed 19 0.80), missed 0.8-1.2 %, false
  0.2-0.6 %, RMSE/PCRLB 0.97-1.06, mean NEES 2.79-3.97. Session 16's steps, in order
  (docs/radar_at_scale.md, session 16): the segment association lowered seeds 1, 5, 6, 8
  and 9 by 0.1 (aircraft 905's 1.6 g turn in four); the published-number rule seeds 16,
  17, 20, 23 by 0.1; without the watch seed 34's mean NEES was 15.62 (aircraft 336 scored
  on 931's track, each track fed by its own elementary tracks at the other's altitude),
  with it 3.05; the watch moved switches by -0.1 on seeds 2, 7 and +0.1 / +0.2 on seeds
  8, 10, 17, 18, 19 (seed 8's NEES 2.96 -> 3.97). Seed 9's 9: 7 in the first 30 s (3
  aircraft whose own track sat 2.5-5.3 km off in altitude; the exchanged pair 173 / 320;
  a mixed track; a two-base ghost), then 814 and 380 (a pass 3 km from the receiver).

Every earlier measurement, the traces that found each cause and the variants tried:
docs/radar_at_scale.md.
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
from origin_switches import OriginLabels

from common.core.track_table import Status
from common.deploy.config import parse, section
from common.evaluation.metrics import count_switches
from common.evaluation.pcrlb import Evaluation, score_targets
from common.radar.fusion.params import FusionParams
from common.sim.simulator import load_scenario
from common.wire.radar_chain import RadarChain
from common.wire.radar_messages import confirmed_tracks, gtracks_message, plots_of
from common.wire.sim_messages import run_scenario, truth_state

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
    origin: tuple[float, float] = (0.0, 0.0)
    step_switches: float = 0.0
    step_nees: float = 0.0
    late_switches: float = 0.0

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

    path = Path(name) if name.endswith(".toml") else REPO / "scenarios" / f"{name}.toml"
    name = path.stem
    doc = tomllib.loads(path.read_text())
    doc.setdefault("radar", {}).setdefault("fusion", {}).update(fusion or {})
    cfg = parse(doc, path)
    scn = load_scenario(doc)
    chain = RadarChain(cfg)
    cost = {"plotter": 0.0, "tracker": 0.0, "fusion": 0.0}
    ev = Evaluation(c=GATE_C, gamma=GATE_C, keep_steps=True)
    missed, false, present, n_scans = [], [], [], 0
    tx, rx = np.array([b.tx for b in cfg.bases]), np.array([b.rx for b in cfg.bases])
    origin = OriginLabels(tx, rx)
    bidx = {b.id: i for i, b in enumerate(cfg.bases)}
    truths: dict[float, tuple[np.ndarray, np.ndarray]] = {}
    for t, msgs in run_scenario(scn, cfg.bases, [], seed, scans):
        n_scans += 1
        truth = next(m for k, m in msgs if k == "sim/truth/radar")
        truths[t] = (np.asarray(truth["id"]), truth_state(truth))
        out, cycles, etracks = [], [], []
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
                etracks.append((bidx[base], tracks))
                cycles += chain.fusion.push(base, tracks, tf)  # message time as wall time
                out += [gtracks_message(g) for g in cycles[len(out):]]
                t1 = time.process_time()
                cost["fusion"] += t1 - t2
        g = next((m for m in out if m["t"] == t), {"tracks": []})
        conf = confirmed_tracks(g)
        ev.add(t, np.asarray(truth["id"]), truth_state(truth), *conf)
        res = ev.metrics.gospa_series[-1]
        for b, tracks in etracks:  # the diagnostic by origin (benchmarks/origin_switches)
            if tracks.t in truths:
                origin.etracks(b, tracks, *truths[tracks.t])
        gt = next((c for c in cycles if c.t == t), None)
        if gt is not None:
            origin.cycle(gt, gt.status == Status.CONFIRMED, truths[t][0], ev.metrics.associations[-1])
        else:
            origin.series.append({})
        if t >= WARMUP:
            n_truth = len(truth["id"])
            present.append(n_truth)
            missed.append(n_truth - res.rows.size)
            false.append(len(conf[0]) - res.rows.size)
    p = section(cfg, "radar.fusion", FusionParams)
    s = ev.metrics.summary()
    joint = ev.metrics.joint_associations()
    bound = (np.array([b.tx for b in cfg.bases]), np.array([b.rx for b in cfg.bases]),
             base_information(radar_scene(cfg), cfg.bases), p.q, p.q_z,
             np.diag([1e6, 1e4, 1e6, 1e4, 1e6, 1e2]), WARMUP)
    sc = score_targets(ev, *bound, joint)  # each truth against the track that follows it
    nees_step = np.mean([v.nees_pos for v in score_targets(ev, *bound).values()])
    j = count_switches(joint)
    late = count_switches(joint, start=sum(t < WARMUP for t in truths))  # after the warm-up
    n_t = len(ev.truth)
    ratio = np.array([v.rmse / v.bound for v in sc.values()])
    by_origin, _, crossings = origin.summary(joint)
    nees = np.array([v.nees_pos for v in sc.values()])
    return Row(name, n_t, n_scans, {k: 1e3 * v / n_scans for k, v in cost.items()},
               float(np.mean(missed)), float(np.mean(false)), 100.0 * j.switches / n_t,
               100.0 * j.breaks / n_t, float(np.median(ratio)), float(np.mean(nees)),
               float(np.mean(present)), (100.0 * by_origin / n_t, 100.0 * crossings / n_t),
               100.0 * s.switches / n_t, float(nees_step), 100.0 * late.switches / n_t)


def table(rows: list[Row]) -> list[str]:
    """The per-density table of issue 14 (costs: ms of CPU per scan, all bases)."""
    out = [f"{'scene':<10} {'targets':>7} {'plotter':>8} {'tracker':>8} {'fusion':>8} {'x real':>7} "
           f"{'missed':>12} {'false':>12} {'switch':>7} {'breaks':>7} {'RMSE/PCRLB':>10} {'NEES':>6} {'origin':>7} {'cross':>6} {'step':>6} {'NEES':>6} {'>30 s':>6}",
           f"{'':<10} {'':>7} {'ms/scan':>8} {'ms/scan':>8} {'ms/scan':>8} {'':>7} "
           f"{'per scan':>12} {'per scan':>12} {'/100 tg':>7} {'/100 tg':>7} {'median':>10} {'pos':>6} {'sw/100':>7} {'/100':>6} {'sw/100':>6} {'step':>6} {'sw/100':>6}"]
    for r in rows:
        total = sum(r.ms.values())
        out.append(f"{r.name:<10} {r.targets:>7} {r.ms['plotter']:>8.1f} {r.ms['tracker']:>8.1f} "
                   f"{r.ms['fusion']:>8.1f} {1e3 / total:>7.1f} "
                   f"{r.missed:>5.1f} ({100 * r.missed / r.present:4.1f}%) "
                   f"{r.false:>5.1f} ({100 * r.false / r.present:4.1f}%) {r.switches:>7.2f} "
                   f"{r.breaks:>7.2f} {r.rmse_ratio:>10.2f} {r.nees:>6.2f} {r.origin[0]:>7.2f} {r.origin[1]:>6.2f} {r.step_switches:>6.2f} {r.step_nees:>6.2f} {r.late_switches:>6.2f}")
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
