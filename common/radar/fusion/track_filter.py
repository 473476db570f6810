"""The Gaussian-sum filter of the global tracks: 001 [55]-[56] (IMM prediction), module 64
(localisation) and module 65 ([49]-[50] EKF update) per mixture component.

State (complement of 001 [44]-[46], stated): every track is a Gaussian sum over
altitude bands x motion models (common.radar.fusion.mixture; common.radar.fusion.initiation.
altitude_bands says why a low target needs it; docs/decisions/011-global-track-filter.md
has the figures). x and P of a track are the moments of its mixture.
Motion model (complement of 001 [51], which uses one fixed Q): an interacting multiple
model filter (common.core.imm) of two [51] CV models, "quiet" (q) and "manoeuvre"
(q_manoeuvre), with mean sojourn times; the model-matched estimates are mixed before
the prediction [55]-[56], updated by [58]-[62] each, weighted by the likelihood of
the scan's measurement [49]; a new track starts from the chain's stationary
probabilities. Association (63), crossing (004) and output use the combined
estimate. With one fixed Q the filter could not be both consistent on a straight
target and follow a 2 deg/s turn, and an adaptive q reacted after the gate [48] had
dissociated the bases at the turn's onset (docs/decisions/011-global-track-filter.md).
Decorrelation (complement of 001, common.radar.fusion.decorrelation): modules 64-65 do not take the
elementary tracks' filtered estimates as measurements (their errors are correlated in
time, which made the global covariance far too small), but the equivalent measurement
of the scan recovered from two successive reports of each elementary track, i.e. the
fused plot that track used. A contributing elementary track without a measurement this
scan (not updated, ambiguous, or not recoverable) keeps its membership but adds nothing.
Module 64 during tracking is an iterated posterior linearisation started at each
band's prediction (common.radar.geometry.localisation.linearised_position, stated deviation: the
per-scan block mean is biased for poorly observed altitudes); a band whose residuals
fail the chi-square test (gate_prob) gets no position update this scan, and a track
none of whose bands passes is not located. The likelihood of the scan's ranges and
azimuths under each band's prediction weighs the bands (common.radar.fusion.mixture).
When the crossing test of 004 scales the gain by alpha, the likelihood is tempered by
the same alpha (alpha = 0, memory mode: probabilities only predicted).
Leave-one-out test of the v_b rows of [49] (complement of 001, stated; issue 14): with
one receiver and transmitters near the ground, the altitude of a target near one
transmitter is observed by that base alone (its range and v_b; the others' d r_b / d z
is small). When that base's elementary track swaps to a neighbour's target (an
elementary crossing, or module 62 extending a new track with the neighbour's track of
that base while the altitude is still open), the gate [48] of that track alone passes
(the manoeuvre component covers the jump) and the EKF explains it by a false z and vz
with a small covariance (how often: docs/decisions/011-global-track-filter.md). The other bases' v_b
do check it: the row j of a contributor whose squared innovation against the
prediction updated with every other row of [49] exceeds the chi-square(1) threshold of
the largest of n rows at gate_prob is left out of modules 64-65 for the scan, the track
located again without it, and the membership dissociated (module 63 re-associates the
base's elementary tracks next cycle from the track's own state).
Seed path (filter = "seed", issue 14): module 62 localises by the blocks [36]-[41]
without the altitude prior and starts the track from [44]-[46] as written (z-(x, y)
terms of [41] kept: common.radar.fusion.initiation.pair_candidates with seed=True); the same
arrays hold one band and one model (A = M = 1), so the weight stays 1 and every step is
001's EKF: [55]-[56] with the fixed Q of [51] (q, q_z), [49]-[50], [58]-[62]. Not
switched, so that the comparison isolates the state and its initialisation: the
decorrelated equivalent measurements, module 64 by posterior linearisation, the gate
[48], the v_b leave-one-out test, the crossing test of 004, the single-base update
(common.radar.fusion.ekf) and the duplicate merge (common.radar.fusion.merge).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np

from common.core import imm
from common.core.gating import chi2_gate
from common.core.track_table import TrackTable
from common.radar.fusion import ekf as global_ekf
from common.radar.fusion import mixture as global_mixture
from common.radar.fusion.assoc import ETrackSet
from common.radar.geometry.bistatic import POS
from common.radar.geometry.localisation import Constraints, linearised_position

if TYPE_CHECKING:
    from common.radar.fusion.params import FusionParams


@dataclass(frozen=True)
class BandFixes:
    """Module 64 per track and altitude band (n, A): located position (n, A, 3), its
    covariance (n, A, 3, 3), log-likelihood of the scan under the band, passed the
    chi-square test; post: posterior position (n, 3) of the heaviest band that passed
    (nan where none did); dropped (n, B): contributors left out (MixtureFilter.locate)."""

    pos: np.ndarray
    cov: np.ndarray
    ll: np.ndarray
    ok: np.ndarray
    post: np.ndarray
    dropped: np.ndarray

    @property
    def located(self) -> np.ndarray:
        """Tracks (n,) with at least one band that passed."""
        return self.ok.any(axis=1)


class MixtureFilter:
    """Prediction and update of the mixtures (bands x models) of the global tracks; the
    rows of a `TrackTable` hold them (fields xm, Pm, mu, see common.radar.fusion.cycle)."""

    def __init__(self, p: FusionParams, tx: np.ndarray, rx: np.ndarray) -> None:
        self.p, self.tx, self.rx = p, tx, rx
        if p.filter == "seed":  # 001: one band, one model with the fixed Q of [51]
            self.A, self.q_models, self.sojourn = 1, np.array([p.q]), np.array([p.sojourn_quiet])
        else:
            self.A = p.alt_bands
            self.q_models = np.array([p.q, p.q_manoeuvre])
            self.sojourn = np.array([p.sojourn_quiet, p.sojourn_manoeuvre])
        self.M = self.q_models.size
        self.mu0 = self.sojourn / self.sojourn.sum()  # stationary probabilities
        self.chi2_gate = np.array([np.inf] + [chi2_gate(p.gate_prob, k)
                                              for k in range(1, 2 * len(tx) + 1)])
        # chi-square(1) threshold of the largest of n rows: P(all n <= it) = gate_prob
        self.max_gate = np.array([np.inf] + [chi2_gate(p.gate_prob ** (1.0 / n), 1)
                                             for n in range(1, len(tx) + 1)])

    def predict(self, tab: TrackTable, t: float, live: np.ndarray) -> tuple[np.ndarray, ...]:
        """IMM mixing and model-matched prediction [55]-[56] of every component of the
        live tracks to t: (x, P) combined, (xm, Pm) per component and the predicted
        weights c, as arrays over all slots (rows of other slots: copies of the table)."""
        x, P, xm, Pm, c = tab.x.copy(), tab.P.copy(), tab.xm.copy(), tab.Pm.copy(), tab.mu.copy()
        if live.size:
            c[live], xm[live], Pm[live] = global_mixture.predict(
                tab.mu[live], tab.xm[live], tab.Pm[live], t - tab.t_last[live], self.A,
                self.sojourn, self.q_models, self.p.q_z)
            x[live], P[live] = imm.combine(c[live], xm[live], Pm[live])
        return x, P, xm, Pm, c

    def initial(self, xb: np.ndarray, Pb: np.ndarray, wb: np.ndarray
                ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Mixtures (xm, Pm, mu) of new tracks from their altitude bands (means, covariances,
        weights: fusion.initiation.altitude_bands), every band in every model with the chain's
        stationary probabilities, pruned (band_prune_init) and merged."""
        M = self.mu0.size
        xm, Pm = np.repeat(xb, M, axis=1), np.repeat(Pb, M, axis=1)
        w = (wb[:, :, None] * self.mu0).reshape(wb.shape[0], xm.shape[1])  # also for 0 tracks
        mu = global_mixture.prune_merge(w, xm, Pm, self.A, self.p.band_prune_init,
                                        self.p.band_merge, self.p.band_linear, self.rx[0, 2])
        return xm, Pm, mu

    def locate(self, xl: np.ndarray, Pl: np.ndarray, cl: np.ndarray, multi: np.ndarray,
               r: np.ndarray, active: np.ndarray, E: ETrackSet) -> BandFixes:
        """Module 64 per altitude band of the tracks `multi` (>= 2 active contributors):
        components (xl, Pl, cl) of n tracks, r (n, B) their rows of E, active (n, B) the
        contributors with an equivalent measurement. A track of >= 3 whose worst v_b row
        fails the leave-one-out test (`_vb_outlier`) is located again without that base
        (BandFixes.dropped)."""
        mass, xb, Pb = global_mixture.band_moments(cl, xl, Pl, self.A)
        bpos, bcov, bpost, bll, bok = self._bands(mass, xb, Pb, multi, r, active, E)
        drop = self._vb_outlier(mass, xb, Pb, bpos, bcov, bok, r, active, E)
        k = np.flatnonzero(drop.any(axis=1))
        if k.size:
            bpos[k], bcov[k], bpost[k], bll[k], bok[k] = self._bands(
                mass[k], xb[k], Pb[k], multi[k], r[k], active[k] & ~drop[k], E)
        located = bok.any(axis=1)
        best = np.argmax(np.where(bok, mass, -1.0), axis=1)
        post = np.where(located[:, None], bpost[np.arange(mass.shape[0]), best], np.nan)
        return BandFixes(bpos, bcov, bll, bok, post, drop)

    def _bands(self, mass: np.ndarray, xb: np.ndarray, Pb: np.ndarray, multi: np.ndarray,
               r: np.ndarray, active: np.ndarray, E: ETrackSet) -> tuple[np.ndarray, ...]:
        """Module 64 per live band (masses, moments): located position (n, A, 3), its
        covariance, posterior position, log-likelihood of the scan and chi-square test
        (BandFixes)."""
        n, A = mass.shape
        bpos, bpost = np.full((n, A, 3), np.nan), np.full((n, A, 3), np.nan)
        bcov = np.full((n, A, 3, 3), np.nan)
        bll, bok = np.zeros((n, A)), np.zeros((n, A), dtype=bool)
        ti, ai = np.nonzero(multi[:, None] & (mass > 0))
        if ti.size:
            rm = r[ti]
            sig = np.sqrt(np.diagonal(E.Rz[rm], axis1=2, axis2=3))
            cons = Constraints(E.z[rm, 0], sig[..., 0], E.z[rm, 2], sig[..., 2], active[ti],
                               self.tx, self.rx)
            zm, Rm, chi2, xpost, ll = linearised_position(  # module 64, per band
                xb[ti, ai][:, POS], Pb[ti, ai][:, POS][:, :, POS], cons, self.p.z_min)
            bpos[ti, ai], bcov[ti, ai], bpost[ti, ai], bll[ti, ai] = zm, Rm, xpost, ll
            bok[ti, ai] = chi2 <= self.chi2_gate[2 * active[ti].sum(1)]
        return bpos, bcov, bpost, bll, bok

    def _vb_outlier(self, mass: np.ndarray, xb: np.ndarray, Pb: np.ndarray, bpos: np.ndarray,
                    bcov: np.ndarray, bok: np.ndarray, r: np.ndarray, active: np.ndarray,
                    E: ETrackSet) -> np.ndarray:
        """(n, B) the contributor to leave out (module doc): in a located track of >= 3
        active contributors, the one whose v_b row of [49] fails the leave-one-out test
        (fusion.ekf.vb_deletion_residuals) the most, under the heaviest band that passed,
        at the chi-square(1) threshold of the largest of n rows (max_gate)."""
        drop = np.zeros(active.shape, dtype=bool)
        i = np.flatnonzero(bok.any(axis=1) & (active.sum(axis=1) >= 3))
        if i.size == 0:
            return drop
        a = np.argmax(np.where(bok[i], mass[i], -1.0), axis=1)
        infl, ri = self.p.meas_inflation, r[i]
        r2 = global_ekf.vb_deletion_residuals(
            xb[i, a], Pb[i, a], bpos[i, a], infl * bcov[i, a], E.z[ri, 1],
            infl * E.Rz[ri, 1, 1], active[i], self.tx, self.rx)
        worst = np.argmax(r2, axis=1)
        n = active[i].sum(axis=1)
        bad = r2[np.arange(i.size), worst] > self.max_gate[n]
        drop[i[bad], worst[bad]] = True
        return drop

    def update(self, xl: np.ndarray, Pl: np.ndarray, cl: np.ndarray, fix: BandFixes,
               single: np.ndarray, r: np.ndarray, active: np.ndarray, E: ETrackSet,
               alpha: np.ndarray) -> np.ndarray:
        """Module 65: EKF update of every component (xl, Pl updated in place) of the
        located tracks (fused, [49]-[50]) and of the tracks `single` (one active
        contributor), with the gains scaled by alpha (004); returns the new weights,
        pruned and merged (common.radar.fusion.mixture)."""
        A = self.A
        band = np.arange(cl.shape[1]) // (cl.shape[1] // A)
        located = fix.located
        infl = self.p.meas_inflation
        ll_comp = np.zeros(cl.shape)
        mu = cl.copy()
        ti, ki = np.nonzero(fix.ok[:, band] & (cl > 0))
        if ti.size:
            rl, ai = r[ti], band[ki]
            xl[ti, ki], Pl[ti, ki], ll = global_ekf.fused_update(  # module 65
                xl[ti, ki], Pl[ti, ki], fix.pos[ti, ai], infl * fix.cov[ti, ai], E.z[rl, 1],
                infl * E.Rz[rl, 1, 1], active[ti], self.tx, self.rx, alpha[ti])
            ll_comp[ti, ki] = alpha[ti] * ll
            mu[located] = global_mixture.reweight(cl[located], alpha[located, None] * fix.ll[located],
                                                  ll_comp[located], A)
        ti, ki = np.nonzero(single[:, None] & (cl > 0))
        if ti.size:
            rs = r[ti][active[ti]]
            bs = np.nonzero(active[ti])[1]
            xl[ti, ki], Pl[ti, ki], ll = global_ekf.single_base_update(
                xl[ti, ki], Pl[ti, ki], E.z[rs], infl * E.Rz[rs], self.tx[bs], self.rx[bs],
                alpha[ti])
            ll_comp[ti, ki] = alpha[ti] * ll
            mu[single] = imm.probabilities(cl[single], ll_comp[single])
        return global_mixture.prune_merge(mu, xl, Pl, A, self.p.band_prune, self.p.band_merge,
                                          self.p.band_linear, self.rx[0, 2])
