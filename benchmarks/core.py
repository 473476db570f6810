"""Micro-benchmarks of the tracking core; prints median times in ms.

Run: .venv/bin/python benchmarks/core.py

Scenario (bistatic plots y = [r_b, v_b, theta], 001 [1]-[4]): N tracks in clusters of
three close targets spread over 0-150 km, 2 pi of azimuth and +-300 m/s, one plot per
track, so each track has a few plots in its chi-square(3) 99 % gate.
"""

from __future__ import annotations

import time
from collections.abc import Callable

import numpy as np

from common.core import gating, kalman, motion
from common.core.angles import wrap_2pi
from common.core.assignment import gnn, nearest_neighbour

H = np.array([[1, 0, 0, 0, 0], [0, 1, 0, 0, 0], [0, 0, 0, 1, 0]], dtype=float)  # 001 [11]
R = np.diag([150.0**2, 2.0**2, np.radians(1.0) ** 2])


def median_ms(fn: Callable[[], object], repeat: int) -> float:
    """Median wall time of fn() over `repeat` runs, in milliseconds."""
    fn()
    times = []
    for _ in range(repeat):
        t0 = time.perf_counter()
        fn()
        times.append(time.perf_counter() - t0)
    return 1e3 * float(np.median(times))


def scenario(N: int, rng: np.random.Generator) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Predicted plots (N, 3), innovation covariances (N, 3, 3) and plots (N, 3)."""
    centres = np.column_stack(
        [
            rng.uniform(5e3, 150e3, N // 3 + 1),
            rng.uniform(-300.0, 300.0, N // 3 + 1),
            rng.uniform(0.0, 2 * np.pi, N // 3 + 1),
        ]
    )
    spread = np.array([150.0, 2.0, np.radians(1.0)])
    z_pred = np.repeat(centres, 3, axis=0)[:N] + rng.normal(size=(N, 3)) * spread
    S = np.tile(2.0 * R, (N, 1, 1))
    z = z_pred + rng.normal(size=(N, 3)) * np.sqrt(np.diag(2.0 * R))
    z[:, 2] = wrap_2pi(z[:, 2])
    return z_pred, S, z


def gated_cost(z_pred: np.ndarray, S: np.ndarray, z: np.ndarray, thr: float) -> np.ndarray:
    """d2 (001 [8]) with np.inf outside the gate, as the trackers gate: a sweep on r_b
    proposes pairs (the marginal i_r^2 <= gamma S_rr), common.core.gating.pair_distances
    scores them (S already holds R here, so R = 0)."""
    half = np.sqrt(thr * S[:, 0, 0])
    t, j = gating.window_pairs(z_pred[:, 0] - half, z_pred[:, 0] + half, z[:, 0])
    _, _, d2 = gating.pair_distances(z_pred, S, z, np.zeros_like(z), t, j, angle_idx=(2,))
    ok = gating.gate(d2, thr)
    cost = np.full((z_pred.shape[0], z.shape[0]), np.inf)
    cost[t[ok], j[ok]] = d2[ok]
    return cost


def dense_gated_cost(z_pred: np.ndarray, S: np.ndarray, z: np.ndarray, thr: float) -> np.ndarray:
    """The same cost from every N x M pair (the MHT mode's dense form)."""
    d2 = gating.mahalanobis_sq(gating.pairwise_innovations(z_pred, z, angle_idx=(2,)), S)
    return np.where(gating.gate(d2, thr), d2, np.inf)


def bench_association(rng: np.random.Generator) -> None:
    thr = gating.chi2_gate(0.99, 3)
    print("association, N tracks x N plots (ms, median)")
    print(f"{'N':>6} {'gated/trk':>9} {'gating':>8} {'dense':>8} {'NN':>8} {'GNN':>8}")
    for N in (100, 500, 1000):
        z_pred, S, z = scenario(N, rng)
        cost = gated_cost(z_pred, S, z, thr)
        assert np.array_equal(np.isfinite(cost), np.isfinite(dense_gated_cost(z_pred, S, z, thr)))
        per_track = np.isfinite(cost).sum(axis=1).mean()
        rep = 30 if N < 1000 else 10
        t_gate = median_ms(lambda: gated_cost(z_pred, S, z, thr), rep)
        t_dense = median_ms(lambda: dense_gated_cost(z_pred, S, z, thr), rep)
        t_nn = median_ms(lambda: nearest_neighbour(cost), rep)
        t_gnn = median_ms(lambda: gnn(cost), rep)
        print(f"{N:>6} {per_track:>9.2f} {t_gate:>8.2f} {t_dense:>8.2f} {t_nn:>8.2f} {t_gnn:>8.2f}")


def bench_kalman(rng: np.random.Generator) -> None:
    print("5-state bistatic KF, per-track dt, predict (incl. F, Q) + update (ms, median)")
    print(f"{'N':>6} {'predict':>8} {'update':>8}")
    for N in (100, 1000, 10000):
        x = rng.normal(size=(N, 5))
        P = np.tile(np.diag([1e4, 10.0, 1.0, 1e-4, 1e-6]), (N, 1, 1))
        dt = rng.uniform(0.5, 1.5, N)
        z = x @ H.T + rng.normal(size=(N, 3))

        def run_predict() -> tuple[np.ndarray, np.ndarray]:
            return kalman.predict(x, P, motion.bistatic_F(dt), motion.bistatic_Q(dt, 1.0, 1e-3))

        xp, Pp = run_predict()
        rep = 30 if N < 10000 else 10
        t_p = median_ms(run_predict, rep)
        t_u = median_ms(
            lambda: kalman.update(xp, Pp, kalman.innovation(z, xp @ H.T, (2,)), H, R), rep
        )
        print(f"{N:>6} {t_p:>8.2f} {t_u:>8.2f}")


def main() -> None:
    rng = np.random.default_rng(0)
    bench_association(rng)
    bench_kalman(rng)


if __name__ == "__main__":
    main()
