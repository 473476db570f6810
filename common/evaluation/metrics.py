"""Multi-target tracking evaluation metrics: GOSPA, OSPA, track switches and breaks.

GOSPA with alpha = 2 (Rahmathullah, Garcia-Fernandez, Svensson, 2017), per time step,
for truths X (n, d) and estimates Y (m, d), Euclidean base distance, cutoff c, order p:
    d^p = min_gamma [ sum_{(i,j) in gamma} d(x_i, y_j)^p + c^p/2 (n + m - 2 |gamma|) ]
over partial assignments gamma whose pairs satisfy d < c. The decomposition is given in
p-th power units: localisation = sum d^p over assigned pairs, missed = c^p/2 per missed
truth, false = c^p/2 per false estimate; distance = (their sum)^(1/p).
OSPA (Schuhmacher, Vo, Vo, 2008), n <= m:
    d^p = (1/m) [ min_pi sum_i min(d(x_i, y_pi(i)), c)^p + c^p (m - n) ].
Switching term (trajectory GOSPA, Garcia-Fernandez, Rahmathullah, Svensson, 2020): for
each truth present at two consecutive steps, a change between two tracks costs
gamma^p and a change between assigned and unassigned gamma^p / 2. `summary` evaluates
it on the per-step optimal GOSPA assignments (no joint optimisation over time), an
upper bound of the trajectory metric; `joint_associations` minimises the whole cost
over all steps at once (the paper's linear program, common.evaluation.trajectory_gospa),
so that a truth changes track only when the exchange pays for its switches.
Track number switches and breaks are counted from a series of truth id -> track id
associations (`count_switches`), per step or joint.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field

import numpy as np
from numpy.typing import ArrayLike
from scipy.optimize import linear_sum_assignment

from common.evaluation.trajectory_gospa import Frame, joint_assignment


def _distances(truth: ArrayLike, est: ArrayLike) -> np.ndarray:
    """Euclidean distance matrix (n, m) between truths and estimates."""
    x = np.asarray(truth, dtype=float)
    y = np.asarray(est, dtype=float)
    if x.size == 0 or y.size == 0:
        return np.zeros((len(x), len(y)))
    x = x.reshape(len(x), -1)
    y = y.reshape(len(y), -1)
    return np.sqrt(((x[:, None, :] - y[None, :, :]) ** 2).sum(axis=-1))


@dataclass(frozen=True)
class GospaResult:
    """One-step GOSPA: distance and its p-th power decomposition, plus the assignment.

    rows, cols: indices of the assigned (truth, estimate) pairs, all with d < c.
    """

    distance: float
    localisation: float
    missed: float
    false: float
    rows: np.ndarray
    cols: np.ndarray
    pair_distances: np.ndarray


def gospa(truth: ArrayLike, est: ArrayLike, c: float, p: float = 2.0) -> GospaResult:
    """GOSPA metric with alpha = 2 between truths (n, d) and estimates (m, d)."""
    D = _distances(truth, est)
    n, m = D.shape
    rows, cols = linear_sum_assignment(np.minimum(D, c) ** p)
    keep = D[rows, cols] < c  # pairs at d >= c cost more assigned than missed + false
    rows, cols = rows[keep], cols[keep]
    dists = D[rows, cols]
    loc = float(np.sum(dists**p))
    missed = 0.5 * c**p * (n - rows.size)
    false = 0.5 * c**p * (m - rows.size)
    return GospaResult(
        distance=(loc + missed + false) ** (1.0 / p),
        localisation=loc,
        missed=missed,
        false=false,
        rows=rows,
        cols=cols,
        pair_distances=dists,
    )


def ospa(truth: ArrayLike, est: ArrayLike, c: float, p: float = 2.0) -> float:
    """OSPA metric between truths (n, d) and estimates (m, d); 0 if both are empty."""
    D = _distances(truth, est)
    n, m = D.shape
    big = max(n, m)
    if big == 0:
        return 0.0
    cost = np.minimum(D, c) ** p
    rows, cols = linear_sum_assignment(cost)
    return float(((cost[rows, cols].sum() + c**p * abs(m - n)) / big) ** (1.0 / p))


@dataclass(frozen=True)
class SwitchCounts:
    """Counts over a series of truth -> track associations.

    switches: a truth gets a track number different from its last assigned one
        (counted once, at the change; gaps in between do not matter).
    breaks: a truth tracked at one step is present but untracked at the next.
    full: consecutive steps with two different tracks (GOSPA switching weight 1).
    half: consecutive steps with assigned <-> unassigned (GOSPA switching weight 1/2).
    """

    switches: int
    breaks: int
    full: int
    half: int


def count_switches(series: Sequence[Mapping[int, int | None]], start: int = 0) -> SwitchCounts:
    """Count switches and breaks; series[k] maps each truth present at step k to its
    assigned track number, or None when it is unassigned (absent truths are omitted).
    Only the events of steps >= start are counted (the earlier steps set the state: a
    warm-up)."""
    last_track: dict[int, int] = {}
    switches = breaks = full = half = 0
    prev: Mapping[int, int | None] = {}
    for k, step in enumerate(series):
        if k < start:
            last_track.update({i: tr for i, tr in step.items() if tr is not None})
            prev = step
            continue
        for truth, track in step.items():
            if truth in prev:
                before = prev[truth]
                if before is not None and track is not None and before != track:
                    full += 1
                elif (before is None) != (track is None):
                    half += 1
                    breaks += track is None
            if track is not None:
                if truth in last_track and last_track[truth] != track:
                    switches += 1
                last_track[truth] = track
        prev = step
    return SwitchCounts(switches=switches, breaks=breaks, full=full, half=half)


def switching_cost(counts: SwitchCounts, gamma: float, p: float = 2.0) -> float:
    """Switching term in p-th power units: gamma^p (full + half / 2)."""
    return gamma**p * (counts.full + 0.5 * counts.half)


@dataclass(frozen=True)
class MetricsSummary:
    """Time-averaged and cumulative metrics of a scenario.

    mean_gospa, mean_ospa: averages over time steps of the per-step distances.
    gospa: (sum over steps of localisation + missed + false, plus switching)^(1/p);
    localisation, missed, false, switching: the p-th power sums composing it.
    rmse: position RMSE of the assigned pairs, per truth id (truths ever assigned).
    """

    steps: int
    mean_gospa: float
    mean_ospa: float
    gospa: float
    localisation: float
    missed: float
    false: float
    switching: float
    switches: int
    breaks: int
    rmse: dict[int, float] = field(default_factory=dict)


class MetricsAccumulator:
    """Accumulates per-step GOSPA / OSPA and assignments; `summary` gives the totals."""

    def __init__(self, c: float, p: float = 2.0, gamma: float = 0.0) -> None:
        self.c, self.p, self.gamma = c, p, gamma
        self.times: list[float] = []
        self.gospa_series: list[GospaResult] = []
        self.ospa_series: list[float] = []
        self.associations: list[dict[int, int | None]] = []
        self.frames: list[Frame] = []
        self._sq_err: dict[int, float] = {}
        self._n_err: dict[int, int] = {}

    def add(
        self,
        t: float,
        truth_ids: ArrayLike,
        truth_pos: ArrayLike,
        track_ids: ArrayLike,
        track_pos: ArrayLike,
    ) -> GospaResult:
        """Score one time step (times must increase); returns its GOSPA result."""
        if self.times and t <= self.times[-1]:
            raise ValueError(f"time {t} not after {self.times[-1]}")
        truth_ids = np.asarray(truth_ids, dtype=np.int64)
        track_ids = np.asarray(track_ids, dtype=np.int64)
        res = gospa(truth_pos, track_pos, self.c, self.p)
        assoc: dict[int, int | None] = {int(i): None for i in truth_ids}
        for r, k, d in zip(res.rows, res.cols, res.pair_distances):
            truth = int(truth_ids[r])
            assoc[truth] = int(track_ids[k])
            self._sq_err[truth] = self._sq_err.get(truth, 0.0) + float(d) ** 2
            self._n_err[truth] = self._n_err.get(truth, 0) + 1
        self.times.append(float(t))
        self.gospa_series.append(res)
        self.ospa_series.append(ospa(truth_pos, track_pos, self.c, self.p))
        self.associations.append(assoc)
        self.frames.append((truth_ids, np.asarray(truth_pos, dtype=float), track_ids,
                            np.asarray(track_pos, dtype=float)))
        return res

    def joint_associations(self) -> list[dict[int, int | None]]:
        """The truth -> track series of the trajectory GOSPA assignment, optimised over
        all steps at once (common.evaluation.trajectory_gospa)."""
        return joint_assignment(self.frames, self.c, self.gamma, self.p)

    def summary(self) -> MetricsSummary:
        """Time averages, cumulative GOSPA with switching term, switches, breaks, RMSE."""
        counts = count_switches(self.associations)
        loc = sum(r.localisation for r in self.gospa_series)
        missed = sum(r.missed for r in self.gospa_series)
        false = sum(r.false for r in self.gospa_series)
        sw = switching_cost(counts, self.gamma, self.p)
        steps = len(self.times)
        return MetricsSummary(
            steps=steps,
            mean_gospa=float(np.mean([r.distance for r in self.gospa_series])) if steps else 0.0,
            mean_ospa=float(np.mean(self.ospa_series)) if steps else 0.0,
            gospa=(loc + missed + false + sw) ** (1.0 / self.p),
            localisation=loc,
            missed=missed,
            false=false,
            switching=sw,
            switches=counts.switches,
            breaks=counts.breaks,
            rmse={k: float(np.sqrt(self._sq_err[k] / self._n_err[k])) for k in self._sq_err},
        )
