"""Benchmarks of the TMA core (002) and the CTMA cycle (003); prints a table.

Run: .venv/bin/python benchmarks/tma.py

Scenario: the classic case of tests/sonar/test_tma.py (own ship 5 kn, 140 deg, turning to
20 deg in 30-deg steps at minutes 12-15; 31 minutes; bearing sigma 1.5 deg), resampled
to N bearings.
"""

from __future__ import annotations

import time

import numpy as np
from core import median_ms  # benchmarks/core.py, beside this script

from common.sonar.tma.bearings_only import solve_tma
from common.sonar.tma.bounds import Bounds
from common.sonar.tma.constrained import TmaTracker, solve_ctma

KN = 1852.0 / 3600.0
SIG = np.radians(1.5)
BETA = np.array([4920.0, 850.0, 4 * KN * np.sin(np.radians(-140.0)), 4 * KN * np.cos(np.radians(-140.0))])
WRONG = Bounds(1000.0, 30e3, 0.0, np.pi, 1 * KN, 3 * KN)


def scenario(n: int, seed: int = 0) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Times, noisy bearings and own positions of the classic case with n bearings."""
    t = np.linspace(0.0, 1860.0, n)
    crs = np.select([t < 720, t < 780, t < 840, t < 900], [140.0, 110.0, 80.0, 50.0], 20.0)
    vel = 5 * KN * np.stack((np.sin(np.radians(crs)), np.cos(np.radians(crs))), 1)
    own = np.vstack(([0.0, 0.0], np.cumsum(vel[:-1] * np.diff(t)[:, None], 0)))
    xt = BETA[0] + BETA[2] * t
    yt = BETA[1] + BETA[3] * t
    brg = np.arctan2(xt - own[:, 0], yt - own[:, 1]) + SIG * np.random.default_rng(seed).standard_normal(n)
    return t, brg, own


def tracker_cycles_per_s(n_tracks: int, bounds: Bounds | None) -> float:
    """CTMA cycles per second: n_tracks trackers fed one bearing a cycle over 32 cycles."""
    data = [scenario(32, seed) for seed in range(n_tracks)]
    trackers = [TmaTracker(bounds) for _ in range(n_tracks)]
    t0 = time.perf_counter()
    for i in range(32):
        for trk, (t, b, own) in zip(trackers, data):
            trk.update(t[i], b[i], SIG, own[i])
    return 32 * n_tracks / (time.perf_counter() - t0)


def main() -> None:
    print(f"{'case':<44}{'value':>12}")
    for n in (32, 200, 1000):
        t, b, own = scenario(n)
        cold = median_ms(lambda: solve_tma(t, b, SIG, own, 0.0), 30)
        sol = solve_tma(t, b, SIG, own, 0.0)
        warm = median_ms(lambda: solve_tma(t, b, SIG, own, 0.0, beta0=sol.beta), 30)
        ctma = median_ms(lambda: solve_ctma(t, b, SIG, own, 0.0, WRONG, sol), 10)
        print(f"{f'TMA solve, {n} bearings, from scratch (ms)':<44}{cold:>12.3f}")
        print(f"{f'TMA solve, {n} bearings, warm start (ms)':<44}{warm:>12.3f}")
        print(f"{f'CTMA solve, {n} bearings, wrong bounds (ms)':<44}{ctma:>12.3f}")
    print(f"{'TmaTracker cycles/s, 50 tracks, no bounds':<44}{tracker_cycles_per_s(50, None):>12.0f}")
    print(f"{'TmaTracker cycles/s, 50 tracks, wrong bounds':<44}{tracker_cycles_per_s(50, WRONG):>12.0f}")


if __name__ == "__main__":
    main()
