"""Module 63 of 001: association of elementary tracks to global tracks.

The global track's predicted state is projected into base b by g of [47] (Jacobian G
from common.radar.geometry.bistatic) and compared with the elementary track's [r_b, v_b, theta]
and covariance R through the statistical distance [48]:
    gamma = v' Gamma^-1 v,  v = Y - g(x~),  Gamma = G P~ G' + R.
Candidate pairs are prefiltered on azimuth (sorted search, module 62's test 1) so that
gamma is computed only for plausible pairs; pairs are kept as flat arrays.

`resolve` is the two-best-candidates loop of the seed, for one base b over the global
tracks that do not contain b (index i) and the free elementary tracks of b (index m):
    p1 = argmin_m {gamma_im < gamma_max}, p2 = the next best;
    no p1: nothing; p1 only: associate p1;
    p1 and p2: if some other global track n has gamma_n,p1 < gamma_i,p1 (n_inv: a
    track for which p1 is more likely; the seed writes ">=" of likelihoods),
    associate p2 with i (the association p1-i is invalidated), else associate p1.
An associated elementary track is no longer available to later global tracks (001:
an elementary track belongs to one global track). The loop runs in index order;
it is vectorised by rounds: a track decides as soon as no earlier undecided track
shares a candidate with it, which reproduces the sequential result exactly.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from common.core.angles import wrap_pi
from common.core.gating import overlap_pairs, pair_distances
from common.radar.fusion.initiation import azimuth_pairs
from common.radar.geometry.bistatic import project, project_jacobian

YR = [0, 1, 3]  # [r_b, v_b, theta] in the elementary state [r_b, v_b, gamma_b, theta, omega]


@dataclass(frozen=True)
class ETrackSet:
    """The elementary tracks of one cycle, all bases stacked (E rows).

    base: base index (into the fusion's base list); id: elementary track number;
    y (E, 3) = [r_b, v_b, theta] and R (E, 3, 3) its covariance (the elementary state
    restricted to these components, 001 module 63); score; confirmed, updated,
    ambiguous: flags of the elementary track; z (E, 3), Rz (E, 3, 3), meas (E,): the
    equivalent measurement of this scan (common.radar.fusion.decorrelation) and whether it exists.

    Association ([48], `gated_pairs`) and initialisation (module 62) use the estimate
    (y, R): a one-off comparison or starting point, and the estimate is more accurate
    than one scan's plot (its error is positively correlated with the global track's,
    so [48] with G P G' + R is conservative). Localisation (64) and the EKF (65), which
    accumulate information scan after scan, use (z, Rz) only.
    """

    base: np.ndarray
    id: np.ndarray
    y: np.ndarray
    R: np.ndarray
    score: np.ndarray
    confirmed: np.ndarray
    updated: np.ndarray
    ambiguous: np.ndarray
    z: np.ndarray
    Rz: np.ndarray
    meas: np.ndarray

    def __len__(self) -> int:
        return int(self.base.size)


def projections(
    x: np.ndarray, P: np.ndarray, tx: np.ndarray, rx: np.ndarray
) -> tuple[np.ndarray, np.ndarray]:
    """g(x~) of 001 [47] (N, 3) and G P~ G' (N, 3, 3) of N global tracks in one base."""
    G = project_jacobian(x, tx, rx)
    return project(x, tx, rx), G @ P @ np.swapaxes(G, 1, 2)


def distance(y_pred: np.ndarray, GPG: np.ndarray, y: np.ndarray, R: np.ndarray) -> np.ndarray:
    """001 [48] for aligned pairs: gamma = v' (G P G' + R)^-1 v, v = y - g(x~) (P,)."""
    k = np.arange(y.shape[0])
    return pair_distances(y_pred, GPG, y, R, k, k, angle_idx=(2,))[2]  # [48]


def gated_pairs(
    x: np.ndarray, P: np.ndarray, tracks: np.ndarray, ets: np.ndarray, E: ETrackSet,
    tx: np.ndarray, rx: np.ndarray, az_gate: float, gamma_max: float,
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Pairs (i, m, gamma) of global tracks `tracks` (rows of x, P) and elementary
    tracks `ets` (rows of E, one base with geometry tx, rx) with gamma <= gamma_max.

    Prefilter: the azimuth of g(x~) within az_gate of the elementary azimuth.
    """
    if tracks.size == 0 or ets.size == 0:
        e = np.zeros(0, dtype=np.intp)
        return e, e, np.zeros(0)
    y_pred, GPG = projections(x[tracks], P[tracks], tx, rx)
    a, b = azimuth_pairs(y_pred[:, 2], E.y[ets, 2], az_gate)
    gam = distance(y_pred[a], GPG[a], E.y[ets[b]], E.R[ets[b]])
    ok = gam <= gamma_max
    return tracks[a[ok]], ets[b[ok]], gam[ok]


def component_gamma(w: np.ndarray, xc: np.ndarray, Pc: np.ndarray, y: np.ndarray,
                    R: np.ndarray, tx: np.ndarray, rx: np.ndarray) -> np.ndarray:
    """[48] for aligned pairs of a track's mixture (w (P, K), xc (P, K, 6), Pc
    (P, K, 6, 6)) and an elementary estimate (y (P, 3), R (P, 3, 3)) of the base with
    geometry tx, rx (P, 3) each: the smallest gamma over the live components (inf if
    none is live); see `gated_component_pairs` for why per component."""
    p, k = np.nonzero(w > 0)
    y_pred, GPG = projections(xc[p, k], Pc[p, k], tx[p], rx[p])
    best = np.full(w.shape[0], np.inf)
    np.minimum.at(best, p, distance(y_pred, GPG, y[p], R[p]))  # [48]
    return best


def component_gate(w: np.ndarray, xc: np.ndarray, Pc: np.ndarray, y: np.ndarray,
                   R: np.ndarray, tx: np.ndarray, rx: np.ndarray, gamma_max: float
                   ) -> np.ndarray:
    """`component_gamma` <= gamma_max (P,) bool, the [48] gate of a membership: the
    heaviest live components first, the others only for the pairs those fail (the
    same answer with a fraction of the projections)."""
    top = (w == w.max(axis=1, keepdims=True)) & (w > 0)
    ok = component_gamma(np.where(top, w, 0.0), xc, Pc, y, R, tx, rx) <= gamma_max
    k = np.flatnonzero(~ok)
    ok[k] = component_gamma(np.where(top[k], 0.0, w[k]), xc[k], Pc[k], y[k], R[k], tx[k],
                            rx[k]) <= gamma_max
    return ok


def gated_component_pairs(
    w: np.ndarray, xc: np.ndarray, Pc: np.ndarray, tracks: np.ndarray, ets: np.ndarray,
    E: ETrackSet, tx: np.ndarray, rx: np.ndarray, az_gate: float, gamma_max: float,
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """`gated_pairs` over the mixture components of each track (weights w (N, K), means
    xc (N, K, 6), covariances Pc (N, K, 6, 6): altitude band x motion model,
    common.radar.fusion.mixture): a pair passes [48] when one live component (w > 0) passes
    it, with that component's gamma (the smallest).

    Deviation (stated): 001 gates the track's single Gaussian. The moments of a mixture
    can fit none of its hypotheses: (1) a new high, close target (z 11.1 km) whose
    bands at 3.8 and 11 km averaged to 3.9 km, so a base of the same target failed the
    gate, left the track and started a duplicate with a fourth base; (2) the onset of a
    turn, which only the manoeuvre model's prediction covers while the quiet model
    still dominates the weights: all four bases failed the gate within two scans and a
    new track took over (figures: docs/decisions/016-global-association.md)."""
    K = w.shape[1]
    rows = (tracks[:, None] * K + np.arange(K)).ravel()[(w[tracks] > 0).ravel()]
    i, m, g = gated_pairs(xc.reshape(-1, 6), Pc.reshape(-1, 6, 6), rows, ets, E, tx, rx,
                          az_gate, gamma_max)
    i = i // K
    order = np.lexsort((g, m, i))
    i, m, g = i[order], m[order], g[order]
    first = np.r_[True, (i[1:] != i[:-1]) | (m[1:] != m[:-1])] if i.size else i.astype(bool)
    return i[first], m[first], g[first]


def resolve(i: np.ndarray, m: np.ndarray, gam: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The two-best-candidates loop (001 module 63) on gated pairs (i, m, gamma).

    Global tracks are processed in increasing i. Returns the decided (i, m) pairs.
    """
    if i.size == 0:
        return i, m
    _, ti = np.unique(i, return_inverse=True)
    _, mi = np.unique(m, return_inverse=True)
    n_t, n_m = ti.max() + 1, mi.max() + 1
    G = np.full((n_t, n_m), np.inf)
    G[ti, mi] = gam
    rows_i = np.zeros(n_t, dtype=i.dtype)
    rows_i[ti] = i
    cols_m = np.zeros(n_m, dtype=m.dtype)
    cols_m[mi] = m
    col_best = G.min(axis=0)
    undecided = np.ones(n_t, dtype=bool)
    free = np.ones(n_m, dtype=bool)
    out_t, out_m = [], []
    while undecided.any():
        avail = np.where(free[None, :] & undecided[:, None], G, np.inf)
        gated = np.isfinite(avail)
        first_row = np.where(gated.any(axis=0), np.argmax(gated, axis=0), n_t)
        ready = undecided & np.all(~gated | (first_row[None, :] == np.arange(n_t)[:, None]), 1)
        order = np.argsort(avail, axis=1)[:, :2]
        p1, p2 = order[:, 0], order[:, 1] if n_m > 1 else order[:, 0]
        r = np.arange(n_t)
        has1 = np.isfinite(avail[r, p1])
        has2 = has1 & (n_m > 1) & np.isfinite(avail[r, p2])
        g1 = G[r, p1]
        n_inv = col_best[p1] < g1  # another global track for which p1 is more likely
        choice = np.where(has2 & n_inv, p2, p1)
        take = ready & has1
        out_t.append(np.flatnonzero(take))
        out_m.append(choice[take])
        free[choice[take]] = False
        undecided &= ~ready
    t_idx = np.concatenate(out_t)
    m_idx = np.concatenate(out_m)
    order = np.argsort(t_idx)
    return rows_i[t_idx[order]], cols_m[m_idx[order]]



def ambiguous_members(w: np.ndarray, xc: np.ndarray, Pc: np.ndarray, x: np.ndarray,
                      P: np.ndarray, row: np.ndarray, tracks: np.ndarray, E: ETrackSet,
                      tx: np.ndarray, rx: np.ndarray, az_gate: float, gamma_max: float,
                      swap_gate: float) -> np.ndarray:
    """Mask (cap, B) of the memberships of `tracks` that are ambiguous this scan: at base
    b, track i holds elementary track m, track j holds m', m' passes [48] against i
    while m passes it against j, and the swapped pairing is not less likely than the
    held one by swap_gate or more: gamma(i, m') + gamma(j, m) - gamma(i, m) -
    gamma(j, m') < swap_gate (the log-likelihood ratio of the two pairings, times 2;
    GlobalFusion uses the chi-square(1) quantile of gate_prob). Mixtures w, xc, Pc and
    their moments x, P over all slots; row (cap, B) the rows of E held, -1 = none.
    Their equivalent measurements are not used this scan (the memberships stay).
    Complement of 001 module 63 (stated): the resolution loop decides each free
    elementary track once, but two aircraft close in one base's measurement space keep
    passing [48] against each other's track, and a young track (velocity and altitude
    still loose) then takes the other's measurements whenever that base's elementary
    tracks swap (both tracks then take them and flip-flop between the two aircraft). As
    004 does for a crossing, an ambiguous measurement is not used; the likelihood
    condition keeps the crossings of two settled tracks in use (the case and figures:
    docs/decisions/016-global-association.md).
    Candidates: held elementary tracks whose ranges differ by less than sqrt(gamma_max)
    (2 sigma_i + sigma_m + 2 sigma_j + sigma_m'), sigma_i the range sigma of track i's
    projected moments, and azimuths by less than 2 az_gate (the prefilter of
    `gated_pairs`, both ways): a superset of the mutual pairs that `gated_pairs` would
    give, at a near-linear cost."""
    amb = np.zeros(row.shape, dtype=bool)
    g = np.sqrt(gamma_max)
    for b in range(row.shape[1]):
        held = tracks[row[tracks, b] >= 0]
        if held.size < 2:
            continue
        m = row[held, b]
        _, GPG = projections(x[held], P[held], tx[b], rx[b])
        half = g * (2.0 * np.sqrt(GPG[:, 0, 0]) + np.sqrt(E.R[m, 0, 0]))
        i, j = overlap_pairs(E.y[m, 0] - half, E.y[m, 0] + half)
        near = np.abs(wrap_pi(E.y[m[i], 2] - E.y[m[j], 2])) <= 2.0 * az_gate
        i, j = i[near], j[near]
        swap = _pair_gammas(w, xc, Pc, held[np.r_[i, j]], m[np.r_[j, i]], E, tx[b], rx[b])
        k = i.size
        both = (swap[:k] <= gamma_max) & (swap[k:] <= gamma_max)  # [48] each way
        i, j, swap = i[both], j[both], swap[:k][both] + swap[k:][both]
        kept = _pair_gammas(w, xc, Pc, held[np.r_[i, j]], m[np.r_[i, j]], E, tx[b], rx[b])
        likely = swap - kept[:i.size] - kept[i.size:] < swap_gate
        amb[held[i[likely]], b] = amb[held[j[likely]], b] = True
    return amb


def _pair_gammas(w: np.ndarray, xc: np.ndarray, Pc: np.ndarray, a: np.ndarray, o: np.ndarray,
                 E: ETrackSet, tx: np.ndarray, rx: np.ndarray) -> np.ndarray:
    """`component_gamma` of tracks a against elementary tracks o (rows of E), one base."""
    n = a.size
    return component_gamma(w[a], xc[a], Pc[a], E.y[o], E.R[o], np.broadcast_to(tx, (n, 3)),
                           np.broadcast_to(rx, (n, 3)))
