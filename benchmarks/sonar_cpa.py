"""Contacts that pass close (issue 31 section 1): does the bearing track follow a bearing
that moves 10-50 deg between samples, and does TMA solve after the approach? In one
process: simulator -> bearing tracker (common.sonar.trackers.bearing_tracker, the
scene's [sonar.tracker]) -> TMA manager (common.sonar.tma.manager.TmaManager, defaults)
fed from the tracker's bearing register, as services/tma is; each TMA solution is given
back to the tracker as a hint for its later cycles, as the bearing-tracker service takes
them from sonar/tma/<a> (common.sonar.bearing.range_noise, tma_prediction;
run_once(..., feedback=False) without). Figures: docs/decisions/028-own-state-along-the-relative-track.md
(026 and 018 before it).

Run: .venv/bin/python benchmarks/sonar_cpa.py [--runs 20] [--case NAME ...] [--mode gnn|mht ...]
[--processes [--same]] (through a real router and the bearing-tracker and tma processes,
the simulator at 300 x real time: the same numbers as in one process when every TMA
solution is back before the next scan; about 8 s a run; --same also runs each seed in one
process and fails when a run differs).

Scenes (scenarios/, docs/scenarios.md): sonar_cpa_coarse (60 s sampling, CPA 0.5 km,
own-ship turn), sonar_cpa_fine_300m (30 s, 0.3 km, no turn), sonar_cpa_coarse_1km (60 s,
1 km, no turn), sonar_cpa_fine_1km_turn (30 s, 1 km, turn), sonar_cpa_cross (the last with
a second contact whose bearing crosses the first's at the approach; the scores are the
first contact's).

Per run: the confirmed tracks within 5 sigma0 of the target's bearing, outside the
cycles where another contact's bearing is within 10 sigma0 of it (a crossing, where a
track of either contact could be either's; a track that swapped shows after it) (numbers:
how many different ones, 1 = the track held); held: the fraction of the samples after the first
one's confirmation at which it is confirmed; the first track's last TMA solution: its
time after the closest approach, its position error against the CRLB
(common.sonar.tma.crlb, all scan times, the array's sigma0) and its NEES (4 dof).

Goals (exit code 1 when one fails): one number in every run, held >= 0.9 in every run,
a TMA solution after the approach in every run; flag: the solved runs whose solution's
range_observable says what the scene allows (true with an own-ship turn, false without:
there the range is unobservable and the CRLB infinite), every one; on the scenes with a
turn: position error RMS <= 1.5 CRLB, no run above 5 CRLB, mean NEES in [2, 8].
"""

from __future__ import annotations

import argparse
import math
import sys
import tempfile
import tomllib
from dataclasses import astuple, dataclass, field, replace
from pathlib import Path
from typing import Any

import numpy as np

REPO = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(REPO))

from common.core.angles import wrap_pi  # noqa: E402
from common.core.crossing import CrossingParams  # noqa: E402
from common.core.gating import quadratic_form  # noqa: E402
from common.deploy.config import load, section  # noqa: E402
from common.sim.simulator import load_scenario  # noqa: E402
from common.sonar.mht.params import MhtParams, SonarTrackerParams  # noqa: E402
from common.sonar.tma.crlb import position_rms_bound  # noqa: E402
from common.sonar.tma.manager import BTrack, BTracks, TmaManager, TrackHistory  # noqa: E402
from common.sonar.trackers import bearing_tracker  # noqa: E402
from common.wire.sim_messages import run_scenario  # noqa: E402
from common.wire.sonar_messages import tma_hints_from, tma_message  # noqa: E402

CASES = ("sonar_cpa_coarse", "sonar_cpa_fine_300m", "sonar_cpa_coarse_1km", "sonar_cpa_fine_1km_turn",
         "sonar_cpa_cross")
MODES = ("gnn", "mht")
GATE = 5.0  # sigma0


@dataclass(frozen=True)
class CpaRun:
    """One seeded run: track numbers on the target, fraction held confirmed, TMA solution
    after the approach, final position error (m), its CRLB (m, inf when unobservable), NEES,
    and the solution's range_observable flag (False without a solution)."""

    numbers: int
    held: float
    solved_after: bool
    err: float
    crlb: float
    nees: float
    observable: bool = False


@dataclass
class Trace:
    """What a run leaves, in one process or through the processes: per cycle the time, own
    position, truth [x, y, vx, vy] of the target and the track numbers near its bearing
    (confirmed, within GATE sigma0) and confirmed; the last TMA solution of every track."""

    times: list[float] = field(default_factory=list)
    own: list[tuple[float, float]] = field(default_factory=list)
    truth: list[list[float]] = field(default_factory=list)
    near: list[list[int]] = field(default_factory=list)
    confirmed: list[set[int]] = field(default_factory=list)
    solutions: dict[int, dict[str, Any]] = field(default_factory=dict)

    def cycle(self, t: float, own: tuple[float, float], tr: dict[str, Any], ids: np.ndarray,
              conf: np.ndarray, brg: np.ndarray, sigma0: float) -> None:
        """One tracker cycle against the truth message of its time."""
        self.times.append(t)
        self.own.append(own)
        self.truth.append([tr["x"][0], tr["y"][0], tr["vx"][0], tr["vy"][0]])
        b0 = tr["brg"][0]
        crossing = bool(np.any(np.abs(wrap_pi(np.asarray(tr["brg"][1:]) - b0)) <= 2 * GATE * sigma0))
        near = conf & (np.abs(wrap_pi(brg - b0)) <= GATE * sigma0) & (not crossing)
        self.near.append([int(i) for i in ids[near]])
        self.confirmed.append({int(i) for i in ids[conf]})


def rho_f(doc: dict[str, Any]) -> float:
    """The MHT's false-alarm density of a scene: its clutter per scan over 2 pi rad x 10 dB."""
    return float(doc["sim"]["sonar"].get("clutter", 1.0) / (2.0 * math.pi * 10.0))


def run_once(path: Path, seed: int, mode: str = "gnn", feedback: bool = True,
             tracker: dict[str, Any] | None = None) -> CpaRun:
    """One scene, one seed, one association mode in one process; feedback: the TMA solutions
    given back to the tracker as the bearing-tracker service does (tma_hints_from); tracker:
    [sonar.tracker] keys over the scene's."""
    cfg = load(path)
    arr = cfg.arrays[0]
    doc = tomllib.loads(path.read_text())
    params = replace(section(cfg, "sonar.tracker", SonarTrackerParams), mode_association=mode,
                     **(tracker or {}))
    trk = bearing_tracker(params, replace(section(cfg, "sonar.tracker.mht", MhtParams), rho_f=rho_f(doc)),
                          arr.kind, arr.sigma0, section(cfg, "sonar.crossing", CrossingParams))
    mgr = TmaManager(arr.id)
    trace = Trace()
    for _, msgs in run_scenario(load_scenario(doc), [], cfg.arrays, seed):
        tr = next(m for k, m in msgs if k == "sim/truth/sonar")
        det = next(m for k, m in msgs if k.startswith("sonar/detections/"))
        o = det["own"]
        c = trk.step(det["t"], np.asarray(det["brg"]), np.asarray(det["amp"]), o["heading"], o["x"], o["y"],
                     sbrg=np.asarray(det["sbrg"]))
        trace.cycle(det["t"], (o["x"], o["y"]), tr, c.ids, c.confirmed, c.x[:, 0], arr.sigma0)
        mgr.add_own(det["t"], o["x"], o["y"])
        mgr.push(BTracks(det["t"], arr.id, [BTrack(int(i), bool(k), x, P.ravel())
                                            for i, k, x, P in zip(c.ids, c.confirmed, c.x, c.P)]))
        for b in mgr.ready()[0]:
            hist = {}
            for tid in mgr.history_wanted(b):
                h = trk.history_of(tid)
                if h is not None:
                    cols = h[1]
                    rows = np.column_stack([cols[k] for k in ("t", "brg", "sbrg", "own_x", "own_y")])
                    hist[tid] = TrackHistory(tid, h[0], rows)
            msg = tma_message(mgr.step(b, hist))
            trace.solutions = {s["track"]: s for s in msg["solutions"]}
            if feedback:  # the solutions back to the tracker for its later cycles, as the service
                for tid, hint in tma_hints_from(msg):
                    trk.tma_hint(tid, hint)
    return score(trace, doc, arr.sigma0)


def run_processes(path: Path, seed: int, mode: str, workdir: Path, speed: float = 300.0) -> CpaRun:
    """One scene, one seed, one mode through the processes: a router, the bearing-tracker
    and tma services (a copy of the scene with [sonar.tracker] mode_association = mode and
    [sonar.tracker.mht] rho_f as in :func:`run_once`) and
    the simulator at ``speed`` x real time (the TMA solution of a scan is back at the
    tracker before the next scan)."""
    from common.bus.local_run import Deployment

    workdir.mkdir(parents=True, exist_ok=True)
    scene = workdir / path.name
    scene.write_text(path.read_text() + f'\n[sonar.tracker]\nmode_association = "{mode}"\n'
                     f'\n[sonar.tracker.mht]\nrho_f = {rho_f(tomllib.loads(path.read_text()))!r}\n')
    cfg = load(scene)
    arr = cfg.arrays[0]
    doc = tomllib.loads(scene.read_text())
    n = int(doc["sim"]["n_scans"])
    with Deployment(workdir) as d:
        for key in (f"sonar/btracks/{arr.id}", f"sonar/tma/{arr.id}", "sim/truth/sonar"):
            d.collect(key)
        d.start("btracker", "bearing-tracker", "--config", str(scene), "--array", arr.id)
        d.start("tma", "tma", "--config", str(scene), "--array", arr.id)
        alive = [f"bearing_tracker/{arr.id}", f"tma/{arr.id}"]
        d.wait_alive(alive)
        d.simulate(scene, seed=seed, wait_alive=alive, speed=speed)
        d.wait_for(lambda: len(d.of(f"sonar/tma/{arr.id}")) >= n, 60)
        bt, tma = d.of(f"sonar/btracks/{arr.id}"), d.of(f"sonar/tma/{arr.id}")
        truth = {m["t"]: m for m in d.of("sim/truth/sonar")}
    trace = Trace()
    for m in sorted(bt, key=lambda m: m["t"]):
        tr = truth[m["t"]]
        tracks = m["tracks"]
        trace.cycle(m["t"], (tr["own"]["x"], tr["own"]["y"]), tr, np.array([k["id"] for k in tracks], int),
                    np.array([k["status"] == "confirmed" for k in tracks], bool),
                    np.array([k["x"][0] for k in tracks], float), arr.sigma0)
    last = max(tma, key=lambda m: m["t"])
    trace.solutions = {s["track"]: s for s in last["solutions"]}
    return score(trace, doc, arr.sigma0)


def same_run(a: CpaRun, b: CpaRun) -> bool:
    """Whether two runs left the same numbers (NaN equal to NaN)."""
    return bool(np.array_equal(np.array(astuple(a), float), np.array(astuple(b), float), equal_nan=True))


def score(trace: Trace, doc: dict[str, Any], sigma0: float) -> CpaRun:
    """The run's numbers (module docstring) from its trace."""
    numbers: list[int] = []
    for near in trace.near:
        numbers.extend(i for i in near if i not in numbers)
    first = numbers[0] if numbers else None
    k0 = next((k for k, near in enumerate(trace.near) if near), len(trace.near))
    conf_after = [first in c for c in trace.confirmed[k0:]]
    t, xy, x = np.asarray(trace.times), np.asarray(trace.own), np.asarray(trace.truth)
    t_cpa = float(t[np.argmin(np.hypot(*(x[:, :2] - xy).T))])
    sol = trace.solutions.get(first) if first is not None else None
    held = float(np.mean(conf_after)) if conf_after else 0.0
    t_eval = float(t[-1]) if sol is None else float(sol["t"])
    turns = bool(doc["sim"]["sonar"]["own"].get("leg"))  # without a turn the range is unobservable
    bound = position_rms_bound(x[0], t, xy, sigma0, float(t[0]), t_eval) if turns else math.inf
    if sol is None:
        return CpaRun(len(numbers), held, False, math.nan, bound, math.nan)
    flag = bool(sol.get("range_observable", False))
    k = int(np.searchsorted(t, sol["t"]))
    e = np.array([sol["x"], sol["y"], sol["vx"], sol["vy"]]) - x[k]
    try:
        nees = float(quadratic_form(e, np.asarray(sol["P"], float).reshape(4, 4)))
    except np.linalg.LinAlgError:  # a singular published P (unobservable range)
        nees = math.inf
    return CpaRun(len(numbers), held, sol["t"] > t_cpa, float(np.hypot(e[0], e[1])), bound, nees, flag)


def summary(runs: list[CpaRun]) -> tuple[dict[str, float], bool]:
    """The row of a scene and mode, and whether it meets the goals."""
    solved = [r for r in runs if np.isfinite(r.err)]
    err, bnd = np.array([r.err for r in solved]), np.array([r.crlb for r in solved])
    observable = bool(np.all(np.isfinite([r.crlb for r in runs])))
    ratios = observable and bool(solved)
    rms_ratio = float(np.sqrt(np.mean(err**2)) / np.sqrt(np.mean(bnd**2))) if ratios else math.nan
    row = {"one number": sum(r.numbers == 1 for r in runs), "min held": min(r.held for r in runs),
           "solved": sum(r.solved_after for r in runs), "RMS/CRLB": rms_ratio,
           "max/CRLB": float(np.max(err / bnd)) if ratios else math.nan,
           "NEES": float(np.mean([r.nees for r in solved])) if solved else math.nan,
           "CRLB m": float(np.sqrt(np.mean(np.square([r.crlb for r in runs])))),
           "flag": sum(r.observable == observable for r in solved)}
    ok = row["one number"] == len(runs) and row["min held"] >= 0.9 and row["solved"] == len(runs)
    ok &= row["flag"] == len(solved)
    if observable:
        ok &= rms_ratio <= 1.5 and row["max/CRLB"] <= 5.0 and 2.0 <= row["NEES"] <= 8.0
    return row, ok


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--runs", type=int, default=20)
    ap.add_argument("--case", nargs="*", default=list(CASES))
    ap.add_argument("--mode", nargs="*", default=list(MODES), choices=MODES)
    ap.add_argument("--processes", action="store_true",
                    help="through the real router, bearing-tracker and tma processes (run_processes)")
    ap.add_argument("--same", action="store_true",
                    help="with --processes: each run also in one process; fail when one differs")
    a = ap.parse_args(argv)
    tmp = Path(tempfile.mkdtemp(prefix="sonar_cpa_"))
    ok = True
    print(f"{'scene':<26}{'mode':>5}{'runs':>5}{'1 number':>9}{'min held':>9}{'solved':>7}{'CRLB m':>9}"
          f"{'RMS/CRLB':>9}{'max/CRLB':>9}{'NEES':>9}{'flag':>6}")
    for case, mode in [(c, m) for c in a.case for m in a.mode]:
        path = REPO / "scenarios" / f"{case}.toml"
        runs = [run_processes(path, s, mode, tmp / f"{case}-{mode}-{s}") if a.processes
                else run_once(path, s, mode) for s in range(1, a.runs + 1)]
        row, good = summary(runs)
        ok &= good
        print(f"{case:<26}{mode:>5}{len(runs):>5}{row['one number']:>9}{row['min held']:>9.2f}{row['solved']:>7}"
              f"{row['CRLB m']:>9.0f}{row['RMS/CRLB']:>9.2f}{row['max/CRLB']:>9.2f}{row['NEES']:>9.2f}{row['flag']:>6}"
              f"{'' if good else '  FAIL'}", flush=True)
        if a.processes and a.same:
            differ = [s for s, r in enumerate(runs, 1) if not same_run(r, run_once(path, s, mode))]
            ok &= not differ
            print(f"  through the processes = in one process in {a.runs - len(differ)} of {a.runs} runs"
                  + (f"; FAIL, seeds {differ} differ" if differ else ""), flush=True)
    print("goals met" if ok else "GOAL FAILED: one number, held >= 0.9, solved after the approach in every run; "
          "range_observable true with a turn, false without, on every solution; "
          "with a turn RMS <= 1.5 CRLB, max <= 5 CRLB, NEES in [2, 8]")
    return 0 if ok else 1


if __name__ == "__main__":
    sys.exit(main())
