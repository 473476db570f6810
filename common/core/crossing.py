"""Crossing management of seed 004: ambiguity test, update weight alpha, maximum duration.

Every tracker of the project (sonar bearings, bistatic elementary tracks, Cartesian
global tracks) calls `CrossingManager.step` once per update, between association and
the Kalman update, with each track's predicted measurement z_pred (N, m) (or the
predicted position components of the state), the covariance of the density g
(measurement noise R, or innovation covariance S) and the associated measurements.

Ambiguity test (Etp1), selectable by `CrossingParams.method`:
  * "eq13": track k is NOT ambiguous at t_l iff (004 eq. 13)
        sum_{j != k} q^j g(Z^k - Z^j) < epsilon r^k,   r^k = q''^k / c,
    with Z^k = C^k_{l-1} + A^k_{l-1}(t_l - t_{l-1}) the prediction of track k.
  * "supnorm": track k is NOT ambiguous iff for all j != k (004, alternative to eq. 13)
        ||Z^k - Z^j|| = sup_p |Z^k_p - Z^j_p| / sigma_p > S.
Update weight (Etp2), selectable by `CrossingParams.mode`:
  * "memory": alpha = 0 while ambiguous, 1 otherwise (004 claim 5).
  * "progressive": alpha = eq. 12 while ambiguous, 1 otherwise:
        alpha^k = r^k / (r^k + sum_{j != k} q^j g(X^k - Z^j)),
    with X^k the measurement associated to track k.
A track ambiguous for longer than `max_duration` is treated as not ambiguous
(004 claim 6) until its test turns negative again, which re-arms the clock.
The returned flag is the ambiguity state to publish with each track (Etp3, claim 2).
Groups (`CrossingManager.groups`): the tracks linked by a term of the test that alone
makes one of them ambiguous (common.core.crossing_groups: 004's pair, generalised).

Mapping of the recursive filter of eq. 11 onto the shared Kalman core:
eq. 11 updates the prediction (C + A dt, A) by alpha M_1 g'(nu) and alpha M_2 g'(nu),
nu = X - C - A dt. For Gaussian g, g'(nu) = g(nu) Sigma^-1 nu (gradient of the
log-likelihood term with respect to the track parameters), so with the stacked gain
[M_1; M_2] Sigma^-1 := K = P H' S^-1 the step is x+ = x~ + alpha K nu, i.e.
`common.core.kalman.update(..., gain_scale=alpha)`. The covariance then follows the Joseph
form for the scaled gain, P+ = (I - aKH) P (I - aKH)' + a^2 K R K', which is the exact
covariance of the sub-optimal gain aK; alpha = 0 gives x+ = x~, P+ = P~ (memory mode:
"the parameters of the prediction no longer evolve").
Deviations: (i) the scalar factor g(nu) of g'(nu) (the seed's soft "gate"
nonlinearity) is replaced by the trackers' hard chi-square gate at association;
(ii) M_1, M_2 are the Kalman gain rather than fixed stability gains; (iii) during
memory mode P still grows by the process noise Q at each prediction.

Proportions q (004 eq. 10 text: "q_l^k is updated with the new proportion of points
assigned to track k"): per track, q^k = (hits + q_prior w) / (seen + w), with hits
the number of measurements associated to k and seen the number of measurements of
all scans since k was first seen; the values of step l-1 are used at step l. The
far-point proportion is q''^k = 1 - q^k ("neglecting the tracks that were ambiguous
with k", eq. 10 text). Deviation: q is clipped to q_max < 1 so that r^k > 0;
otherwise a track owning every point (r^k = 0) would be ambiguous for ever.

Sparse evaluation: the sums of eq. 12-13 and the sup-norm test only look at the pairs
(k, j) within a per-component box of track j's sigmas (`near_pairs`, a KD-tree, about
O(N log N + pairs) instead of O(N^2)). The sup-norm test with radius S is exact.
Deviation: eq. 12-13 drop the pairs outside CUTOFF_RADIUS = 7.43 sigma on some
component, whose terms q^j g_j are below DENSITY_CUTOFF = 1e-12 of q^j g_j(0).

Second order (004 eq. 14-16): the module only sees predictions Z^k produced by the
tracker's own motion model, so a constant-acceleration tracker gets the order-3
generalisation of eq. 12-13 (C + A dt + D dt^2) without further code here.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from typing import ClassVar, Literal

import numpy as np
from numpy.typing import ArrayLike
from scipy.spatial import cKDTree

from common.core.angles import wrap_pi
from common.core.crossing_groups import ambiguity_groups
from common.core.params import PROB_OPEN, Params, Range, non_negative, positive

DENSITY_CUTOFF = 1e-12  # g terms below this fraction of their peak g_j(0) are dropped
CUTOFF_RADIUS = float(np.sqrt(-2.0 * np.log(DENSITY_CUTOFF)))  # Mahalanobis 7.43


@dataclass(frozen=True)
class CrossingParams(Params):
    """Parameters of seed 004 crossing management.

    method: ambiguity test, "eq13" (004 eq. 13) or "supnorm" (sup-norm threshold S).
    mode: "memory" (alpha = 0 while ambiguous) or "progressive" (alpha from eq. 12).
    S: sup-norm threshold in standard deviations (default 3 sigma).
    epsilon: coefficient of eq. 13 (0.1, the value given in seed 004).
    volume: c, the integral of the admissible measurement domain, in the units of
        z_pred (default 2 pi: a bearing-only tracker; set it for other spaces).
    max_duration: maximum ambiguity duration in seconds (004 claim 6). 600 s, the sonar
        default: with 60 s (the default before issue 31) the flag cleared while two
        contacts crossing at 2-3 deg/min were still unresolved, and the single-hypothesis
        tracker kept swaps unflagged in 12, 14 and 30 runs of 40 on sonar_x_clutter,
        sonar_x_turn and sonar_x_three (0, 0 and 6 with 600 s; benchmarks/sonar_default.py,
        docs/decisions/023-sonar-defaults.md; 0 on sonar_x_three with the memory-mode
        groups of docs/decisions/027-sonar-crossing-groups.md). The radar tables set
        their own (10 s, 60 s).
    q_prior, q_prior_weight: prior proportion and its weight in pseudo-counts for q.
    q_max: upper clip of q so that r = (1 - q) / c stays positive.
    """

    method: Literal["eq13", "supnorm"] = "eq13"
    mode: Literal["memory", "progressive"] = "memory"
    S: float = 3.0
    epsilon: float = 0.1
    volume: float = 2.0 * np.pi
    max_duration: float = 600.0
    q_prior: float = 0.5
    q_prior_weight: float = 2.0
    q_max: float = 0.95

    RANGES: ClassVar[dict[str, Range]] = {
        "S": positive("sigma"), "epsilon": positive(), "volume": positive("units of z^m"),
        "max_duration": positive("s"), "q_prior": PROB_OPEN,
        "q_prior_weight": non_negative("pseudo-counts"), "q_max": PROB_OPEN,
    }


def _broadcast_cov(cov: ArrayLike, n: int, m: int) -> np.ndarray:
    """Covariance of g as (N, m, m) from (m, m) shared or (N, m, m) per track."""
    c = np.asarray(cov, dtype=float)
    return np.broadcast_to(c, (n, m, m)) if c.ndim == 2 else c


def _sigmas(cov: ArrayLike, n: int, m: int) -> np.ndarray:
    """Standard deviations (N, m) of the components of each track's density g."""
    return np.sqrt(np.diagonal(_broadcast_cov(cov, n, m), axis1=1, axis2=2))


def wrapped_diff(a: np.ndarray, b: np.ndarray, angle_idx: Sequence[int] = ()) -> np.ndarray:
    """a - b (broadcast, last axis = components), angle_idx components wrapped to [-pi, pi)."""
    d = np.asarray(a, dtype=float) - np.asarray(b, dtype=float)
    if len(angle_idx):
        idx = list(angle_idx)
        d[..., idx] = wrap_pi(d[..., idx])
    return d


def _tree_coords(x: np.ndarray, centre: np.ndarray, scale: np.ndarray,
                 box: np.ndarray) -> np.ndarray:
    """KD-tree coordinates (x - centre) / scale; periodic components (box > 0) in [0, box)."""
    c = (x - centre) / scale
    per = box > 0.0
    c[:, per] = np.mod(c[:, per], box[per])
    c[:, per] = np.where(c[:, per] >= box[per], 0.0, c[:, per])  # mod rounding up to box
    return c


def near_pairs(
    z_pred: np.ndarray,
    sigma: np.ndarray,
    radius: float,
    angle_idx: Sequence[int] = (),
    points: np.ndarray | None = None,
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """All pairs (k, j), k != j, with |points_k,p - Z^j_p| / sigma_j,p <= radius on every
    component p (angle_idx components on the circle), and their differences d (P, m);
    points defaults to z_pred.

    Sparse replacement of the all-pairs (N, N) evaluation: a KD-tree in the coordinates
    z_p / max_j sigma_j,p (angle components on a torus of period 2 pi / max_j sigma_j,p)
    returns the pairs within Chebyshev radius `radius` (inflated by 1e-9 against
    rounding), a superset of the wanted ones; the exact per-pair test follows.
    """
    n, m = z_pred.shape
    if n < 2:
        e = np.zeros(0, dtype=np.intp)
        return e, e, np.zeros((0, m))
    scale = sigma.max(axis=0)
    box = np.zeros(m)
    box[list(angle_idx)] = 2.0 * np.pi / scale[list(angle_idx)]
    centre = np.where(box > 0.0, 0.0, z_pred.mean(axis=0))
    tree_z = cKDTree(_tree_coords(z_pred, centre, scale, box), boxsize=box)
    r_tree = radius * (1.0 + 1e-9)
    if points is None:
        points = z_pred
        a, b = tree_z.query_pairs(r_tree, p=np.inf, output_type="ndarray").T
        k, j = np.concatenate([a, b]), np.concatenate([b, a])
    else:
        tree_x = cKDTree(_tree_coords(points, centre, scale, box), boxsize=box)
        found = tree_x.sparse_distance_matrix(tree_z, r_tree, p=np.inf, output_type="ndarray")
        k, j = found["i"], found["j"]
    d = wrapped_diff(points[k], z_pred[j], angle_idx)
    keep = (k != j) & np.all(np.abs(d) / sigma[j] <= radius, axis=1)
    return k[keep], j[keep], d[keep]


def pair_terms(
    points: np.ndarray,
    z_pred: np.ndarray,
    cov: ArrayLike,
    q: np.ndarray,
    angle_idx: Sequence[int] = (),
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The terms q^j g_j(points_k - Z^j) of the sums of 004 eq. 12 and 13, as pairs (k, j)
    and their values w (P,).

    g_j is the zero-mean Gaussian density of covariance cov[j] (the track whose points
    would be mistaken for k's, as g(X - C^j) in 004 eq. 12).
    Deviation (speed): only the pairs of `near_pairs` with radius CUTOFF_RADIUS. A dropped
    pair has |d_p| > CUTOFF_RADIUS sigma_j,p on some component, hence
    d' cov_j^-1 d > CUTOFF_RADIUS^2 (the box bounds the ellipsoid), and its term is
    below DENSITY_CUTOFF q^j g_j(0).
    """
    pts = None if points is z_pred else np.asarray(points, dtype=float)  # eq. 13: symmetric
    z_pred = np.asarray(z_pred, dtype=float)
    n, m = z_pred.shape
    c = _broadcast_cov(cov, n, m)
    k, j, d = near_pairs(z_pred, _sigmas(c, n, m), CUTOFF_RADIUS, angle_idx, pts)
    inv = np.linalg.inv(c)
    norm = np.sqrt((2.0 * np.pi) ** m * np.linalg.det(c))
    d2 = np.einsum("pa,pab,pb->p", d, inv[j], d)
    return k, j, np.asarray(q, dtype=float)[j] * np.exp(-0.5 * d2) / norm[j]


def neighbour_sum(
    points: np.ndarray,
    z_pred: np.ndarray,
    cov: ArrayLike,
    q: np.ndarray,
    angle_idx: Sequence[int] = (),
) -> np.ndarray:
    """sum_{j != k} q^j g_j(points_k - Z^j), shape (N,): the sums of 004 eq. 12 and 13
    (the terms of `pair_terms`)."""
    k, _, w = pair_terms(points, z_pred, cov, q, angle_idx)
    return np.bincount(k, weights=w, minlength=np.shape(z_pred)[0])


def far_density(q: np.ndarray, volume: float) -> np.ndarray:
    """r^k = q''^k / c with q''^k = 1 - q^k (004 eq. 10 text, eq. 13)."""
    return (1.0 - q) / volume


def eq13_test(
    z_pred: np.ndarray,
    cov: ArrayLike,
    q: np.ndarray,
    volume: float,
    epsilon: float,
    angle_idx: Sequence[int] = (),
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Ambiguity flags (N,) of `eq13_ambiguous` and the links (k, j): the pairs whose one
    term makes k ambiguous, q^j g(Z^k - Z^j) >= eps r^k (004 eq. 13 with j the closest
    neighbour of 004's model, the "pista cercana" of eq. 2)."""
    k, j, w = pair_terms(z_pred, z_pred, cov, q, angle_idx)
    bound = epsilon * far_density(q, volume)
    lhs = np.bincount(k, weights=w, minlength=np.shape(z_pred)[0])
    link = w >= bound[k]
    return ~(lhs < bound), k[link], j[link]  # 004 eq. 13


def eq13_ambiguous(
    z_pred: np.ndarray,
    cov: ArrayLike,
    q: np.ndarray,
    volume: float,
    epsilon: float,
    angle_idx: Sequence[int] = (),
) -> np.ndarray:
    """Ambiguity flags (N,) bool; k is NOT ambiguous iff sum_j q^j g(Z^k - Z^j) < eps r^k.

    004 eq. 13, with Z the predictions at t_l and r from `far_density`.
    """
    return eq13_test(z_pred, cov, q, volume, epsilon, angle_idx)[0]


def supnorm_test(
    z_pred: np.ndarray, cov: ArrayLike, S: float, angle_idx: Sequence[int] = ()
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Ambiguity flags (N,) of `supnorm_ambiguous` and the links (k, j): the pairs with
    ||Z^k - Z^j|| <= S."""
    z_pred = np.asarray(z_pred, dtype=float)
    n, m = z_pred.shape
    k, j, _ = near_pairs(z_pred, _sigmas(cov, n, m), S, angle_idx)
    return np.bincount(k, minlength=n) > 0, k, j


def supnorm_ambiguous(
    z_pred: np.ndarray, cov: ArrayLike, S: float, angle_idx: Sequence[int] = ()
) -> np.ndarray:
    """Ambiguity flags (N,) bool; k is NOT ambiguous iff ||Z^k - Z^j|| > S for all j != k.

    ||X|| = sup_p |x_p| / sigma_p, sigma_p the standard deviation of component p in the
    density g of track j (004, sup-norm alternative to eq. 13). The pairs with
    ||Z^k - Z^j|| <= S are exactly those of `near_pairs` with radius S.
    """
    return supnorm_test(z_pred, cov, S, angle_idx)[0]


def progressive_weight(
    z_meas: np.ndarray,
    z_pred: np.ndarray,
    cov: ArrayLike,
    q: np.ndarray,
    volume: float,
    angle_idx: Sequence[int] = (),
) -> np.ndarray:
    """alpha^k = r^k / (r^k + sum_{j != k} q^j g(X^k - Z^j)), shape (N,) (004 eq. 12)."""
    r = far_density(q, volume)
    return r / (r + neighbour_sum(z_meas, z_pred, cov, q, angle_idx))  # 004 eq. 12


def proportions(
    hits: np.ndarray, seen: np.ndarray, q_prior: float, weight: float, q_max: float
) -> np.ndarray:
    """q^k: smoothed proportion of the points classified in track k (004 eq. 10 text)."""
    return np.minimum((hits + q_prior * weight) / (seen + weight), q_max)


class CrossingManager:
    """Per-track ambiguity clocks and point counts of one tracker (seed 004, Etp1-Etp3).

    State is keyed by track number: ambiguity start time (NaN when not ambiguous),
    number of associated measurements and number of measurements seen; `groups` holds
    the group labels (`ambiguity_groups` of the test's links) of the tracks of the last
    step, in their order.
    """

    def __init__(self, params: CrossingParams | None = None) -> None:
        self.params = params or CrossingParams()
        self._ids = np.empty(0, dtype=np.int64)
        self._start = np.empty(0)
        self._hits = np.empty(0)
        self._seen = np.empty(0)
        self.groups = np.empty(0, dtype=np.intp)  # `ambiguity_groups` of the last step

    def _rows(self, ids: np.ndarray) -> np.ndarray:
        """Row index of each id in the state arrays, adding new ids."""
        new = np.setdiff1d(ids, self._ids)
        if new.size:
            self._ids = np.concatenate([self._ids, new])
            self._start = np.concatenate([self._start, np.full(new.size, np.nan)])
            self._hits = np.concatenate([self._hits, np.zeros(new.size)])
            self._seen = np.concatenate([self._seen, np.zeros(new.size)])
            order = np.argsort(self._ids)
            self._ids, self._start = self._ids[order], self._start[order]
            self._hits, self._seen = self._hits[order], self._seen[order]
        return np.searchsorted(self._ids, ids)

    def step(
        self,
        t: float,
        ids: ArrayLike,
        z_pred: ArrayLike,
        cov: ArrayLike,
        z_meas: ArrayLike | None = None,
        n_meas: int | None = None,
        angle_idx: Sequence[int] = (),
    ) -> tuple[np.ndarray, np.ndarray]:
        """Ambiguity test and update weights at time t; returns (alpha (N,), ambiguous (N,)).

        ids (N,) track numbers; z_pred (N, m) predictions at t; cov (m, m) or (N, m, m)
        covariance of g; z_meas (N, m) measurement associated to each track (NaN row
        if none) for eq. 12 and for the counts of q; n_meas the number of measurements
        of the scan (counts are updated only when both are given). Without a
        measurement eq. 12 is evaluated at the prediction Z^k (the expected point).
        """
        p = self.params
        ids = np.asarray(ids, dtype=np.int64)
        z_pred = np.asarray(z_pred, dtype=float)
        rows = self._rows(ids)
        q = proportions(self._hits[rows], self._seen[rows], p.q_prior, p.q_prior_weight, p.q_max)
        if p.method == "eq13":
            raw, k, j = eq13_test(z_pred, cov, q, p.volume, p.epsilon, angle_idx)
        else:
            raw, k, j = supnorm_test(z_pred, cov, p.S, angle_idx)
        self.groups = ambiguity_groups(ids.size, k, j)

        start = self._start[rows]
        start = np.where(raw, np.where(np.isnan(start), t, start), np.nan)
        self._start[rows] = start
        ambiguous = raw & (t - start <= p.max_duration)  # 004 claim 6

        if p.mode == "memory":
            alpha = np.where(ambiguous, 0.0, 1.0)  # 004 claim 5
        else:
            x = z_pred if z_meas is None else np.asarray(z_meas, dtype=float)
            x = np.where(np.isnan(x), z_pred, x)
            w = progressive_weight(x, z_pred, cov, q, p.volume, angle_idx)
            alpha = np.where(ambiguous, w, 1.0)

        if z_meas is not None and n_meas is not None:
            self._hits[rows] += ~np.isnan(np.asarray(z_meas, dtype=float)).any(axis=1)
            self._seen[rows] += n_meas
        return alpha, ambiguous

    def proportions(self, ids: ArrayLike) -> np.ndarray:
        """q^k (N,) of the tracks ids from the counts so far (q_prior for an unknown id)."""
        ids = np.asarray(ids, dtype=np.int64)
        hits, seen = np.zeros(ids.size), np.zeros(ids.size)
        if self._ids.size:
            rows = np.minimum(np.searchsorted(self._ids, ids), self._ids.size - 1)
            known = self._ids[rows] == ids
            hits[known], seen[known] = self._hits[rows[known]], self._seen[rows[known]]
        p = self.params
        return proportions(hits, seen, p.q_prior, p.q_prior_weight, p.q_max)

    def forget(self, ids: ArrayLike) -> None:
        """Drop the state of deleted tracks (their numbers may be recycled)."""
        keep = ~np.isin(self._ids, np.asarray(ids, dtype=np.int64))
        self._ids, self._start = self._ids[keep], self._start[keep]
        self._hits, self._seen = self._hits[keep], self._seen[keep]
