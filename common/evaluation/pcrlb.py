"""Posterior Cramer-Rao lower bound of the global tracking problem, and the scoring of
global tracks against truth with it (RMSE / bound ratio, NEES).

PCRLB (Tichavsky, Muravchik, Nehorai 1998), recursive information matrix for the CV
model of 001 [51] (linear, Gaussian process noise) and the bistatic measurements
y_b = g_b(x) + v of every base b ([1]-[3], g of [47]):
    J_{k+1} = (Q + F J_k^-1 F')^-1 + sum_b G_b' I_b G_b,   G_b = dg_b/dx at the truth,
with I_b the expected information of one scan of base b. Detection probability
enters through the information reduction factor of the no-clutter case:
I_b = sum over channels pd_c R_c^-1 (R_c the diagonal covariance [4] of channel c).
Vectorised over targets; the recursion runs over time. A target's recursion starts
at its first presence with the prior information P0^-1.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np
from scipy.special import gammaincinv

from common.core.gating import quadratic_form
from common.core.motion import cv_F, cv_Q
from common.evaluation.metrics import MetricsAccumulator
from common.radar.geometry.bistatic import POS, project_jacobian

PairRow = tuple[float, int, float, float, float]  # t, truth id, NEES pos, NEES state, error^2
Series = list[dict[int, int | None]]  # truth -> track per step (metrics.joint_associations)


def base_information(radar: Any, bases: Sequence[Any]) -> np.ndarray:
    """Expected information per base (B, 3, 3) of one scan: `channel_information` of each
    base's channels, whose pd, srb, svb, saz come from ``radar.channel(id)`` (the
    simulator's radar scene, common.sim.scenario.RadarSim)."""
    out = []
    for b in bases:
        ch = [radar.channel(c) for c in b.channels]
        out.append(channel_information(np.array([c.pd for c in ch]), np.array([c.srb for c in ch]),
                                       np.array([c.svb for c in ch]), np.array([c.saz for c in ch])))
    return np.array(out)


def channel_information(pd: np.ndarray, srb: np.ndarray, svb: np.ndarray,
                        saz: np.ndarray) -> np.ndarray:
    """Expected information (3, 3) of one scan of a base from its channels:
    sum_c pd_c diag(1/srb_c^2, 1/svb_c^2, 1/saz_c^2)."""
    inv = np.stack([1 / np.square(srb), 1 / np.square(svb), 1 / np.square(saz)], axis=-1)
    return np.diag(np.sum(np.asarray(pd, float)[:, None] * inv, axis=0))


def pcrlb(
    times: np.ndarray, states: np.ndarray, present: np.ndarray, tx: np.ndarray,
    rx: np.ndarray, info: np.ndarray, q: float, q_z: float, P0: np.ndarray,
    pd: np.ndarray | None = None,
) -> np.ndarray:
    """Bounds (K, N, 6, 6) for truth states (K, N, 6) [x vx y vy z vz] at times (K,),
    present (K, N); tx, rx (B, 3); info (B, 3, 3), scaled per target by pd (K, N, B)
    when given (a P_D that depends on the geometry). NaN where a target is absent."""
    K, N, _ = states.shape
    out = np.full((K, N, 6, 6), np.nan)
    J = np.zeros((N, 6, 6))
    alive = np.zeros(N, dtype=bool)
    J0 = np.linalg.inv(P0)
    for k in range(K):
        on = present[k]
        if k > 0:
            dt = times[k] - times[k - 1]
            F, Q = cv_F(dt), cv_Q(dt, q, q_z)
            prev = alive & on
            J[prev] = np.linalg.inv(Q + F @ np.linalg.inv(J[prev]) @ F.T)
        J[on & ~alive] = J0
        alive = on
        for b in range(tx.shape[0]):
            G = project_jacobian(states[k, on], tx[b], rx[b])
            Ib = info[b] if pd is None else pd[k, on, b][:, None, None] * info[b]
            J[on] += np.swapaxes(G, 1, 2) @ Ib @ G
        out[k, on] = np.linalg.inv(J[on])
    return out


def nees(err: np.ndarray, P: np.ndarray) -> np.ndarray:
    """Normalised estimation error squared e' P^-1 e for errors (M, n), P (M, n, n)."""
    return quadratic_form(err, P)


def mean_nees_interval(dof: int, samples: int, prob: float = 0.95) -> tuple[float, float]:
    """Two-sided interval of the mean of `samples` independent chi-square(dof) NEES."""
    a = (1 - prob) / 2
    n = dof * samples
    # chi2(n) quantiles as scipy.stats.chi2.ppf computes them, without its import cost
    return float(2.0 * gammaincinv(n / 2, a) / samples), float(2.0 * gammaincinv(n / 2, 1 - a) / samples)


@dataclass(frozen=True)
class MonteCarloNees:
    """Average NEES over Monte Carlo runs at each time (Bar-Shalom, Li, Kirubarajan 5.4.2):
    times (K,), anees (K,) the mean of the n (K,) samples (runs x targets) at each time,
    and their two-sided chi-square(dof n) / n intervals lo, hi (K,)."""

    times: np.ndarray
    anees: np.ndarray
    n: np.ndarray
    lo: np.ndarray
    hi: np.ndarray

    @property
    def inside(self) -> float:
        """Fraction of the times at which the average NEES is inside its interval."""
        return float(np.mean((self.anees >= self.lo) & (self.anees <= self.hi)))


def monte_carlo_nees(runs: list[np.ndarray], dof: int = 3, prob: float = 0.95,
                     min_fraction: float = 0.75) -> MonteCarloNees:
    """Average NEES per time over independent runs: each run gives rows (time from the
    run's start, NEES) of its targets. Under consistency n * ANEES_k is chi-square with
    dof * n degrees of freedom at every time k, whatever the correlation in time within
    a run (which makes the time average of one run a poor test). Times with fewer
    samples than `min_fraction` of the most populated time are left out."""
    rows = np.concatenate([np.asarray(r, dtype=float).reshape(-1, 2) for r in runs])
    times, inv = np.unique(rows[:, 0], return_inverse=True)
    n = np.bincount(inv, minlength=times.size)
    anees = np.bincount(inv, rows[:, 1], minlength=times.size) / np.maximum(n, 1)
    keep = n >= min_fraction * n.max()
    lo, hi = np.array([mean_nees_interval(dof, int(k), prob) for k in n[keep]]).reshape(-1, 2).T
    return MonteCarloNees(times[keep], anees[keep], n[keep], lo, hi)


@dataclass
class Evaluation:
    """Global tracks scored against truth, step by step (times must increase).

    GOSPA / OSPA / switches / breaks on positions via common.evaluation.metrics; for the GOSPA
    pairs: position and state NEES and squared position errors per truth id, kept
    with the time, so that RMSE and NEES can be taken after a convergence time.
    """

    c: float = 2000.0
    gamma: float = 2000.0
    keep_steps: bool = False
    metrics: MetricsAccumulator = field(init=False)
    truth: dict[int, list[tuple[float, np.ndarray]]] = field(default_factory=dict)
    pairs: list[PairRow] = field(default_factory=list)
    steps: list[tuple[float, np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray]] = field(
        default_factory=list)

    def __post_init__(self) -> None:
        self.metrics = MetricsAccumulator(self.c, 2.0, self.gamma)

    def add(self, t: float, truth_ids: np.ndarray, truth_x: np.ndarray, track_ids: np.ndarray,
            track_x: np.ndarray, track_P: np.ndarray) -> None:
        """truth_x (n, 6) and track_x (m, 6) as [x vx y vy z vz], track_P (m, 6, 6)."""
        for i, s in zip(truth_ids.tolist(), truth_x):
            self.truth.setdefault(int(i), []).append((t, s))
        res = self.metrics.add(t, truth_ids, truth_x[:, POS], track_ids, track_x[:, POS])
        if self.keep_steps:
            self.steps.append((t, np.array(truth_ids), np.array(truth_x), np.array(track_ids),
                               np.array(track_x), np.array(track_P)))
        self.pairs += _pair_rows(t, truth_ids, truth_x, track_x, track_P, res.rows, res.cols)

    def joint_pairs(self, series: Series) -> list[PairRow]:
        """The rows of `pairs` for the pairs of a truth -> track series over the kept steps
        (keep_steps), e.g. the trajectory GOSPA assignment (metrics.joint_associations):
        each truth scored against the track that follows it over the run, not against a
        neighbour's track that one scan's GOSPA pairs it with."""
        out: list[PairRow] = []
        for (t, ti, tx, ki, kx, kP), step in zip(self.steps, series):
            col = {int(k): j for j, k in enumerate(ki)}
            rc = np.array([(r, col[trk]) for r, i in enumerate(ti.tolist())
                           if (trk := step.get(int(i))) is not None and trk in col],
                          dtype=np.intp).reshape(-1, 2)
            out += _pair_rows(t, ti, tx, kx, kP, rc[:, 0], rc[:, 1])
        return out

    def after(self, settle: float, series: Series | None = None) -> dict[int, np.ndarray]:
        """Per truth id, rows (t, nees_pos, nees_state, sq_err) of the pairs made at
        least `settle` seconds after that truth was first paired: the per-step GOSPA
        pairs, or those of `series` (`joint_pairs`)."""
        pairs = self.pairs if series is None else self.joint_pairs(series)
        a = np.array(pairs, dtype=float).reshape(-1, 5)
        out = {}
        for i in np.unique(a[:, 1]).astype(int):
            rows = a[a[:, 1] == i]
            out[int(i)] = rows[rows[:, 0] >= rows[0, 0] + settle][:, [0, 2, 3, 4]]
        return out

    def truth_arrays(self) -> tuple[np.ndarray, np.ndarray, np.ndarray, list[int]]:
        """(times (K,), states (K, N, 6), present (K, N), ids) of all truths seen."""
        ids = sorted(self.truth)
        times = np.array(sorted({t for v in self.truth.values() for t, _ in v}))
        states = np.zeros((times.size, len(ids), 6))
        present = np.zeros((times.size, len(ids)), dtype=bool)
        for j, i in enumerate(ids):
            for t, s in self.truth[i]:
                k = np.searchsorted(times, t)
                states[k, j], present[k, j] = s, True
        return times, states, present, ids


@dataclass(frozen=True)
class TargetScore:
    """Per truth after convergence: samples, position RMSE (m), RMS of the PCRLB
    position bound sqrt(trace) over the same times (m), mean position / state NEES."""

    n: int
    rmse: float
    bound: float
    nees_pos: float
    nees_state: float


def _pair_rows(t: float, truth_ids: np.ndarray, truth_x: np.ndarray, track_x: np.ndarray,
               track_P: np.ndarray, rows: np.ndarray, cols: np.ndarray) -> list[PairRow]:
    """(t, truth id, position NEES, state NEES, squared position error) of the pairs
    (truth row, track column)."""
    e = track_x[cols] - truth_x[rows]
    Pm = track_P[cols]
    n_pos = nees(e[:, POS], Pm[:, POS][:, :, POS])
    n_all = nees(e, Pm)
    d2 = np.sum(e[:, POS] ** 2, axis=1)
    return [(t, int(truth_ids[r]), float(a), float(b), float(d))
            for r, a, b, d in zip(rows, n_pos, n_all, d2)]


def score_targets(
    ev: Evaluation, tx: np.ndarray, rx: np.ndarray, info: np.ndarray, q: float, q_z: float,
    P0: np.ndarray, settle: float, series: Series | None = None,
) -> dict[int, TargetScore]:
    """RMSE against the PCRLB and NEES, per truth id, `settle` s after first pairing (the
    per-step GOSPA pairs, or those of `series`: Evaluation.after)."""
    times, states, present, ids = ev.truth_arrays()
    bound = pcrlb(times, states, present, tx, rx, info, q, q_z, P0)
    pos_var = np.trace(bound[:, :, POS][:, :, :, POS], axis1=2, axis2=3)
    out = {}
    for i, rows in ev.after(settle, series).items():
        if rows.shape[0] == 0:
            continue
        k = np.searchsorted(times, rows[:, 0])
        j = ids.index(i)
        out[i] = TargetScore(
            n=int(rows.shape[0]), rmse=float(np.sqrt(rows[:, 3].mean())),
            bound=float(np.sqrt(pos_var[k, j].mean())), nees_pos=float(rows[:, 1].mean()),
            nees_state=float(rows[:, 2].mean()))
    return out
