"""Sonar tracks that hold (issue 13 section 2): false confirmed tracks, breaks, swaps and
bearing RMSE of the bearing tracker on scenes it was not tuned on, 20 seeds each, in one
process (simulator -> common.sonar.bearing.tracker, the code the service runs).

Run: .venv/bin/python benchmarks/sonar_hold.py [--runs 20] [--case NAME ...] [--mode gnn|mht ...]

Scenes (scenarios/, written before the tracker changes they measure; the tracker runs
with the defaults of docs/configuration.md, crossing management with them except
max_duration = 600 s, the same on every scene, set after the first measurement):
  sonar_hold5        5 contacts, 3 false detections a cycle, own-ship turn, a crossing
                     pair, a North crossing, 240 cycles of 5 s;
  sonar_hold_cpa     a 15 kn contact passing 1 km from the own ship (up to 35 deg/min),
                     2 deg sigma, 3 false detections, 300 cycles of 2 s;
  sonar_hold_cross_eq / _uneq   equal / unequal speed crossings, 3 false detections;
  sonar_hold_cross_turn   an equal-speed crossing while the own ship turns 90 deg, 3 false
                     detections (written 2026-11-26 before the changes it measures);
  sonar_hold_cross_slow   a slow unequal-speed crossing, 1.25 deg/min relative rate, 3
                     false detections (written 2026-11-26 before the changes it measures).

Modes: gnn, the single-hypothesis tracker with seed 004 crossing management
(common.sonar.bearing.tracker); mht, the multiple-hypothesis mode (common.sonar.mht.tracker) with
[sonar.tracker.mht] and rho_F = the scene's false detections per rad and per 10 dB (as
benchmarks/mht.py).

Scoring per cycle: truths and confirmed tracks are paired one to one within 5 sigma of
bearing (sigma = the array's sigma0; common.evaluation.crossing_eval.one_to_one, least
total distance; until session 13 each truth took its nearest track, shared); a
confirmed track that is never paired over its whole life is a false track (per 100 cycles: false tracks / cycles x 100);
at a cycle where a truth is resolved (no other truth within 6 sigma), a track it was not
resolved on before is a break if no other truth was resolved on it (a new number for the
target: a lost track replaced, or a duplicate track taking over), a swap otherwise (as
common.evaluation.crossing_eval, which skips unresolved cycles too). Track numbers are
reused by the tracker: the scorer gives each new holder of a number a new serial.
Bearing RMSE over the associated cycles.

Measured 2026-11-26, 20 seeds per scene (false: per 100 cycles; breaks, swaps: runs with one
(total); RMSE deg). Before: a5ff39b; after: the bearing IMM in 004 memory mode predicts with
its quiet Q (common.sonar.bearing.imm), and the MHT mode carries the IMM's two bearing-rate
models per hypothesis, the quiet one only in a resolution conflict (common.sonar.mht.models).
  scene                  mode   before: false breaks  swaps   RMSE   after: false breaks swaps  RMSE
  sonar_hold5            gnn           0.00  0 (0)   0 (0)   0.42          0.00  0 (0)  0 (0)  0.42
  sonar_hold5            mht           0.00  3 (4)   7 (13)  0.64          0.00  3 (4)  0 (0)  0.40
  sonar_hold_cpa         gnn           0.10  0 (0)   0 (0)   0.96          0.10  0 (0)  0 (0)  0.96
  sonar_hold_cpa         mht           0.07  1 (1)   0 (0)   0.94          0.07  1 (1)  0 (0)  0.98
  sonar_hold_cross_eq    gnn           0.06  0 (0)   2 (2)   0.55          0.06  0 (0)  1 (1)  0.52
  sonar_hold_cross_eq    mht           0.03  1 (1)   9 (16)  0.88          0.03  0 (0)  0 (0)  0.38
  sonar_hold_cross_uneq  gnn           0.06  0 (0)   0 (0)   0.54          0.06  0 (0)  0 (0)  0.49
  sonar_hold_cross_uneq  mht           0.03  0 (0)  11 (21)  0.88          0.03  0 (0)  0 (0)  0.39
  sonar_hold_cross_turn  gnn           0.06  0 (0)   1 (1)   0.61          0.06  0 (0)  0 (0)  0.52
  sonar_hold_cross_turn  mht           0.03  0 (0)  11 (21)  0.87          0.03  0 (0)  0 (0)  0.42
  sonar_hold_cross_slow  gnn           0.04  0 (0)   1 (1)   0.74          0.04  0 (0)  0 (0)  0.53
  sonar_hold_cross_slow  mht           0.02  0 (0)   7 (14)  0.85          0.02  0 (0)  0 (0)  0.39
With 40 seeds (--runs 40), swap runs GNN before -> after: cross_eq 2 -> 1, cross_uneq 0 -> 0,
cross_turn 2 -> 1, cross_slow 3 -> 1 (break runs 0/1/1/0 -> 0/0/1/0); MHT after: 0 swaps on all
six scenes, break runs hold5 3, cpa 1, cross_uneq 1, cross_turn 1.
Open: the GNN swap on sonar_hold_cross_eq (seed 12): at the end of the memory mode both
tracks' gates are wide (bearing sigma 1.8 deg, amplitude sigma 13 dB after 135 s of
coasting), GNN gives the track of the detected target a clutter detection 3.5 deg off and
the other track that target's detection, which the exit rule of
common.sonar.bearing.crossing then drops; the track recovers with a wrong bearing rate,
re-enters the ambiguity beside the other track and coasts onto the other target. Barring
those pairs before the GNN instead of dropping them after it fixed that run but gave
swaps on cross_uneq (1), cross_turn (2), cross_slow (1) (after the own-ship turn both
coasting predictions are off by 2 deg, and the nearest-prediction rule then picks the
wrong target), so it was not kept; updating the amplitude during the memory mode (alpha on
the bearing only) gave 2 swap runs on cross_eq and was not kept either; nor was a GNN that
may leave a confirmed track unassigned (pair cost d^2 - G, a miss 0: the most likely
assignment by 000's dL instead of the most pairs), which stops a track taking the other
target's detection when its own is missed (cross_slow seed 26) but at 40 seeds gave the
same 3 swap runs in all (cross_eq 1, cross_turn 0, cross_slow 2). Over seeds 1-160
(benchmarks/crossing_seeds.py, 2026-11-26) the GNN swap runs are cross_eq 3, cross_uneq
1, cross_turn 8, cross_slow 9 (break runs 1, 0, 4, 2; sonar_hold5 0 swap runs, 1 break
run): seed 12 is one of several, and 20 seeds cannot tell a change of the rates from a
change of the failing seeds. Tried there and not kept: the exit rule also dropping the
pair GNN gave the track nearest to the vetoed detection (seeds 1-40: cross_eq 1 -> 0, no
scene worse; seeds 1-160: 38 -> 43 swap runs on the ten crossing scenes), the level held
in the memory mode, the memory mode entered from 004's straight line (eq. 1, 8) fitted to
the track's register, 004's progressive mode, a hysteresis on the eq. 13 test (seeds
1-160: 38 -> 30 with epsilon / 3 to leave, but sonar_cross_2dpm_uneq and 4dpm_eq worse).
The MHT breaks on
hold5 (3 runs, seeds 3, 9, 18) were confirmed tracks deleted by the SPRT counter after a
run of missed detections (seed 9: contact 3 undetected 4 cycles in a row at the North
crossing, no detection in the simulator's output) and replaced by a new number: the
deletion rule counted the misses while the track was still confirmed towards n_delete,
so SA's demotion (ZA from za_max 6 below ZA_krit 3: 4 misses) deleted it at once. The
n_delete cycles now count from the demotion (common.sonar.mht.tracker), 6 misses in a row delete.
MHT, 20 seeds, after that: every scene false <= 0.07, breaks 0 runs, swaps 0 runs (hold5
RMSE 0.39, cpa 0.97, cross_* 0.38-0.42 deg); 40 seeds: breaks 0 runs but cross_turn 1 run
(1 break), swaps 0 everywhere.
Session 17 (2026-11-26): the single-hypothesis tracker's memory-mode pairs
(common.sonar.bearing.pairs: a frozen pair whose order the prediction is sure of is
released for the scan, else the centroid of its two detections updates its centroid).
20 seeds, GNN: swap runs 0 and break runs 0 on every scene (cross_eq 1 swap run before);
false <= 0.10 per 100 cycles; RMSE hold5 0.40, cpa 0.96, cross_eq 0.41, cross_uneq 0.43,
cross_turn 0.43, cross_slow 0.40 deg (0.52-0.55 before: the frozen pairs coasted). MHT
unchanged (0 swap and break runs, RMSE 0.39-0.42 on the cross scenes). Over seeds 1-480
the GNN's swap runs on these four crossing scenes are 1 in 1920 (cross_turn 328;
benchmarks/crossing_seeds.py).

Goals (exit code 1 when one fails): false confirmed tracks < 1 per 100 cycles on every
scene; breaks 0 in >= 95 % of runs; swaps 0 in every run.
"""

from __future__ import annotations

import argparse
import math
import sys
import tomllib
from dataclasses import dataclass, replace
from pathlib import Path

import numpy as np

REPO = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(REPO))

from common.core.angles import wrap_pi  # noqa: E402
from common.core.crossing import CrossingParams  # noqa: E402
from common.deploy.config import load, section  # noqa: E402
from common.evaluation.crossing_eval import one_to_one  # noqa: E402
from common.sim.simulator import load_scenario  # noqa: E402
from common.sonar.mht.params import MhtParams, SonarTrackerParams  # noqa: E402
from common.sonar.trackers import bearing_tracker  # noqa: E402
from common.wire.sim_messages import run_scenario  # noqa: E402

CASES = ("sonar_hold5", "sonar_hold_cpa", "sonar_hold_cross_eq", "sonar_hold_cross_uneq",
         "sonar_hold_cross_turn", "sonar_hold_cross_slow")
MODES = ("gnn", "mht")
GATE, RESOLVED = 5.0, 6.0  # sigma0 units


@dataclass
class RunScore:
    """One seeded run: cycles, false confirmed tracks, breaks, swaps, squared bearing
    errors (rad^2) of the associated cycles."""

    cycles: int = 0
    false_tracks: int = 0
    breaks: int = 0
    swaps: int = 0
    sq_err: float = 0.0
    n_err: int = 0


class Scorer:
    """Scores one run cycle by cycle (rules in the module docstring); sigma: the array's
    bearing sigma (rad), the unit of the gate and of the resolution distance."""

    def __init__(self, sigma: float) -> None:
        self.sig = sigma
        self.s = RunScore()
        self.useful: set[int] = set()
        self.confirmed: set[int] = set()
        self.owner: dict[int, set[int]] = {}  # truth -> track serials it was resolved on
        self.serial: dict[int, int] = {}  # track number -> serial of its holder (numbers are reused)
        self.n_serial = 0

    def add(self, truth_ids: list[int], truth_brg: np.ndarray, track_ids: list[int],
            confirmed: np.ndarray, track_brg: np.ndarray) -> None:
        """One tracker cycle: the truths, and every live track (number, confirmed, bearing)."""
        s = self.s
        s.cycles += 1
        self.serial = {k: self.serial[k] for k in track_ids if k in self.serial}
        for k in track_ids:
            if k not in self.serial:
                self.serial[k] = self.n_serial
                self.n_serial += 1
        ids = np.array([self.serial[k] for k, c in zip(track_ids, confirmed) if c], dtype=np.int64)
        brg = np.asarray(track_brg, dtype=float)[np.asarray(confirmed, dtype=bool)]
        self.confirmed.update(ids.tolist())
        tb = np.asarray(truth_brg, dtype=float)
        if tb.size == 0 or ids.size == 0:
            return
        d = np.abs(wrap_pi(tb[:, None] - brg[None, :])) / self.sig
        sep = np.abs(wrap_pi(tb[:, None] - tb[None, :])) / self.sig
        np.fill_diagonal(sep, np.inf)
        for i, (tid, j) in enumerate(zip(truth_ids, one_to_one(d, GATE).tolist())):
            if j < 0:
                continue
            k = int(ids[j])
            self.useful.add(k)
            s.sq_err += float(wrap_pi(tb[i] - brg[j]) ** 2)
            s.n_err += 1
            owned = self.owner.setdefault(tid, set())
            if sep[i].min() <= RESOLVED or k in owned:
                continue
            if any(k in ks for t2, ks in self.owner.items() if t2 != tid):
                s.swaps += 1  # the track of another truth
            elif owned:
                s.breaks += 1  # a new number for this truth
            owned.add(k)

    def result(self) -> RunScore:
        """The run's score (false tracks: confirmed serials never a truth's nearest)."""
        self.s.false_tracks = len(self.confirmed - self.useful)
        return self.s


def run_once(path: Path, seed: int, mode: str = "gnn") -> RunScore:
    """Run the scene of one deployment/scenario file with one seed through one mode
    ("gnn" or "mht") and score it."""
    cfg = load(path)
    arr = cfg.arrays[0]
    doc = tomllib.loads(path.read_text())
    scn = load_scenario(doc)
    params = replace(section(cfg, "sonar.tracker", SonarTrackerParams), mode_association=mode)
    rho_f = doc["sim"]["sonar"]["clutter"] / (2.0 * math.pi * 10.0)
    trk = bearing_tracker(params, replace(section(cfg, "sonar.tracker.mht", MhtParams), rho_f=rho_f),
                          arr.kind, arr.sigma0, section(cfg, "sonar.crossing", CrossingParams))
    sc = Scorer(arr.sigma0)
    for _, msgs in run_scenario(scn, [], cfg.arrays, seed):
        truth = next(m for k, m in msgs if k == "sim/truth/sonar")
        det = next(m for k, m in msgs if k.startswith("sonar/detections/"))
        own = det["own"]
        c = trk.step(det["t"], np.asarray(det["brg"]), np.asarray(det["amp"]), own["heading"],
                     own["x"], own["y"], sbrg=np.asarray(det["sbrg"]))
        sc.add(list(truth["id"]), np.asarray(truth["brg"]), c.ids.tolist(), c.confirmed, c.x[:, 0])
    return sc.result()


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--runs", type=int, default=20)
    ap.add_argument("--case", nargs="*", default=list(CASES))
    ap.add_argument("--mode", nargs="*", default=list(MODES), choices=MODES)
    a = ap.parse_args(argv)
    ok = True
    print(f"{'scene':<24}{'mode':>5}{'runs':>5}{'false/100cyc':>13}{'break runs':>11}{'breaks':>7}"
          f"{'swap runs':>10}{'swaps':>6}{'RMSE deg':>9}")
    for case, mode in [(c, m) for c in a.case for m in a.mode]:
        scores = [run_once(REPO / "scenarios" / f"{case}.toml", seed, mode) for seed in range(1, a.runs + 1)]
        cycles = sum(r.cycles for r in scores)
        false_rate = 100.0 * sum(r.false_tracks for r in scores) / cycles
        break_runs = sum(r.breaks > 0 for r in scores)
        swap_runs = sum(r.swaps > 0 for r in scores)
        rmse = np.degrees(np.sqrt(sum(r.sq_err for r in scores) / max(1, sum(r.n_err for r in scores))))
        print(f"{case:<24}{mode:>5}{len(scores):>5}{false_rate:>13.2f}{break_runs:>11}"
              f"{sum(r.breaks for r in scores):>7}{swap_runs:>10}{sum(r.swaps for r in scores):>6}{rmse:>9.2f}",
              flush=True)
        ok &= false_rate < 1.0 and break_runs <= 0.05 * len(scores) and swap_runs == 0
    print("goals met" if ok else "GOAL FAILED: false < 1/100 cycles, breaks 0 in 95 % of runs, swaps 0")
    return 0 if ok else 1


if __name__ == "__main__":
    sys.exit(main())
