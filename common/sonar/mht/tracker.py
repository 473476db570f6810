"""Multiple-hypothesis bearing tracker of seed 000 (second embodiment, "seguimiento de
multiples hipotesis"), the `mode_association = "mht"` of the bearing tracker.

A track i is a weighted set of hypotheses (x_ij, P_ij, c_ij), held for all tracks in flat
arrays (common.sonar.mht.hypotheses); its published state and covariance are the
mixture's moments. One `MhtTracker.step` per detection list (clock cycle k -> k+1):
  1. prediction of every hypothesis, x^pre = F x, P^pre = F P F' + Q (000 F, Q); near a
     closest approach the bearing block from the contact's TMA solution
     (common.sonar.bearing.tma_prediction: the track's bearing and rate propagated along a
     straight relative track, its linearised transition in F for the retrodiction);
  2. gate y' S^-1 y < lambda^2 per hypothesis x measurement (common.core.gating: a batched
     Mahalanobis gate with the largest R, then the exact S of each pair);
  3. new hypotheses: one missed detection plus one Kalman update per gated measurement,
     weights by the 000 formula with P_D from the predicted amplitude (erfc) and rho_F;
  4. resolution conflicts of confirmed tracks (common.sonar.mht.conflict);
  5. pruning below c_krit and the caps per track / per cycle;
  6. track split (d_split), track merge (d_merge), hypothesis merge (d_merge_hyp);
  7. new tentative tracks from measurements in no gate: x = H' z, P0, c = 1, SA = ZA = 0;
  8. LR_i = sum_h c_ih, SPRT counter ZA against A and B, status SA by ZA_krit, weights
     normalised when B is exceeded;
  9. end of conflicts: a newly confirmed track near a conflicting track is re-linked;
 10. retrodiction over n_retro cycles (common.sonar.mht.retrodiction), which also keeps the
     bearing register served on sonar/history.
Model, measurement noise and P0 are those of the single-hypothesis mode ([sonar.tracker]),
with its two bearing-rate models as a label per hypothesis (common.sonar.mht.models).

Deviations (stated):
- Deletion: the seed never deletes a track; a track whose status is tentative is
  deleted after `n_delete` cycles in a row as tentative without LR > B (a confirmed track
  that SA demotes gets those cycles too: its misses while still confirmed do not count),
  and any track whose bearing sigma exceeds `sigma_max_deg` (a target lost for good would
  otherwise coast forever), except a track with a fresh converged TMA solution while its
  sigma stays within tma_prediction's MAX_SIGMA (a wide, honest prediction near an approach).
- "Covariances not excessive" (track merge): both bearing sigmas below `merge_sigma_max_deg`.
- Order: conflicts before pruning (the seed: after the Kalman update): pruning sees their weights.
- Conflict start: besides the seed's rule (the main hypotheses of two confirmed tracks
  took the same measurement), a conflict starts when their main predicted hypotheses
  gate a common measurement, so that the first shared measurement is already
  interpreted jointly (with the seed's rule alone, the cycle that starts a conflict
  updated each track alone: seed 10 of sonar_cross_2dpm_eq with 3 false detections per
  cycle, one track took the other target's detection, jumped 3 deg and was lost).
- A track split off starts tentative (SA = ZA = 0; the seed lets it inherit the status
  of its track: a confirmed split-off of a clutter hypothesis was a confirmed false
  track, and a duplicate of the target until the SPRT removed it) and shares the
  register of its track up to the split; one that departs from its prediction more
  than the track's heaviest takes a new track's rates (`mht.hypotheses.split_off_rates`).
- Re-link at the end of a conflict: "track omega is linked to the past of track i" is
  implemented as track i continuing with omega's hypotheses and state of this cycle (its
  number and register kept, its own hypotheses dropped) and omega removed. The seed
  re-links only when omega is within d_Auf of a hypothesis of i or j; when i and j have
  coalesced on one target (main hypotheses closer than d_merge: both followed one target
  out of a slow crossing), omega, the lost target's new track, is far from both: it is
  re-linked when within relink_deg of them, to the one whose state from before the
  conflict (k_Auf - 1, quiet model) it continues likelier, the pair's main hypothesis on
  the other (both pairings, `exchanged_likelier`: the seed's sign of omega's young rate
  chose wrong); if they only took one measurement (000's interpretation (1)), they hold
  both targets and omega inside their gate is a duplicate, deleted. A conflict ends also
  when the pair's P_u < 1e-3 (the seed: by the re-link only); a pair coalesced in it (one
  measurement or d_merge) then takes the likelier order (`crossing_order`).
- Confirmation evidence: a tentative track whose main hypothesis took the measurement
  of the main hypothesis of a confirmed or an older track does not pass the test this
  cycle (its LR counts as at most B). Without it a track born on clutter next to a
  target, fed by the target's detections (which every track may use), confirmed as a
  duplicate (seen at crossings: a third confirmed track between the two), and two
  tentative tracks on one target confirmed together.
- Track numbers are never reused (the register of a number stays unambiguous).
- Resolution conflicts need the broadband model (as in the seed); narrowband tracks run
  without them, and without multi-line grouping.
"""

from __future__ import annotations

import math

import numpy as np

from common.core.angles import wrap_2pi
from common.core.gating import gate, mahalanobis_sq, pair_distances, pairwise_innovations
from common.core.kalman import diagonal_covariances, predict, update
from common.sonar.bearing.measurements import detection_measurements
from common.sonar.bearing.model import detection_probability, measurement_matrix
from common.sonar.bearing.multiline import NEW
from common.sonar.bearing.params import TrackerParams, process_noise, transition
from common.sonar.bearing.range_noise import RangeNoise, TmaHint
from common.sonar.bearing.tma_prediction import MAX_SIGMA, with_bearing
from common.sonar.bearing.tracker import Cycle
from common.sonar.mht.hypotheses import (
    LN_2PI,
    heaviest,
    hit_weights,
    merge_apply,
    merge_clusters,
    miss_weights,
    mixture_moments,
    pair_distance2,
    prune,
    split_off_rates,
    sprt,
    track_sums,
)
from common.sonar.mht.models import branch
from common.sonar.mht.params import MhtParams
from common.sonar.mht.retrodiction import CycleRecord, Retrodiction
from common.sonar.mht.tracks import TrackArrays, conflict_flags, duplicates, relink, resolve_conflicts


class MhtTracker:
    """Seed 000 multiple-hypothesis bearing tracker for one array (module docstring);
    same `step`, `Cycle` and `history_of` as common.sonar.bearing.tracker."""

    def __init__(self, params: TrackerParams, mht: MhtParams, array_kind: str,
                 sigma0: float) -> None:
        if params.mode == "auto":
            raise ValueError('resolve mode "auto" before building the tracker')
        self.params, self.mp = params, mht
        self.narrowband = params.mode == "narrowband"
        self.array_kind, self.sigma0 = array_kind, sigma0
        self.H = measurement_matrix(self.narrowband)
        self.m, self.n = self.H.shape
        n = self.n
        self.hx, self.hP = np.zeros((0, n)), np.zeros((0, n, n))
        self.hc, self.ht = np.zeros(0), np.zeros(0, dtype=np.intp)
        self.hmeas, self.hm = np.zeros(0, dtype=np.intp), np.zeros(0, dtype=np.intp)
        p = params  # the bearing-rate models of the IMM (common.sonar.mht.models)
        two = 0.0 < p.q_theta_quiet < p.q_theta
        self.q_models = (p.q_theta_quiet, p.q_theta) if two else (p.q_theta,)
        self.sojourn = np.asarray(p.imm_sojourn_s if two else [1.0], dtype=float)
        self.tr = TrackArrays(n)
        self.retro = Retrodiction(mht.n_retro, params.history_keep_deleted)
        self.t: float | None = None
        self.t_cycle = 0.0
        self.k = 0
        self.range_noise = RangeNoise()
        self.n_hyp_max = 0

    # ------------------------------------------------------------------ model

    def transition(self, T: float) -> np.ndarray:
        """000 F of this tracker's state over T seconds."""
        return transition(self.narrowband, T)

    def process_noise(self, T: np.ndarray | float, q_theta: np.ndarray | float) -> np.ndarray:
        """000 Q of this tracker's state over T seconds with bearing noise power q_theta."""
        return process_noise(self.params, self.narrowband, T, q_theta)

    # ------------------------------------------------------------------ cycle

    def step(self, t: float, brg: np.ndarray, amp: np.ndarray, heading: float,
             own_x: float = 0.0, own_y: float = 0.0, freq: np.ndarray | None = None,
             sbrg: np.ndarray | None = None) -> Cycle:
        """Process the detection list of time t (as BearingTracker.step)."""
        mp, H, tr = self.mp, self.H, self.tr
        _, z, Rd = detection_measurements(self.params, self.array_kind, self.sigma0, self.t, t,
                                          brg, amp, heading, freq, sbrg)
        self.t_cycle = t
        T = 0.0 if self.t is None else t - self.t
        F = self.transition(T)
        self.k += 1

        self.hx, self.hP, self.hc, self.ht, self.hm, src = branch(  # models (mht.models)
            self.hx, self.hP, self.hc, self.ht, self.hm, T, self.sojourn, tr.IN[self.ht] >= 0)
        self.hmeas = self.hmeas[src]
        Qm = np.stack([self.process_noise(T, q) for q in self.q_models])[self.hm]
        self.range_noise.cycle(t, own_x, own_y)  # issue 31: the contact's TMA solution
        q_man = self.range_noise.q_theta(tr.uid, self.params.q_theta)[self.ht]
        raised = (self.hm == len(self.q_models) - 1) & (q_man > self.params.q_theta)
        if raised.any():
            Qm[raised] = self.process_noise(np.full(int(raised.sum()), T), q_man[raised])
        xp, Pp = predict(self.hx, self.hP, F, Qm)  # 000 x^pre = F x, P^pre = F P F' + Q
        xp[:, 0] = wrap_2pi(xp[:, 0])
        k, m2, C2, Fk = self.range_noise.predictions(  # the bearing block from the TMA solution
            tr.uid[self.ht], self.hx[:, :2], self.hP[:, :2, :2], xp[:, :2], Pp[:, :2, :2])
        xp, Pp = with_bearing(xp, Pp, k, m2, C2)
        Fh = np.repeat(F[None], xp.shape[0], axis=0)  # per hypothesis, for the retrodiction
        Fh[k, :2, :2] = Fk  # the bearing block's linearised transition (tma_prediction)
        by_tma = self.range_noise.solved(tr.uid)  # not deleted for its bearing sigma
        pd = detection_probability(xp[:, 2], np.sqrt(Pp[:, 2, 2]), mp.p_d_max, mp.d_thr)
        hi, lj, y, S, d2 = self._gate(xp, Pp, z, Rd)
        nT = tr.size
        ci = track_sums(self.hc, self.ht, nT)
        c_rel = self.hc / ci[self.ht] if self.hc.size else self.hc
        xu, Pu, _, _ = update(xp[hi], Pp[hi], y, H, diagonal_covariances(Rd[lj]), joseph=True)
        xu[:, 0] = wrap_2pi(xu[:, 0])
        detS = np.linalg.det(S)
        Hn = self.hx.shape[0]
        cx = np.concatenate([xp, xu])
        cP = np.concatenate([Pp, Pu])
        cc = np.concatenate([miss_weights(c_rel, pd),  # 000 c_ih, alpha = 0
                             hit_weights(c_rel[hi], pd[hi], d2, detS, self.m, mp.rho_f)])
        cpar = np.concatenate([np.arange(Hn), hi])
        cmeas = np.concatenate([np.full(Hn, -1, dtype=np.intp), lj])
        if not self.narrowband:  # 4. resolution conflicts
            lgN = np.concatenate([np.zeros(Hn), -0.5 * (d2 + self.m * LN_2PI + np.log(detS))])
            cx, cP, cc, cpar, cmeas = resolve_conflicts(self, xp, Pp, pd, hi, lj, lgN, z, Rd,
                                                        cx, cP, cc, cpar, cmeas)

        ct, cm = self.ht[cpar], self.hm[cpar]
        keep = prune(cc, ct, nT, mp.c_krit, mp.max_hyp_track, mp.max_hyp_cycle)  # 000 c < c_krit
        cx, cP, cc, ct, cpar, cmeas = cx[keep], cP[keep], cc[keep], ct[keep], cpar[keep], cmeas[keep]
        cm = cm[keep]
        cx, cP, ct = self._split(cx, cP, cc, ct, xp[cpar], Pp[cpar])  # 000 split, may add tracks
        head = merge_clusters(cx, cP, cc, ct * self.sojourn.size + cm, mp.d_merge_hyp)  # 000 merge
        heads, cx, cP, cc = merge_apply(cx, cP, cc, head)
        ct, cpar, cmeas, cm = ct[heads], cpar[heads], cmeas[heads], cm[heads]
        self.hx, self.hP, self.hc, self.ht, self.hmeas, self.hm = cx, cP, cc, ct, cmeas, cm
        x_pre, P_pre, F_pre = xp[cpar], Pp[cpar], Fh[cpar]
        cpar = src[cpar]  # the retrodiction's parents: the hypotheses of the previous cycle

        unused = np.ones(z.shape[0], dtype=bool)
        unused[lj] = False
        self._open(z[unused], Rd[unused])  # 000 new tentative tracks
        n_new = int(unused.sum())
        zs = np.column_stack([z[:, 0], np.sqrt(Rd[:, 0])])  # register: detection brg, sbrg
        det = np.concatenate([np.where((cmeas >= 0)[:, None], zs[np.maximum(cmeas, 0)], np.nan)
                              if zs.size else np.full((cmeas.size, 2), np.nan), zs[unused]])
        x_pre = np.concatenate([x_pre, self.hx[-n_new:] if n_new else x_pre[:0]])
        P_pre = np.concatenate([P_pre, self.hP[-n_new:] if n_new else P_pre[:0]])
        F_pre = np.concatenate([F_pre, np.repeat(F[None], n_new, axis=0)])
        cpar = np.concatenate([cpar, np.full(n_new, -1, dtype=np.intp)])

        LR = track_sums(self.hc, self.ht, tr.size)  # 000 LR_i = sum_h c_ih
        was = tr.SA.copy()
        main = heaviest(self.hc, self.ht, tr.size)
        mmeas = np.where(main >= 0, self.hmeas[np.maximum(main, 0)], -1)
        dup = duplicates(tr, mmeas, z.shape[0])
        tr.ZA, tr.SA, norm = sprt(np.where(dup, np.minimum(LR, mp.B), LR), tr.ZA, tr.SA,
                                  mp.A, mp.B, mp.za_krit, mp.za_max)
        self.hc = np.where(norm[self.ht], self.hc / np.where(LR > 0, LR, 1.0)[self.ht], self.hc)
        tr.no_b = np.where(norm | (tr.SA == 1), 0, tr.no_b + 1)  # counted while tentative only
        conflict_flags(self, t)
        newly = np.flatnonzero((tr.SA == 1) & (was == 0))
        drop = relink(self, newly, t)
        drop |= self._merge_tracks()  # 000 track merge
        _, xi, Pi = mixture_moments(self.hx, self.hP, self.hc, self.ht, tr.size)
        drop |= (tr.SA == 0) & (tr.no_b >= mp.n_delete)
        by_tma = np.r_[by_tma, np.zeros(drop.size - by_tma.size, bool)]  # tracks split or opened: none
        sig = np.sqrt(Pi[:, 0, 0])  # a track with a fresh solution: up to tma_prediction's MAX_SIGMA
        drop |= (sig > math.radians(mp.sigma_max_deg)) & ~(by_tma & (sig <= MAX_SIGMA))
        for u in tr.uid[drop & (tr.ever_confirmed)]:
            self.retro.retire(int(u))
        live_h = ~drop[self.ht]
        remap = np.cumsum(~drop) - 1
        self.hx, self.hP, self.hc = self.hx[live_h], self.hP[live_h], self.hc[live_h]
        self.ht, self.hmeas, self.hm = remap[self.ht[live_h]], self.hmeas[live_h], self.hm[live_h]
        x_pre, P_pre, F_pre, cpar, det = x_pre[live_h], P_pre[live_h], F_pre[live_h], cpar[live_h], det[live_h]
        tr.keep(~drop)
        det[tr.IN[self.ht] >= 0] = np.nan  # a resolution conflict's detections may be the other's
        xi, Pi = xi[~drop], Pi[~drop]
        tr.ever_confirmed |= tr.SA == 1

        rows = np.column_stack([np.full(tr.size, t), xi[:, 0], np.sqrt(Pi[:, 0, 0]),
                                np.full(tr.size, own_x), np.full(tr.size, own_y),
                                np.full((tr.size, 2), np.nan)])
        self.retro.push(CycleRecord(self.hx, self.hP, self.hc, self.ht, tr.uid.copy(), cpar,
                                    x_pre, P_pre, F_pre, rows, det))  # 000 retrodiction
        self.retro.compact(tr.uid)
        self.range_noise.forget(tr.uid)
        self.n_hyp_max = max(self.n_hyp_max, int(np.bincount(self.ht).max(initial=0)))
        self.t = t
        return Cycle(t, tr.uid.copy(), tr.SA == 1, xi, Pi, tr.ZA.astype(float),
                     tr.IN >= 0, np.full(tr.size, NEW, dtype=np.int64), [])

    def _gate(self, xp: np.ndarray, Pp: np.ndarray, z: np.ndarray, Rd: np.ndarray
              ) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        """000 gate y' S^-1 y <= lambda^2: hypothesis rows, measurement columns,
        innovations, S and d^2 of the pairs inside. The batched gate uses S with the
        largest R of the list (never smaller than a pair's S, so it loses no pair), then
        each candidate pair is tested with its own S = H P^pre H' + R_l."""
        H, lam2 = self.H, self.mp.gate**2
        empty = np.zeros(0, dtype=np.intp)
        if xp.shape[0] == 0 or z.shape[0] == 0:
            return empty, empty, np.zeros((0, self.m)), np.zeros((0, self.m, self.m)), np.zeros(0)
        zp = xp @ H.T
        A = H @ Pp @ H.T
        Y = pairwise_innovations(zp, z, angle_idx=(0,))  # 000 y = z - H x^pre
        d2max = mahalanobis_sq(Y, A + np.diag(Rd.max(axis=0)))
        hi, lj = np.nonzero(gate(d2max, lam2))
        y, S, d2 = pair_distances(zp, A, z, Rd, hi, lj, angle_idx=(0,))  # 000 S = H P^pre H' + R
        ok = gate(d2, lam2)  # 000 y' S^-1 y <= lambda^2
        return hi[ok], lj[ok], y[ok], S[ok], d2[ok]

    def _open(self, z: np.ndarray, Rd: np.ndarray) -> None:
        """000 tentative tracks: x = H' z, P = P0, c = 1, SA = ZA = IN = 0 (IN = -1 here)."""
        k = z.shape[0]
        if k == 0:
            return
        var = np.empty((k, self.n))
        var[:, 0::2] = Rd
        var[:, 1::2] = self._rate_var()
        slots = self.tr.add(k, self.k)
        self.hx = np.concatenate([self.hx, z @ self.H])  # 000 x = H' z
        self.hP = np.concatenate([self.hP, diagonal_covariances(var)])  # 000 P0
        self.hc = np.concatenate([self.hc, np.ones(k)])
        self.ht = np.concatenate([self.ht, slots])
        self.hmeas = np.concatenate([self.hmeas, np.full(k, -1, dtype=np.intp)])
        self.hm = np.concatenate([self.hm, np.zeros(k, dtype=np.intp)])

    def _rate_var(self) -> np.ndarray:
        """Variances of the rate components of 000 P0 (bearing, amplitude, frequency rate)."""
        p = self.params
        return np.square([p.init_brg_rate_sigma, p.init_amp_rate_sigma, p.init_freq_rate_sigma][: self.m])

    def _split(self, x: np.ndarray, P: np.ndarray, c: np.ndarray, track: np.ndarray,
               x_pre: np.ndarray, P_pre: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """000 track split: when the two heaviest hypotheses of a track are farther than
        d_split, the lighter becomes a track of its own, its rates by
        `split_off_rates` (predictions x_pre, P_pre); returns x, P and the new track index."""
        nT = self.tr.size
        h1 = heaviest(c, track, nT)
        c2 = c.copy()
        c2[h1[h1 >= 0]] = -np.inf
        h2 = heaviest(c2, track, nT)
        both = np.flatnonzero((h1 >= 0) & (h2 >= 0) & np.isfinite(c2[np.maximum(h2, 0)]))
        if both.size == 0:
            return x, P, track
        a, b = h1[both], h2[both]
        far = pair_distance2(x[a], P[a], x[b], P[b]) > self.mp.d_split**2  # 000 d^2 > d_split^2
        if not far.any():
            return x, P, track
        src = both[far]
        slots = self.tr.split(src, self.k)
        for s_old, s_new in zip(src, slots):
            self.retro.inherit(int(self.tr.uid[s_new]), int(self.tr.uid[s_old]), self.t_cycle)
        track = track.copy()
        track[b[far]] = slots
        x, P = split_off_rates(x, P, x_pre, P_pre, a[far], b[far], self._rate_var())
        return x, P, track

    def _merge_tracks(self) -> np.ndarray:
        """000 track merge: a confirmed and a tentative track closer than d_merge, with
        covariances not excessive: the newer of the two is marked for deletion."""
        tr, mp = self.tr, self.mp
        drop = np.zeros(tr.size, dtype=bool)
        _, xi, Pi = mixture_moments(self.hx, self.hP, self.hc, self.ht, tr.size)
        ok = np.sqrt(Pi[:, 0, 0]) < math.radians(mp.merge_sigma_max_deg)
        conf, tent = np.flatnonzero(ok & (tr.SA == 1)), np.flatnonzero(ok & (tr.SA == 0))
        if conf.size == 0 or tent.size == 0:
            return drop
        db = np.abs(np.angle(np.exp(1j * (xi[conf, None, 0] - xi[None, tent, 0]))))
        near = db < mp.d_merge * np.sqrt(Pi[conf, None, 0, 0] + Pi[None, tent, 0, 0])
        a, b = conf[np.nonzero(near)[0]], tent[np.nonzero(near)[1]]
        close = pair_distance2(xi[a], Pi[a], xi[b], Pi[b]) < mp.d_merge**2  # 000 d^2 < d_merge^2
        a, b = a[close], b[close]
        newer = np.where(tr.uid[a] > tr.uid[b], a, b)
        drop[newer] = True
        return drop

    # ------------------------------------------------------------------ register

    def tma_hint(self, track_id: int, hint: TmaHint) -> None:
        """The contact's latest TMA solution, used by later cycles (range_noise)."""
        self.range_noise.set(track_id, hint)

    def history_of(self, track_id: int) -> tuple[str, dict[str, np.ndarray]] | None:
        """("confirmed" | "deleted", register) of a confirmed live or recently deleted
        track, None otherwise. Register: the detections of the track's main hypothesis
        by the retro weights (t, brg, sbrg, own_x, own_y) and the retrodicted bearings at
        every cycle (t_retro, brg_retro, sbrg_retro; common.sonar.mht.retrodiction)."""
        slot = self.tr.slot_of(track_id)
        if slot >= 0:
            if self.tr.SA[slot] != 1:
                return None
            status = "confirmed"
        elif track_id in self.retro.retired:
            status = "deleted"
        else:
            return None
        smoothed = {f"{c}_retro": v for c, v in self.retro.smoothed(track_id).items()}
        return status, {**self.retro.rows(track_id), **smoothed}
