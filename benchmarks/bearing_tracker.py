"""Cycle time and bearing GOSPA of the seed 000 bearing tracker, next to Stone Soup.

Run: .venv/bin/python benchmarks/bearing_tracker.py

Problem: N targets with straight-line bearing tracks (bearings spread over
[0.2, 2 pi - 0.2] so that no track wraps, rates +-1e-4 rad/s), 10 s cycles,
P_D = 0.9, bearing sigma 0.2 deg, level 20 dB +- 2 dB; N/2 false detections per cycle,
uniform in bearing, level 3 dB + Exp(2 dB). Tracker parameters: defaults except P_D,
P_FA (see `params`) and P0 of the bearing rate (2e-4 rad/s, the rates of the problem).
WARM warm-up cycles, then TIMED timed cycles.

Ours: the whole cycle of `BearingTracker.step` (predict, gate G, GNN, crossing
management, Joseph update, quality L, track opening on clutter, register).
Stone Soup (if installed): the same model (ConstantVelocity blocks on bearing and level,
LinearGaussian H, the same R), GNN (GNNWith2DAssignment over a DistanceHypothesiser with
Mahalanobis distance and a chi-square(2) 99.9 % gate, since Stone Soup has no per-pair
gate G), tracks initialised at the truth and
never deleted: it does less work than ours (no track management). GOSPA (c = 2 deg,
p = 2) on the confirmed bearings, averaged over the timed cycles.
"""

from __future__ import annotations

import datetime
import math
import time
from dataclasses import replace

import numpy as np

from common.core.angles import wrap_2pi
from common.evaluation.metrics import gospa
from common.sonar.mht.params import MhtParams, SonarTrackerParams
from common.sonar.trackers import bearing_tracker

DT, SIGMA, PD, WARM, TIMED = 10.0, math.radians(0.2), 0.9, 15, 20
C_DEG = 2.0
PARAMS = SonarTrackerParams(mode="broadband", p_d=PD, init_brg_rate_sigma=2e-4)


def params(N: int) -> SonarTrackerParams:
    """PARAMS with P_FA scaled by the clutter density (N/2 false detections per cycle):
    1e-3 per beam at N = 10, i.e. per beam and per dB of level near the targets' level
    (the clutter levels are far below the targets', so the bearing-only rate N/2 x
    beam / 2 pi would overstate it)."""
    return replace(PARAMS, p_fa=1e-3 * N / 10)


def scenario(N: int, seed: int = 0) -> list[tuple[float, np.ndarray, np.ndarray, np.ndarray]]:
    """Per cycle: (t, detected bearings, linear amplitudes, true bearings (N,))."""
    rng = np.random.default_rng(seed)
    b0 = np.linspace(0.2, 2 * math.pi - 0.2, N) + rng.uniform(-0.2, 0.2, N) * (2 * math.pi / N)
    rate = rng.uniform(-1e-4, 1e-4, N)
    out = []
    for k in range(WARM + TIMED):
        t = k * DT
        truth = b0 + rate * t
        det = rng.random(N) < PD
        brg = truth[det] + SIGMA * rng.standard_normal(det.sum())
        lvl = 20.0 + 2.0 * rng.standard_normal(det.sum())
        nc = rng.poisson(N / 2)
        brg = np.concatenate([brg, rng.uniform(0.0, 2 * math.pi, nc)])
        lvl = np.concatenate([lvl, 3.0 + rng.exponential(2.0, nc)])
        out.append((t, wrap_2pi(brg), 10.0 ** (lvl / 10.0), truth))
    return out


def run_ours(cycles: list, N: int) -> tuple[float, float]:
    """Median ms per timed cycle and mean GOSPA (deg) of our tracker."""
    tr = bearing_tracker(params(N), MhtParams(), "cylindrical", SIGMA)
    times, g = [], []
    for k, (t, brg, amp, truth) in enumerate(cycles):
        t0 = time.perf_counter()
        c = tr.step(t, brg, amp, 0.0)
        if k >= WARM:
            times.append(time.perf_counter() - t0)
            est = np.degrees(c.x[c.confirmed, 0])[:, None]
            g.append(gospa(np.degrees(truth)[:, None], est, C_DEG).distance)
    return 1e3 * float(np.median(times)), float(np.mean(g))


def run_stonesoup(cycles: list) -> tuple[float, float] | None:
    """Same numbers for Stone Soup GNN with the same model, or None if not installed."""
    try:
        from stonesoup.dataassociator.neighbour import GNNWith2DAssignment
        from stonesoup.hypothesiser.distance import DistanceHypothesiser
        from stonesoup.measures import Mahalanobis
        from stonesoup.models.measurement.linear import LinearGaussian
        from stonesoup.models.transition.linear import (
            CombinedLinearGaussianTransitionModel,
            ConstantVelocity,
        )
        from stonesoup.predictor.kalman import KalmanPredictor
        from stonesoup.types.detection import Detection
        from stonesoup.types.state import GaussianState
        from stonesoup.types.track import Track
        from stonesoup.updater.kalman import KalmanUpdater
    except ImportError:
        return None
    from scipy.stats import chi2

    trans = CombinedLinearGaussianTransitionModel(
        [ConstantVelocity(PARAMS.q_theta), ConstantVelocity(PARAMS.q_a)]
    )
    meas = LinearGaussian(4, (0, 2), np.diag([SIGMA**2, PARAMS.sigma_amp_db**2]))
    predictor, updater = KalmanPredictor(trans), KalmanUpdater(meas)
    hyp = DistanceHypothesiser(predictor, updater, Mahalanobis(), missed_distance=math.sqrt(chi2.ppf(0.999, 2)))
    assoc = GNNWith2DAssignment(hyp)
    t_ref = datetime.datetime(2000, 1, 1)
    truth0 = cycles[0][3]
    tracks = {
        Track([GaussianState(np.array([[b], [0.0], [20.0], [0.0]]),
                             np.diag([SIGMA**2, 1e-8, 4.0, 1e-4]), timestamp=t_ref)])
        for b in truth0
    }
    times, g = [], []
    for k, (t, brg, amp, truth) in enumerate(cycles[1:], start=1):
        ts = t_ref + datetime.timedelta(seconds=t)
        lvl = 10.0 * np.log10(amp)
        dets = {Detection(np.array([[b], [a]]), timestamp=ts, measurement_model=meas)
                for b, a in zip(brg, lvl)}
        t0 = time.perf_counter()
        hyps = assoc.associate(tracks, dets, ts)
        for track, h in hyps.items():
            track.append(updater.update(h) if h else h.prediction)
        if k >= WARM:
            times.append(time.perf_counter() - t0)
            est = np.degrees([[tr.state_vector[0, 0]] for tr in tracks])
            g.append(gospa(np.degrees(truth)[:, None], est, C_DEG).distance)
    return 1e3 * float(np.median(times)), float(np.mean(g))


def main() -> None:
    print(f"{'N':>5} {'ours ms/cycle':>14} {'ours GOSPA deg':>15} {'SS ms/cycle':>12} {'SS GOSPA deg':>13}")
    for N in (10, 50, 200):
        cycles = scenario(N)
        ms, g = run_ours(cycles, N)
        ss = run_stonesoup(cycles)
        ss_txt = f"{ss[0]:12.2f} {ss[1]:13.3f}" if ss else "   (stonesoup not installed: column skipped)"
        print(f"{N:5d} {ms:14.2f} {g:15.3f} {ss_txt}")


if __name__ == "__main__":
    main()
