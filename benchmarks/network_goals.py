"""Goals of a passive radar network (issue 29 section 3, docs/networks.md "Goals").

Run: PYTHONPATH=. .venv/bin/python benchmarks/network_goals.py [--scenes 300 1000]
     [--seeds 1 2 3 4 5] [--duration 120] [--warm-up 30] [--scale-bases 4 8 16 32]
     [--per-aircraft N]

The in-process chain (simulator -> every base's channel plotter and elementary tracker
-> the network fusion core, the parts of common.wire.radar_chain.RadarChain) on the
scenes of benchmarks/network_scene.py (8 receivers, 21 range-Doppler bases, P_D from
the radar equation). Per scene and seed, over the global reports after the warm-up
(confirmed tracks; an aircraft and a track are paired by a one-to-one assignment
within NEAR): missed and false in % of aircraft per report, switches (changes of the
track paired with an aircraft) per 100 aircraft, position RMSE / PCRLB (RMS of the
error over RMS of sqrt(trace) of the position bound, over the same pairs; the PCRLB is
common.evaluation.pcrlb.pcrlb with r_b, v_b information of each base's channel, no
azimuth, scaled per target and time by the radar-equation P_D inside the window:
common.sim.radar.detection_probability, times the number of the base's scans since the
previous report; q, q_z of NetworkParams), mean position NEES
and % beyond chi-square(3) 99 %, the fusion centre's CPU per base report and its
x real time (scene seconds per CPU second). Then the CPU per scene second of each
service against the number of bases (first n bases of a 16-receiver network,
--scale-aircraft aircraft, seed 1) with the log-log slope. Exits 1 when a goal fails.
--pd-model fixed runs the goal scenes with Bernoulli(pd) detection instead (comparison);
--per-aircraft N lists after each row the N aircraft of largest share of the squared
error (RMSE against the bound, in z, NEES, outside the sites' hull or not).
"""

from __future__ import annotations

import argparse
import sys
import time
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np
from scipy.optimize import linear_sum_assignment
from scipy.spatial import Delaunay
from scipy.stats import chi2

REPO = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(REPO))

from benchmarks.network_scene import scene_doc  # noqa: E402
from common.core.gating import quadratic_form  # noqa: E402
from common.core.track_table import Status  # noqa: E402
from common.deploy.config import Config, parse  # noqa: E402
from common.evaluation.pcrlb import channel_information, pcrlb  # noqa: E402
from common.radar.fusion.report import GlobalTracks  # noqa: E402
from common.radar.geometry.bistatic import POS  # noqa: E402
from common.radar.network.params import NetworkParams  # noqa: E402
from common.sim.radar import detection_probability  # noqa: E402
from common.sim.radar_scenario import PD_MODELS, RadarSim  # noqa: E402
from common.sim.scenario import load_scenario  # noqa: E402
from common.wire.radar_chain import RadarChain  # noqa: E402
from common.wire.radar_messages import plots_of  # noqa: E402
from common.wire.sim_messages import run_scenario, truth_state  # noqa: E402

NEAR = 2000.0  # m: pairing gate of an aircraft and a confirmed track
P0 = np.diag([1e8, 1e4, 1e8, 1e4, 1e8, 1e4])  # prior of the PCRLB (m^2, m^2/s^2)
CHI2_99 = float(chi2.ppf(0.99, 3))


@dataclass
class Run:
    """What one run of the chain measured."""

    duration: float
    reports: int = 0
    aircraft: int = 0
    missed: int = 0
    false: int = 0
    switches: int = 0
    cpu: dict[str, float] = field(default_factory=lambda: {"plotter": 0.0, "tracker": 0.0, "fusion": 0.0})
    base_reports: int = 0
    err2: list[float] = field(default_factory=list)
    nees: list[float] = field(default_factory=list)
    pairs: list[tuple[float, int]] = field(default_factory=list)  # t, truth id of err2 rows
    ez: list[float] = field(default_factory=list)  # z error of err2 rows
    sz2: list[float] = field(default_factory=list)  # the track's z variance of err2 rows
    truth: dict[float, np.ndarray] = field(default_factory=dict)  # report t -> rows [id, state]


def run_chain(cfg: Config, doc: dict[str, Any], seed: int, warm_up: float, score: bool = True) -> Run:
    """The chain on one scene; scores the global reports after `warm_up` when `score`."""
    scn = load_scenario(doc)
    chain = RadarChain(cfg)
    run = Run(scn.duration)
    truth: dict[float, dict[str, Any]] = {}
    held: dict[int, int] = {}
    out: list[GlobalTracks] = []
    for t, msgs in run_scenario(scn, cfg.bases, cfg.arrays, seed):
        for key, msg in msgs:
            if key == "sim/truth/radar":
                truth[round(t, 9)] = msg
            if not key.startswith("radar/plots/"):
                continue
            b = msg["base"]
            c0 = time.process_time()
            fused = chain.plotters[b].push(msg["channel"], msg["t"], plots_of(msg, chain.azimuth[b]))
            c1 = time.process_time()
            run.cpu["plotter"] += c1 - c0
            for tt, f in fused:
                c1 = time.process_time()
                tracks = chain.trackers[b].step(tt, f)
                c2 = time.process_time()
                out += chain.fusion.push(b, tracks, tt)
                c3 = time.process_time()
                run.cpu["tracker"] += c2 - c1
                run.cpu["fusion"] += c3 - c2
                run.base_reports += 1
    c0 = time.process_time()
    out += chain.fusion.flush()
    run.cpu["fusion"] += time.process_time() - c0
    for g in (g for g in out if score and round(g.t, 9) in truth):
        m = truth[round(g.t, 9)]
        run.truth[g.t] = np.column_stack([np.asarray(m["id"], dtype=float), truth_state(m)])
        if g.t >= warm_up:
            _score(run, g, m, held)
    return run


def _score(run: Run, g: GlobalTracks, truth: dict[str, Any], held: dict[int, int]) -> None:
    ids = np.asarray(truth["id"], dtype=int)
    X = truth_state(truth)
    conf = g.status == Status.CONFIRMED
    x, P, tid = g.x[conf], g.P[conf], g.id[conf]
    d = np.linalg.norm(X[:, None, POS] - x[None, :, POS], axis=2).reshape(len(X), len(x))
    r, c = linear_sum_assignment(np.where(d <= NEAR, d, 1e9))
    ok = d[r, c] <= NEAR
    r, c = r[ok], c[ok]
    run.reports += 1
    run.aircraft += len(X)
    run.missed += len(X) - len(r)
    run.false += len(x) - len(c)
    for i, j in zip(ids[r].tolist(), tid[c].tolist()):
        run.switches += int(held.get(i, j) != j)
        held[i] = j
    e = x[c][:, POS] - X[r][:, POS]
    run.err2 += np.sum(e**2, axis=1).tolist()
    run.ez += e[:, 2].tolist()
    run.sz2 += P[c][:, 4, 4].tolist()
    run.nees += quadratic_form(e, P[c][:, POS][:, :, POS]).tolist()
    run.pairs += [(g.t, i) for i in ids[r].tolist()]


def scans(base_times: np.ndarray, times: np.ndarray) -> np.ndarray:
    """Scans of a base in each interval (t_k-1, t_k] of the report times (K,), all
    before t_0 in the first: the bound takes one step per report, and a base scans every
    0.5-1 s, so its information per step is that of this many scans."""
    edges = np.searchsorted(base_times, times, side="right")
    return np.diff(edges, prepend=0).astype(float)


def bound_ratio(run: Run, cfg: Config, radar: RadarSim) -> float:
    """RMSE / PCRLB over the scored pairs (module doc)."""
    var, _ = pair_bounds(run, cfg, radar)
    return float(np.sqrt(np.mean(run.err2)) / np.sqrt(np.mean(var)))


def pair_bounds(run: Run, cfg: Config, radar: RadarSim) -> tuple[np.ndarray, np.ndarray]:
    """Trace of the position PCRLB and its z variance at each scored pair."""
    times = np.array(sorted(run.truth))
    ids = np.unique(np.concatenate([v[:, 0] for v in run.truth.values()])).astype(int)
    states = np.zeros((times.size, ids.size, 6))
    present = np.zeros((times.size, ids.size), dtype=bool)
    for k, t in enumerate(times):
        j = np.searchsorted(ids, run.truth[t][:, 0].astype(int))
        states[k, j], present[k, j] = run.truth[t][:, 1:], True
    tx = np.array([b.tx for b in cfg.bases])
    rx = np.array([b.rx for b in cfg.bases])
    info, pd = [], np.zeros((times.size, ids.size, len(cfg.bases)))
    for i, b in enumerate(cfg.bases):
        ch = radar.channel(b.channels[0])
        info.append(channel_information(np.ones(1), np.array([ch.srb]), np.array([ch.svb]),
                                        np.array([np.inf])))
        r_t = np.linalg.norm(states[..., POS] - b.tx, axis=-1)
        r_r = np.linalg.norm(states[..., POS] - b.rx, axis=-1)
        pd[..., i] = detection_probability(r_t, r_r, ch, radar) * (r_t + r_r <= radar.rb_max)
        pd[..., i] *= scans(radar.base_times(b.id, run.duration), times)[:, None]
    p = NetworkParams()  # the bound starts from P0 at an aircraft's first report
    J = pcrlb(times, states, present, tx, rx, np.array(info), p.q, p.q_z, P0, pd)
    var = np.trace(J[:, :, POS][:, :, :, POS], axis1=2, axis2=3)
    k = np.searchsorted(times, [t for t, _ in run.pairs])
    j = np.searchsorted(ids, [i for _, i in run.pairs])
    return var[k, j], J[k, j, 4, 4]


def contributors(run: Run, cfg: Config, radar: RadarSim, top: int) -> None:
    """The `top` aircraft of largest share of the squared error: share, samples, RMSE,
    PCRLB, z RMSE, the track's z sigma, z PCRLB (RMS over the pairs, m), mean NEES, %
    beyond 99 %, whether outside the sites' hull in the plane (fraction of the pairs)."""
    var, varz = pair_bounds(run, cfg, radar)
    ids = np.array([i for _, i in run.pairs])
    err2, ez, sz2, nees = (np.array(v) for v in (run.err2, run.ez, run.sz2, run.nees))
    pos = np.array([run.truth[t][run.truth[t][:, 0] == i][0, [1, 3]] for t, i in run.pairs])
    sites = np.concatenate([[b.tx[:2] for b in cfg.bases], [b.rx[:2] for b in cfg.bases]])
    out = Delaunay(sites).find_simplex(pos) < 0
    rows = []
    for i in np.unique(ids):
        m = ids == i
        rows.append((err2[m].sum() / err2.sum(), i, m.sum(), *np.sqrt([err2[m].mean(), var[m].mean(),
                     np.mean(ez[m] ** 2), sz2[m].mean(), varz[m].mean()]), nees[m].mean(),
                     100.0 * np.mean(nees[m] > CHI2_99), out[m].mean()))
    print(f"  {'share':>5} {'id':>4} {'n':>4} {'rmse':>6} {'pcrlb':>6} {'z rmse':>6} {'z sig':>6} "
          f"{'z bnd':>6} {'nees':>6} {'>99 %':>6} {'out':>4}")
    for r in sorted(rows, reverse=True)[:top]:
        print(f"  {r[0]:>5.2f} {r[1]:>4d} {r[2]:>4d} " + " ".join(f"{v:>6.0f}" for v in r[3:8])
              + f" {r[8]:>6.1f} {r[9]:>6.1f} {r[10]:>4.1f}")


def goals(args: argparse.Namespace) -> bool:
    print(f"{'scene':>5} {'seed':>4} {'bases':>5} {'missed %':>8} {'false %':>7} {'sw/100':>6} "
          f"{'rmse/pcrlb':>10} {'nees':>6} {'>99% %':>6} {'ms/report':>9} {'x rt':>6}")
    ok = True
    for name in args.scenes:
        for seed in args.seeds:
            doc = scene_doc(int(name), seed=seed, duration=args.duration)
            doc["sim"]["radar"]["pd_model"] = args.pd_model
            cfg = parse(doc)
            radar = load_scenario(doc).radar
            assert radar is not None
            run = run_chain(cfg, doc, seed, args.warm_up)
            n = max(run.aircraft, 1)
            missed, false = 100.0 * run.missed / n, 100.0 * run.false / n
            sw = 100.0 * run.switches / max(int(name), 1)
            ratio = bound_ratio(run, cfg, radar) if run.err2 else float("nan")
            nees = float(np.mean(run.nees)) if run.nees else float("nan")
            beyond = 100.0 * float(np.mean(np.array(run.nees) > CHI2_99)) if run.nees else float("nan")
            fus = run.cpu["fusion"]
            print(f"{name:>5} {seed:>4} {len(cfg.bases):>5} {missed:>8.2f} {false:>7.2f} {sw:>6.1f} "
                  f"{ratio:>10.2f} {nees:>6.2f} {beyond:>6.2f} {1e3 * fus / max(run.base_reports, 1):>9.2f} "
                  f"{run.duration / max(fus, 1e-9):>6.1f}", flush=True)
            if args.per_aircraft and run.err2:
                contributors(run, cfg, radar, args.per_aircraft)
            ok &= bool(missed < 1 and false < 1 and sw < 1 and ratio <= 1.3 and nees <= 4.5 and beyond < 2)
    return ok


def scaling(args: argparse.Namespace) -> None:
    if not args.scale_bases:
        return
    print(f"\nCPU s per scene s, {args.scale_aircraft} aircraft, {args.scale_duration:g} s, seed 1")
    print(f"{'bases':>5} {'plotter':>8} {'tracker':>8} {'fusion':>8}")
    rows = []
    for nb in args.scale_bases:
        doc = scene_doc(args.scale_aircraft, receivers=16, seed=1, duration=args.scale_duration, n_bases=nb)
        run = run_chain(parse(doc), doc, 1, args.warm_up, score=False)
        rows.append([run.cpu[s] / run.duration for s in ("plotter", "tracker", "fusion")])
        print(f"{nb:>5} " + " ".join(f"{v:>8.4f}" for v in rows[-1]), flush=True)
    if len(rows) > 1:
        slope = np.polyfit(np.log(args.scale_bases), np.log(np.maximum(np.array(rows), 1e-9)), 1)[0]
        print("slope " + " ".join(f"{v:>8.2f}" for v in slope))


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser()
    ap.add_argument("--scenes", nargs="*", default=["300", "1000"],
                    help="aircraft per scene (none: the cost growth alone)")
    ap.add_argument("--seeds", type=int, nargs="+", default=[1, 2, 3, 4, 5])
    ap.add_argument("--duration", type=float, default=120.0)
    ap.add_argument("--warm-up", type=float, default=30.0)
    ap.add_argument("--pd-model", choices=PD_MODELS, default="snr",
                    help="detection model of the goal scenes (fixed: pd alone, for comparison)")
    ap.add_argument("--per-aircraft", type=int, default=0, metavar="N",
                    help="after each row, the N aircraft of largest share of the squared error")
    ap.add_argument("--scale-bases", type=int, nargs="*", default=[4, 8, 16, 32])
    ap.add_argument("--scale-aircraft", type=int, default=100)
    ap.add_argument("--scale-duration", type=float, default=30.0)
    a = ap.parse_args(argv)
    ok = goals(a)
    scaling(a)
    print("goals:", "not run" if not a.scenes else "met" if ok else "FAILED")
    return 0 if ok else 1


if __name__ == "__main__":
    sys.exit(main())
