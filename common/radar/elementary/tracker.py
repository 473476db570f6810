"""Elementary tracks of one bistatic base (seed 001, step 23, operation 222).

The tracker is parametrised by its base's measurement model
(`common.radar.elementary.model`): AZIMUTH as below, or RANGE_DOPPLER for a base
without theta (state [r_b, v_b, gamma_b], gate chi-square(2), crossing management on
(r_b, v_b) instead of (r_b, theta)).

Per scan of fused plots at time t (module 41 sequencing):
  1. module 44 prediction of every track to t: F [19], Q [20], 001 [25]-[26];
  2. module 43 gating d = i' S^-1 i (001 [8]-[11]), S = H P~ H' + R_j per pair, gate
     gamma = chi-square(3) quantile at `gate_prob`, nearest neighbour 001 [12]
     (`common.core.assignment.nearest_neighbour`, which also flags ambiguous decisions);
  3. crossing management (seed 004, `common.core.crossing`) on the predicted (r_b, theta)
     of confirmed and coasting tracks: the ambiguity flag is published, alpha is the
     gain weight of the update;
  4. module 44 update 001 [27]-[31] (Joseph form, `common.core.kalman.update`), pure
     prediction for tracks without a plot;
  5. module 42 initialisation from the plots of t and of the previous scan left over
     by association (`common.radar.elementary.initiation`);
  6. module 41 scores, status, deletion and number recycling (`TrackTable`).

Score rules (module 41): a new track starts at score_per_channel * n_ch of the plot
that opened it; each associated plot adds score_per_channel * n_ch minus
ambiguity_penalty when the association decision was ambiguous; a scan in prediction
mode subtracts miss_penalty; the score is capped at score_max. Tentative -> confirmed
when score >= confirm_score; confirmed -> coasting when unsupported; coasting ->
confirmed on the next associated plot. A track is deleted when its score falls to
score_delete or below, or after more than max_coast consecutive scans in prediction
(max_coast_tentative for a tentative track); its number is then recycled.

Deviation: crossing management runs on confirmed and coasting tracks only. The tracks
that initialisation opens in bunches from one plot are mutually "ambiguous" by
construction; in memory mode (alpha = 0) none of them could ever be updated, so the
unsupported ones could not be told apart from the right one.
"""

from __future__ import annotations

from dataclasses import dataclass, replace
from typing import ClassVar

import numpy as np

from common.core import kalman
from common.core.angles import wrap_2pi, wrap_pi
from common.core.assignment import nearest_neighbour
from common.core.crossing import CrossingManager, CrossingParams
from common.core.gating import chi2_gate, gate, overlap_pairs, pair_distances, window_pairs
from common.core.params import PROB_OPEN, Params, Range, Rule, count, non_negative, order, positive, unbounded
from common.core.rejection import Rejected
from common.core.track_table import Status, TrackTable
from common.radar.elementary.initiation import compatible, initial_state, propagate
from common.radar.elementary.model import AZIMUTH, MeasurementModel
from common.radar.plots.channel_fusion import Plots

NEAR_SIGMAS = 8.0  # crossing candidates: another track within this many sigmas


def neighbours(z: np.ndarray, sigma: np.ndarray, k: float, angle: bool = True) -> np.ndarray:
    """(N,) mask of points z = (r_b, theta) (or (r_b, v_b), angle false) with another
    point j such that |dz_c| <= k (sigma_c + sigma_jc) on both components (theta on the
    circle); a superset of the pairs within k sqrt(sigma_c^2 + sigma_jc^2). Sweep on r_b."""
    a, b = overlap_pairs(z[:, 0] - k * sigma[:, 0], z[:, 0] + k * sigma[:, 0])
    dz = z[a, 1] - z[b, 1]
    ok = np.abs(wrap_pi(dz) if angle else dz) <= k * (sigma[a, 1] + sigma[b, 1])
    mask = np.zeros(z.shape[0], dtype=bool)
    mask[a[ok]] = mask[b[ok]] = True
    return mask


def drop_acceleration(x: np.ndarray, P: np.ndarray, memory: np.ndarray) -> None:
    """Memory-mode tracks (004 alpha = 0) in place: gamma_b := 0, P_gamma += gamma_b^2.

    004 memory mode extrapolates the last estimate with the linear model of its eq. 1
    (C + A dt: r_b + v_b dt, theta + omega dt); the order-3 model of eq. 14 (a D t^2
    term) is an option of the seed, not used here. The gamma_b estimate of the 5-state
    filter (white jerk, 001 [20]) is mostly noise: extrapolated as 1/2 gamma_b T^2 over
    a 20 s ambiguity it moved tracks by up to 1.3 km (crossing.toml). The discarded
    estimate is kept as uncertainty (P_gamma += gamma_b^2), which 001 [26] propagates
    to r_b and v_b, so the gate after the ambiguity still covers a real acceleration.
    """
    P[memory, 2, 2] += np.square(x[memory, 2])
    x[memory, 2] = 0.0


@dataclass(frozen=True)
class ElementaryParams(Params):
    """Parameters of table [radar.tracker] (units: m, s, rad).

    sigma_gamma: sigma_gamma of Q [20] (white jerk on r_b), also sigma_v~ of [14].
    sigma_omega: sigma_omega of Q [20] (white azimuth acceleration), also of [14].
    gate_prob: probability of correct association defining the chi-square(3) gate.
    delta_vb: Delta_vb, the wide v_b window of the compatibility test [15].
    sigma_gamma_init, sigma_omega_init: the constants of the initial covariance [17].
    score_per_channel, ambiguity_penalty, miss_penalty, score_max, confirm_score,
    score_delete, max_coast, max_coast_tentative: module 41 rules (module docstring).
    """

    sigma_gamma: float = 5.0
    sigma_omega: float = 1e-3
    gate_prob: float = 0.999
    delta_vb: float = 50.0
    sigma_gamma_init: float = 10.0
    sigma_omega_init: float = 0.02
    score_per_channel: float = 1.0
    ambiguity_penalty: float = 0.5
    miss_penalty: float = 1.0
    score_max: float = 20.0
    confirm_score: float = 6.0
    score_delete: float = 0.0
    max_coast: int = 5
    max_coast_tentative: int = 1

    RANGES: ClassVar[dict[str, Range]] = {
        "sigma_gamma": positive("m/s^3 (jerk sigma)"), "sigma_omega": positive("rad/s^2"),
        "gate_prob": PROB_OPEN, "delta_vb": positive("m/s"),
        "sigma_gamma_init": positive("m/s^2"), "sigma_omega_init": positive("rad/s"),
        "score_per_channel": non_negative("score"), "ambiguity_penalty": non_negative("score"),
        "miss_penalty": non_negative("score"), "score_max": positive("score"),
        "confirm_score": unbounded("score", "a score has no natural end; the rules place it"),
        "score_delete": unbounded("score", "a score has no natural end; the rules place it"),
        "max_coast": count(0), "max_coast_tentative": count(0),
    }
    RULES: ClassVar[tuple[Rule, ...]] = (
        order("score_delete", "confirm_score"), order("confirm_score", "score_max", strict=False))


@dataclass(frozen=True)
class RadarCrossingParams(CrossingParams):
    """Table [radar.crossing]: the fields of CrossingParams plus `enabled`.

    enabled: run seed 004 crossing management on confirmed and coasting tracks.

    Radar defaults: volume is the (r_b, theta) domain 200 km x 2 pi (instead of 2 pi);
    max_duration is 10 s (instead of 600 s): in memory mode a track is extrapolated
    while ambiguous, and on the crossing scenario extrapolations longer than about ten
    1 s scans left the gate and lost the track.
    """

    volume: float = 200e3 * 2.0 * np.pi
    max_duration: float = 10.0
    enabled: bool = True


@dataclass
class ElementaryTracks:
    """Live tracks after a scan (one row per track, ascending number): x (N, 5) and
    P (N, 5, 5) of the AZIMUTH model, x (N, 3) = [r_b, v_b, gamma_b] and P (N, 3, 3) of
    the RANGE_DOPPLER one."""

    t: float
    id: np.ndarray
    status: np.ndarray
    x: np.ndarray
    P: np.ndarray
    score: np.ndarray
    n_ch: np.ndarray
    updated: np.ndarray
    ambiguous: np.ndarray

    def __len__(self) -> int:
        return int(self.id.shape[0])


def gate_pairs(z_pred: np.ndarray, S_pred: np.ndarray, plots: Plots, gamma: float,
               angles: tuple[int, ...] = AZIMUTH.angles
               ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Pairs (t, j) with d = i' S^-1 i <= gamma, S = H P~ H' + R_j (001 [8]-[10]), and d.

    z_pred (N, m) = H x~, S_pred (N, m, m) = H P~ H' (m = 3, or 2 without azimuth);
    `angles` the measurement components on the circle. Candidates come from a sweep on
    r_b with the necessary condition i_r^2 <= gamma S_rr (a marginal of d), then the
    same on v_b and theta, then the exact d on the survivors only.
    """
    if z_pred.shape[0] == 0 or len(plots) == 0:
        e = np.zeros(0, dtype=np.intp)
        return e, e, np.zeros(0)
    half = np.sqrt(gamma * (S_pred[:, 0, 0] + plots.srb.max() ** 2))
    t, j = window_pairs(z_pred[:, 0] - half, z_pred[:, 0] + half, plots.rb)
    i = plots.y[j] - z_pred[t]  # 001 [9]
    for a in angles:
        i[:, a] = wrap_pi(i[:, a])
    sig2 = np.square(plots.sigma)
    diag = list(range(z_pred.shape[1]))
    ok = np.all(i**2 <= gamma * (S_pred[t][:, diag, diag] + sig2[j]), axis=1)
    t, j = t[ok], j[ok]
    _, _, d = pair_distances(z_pred, S_pred, plots.y, sig2, t, j, angle_idx=angles)  # 001 [8]-[10]
    ok = gate(d, gamma)
    return t[ok], j[ok], d[ok]


class ElementaryTracker:
    """Modules 41-44 for one base, driven by fused-plot scans (message times only).

    model: AZIMUTH (001 as written) or RANGE_DOPPLER (a base without theta); the 004
    domain volume of [radar.crossing] is scaled by the model's volume_scale."""

    def __init__(self, params: ElementaryParams | None = None,
                 crossing: RadarCrossingParams | None = None,
                 model: MeasurementModel = AZIMUTH) -> None:
        self.params = params or ElementaryParams()
        self.model = model
        self.crossing_params = crossing or RadarCrossingParams()
        self.crossing = CrossingManager(replace(
            self.crossing_params, volume=self.crossing_params.volume * model.volume_scale))
        self.gamma = chi2_gate(self.params.gate_prob, model.m)  # 001: chi-square, m dof
        self.table = TrackTable(model.n, extra={"n_ch": ((), np.int64), "r": ((model.m,), np.float64),
                                                "updated": ((), np.bool_), "ambiguous": ((), np.bool_)})
        self.t: float | None = None
        self._prev = Plots.empty(model.azimuth)

    def step(self, t: float, plots: Plots) -> ElementaryTracks:
        """Process the fused plots of time t; returns every live track."""
        if self.t is not None and t <= self.t:
            raise Rejected("time_backwards", f"fused scan t={t} not after t={self.t}")
        if plots.azimuth != self.model.azimuth:
            raise Rejected("azimuth_mismatch", f"fused plots with azimuth = {plots.azimuth} "
                           f"at a base with azimuth = {self.model.azimuth}")
        tab, H = self.table, self.model.H
        idx = tab.active_indices()
        x, P = self._predict(idx, t)
        z_pred = x[:, list(self.model.meas)]
        S_pred = H @ P @ H.T
        ti, pj, d = gate_pairs(z_pred, S_pred, plots, self.gamma, self.model.angles)
        cost = np.full((idx.size, len(plots)), np.inf)
        cost[ti, pj] = d
        rows, cols, nn_amb = nearest_neighbour(cost)  # 001 [12]
        alpha, amb = self._crossing(t, idx, x, P, plots, rows, cols)

        m = self.model.m
        R = np.zeros((rows.size, m, m))
        R[:, range(m), range(m)] = np.square(plots.sigma[cols])  # 001 [21]
        innov = kalman.innovation(plots.y[cols], z_pred[rows], self.model.angles)  # 001 [27]
        x[rows], P[rows], _, _ = kalman.update(x[rows], P[rows], innov, H, R,
                                               gain_scale=alpha[rows])  # 001 [28]-[31]
        for w in self.model.wrap:
            x[:, w] = wrap_2pi(x[:, w])
        drop_acceleration(x, P, alpha == 0.0)
        tab.x[idx], tab.P[idx] = x, P
        tab.t_last[idx] = t
        tab.ambiguous[idx] = amb

        hit = np.zeros(idx.size, dtype=bool)
        hit[rows] = True
        n_ch = np.zeros(idx.size, dtype=np.int64)
        n_ch[rows] = plots.n_ch[cols]
        tab.r[idx[rows]] = np.square(plots.sigma[cols])
        self._score(idx, hit, n_ch, nn_amb)

        used = np.zeros(len(plots), dtype=bool)
        used[cols] = True
        self._initialise(t, plots, np.flatnonzero(~used))
        self.t = t
        return self.report()

    def _predict(self, idx: np.ndarray, t: float) -> tuple[np.ndarray, np.ndarray]:
        """001 [25]-[26] with F [19], Q [20] (of the model) over each track's own time step."""
        tab, p, model = self.table, self.params, self.model
        T = t - tab.t_last[idx]
        x, P = kalman.predict(tab.x[idx], tab.P[idx], model.F(T),
                              model.Q(T, p.sigma_gamma, p.sigma_omega))
        for w in model.wrap:
            x[:, w] = wrap_2pi(x[:, w])
        return x, P

    def _crossing(self, t: float, idx: np.ndarray, x: np.ndarray, P: np.ndarray,
                  plots: Plots, rows: np.ndarray, cols: np.ndarray
                  ) -> tuple[np.ndarray, np.ndarray]:
        """Seed 004 on the predicted (r_b, theta) of confirmed/coasting tracks (r_b, v_b
        at a range-Doppler base, a stated deviation): (alpha, ambiguous) per track of
        idx; alpha = 1, not ambiguous for the others. The density g has covariance R of
        the track's last plot on those components (004).

        Deviation (speed): only tracks with another one within NEAR_SIGMAS sigmas on
        both r_b and theta are passed to the CrossingManager, whose test is O(N^2).
        The others cannot be ambiguous (sup-norm test with S < NEAR_SIGMAS; eq. 13
        neighbour sum below exp(-NEAR_SIGMAS^2 / 2)), but their proportions q of 004
        are then counted only over the scans where they have such a neighbour."""
        alpha = np.ones(idx.size)
        amb = np.zeros(idx.size, dtype=bool)
        sel = np.flatnonzero(self.table.status[idx] != Status.TENTATIVE)
        if not self.crossing_params.enabled or sel.size < 2:
            return alpha, amb
        model = self.model
        mc = list(model.cross)
        rc = [model.meas[c] for c in mc]
        cov = np.zeros((sel.size, 2, 2))  # 004: g is the measurement noise density (R)
        cov[:, [0, 1], [0, 1]] = self.table.r[idx[sel]][:, mc]
        near = neighbours(x[sel][:, rc], np.sqrt(cov[:, [0, 1], [0, 1]]), NEAR_SIGMAS,
                          angle=bool(model.cross_angles))
        sel, cov = sel[near], cov[near]
        if sel.size == 0:
            return alpha, amb
        z_meas = np.full((idx.size, 2), np.nan)
        z_meas[rows] = plots.y[cols][:, mc]
        alpha[sel], amb[sel] = self.crossing.step(
            t, self.table.id[idx[sel]], x[sel][:, rc], cov, z_meas[sel], len(plots),
            angle_idx=model.cross_angles)
        return alpha, amb

    def _score(self, idx: np.ndarray, hit: np.ndarray, n_ch: np.ndarray,
               nn_amb: np.ndarray) -> None:
        """Module 41: score evolution, status transitions, deletion (module docstring)."""
        p, tab = self.params, self.table
        gain = p.score_per_channel * n_ch - p.ambiguity_penalty * nn_amb
        score = np.where(hit, np.minimum(tab.score[idx] + gain, p.score_max),
                         tab.score[idx] - p.miss_penalty)
        tab.score[idx] = score
        tab.n_ch[idx] = n_ch
        tab.updated[idx] = hit
        tab.n_updates[idx] += hit
        tab.n_coast[idx] = np.where(hit, 0, tab.n_coast[idx] + 1)
        status = tab.status[idx]
        tentative = status == Status.TENTATIVE
        status = np.where(tentative & (score >= p.confirm_score), Status.CONFIRMED, status)
        status = np.where(~tentative & hit, Status.CONFIRMED, status)
        status = np.where(~tentative & ~hit, Status.COASTING, status)
        tab.status[idx] = status
        max_coast = np.where(tentative, p.max_coast_tentative, p.max_coast)
        dead = idx[(score <= p.score_delete) | (tab.n_coast[idx] > max_coast)]
        if dead.size:
            self.crossing.forget(tab.id[dead])
            tab.remove(dead)

    def _initialise(self, t: float, plots: Plots, free: np.ndarray) -> None:
        """Module 42 on the previous scan's left-over plots and this scan's (`free`)."""
        p, tab = self.params, self.table
        cur = plots.take(free)
        i = j = np.zeros(0, dtype=np.intp)
        if self.t is not None and len(self._prev):
            dt = t - self.t
            y_prop, s_prop = propagate(self._prev, dt, p.sigma_gamma, p.sigma_omega)
            i, j = compatible(y_prop, s_prop, cur, p.delta_vb)  # 001 [13]-[15]
        if j.size:
            x0, P0 = initial_state(self._prev, cur, i, j, t - self.t,
                                   p.sigma_gamma_init, p.sigma_omega_init)  # 001 [16]-[17]
            new = tab.add(j.size)
            tab.x[new], tab.P[new] = x0, P0
            tab.t_last[new] = t
            tab.score[new] = p.score_per_channel * cur.n_ch[j]
            tab.n_ch[new] = cur.n_ch[j]
            tab.r[new] = np.square(cur.sigma[j])
            tab.updated[new] = True
            tab.ambiguous[new] = False
            confirm = tab.score[new] >= p.confirm_score
            tab.status[new[confirm]] = Status.CONFIRMED
        opened = np.zeros(len(cur), dtype=bool)
        opened[j] = True
        self._prev = cur.take(np.flatnonzero(~opened))

    def report(self) -> ElementaryTracks:
        """Every live track, by ascending number."""
        tab = self.table
        idx = tab.active_indices()
        idx = idx[np.argsort(tab.id[idx])]
        return ElementaryTracks(
            float(self.t if self.t is not None else 0.0), tab.id[idx].copy(),
            tab.status[idx].copy(), tab.x[idx].copy(), tab.P[idx].copy(),
            tab.score[idx].copy(), tab.n_ch[idx].copy(), tab.updated[idx].copy(),
            tab.ambiguous[idx].copy())
