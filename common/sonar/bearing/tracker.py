"""Single-hypothesis bearing tracker of seed 000 (first embodiment), on the shared core.

One `BearingTracker.step` per detection list (one clock cycle k), driven by the message
time only:
  1. prediction with the straight-line-segment model (000 F, Q; common.core.motion);
  2.-3. gated GNN (common.sonar.bearing.assoc): d^2 = y' S^-1 y (000 d_1^2), gate G per
     pair with P_D from the track's predicted amplitude (000 erfc law) and P_FA from
     the detection's level, global nearest neighbour on d^2 (000 GNN);
  4. seed 004 crossing management on the confirmed tracks: alpha as gain weight (in
     memory mode the IMM predicts with its quiet Q, common.sonar.bearing.imm); a track
     leaving the ambiguity keeps its detection only if no other confirmed track's
     prediction is nearer to it (deviation; common.sonar.bearing.crossing); a group of
     frozen tracks (004's ambiguity groups) whose order is sure, or a frozen pair whose
     resolved detections follow the V of its separations, is released for the scan
     (deviations; common.sonar.bearing.pairs, common.sonar.bearing.pair_order); a track
     given its contact's TMA solution (`tma_hint`)
     predicts its manoeuvre model with the range-matched noise of
     common.sonar.bearing.range_noise and its bearing and bearing rate along the
     solution's relative track (observable range) or, near a closest approach, from the
     solution itself (common.sonar.bearing.tma_prediction, both models); a number reopened
     for a new track drops its hint;
  5. Kalman update with the Joseph-form covariance (000 P(k/k)); the other frozen groups'
     centroids from their detections (deviation; common.sonar.bearing.pairs);
     5b. with `block_estimator`, a track whose 004 flag clears resumes from the line 004's
     block estimator (eq. 6-10) fitted to the crossing's detections
     (common.sonar.bearing.block);
  6. track quality L(k) = L(k-1) + dL (000 claim 4, with those P_D, P_FA), ln(1 - P_D)
     for a miss; tentative above T2 -> confirmed, below T1 -> deleted (000 claim 2);
     confirmed deleted when L falls `delete_drop` below its maximum (000 Fig. 3, t_3);
  7. every unassociated detection opens a tentative track, x(1) = H' z, P(1) = P0,
     L(1) = 0 (000 initialisation);
  8. narrowband: multi-line tracks (000 claims 12-13, common.sonar.bearing.multiline);
  9. the bearing register (000 register 13, common.sonar.bearing.history): each track's
     associated detections (not its estimates: deviation stated there) and own positions.

Amplitude is tracked as a level in dB, a = 10 log10(amp) (000: "la amplitud o el
nivel"), so that the simulator's log-normal amplitude noise is additive; the linear
amplitude enters the linear-array sigma law. Bearings wrap at 0 / 2 pi everywhere
(innovations wrapped to [-pi, pi), estimates to [0, 2 pi)).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from common.core.angles import wrap_2pi
from common.core.crossing import CrossingParams
from common.core.kalman import diagonal_covariances, predict, update
from common.core.track_table import Status, TrackTable
from common.sonar.bearing.assoc import associate
from common.sonar.bearing.block import CrossingBlocks
from common.sonar.bearing.clutter_level import ClutterLevel
from common.sonar.bearing.crossing import BearingCrossing
from common.sonar.bearing.history import BearingHistory
from common.sonar.bearing.imm import BearingImm
from common.sonar.bearing.measurements import bearing_sigmas, detection_measurements, measurement_variances
from common.sonar.bearing.merge import merged_tentative
from common.sonar.bearing.model import (
    detection_probability,
    false_alarm_probability,
    measurement_matrix,
    missed_increment,
    quality_increment,
    thresholds,
)
from common.sonar.bearing.multiline import NEW, MultiLineGrouper, MultiLineTrack, multiline_tracks
from common.sonar.bearing.pair_order import PairOrders
from common.sonar.bearing.pairs import centroid_update, memory_groups, per_track, release
from common.sonar.bearing.params import TrackerParams, process_noise, transition
from common.sonar.bearing.range_noise import RangeNoise, TmaHint
from common.sonar.bearing.tma_prediction import with_bearing


@dataclass(frozen=True)
class Cycle:
    """Tracks after one step, in slot order: ids (N,), confirmed (N,) bool, x (N, n),
    P (N, n, n), quality L (N,), ambiguous (N,), ml (N,) multi-line numbers (NEW = -1
    when not a confirmed narrowband line), and the multi-line tracks."""

    t: float
    ids: np.ndarray
    confirmed: np.ndarray
    x: np.ndarray
    P: np.ndarray
    quality: np.ndarray
    ambiguous: np.ndarray
    ml: np.ndarray
    multiline: list[MultiLineTrack]


class BearingTracker:
    """Seed 000 single-hypothesis bearing tracker for one array (see module docstring)."""

    def __init__(
        self,
        params: TrackerParams,
        array_kind: str,
        sigma0: float,
        crossing: CrossingParams | None = None,
    ) -> None:
        self.params = p = params
        if p.mode == "auto":
            raise ValueError('resolve mode "auto" before building the tracker')
        self.narrowband = p.mode == "narrowband"
        self.array_kind = array_kind
        self.sigma0 = sigma0
        self.H = measurement_matrix(self.narrowband)
        self.m, self.n = self.H.shape
        self.beam = math.radians(p.beam_spacing_deg)
        self.T1, self.T2 = thresholds(p.alpha, p.beta)
        self.imm = (BearingImm((p.q_theta_quiet, p.q_theta), tuple(p.imm_sojourn_s))
                    if 0.0 < p.q_theta_quiet < p.q_theta else None)
        self.table = TrackTable(
            self.n,
            extra={"L_max": ((), np.float64), "uid": ((), np.int64),
                   "ml": ((), np.int64), "ambiguous": ((), np.bool_), "mu": ((2,), np.float64),
                   "xm": ((2, self.n), np.float64), "Pm": ((2, self.n, self.n), np.float64)},
        )
        self.crossing = (BearingCrossing(crossing or CrossingParams(), self.H,
                                         p.band_hz if self.narrowband else None)
                         if p.crossing else None)
        self.blocks = (CrossingBlocks(self.crossing.manager.params.volume, p.block_window_s)
                       if self.crossing is not None and p.block_estimator else None)
        self.multiline = (MultiLineGrouper(math.radians(p.ml_brg_tol_deg), math.radians(p.ml_rate_tol_deg_s))
                          if self.narrowband else None)
        self.history = BearingHistory(p.history_keep_deleted)
        self.range_noise = RangeNoise()
        self.pair_orders = PairOrders()
        self.clutter = (ClutterLevel(p.clutter_prior_db, p.clutter_window,
                                     (p.clutter_bounds_db[0], p.clutter_bounds_db[1]))
                        if p.clutter_estimate and p.clutter_level_db == 0 else None)
        self.t: float | None = None
        self._next_uid = 0
        self._ml_tracks: list[MultiLineTrack] = []

    # ------------------------------------------------------------------ model

    def _F(self, T: np.ndarray) -> np.ndarray:
        return transition(self.narrowband, T)

    def _Q(self, T: np.ndarray, q_theta: np.ndarray | float | None = None) -> np.ndarray:
        return process_noise(self.params, self.narrowband, T, q_theta)

    def bearing_sigma(self, brg: np.ndarray, amp: np.ndarray, heading: float) -> np.ndarray:
        """sigma^mess of the bearing: 000 claim 6 for linear arrays, sigma0 otherwise."""
        return bearing_sigmas(self.params, self.array_kind, self.sigma0, brg, amp, heading)

    def _R_diag(self, brg: np.ndarray, level: np.ndarray, heading: float) -> np.ndarray:
        """Diagonal of 000 R per measurement (K, m): sigma_brg^2, sigma_a^2[, sigma_f^2]."""
        return measurement_variances(self.params, self.array_kind, self.sigma0, brg, level, heading)

    # ------------------------------------------------------------------ cycle

    def step(
        self,
        t: float,
        brg: np.ndarray,
        amp: np.ndarray,
        heading: float,
        own_x: float = 0.0,
        own_y: float = 0.0,
        freq: np.ndarray | None = None,
        sbrg: np.ndarray | None = None,
    ) -> Cycle:
        """Process the detection list of time t (true bearings rad, linear amplitudes > 0,
        frequencies Hz for narrowband; sbrg, when given, the sensor's bearing sigmas
        used instead of the array law) and return the tracks."""
        p, tab, H = self.params, self.table, self.H
        level, z, Rd = detection_measurements(p, self.array_kind, self.sigma0, self.t, t, brg, amp,
                                              heading, freq, sbrg)
        n_det = z.shape[0]

        idx = tab.active_indices()
        x, P = tab.x[idx], tab.P[idx]
        T = t - tab.t_last[idx]
        self.range_noise.cycle(t, own_x, own_y)  # issue 31: the contact's TMA solution
        q_man = self.range_noise.q_theta(tab.id[idx], p.q_theta)
        x0, P0 = x[:, :2].copy(), P[:, :2, :2].copy()
        if idx.size and self.imm is not None:  # 004 memory mode: quiet Q in both models
            memory = tab.ambiguous[idx] & (self.crossing is not None and self.crossing.memory)
            c, xm, Pm, x, P = self.imm.predict(tab.mu[idx], tab.xm[idx], tab.Pm[idx], T, self._F(T),
                                               self._Q, memory, q_man)
        elif idx.size:
            x, P = predict(x, P, self._F(T), self._Q(T, q_man))  # 000 x^pre = F x, P^pre = F P F' + Q
            x[:, 0] = wrap_2pi(x[:, 0])
        if idx.size:  # the bearing block from the TMA solution (tma_prediction)
            k, m2, C2, _ = self.range_noise.predictions(tab.id[idx], x0, P0, x[:, :2], P[:, :2, :2])
            x, P = with_bearing(x, P, k, m2, C2)
            if k.size and self.imm is not None:
                for j in range(xm.shape[1]):
                    xm[:, j], Pm[:, j] = with_bearing(xm[:, j], Pm[:, j], k, m2, C2)
        conf = tab.status[idx] == Status.CONFIRMED
        laws = p.clutter_level_db > 0 or self.clutter is not None
        mu = self.clutter.value if self.clutter is not None else p.clutter_level_db
        p_d = (detection_probability(x[:, 2], np.sqrt(P[:, 2, 2]), p.p_d, p.d_thr)  # 000 P_D(erfc)
               if laws else np.full(idx.size, p.p_d))
        p_fa = false_alarm_probability(level, p.p_fa, p.d_thr, mu) if laws else np.full(n_det, p.p_fa)
        rows, cols_, y, detS, d2, gated = associate(x, P, H, z, Rd, conf, p_d, p.p_d, p_fa, self.beam)
        alpha, ambiguous = np.ones(idx.size), np.zeros(idx.size, dtype=bool)
        keep = np.ones(rows.size, dtype=bool)
        if self.crossing is not None:  # seed 004 (common.sonar.bearing.crossing)
            alpha, ambiguous = self.crossing.gains(
                t, tab.id[idx], conf, x, z, rows, cols_,
                lambda zp: self._R_diag(zp[:, 0], zp[:, 1], heading), n_det)
            keep = self.crossing.exit_pairs(conf, tab.ambiguous[idx], ambiguous, x, z, Rd,
                                            rows, cols_)
        rows, cols_, y, detS, d2 = rows[keep], cols_[keep], y[keep], detS[keep], d2[keep]
        frozen: list[np.ndarray] = []
        if self.crossing is not None and self.crossing.memory:  # 004 memory-mode groups
            groups = memory_groups(self.crossing.groups, x[:, 0], conf & ambiguous)
            det = per_track(idx.size, rows, z[cols_, 0])
            self.pair_orders.observe(t, tab.uid[idx], groups, x[:, 0], det)
            released = release(groups, x[:, 0], P[:, 0, 0], rows, z[cols_, 0])
            released, frozen = self.pair_orders.settle(tab.uid[idx], released, groups, det,
                                                       per_track(idx.size, rows, Rd[cols_, 0]))
            alpha[released] = 1.0
        R = diagonal_covariances(Rd[cols_])

        if idx.size and self.imm is not None:  # 000 x^(k/k) per model, combined
            tab.mu[idx], tab.xm[idx], tab.Pm[idx], x, P = self.imm.update(
                c, xm, Pm, rows, z[cols_], H, R, alpha[rows])
        elif rows.size:  # 000 x^(k/k), K(k), Joseph-form P^(k/k)
            xu, Pu, _, _ = update(x[rows], P[rows], y, H, R, joseph=True, gain_scale=alpha[rows])
            xu[:, 0] = wrap_2pi(xu[:, 0])
            x[rows], P[rows] = xu, Pu

        if frozen:  # the frozen groups' centroids (common.sonar.bearing.pairs)
            x, P = self._centroids(idx, frozen, x, P, rows, z[cols_, 0], Rd[cols_, 0])
        if self.blocks is not None:  # 004 eq. 6-10 (common.sonar.bearing.block)
            self._block_exits(t, idx, conf, ambiguous, x, P, z[:, 0], Rd[:, 0])
        dL = missed_increment(p_d)
        dL[rows] = quality_increment(p_d[rows], p_fa[cols_], self.beam, detS, d2, self.m)  # 000 claim 4
        L = tab.score[idx] + dL  # 000 L(k) = L(k-1) + dL
        L_max = np.maximum(tab.L_max[idx], L)
        tentative = tab.status[idx] == Status.TENTATIVE
        confirm = tentative & (L > self.T2)  # 000 claim 2
        delete = (tentative & (L < self.T1)) | (~tentative & (L < L_max - p.delete_drop))
        hit = np.zeros(idx.size, dtype=bool)
        hit[rows] = True

        tab.x[idx], tab.P[idx], tab.t_last[idx] = x, P, t
        tab.score[idx], tab.L_max[idx], tab.ambiguous[idx] = L, L_max, ambiguous
        tab.n_updates[idx] += hit
        tab.n_coast[idx] = np.where(hit, 0, tab.n_coast[idx] + 1)
        tab.status[idx[confirm]] = Status.CONFIRMED
        conf = tab.status[idx] == Status.CONFIRMED
        merged = merged_tentative(x, P, conf, p.d_merge) & ~delete  # 000 d_merge
        self._delete(idx[delete | merged])

        unused = ~gated
        unused[cols_] = False
        if self.clutter is not None:  # the false level from the detections no confirmed track took
            taken = np.zeros(n_det, dtype=bool)
            taken[cols_[conf[rows]]] = True
            self.clutter.update(level[~taken], p.d_thr)
        opened = self._open(t, z[unused], Rd[unused])
        self.range_noise.born(tab.id[opened], t)  # a reused number is a new track
        self._group_lines()

        live = tab.active_indices()
        self.range_noise.forget(tab.id[live])
        ok = alpha[rows] == 1.0  # the register: the detections used in full (not 004's frozen)
        reg = np.r_[cols_[ok], np.flatnonzero(unused)]
        self.history.append(t, np.r_[tab.uid[idx[rows[ok]]], tab.uid[opened]], z[reg, 0],
                            np.sqrt(Rd[reg, 0]), own_x, own_y)
        self.history.maybe_compact(tab.uid[live])
        self.t = t
        return self._cycle(t, live)

    def _centroids(self, idx: np.ndarray, groups: list[np.ndarray], x: np.ndarray, P: np.ndarray,
                   rows: np.ndarray, zb: np.ndarray, rb: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """x, P after the common-mode update of the frozen groups (per IMM model)."""
        tab, imm = self.table, self.imm is not None
        xm, Pm = (tab.xm[idx], tab.Pm[idx]) if imm else (x[:, None].copy(), P[:, None].copy())
        centroid_update(groups, rows, zb, rb, xm, Pm)
        if not imm:
            return xm[:, 0], Pm[:, 0]
        tab.xm[idx], tab.Pm[idx] = xm, Pm
        return self.imm.combined(tab.mu[idx], xm, Pm)

    def _block_exits(self, t: float, idx: np.ndarray, conf: np.ndarray, flagged: np.ndarray,
                     x: np.ndarray, P: np.ndarray, z_brg: np.ndarray, z_var: np.ndarray) -> None:
        """Step 5b in place on x, P (N, ...) and the IMM models: tracks leaving 004's
        ambiguity take the bearing and rate of their block line."""
        tab = self.table
        uids = tab.uid[idx]
        rising = conf & flagged & ~tab.ambiguous[idx]
        hist = {int(u): tuple(self.history.rows(int(u))[c] for c in ("t", "brg", "sbrg")) for u in uids[rising]}
        q = self.crossing.manager.proportions(tab.id[idx]) if self.crossing is not None else np.zeros(idx.size)
        for ex in self.blocks.step(t, uids, conf, flagged, x, P, q, z_brg, z_var, hist):
            k = int(np.flatnonzero(uids == ex.uid)[0])
            s = slice(0, 2)
            for xs, Ps in ((x[k], P[k]), *zip(tab.xm[idx[k]], tab.Pm[idx[k]])):
                xs[0], xs[1] = wrap_2pi(ex.brg), ex.rate
                Ps[s, 2:], Ps[2:, s], Ps[s, s] = 0.0, 0.0, ex.cov

    def _delete(self, slots: np.ndarray) -> None:
        """Delete tracks; confirmed ones keep their history under their number."""
        tab = self.table
        conf = slots[tab.status[slots] == Status.CONFIRMED]
        self.history.retire(tab.id[conf], tab.uid[conf])
        if self.crossing is not None:
            self.crossing.forget(tab.id[slots])
        tab.remove(slots)

    def _open(self, t: float, z: np.ndarray, Rd: np.ndarray) -> np.ndarray:
        """000 initialisation: one tentative track per unassociated measurement,
        x(1) = H' z, P(1) = P0 (measurement variances, configured rate variances)."""
        k = z.shape[0]
        if k == 0:
            return np.zeros(0, dtype=np.intp)
        p, tab = self.params, self.table
        slots = tab.add(k)
        self.history.release(tab.id[slots])
        tab.x[slots] = z @ self.H
        rates = [p.init_brg_rate_sigma, p.init_amp_rate_sigma, p.init_freq_rate_sigma][: self.m]
        var = np.empty((k, self.n))
        var[:, 0::2] = Rd
        var[:, 1::2] = np.square(rates)
        tab.P[slots] = diagonal_covariances(var)
        tab.xm[slots] = tab.x[slots, None, :]
        tab.Pm[slots] = tab.P[slots, None]
        tab.mu[slots] = self.imm.mu0 if self.imm is not None else (1.0, 0.0)
        tab.t_last[slots] = t
        tab.L_max[slots] = 0.0
        tab.ml[slots] = NEW
        tab.uid[slots] = np.arange(self._next_uid, self._next_uid + k)
        self._next_uid += k
        return slots

    def _group_lines(self) -> None:
        """Claims 12-13 over the confirmed line tracks (narrowband only)."""
        if self.multiline is None:
            return
        tab = self.table
        live = tab.active_indices()
        conf = live[tab.status[live] == Status.CONFIRMED]
        tab.ml[live] = np.where(tab.status[live] == Status.CONFIRMED, tab.ml[live], NEW)
        if conf.size == 0:
            self._ml_tracks = []
            return
        tab.ml[conf], self._ml_tracks = multiline_tracks(
            self.multiline, tab.id[conf], tab.ml[conf], tab.x[conf, 0], tab.x[conf, 1])

    def _cycle(self, t: float, live: np.ndarray) -> Cycle:
        tab = self.table
        return Cycle(
            t, tab.id[live].copy(), tab.status[live] == Status.CONFIRMED, tab.x[live].copy(),
            tab.P[live].copy(), tab.score[live].copy(), tab.ambiguous[live].copy(),
            tab.ml[live].copy(), list(self._ml_tracks),
        )

    def tma_hint(self, track_id: int, hint: TmaHint) -> None:
        """The contact's latest TMA solution, used by later cycles (range_noise)."""
        self.range_noise.set(track_id, hint)

    # ------------------------------------------------------------------ register

    def history_of(self, track_id: int, as_of: float | None = None
                   ) -> tuple[str, dict[str, np.ndarray]] | None:
        """("confirmed" | "deleted", columns t, brg, sbrg, own_x, own_y) of a confirmed
        (live or recently deleted) track, from its first detection; None otherwise.
        With ``as_of`` (common.sonar.history_as_of): the rows up to that cycle time of any
        live or recently deleted track, whatever its status now (rows are never rewritten)."""
        tab = self.table
        slot = track_id - tab.first_id
        if 0 <= slot < tab.capacity and tab.id[slot] == track_id:
            if tab.status[slot] != Status.CONFIRMED and as_of is None:
                return None
            found = ("confirmed", self.history.rows(int(tab.uid[slot])))
        else:
            uid = self.history.retired_uid(track_id)
            if uid is None:
                return None
            found = ("deleted", self.history.rows(uid))
        if as_of is None:
            return found
        keep = found[1]["t"] <= as_of
        return found[0], {k: v[keep] for k, v in found[1].items()}
