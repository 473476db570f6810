"""Per-base radar chain benchmark: channel plotter (001 modules 31-34) and elementary
tracker (modules 41-44) time per scan, core objects driven directly (no Zenoh), and the
same elementary-tracking problem through Stone Soup's GNN tracker when installed.

Run: .venv/bin/python benchmarks/radar_base.py [--scans N] [--stonesoup-scans N]

Problems: scenarios/dense.toml (every base), and N = 300 and 1000 straight-flying
targets over one 3-channel base (receiver and transmitter of two_targets.toml base b1,
default channel model: pd 0.9, 2 false plots per channel and scan, 150 m, 2 m/s,
1.5 deg). Stone Soup gets the same fused plots and the same 5-state model: transition
ConstantAcceleration(sigma_gamma^2) x ConstantVelocity(sigma_omega^2), i.e. F [19] and
Q [20], measurement [r_b, v_b, theta] with each fused plot's own R, Mahalanobis gate at
the same chi-square(3) probability, GNNWith2DAssignment, MultiMeasurementInitiator
(3 points, prior covariance of [17] on gamma_b, omega), deletion after max_coast
scans without update. GOSPA (p = 2, c = 10) is computed per scan on confirmed and
coasting tracks (ours) and on all released tracks (Stone Soup) against the true
[r_b, v_b, theta], each component in units of the default channel sigma, and averaged
over the scans. Stone Soup has no angle wrapping on theta (a difference across North
is seen as ~2 pi); the scenarios keep targets away from North rarely enough to ignore.
"""

from __future__ import annotations

import argparse
import datetime
import time
import tomllib
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from common.core.gating import chi2_gate
from common.core.track_table import Status
from common.deploy.config import RadarBase, load
from common.evaluation.metrics import gospa
from common.radar.elementary.tracker import ElementaryParams, ElementaryTracker, RadarCrossingParams
from common.radar.geometry.bistatic import azimuth, bistatic_range, bistatic_range_rate
from common.radar.plots.channel_fusion import PlotFusion, Plots
from common.sim.radar import radar_plots
from common.sim.radar_scenario import RadarChannelSim, RadarSim
from common.sim.simulator import load_scenario
from common.wire.sim_messages import run_scenario

REPO = Path(__file__).resolve().parents[1]
UNITS = np.array([150.0, 2.0, np.radians(1.5)])  # GOSPA units: default channel sigmas
GOSPA_C = 10.0


@dataclass
class BaseRun:
    """Channel plots per scan of one base and the truth in its measurement space."""

    base: RadarBase
    scans: list[tuple[float, list[tuple[str, Plots]]]] = field(default_factory=list)
    truth: list[np.ndarray] = field(default_factory=list)


def to_plots(cols: dict) -> Plots:
    return Plots(*(np.asarray(cols[c], dtype=float) for c in ("rb", "vb", "az", "srb", "svb", "saz")))


def truth_meas(base: RadarBase, pos: np.ndarray, vel: np.ndarray) -> np.ndarray:
    """True [r_b, v_b, theta] (001 [1]-[3]) of targets at pos, vel (N, 3)."""
    return np.column_stack([bistatic_range(pos, base.tx, base.rx),
                            bistatic_range_rate(pos, vel, base.tx, base.rx),
                            azimuth(pos, base.rx)])


def dense_runs(n_scans: int) -> list[BaseRun]:
    path = REPO / "scenarios" / "dense.toml"
    cfg = load(path)
    scn = load_scenario(tomllib.loads(path.read_text()))
    runs = {b.id: BaseRun(b) for b in cfg.bases}
    for t, msgs in run_scenario(scn, cfg.bases, cfg.arrays, seed=1, n_scans=n_scans):
        for r in runs.values():
            r.scans.append((t, []))
        for key, m in msgs:
            if key == "sim/truth/radar":
                pos = np.column_stack([m["x"], m["y"], m["z"]])
                vel = np.column_stack([m["vx"], m["vy"], m["vz"]])
                for r in runs.values():
                    r.truth.append(truth_meas(r.base, pos, vel))
            elif key.startswith("radar/plots/"):
                runs[m["base"]].scans[-1][1].append((m["channel"], to_plots(m)))
    return list(runs.values())


def synthetic_run(n_targets: int, n_scans: int, seed: int = 1) -> BaseRun:
    """n_targets straight-flying targets seen by one 3-channel base."""
    rng = np.random.default_rng(seed)
    base = RadarBase("b1", np.array([-35000.0, 20000.0, 300.0]), np.array([0.0, 0.0, 30.0]),
                     ["c1", "c2", "c3"], 1)
    radar = RadarSim(RadarChannelSim(pd=0.9, clutter=2.0, srb=150.0, svb=2.0,
                                     saz=np.radians(1.5)), {}, [], 1.0)
    r = np.sqrt(rng.uniform(10e3**2, 80e3**2, n_targets))
    a = rng.uniform(0, 2 * np.pi, n_targets)
    pos0 = np.column_stack([r * np.sin(a), r * np.cos(a), rng.uniform(1e3, 10e3, n_targets)])
    h = rng.uniform(0, 2 * np.pi, n_targets)
    v = rng.uniform(100.0, 250.0, n_targets)
    vel = np.column_stack([v * np.sin(h), v * np.cos(h), np.zeros(n_targets)])
    run = BaseRun(base)
    rngs = {c: np.random.default_rng([seed, k]) for k, c in enumerate(base.channels)}
    for k in range(n_scans):
        t = float(k)
        pos = pos0 + vel * t
        run.truth.append(truth_meas(base, pos, vel))
        run.scans.append((t, [(c, to_plots(radar_plots(pos, vel, base, radar.channel(c), radar, rngs[c])))
                              for c in base.channels]))
    return run


def estimates_ours(rep) -> np.ndarray:
    keep = rep.status != Status.TENTATIVE
    return rep.x[keep][:, [0, 1, 3]]


def mean_gospa(truth: list[np.ndarray], est: list[np.ndarray]) -> float:
    """Mean over scans of GOSPA in units of the default channel sigmas (azimuth not
    wrapped: a pair across North counts as far apart, the same for both trackers)."""
    return float(np.mean([gospa(tr / UNITS, es / UNITS, GOSPA_C).distance
                          for tr, es in zip(truth, est)]))


def run_ours(run: BaseRun, params: ElementaryParams, crossing: bool = True) -> dict:
    fusion = PlotFusion(run.base.channels, run.base.p)
    tracker = ElementaryTracker(params, RadarCrossingParams(enabled=crossing))
    t_plot, t_track, n_plots = [], [], 0
    fused_scans, est = [], []
    for t, chans in run.scans:
        out = []
        t0 = time.perf_counter()
        for c, p in chans:
            out += fusion.push(c, t, p)
        t_plot.append(time.perf_counter() - t0)
        n_plots += sum(len(p) for _, p in chans)
        for s, f in out:
            t0 = time.perf_counter()
            rep = tracker.step(s, f)
            t_track.append(time.perf_counter() - t0)
            fused_scans.append((s, f))
            est.append(estimates_ours(rep))
    return {"plot_ms": 1e3 * np.mean(t_plot), "plots_per_s": n_plots / np.sum(t_plot),
            "track_ms": 1e3 * np.mean(t_track), "track_max_ms": 1e3 * np.max(t_track[2:] or t_track),
            "gospa": mean_gospa(run.truth[: len(est)], est), "fused": fused_scans,
            "n_plots": n_plots / len(run.scans)}


def run_stonesoup(fused: list[tuple[float, Plots]], truth: list[np.ndarray],
                  params: ElementaryParams) -> dict | None:
    """Stone Soup GNN tracker on the same fused plots; None if not installed."""
    try:
        from stonesoup.dataassociator.neighbour import GNNWith2DAssignment
        from stonesoup.deleter.time import UpdateTimeStepsDeleter
        from stonesoup.hypothesiser.distance import DistanceHypothesiser
        from stonesoup.initiator.simple import MultiMeasurementInitiator
        from stonesoup.measures import Mahalanobis
        from stonesoup.models.measurement.linear import LinearGaussian
        from stonesoup.models.transition.linear import (
            CombinedLinearGaussianTransitionModel,
            ConstantAcceleration,
            ConstantVelocity,
        )
        from stonesoup.predictor.kalman import KalmanPredictor
        from stonesoup.types.detection import Detection
        from stonesoup.types.state import GaussianState
        from stonesoup.updater.kalman import KalmanUpdater
    except ImportError:
        return None
    transition = CombinedLinearGaussianTransitionModel([
        ConstantAcceleration(noise_diff_coeff=params.sigma_gamma**2),  # 001 [19]-[20]
        ConstantVelocity(noise_diff_coeff=params.sigma_omega**2),
    ])
    mapping = (0, 1, 3)
    default_mm = LinearGaussian(ndim_state=5, mapping=mapping, noise_covar=np.diag(UNITS**2))
    predictor = KalmanPredictor(transition)
    updater = KalmanUpdater(default_mm)
    hyp = DistanceHypothesiser(predictor, updater, Mahalanobis(),
                               missed_distance=float(np.sqrt(chi2_gate(params.gate_prob, 3))))
    assoc = GNNWith2DAssignment(hyp)
    deleter = UpdateTimeStepsDeleter(params.max_coast + 1)
    prior = GaussianState(np.zeros((5, 1)), np.diag(
        [1e10, 1e6, params.sigma_gamma_init**2, 10.0, params.sigma_omega_init**2]))
    initiator = MultiMeasurementInitiator(prior, deleter, assoc, updater, default_mm, min_points=3)
    t_epoch = datetime.datetime(2000, 1, 1)
    tracks: set = set()
    times, est = [], []
    for s, f in fused:
        when = t_epoch + datetime.timedelta(seconds=s)
        dets = {Detection(np.array([[f.rb[j]], [f.vb[j]], [f.az[j]]]), timestamp=when,
                          measurement_model=LinearGaussian(5, mapping, np.diag(
                              [f.srb[j] ** 2, f.svb[j] ** 2, f.saz[j] ** 2])))
                for j in range(len(f))}
        t0 = time.perf_counter()
        hyps = assoc.associate(tracks, dets, when)
        used = set()
        for track in tracks:
            h = hyps[track]
            if h:
                track.append(updater.update(h))
                used.add(h.measurement)
            else:
                track.append(h.prediction)
        tracks -= deleter.delete_tracks(tracks)
        tracks |= initiator.initiate(dets - used, when)
        times.append(time.perf_counter() - t0)
        est.append(np.array([np.ravel(tr.state_vector)[list(mapping)] for tr in tracks]).reshape(-1, 3))
    return {"track_ms": 1e3 * np.mean(times), "gospa": mean_gospa(truth[: len(est)], est)}


def report(name: str, runs: list[BaseRun], params: ElementaryParams, ss_scans: int,
           crossing: bool = True) -> None:
    for run in runs:
        ours = run_ours(run, params, crossing)
        line = (f"{name:>8} {run.base.id:>3} ch={len(run.base.channels)} "
                f"plots/scan={ours['n_plots']:7.0f} | plotter {ours['plot_ms']:7.2f} ms/scan "
                f"({ours['plots_per_s']:9.0f} plots/s) | tracker {ours['track_ms']:7.2f} ms/scan "
                f"(max {ours['track_max_ms']:6.1f}) GOSPA {ours['gospa']:7.2f}")
        if ss_scans > 0:
            ours_k = run_ours(BaseRun(run.base, run.scans[:ss_scans], run.truth[:ss_scans]), params)
            ss = run_stonesoup(ours_k["fused"], run.truth, params)
            if ss is None:
                line += " | Stone Soup: not installed (pip install stonesoup; extra 'bench')"
            else:
                line += (f" | first {ss_scans} scans: ours {ours_k['track_ms']:6.2f} ms GOSPA "
                         f"{ours_k['gospa']:6.2f}, Stone Soup GNN {ss['track_ms']:8.1f} ms GOSPA "
                         f"{ss['gospa']:6.2f}")
        print(line, flush=True)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--scans", type=int, default=60)
    ap.add_argument("--stonesoup-scans", type=int, default=10,
                    help="scans of dense.toml run through Stone Soup as well (0: skip); "
                         "Stone Soup takes seconds per scan here, so N=300 gets at most 3 "
                         "and N=1000 none")
    args = ap.parse_args()
    params = ElementaryParams()
    report("dense", dense_runs(args.scans), params, args.stonesoup_scans)
    report("N=300", [synthetic_run(300, args.scans)], params, min(args.stonesoup_scans, 3))
    big = [synthetic_run(1000, args.scans)]
    report("N=1000", big, params, 0)
    report("no-cross", big, params, 0, crossing=False)


if __name__ == "__main__":
    main()
