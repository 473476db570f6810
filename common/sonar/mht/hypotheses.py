"""Equations of the multiple-hypothesis embodiment of seed 000 on flat hypothesis arrays.

Hypotheses of all tracks live in flat arrays: x (H, n), P (H, n, n), c (H,) and the
owning track index `track` (H,). Every function is vectorised over all hypotheses of
all tracks; none keeps state. The bearing (state component 0) is an angle: differences
of it are wrapped to [-pi, pi) and means are taken around a reference hypothesis.

Deviations (stated):
- Hypothesis merge (000 "fusion de hipotesis"): the seed prints x_12 = sum c_r x_r and
  P_12 = sum c_r [...] without dividing by c_12 = sum c_r; we divide (the moment-matched
  mean and covariance of the pair; without it the state scales with the weights).
- Merge clusters: every hypothesis joins the heaviest hypothesis of its track within
  d_merge_hyp (its own if none is heavier); chains of such links are followed to their
  end, so a cluster may hold hypotheses farther than d_merge_hyp from each other (the
  seed merges pairs and leaves the order open).
- SPRT counter ZA is capped at `za_max` so that a long-confirmed track can still fall
  back below ZA_krit in a bounded number of cycles (the seed leaves ZA unbounded).
"""

from __future__ import annotations

import math

import numpy as np

from common.core.angles import wrap_2pi, wrap_pi
from common.core.gating import quadratic_form

LN_2PI = math.log(2.0 * math.pi)


def state_diff(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """a - b with the bearing component (0) wrapped to [-pi, pi)."""
    d = np.asarray(a, dtype=float) - np.asarray(b, dtype=float)
    d[..., 0] = wrap_pi(d[..., 0])
    return d


def pair_distance2(xa: np.ndarray, Pa: np.ndarray, xb: np.ndarray, Pb: np.ndarray) -> np.ndarray:
    """000 d^2 = (x_a - x_b)' (P_a + P_b)^-1 (x_a - x_b), batched over pairs (split,
    track merge and hypothesis merge use the same formula)."""
    d = state_diff(xa, xb)
    return quadratic_form(d, Pa + Pb)


def hit_weights(c_rel: np.ndarray, p_d: np.ndarray, d2: np.ndarray, det_S: np.ndarray,
                m: int, rho_f: float) -> np.ndarray:
    """000 c_ih for alpha > 0: c_rel P_D exp(-d^2/2) / (rho_F sqrt(det(2 pi S))), with
    det(2 pi S) = (2 pi)^m det S for the m x m innovation covariance S."""
    log_sqrt_det = 0.5 * (m * LN_2PI + np.log(det_S))
    return c_rel * p_d * np.exp(-0.5 * d2 - log_sqrt_det) / rho_f  # 000 c_ih, alpha > 0


def miss_weights(c_rel: np.ndarray, p_d: np.ndarray) -> np.ndarray:
    """000 c_ih for alpha = 0 (missed detection): c_rel (1 - P_D)."""
    return c_rel * (1.0 - p_d)  # 000 c_ih, alpha = 0


def fresh_rates(x: np.ndarray, P: np.ndarray, rate_var: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Hypotheses x (K, n), P (K, n, n) with their rate components (the odd state
    components: bearing rate, amplitude rate, frequency rate) those of a new track, 000
    x = H' z, P0 (rate 0, variance rate_var (n/2,), uncorrelated); the measured
    components keep their mean and covariance block."""
    x, P = x.copy(), P.copy()
    x[:, 1::2] = 0.0
    P[:, 1::2, :] = 0.0
    P[:, :, 1::2] = 0.0
    i = np.arange(1, x.shape[1], 2)
    P[:, i, i] = rate_var
    return x, P


def departure(x: np.ndarray, x_pre: np.ndarray, P_pre: np.ndarray, h: np.ndarray) -> np.ndarray:
    """d^2 of hypotheses h from their predictions in the measured components (bearing,
    level, frequency): (x - x^pre)' P^pre^-1 (x - x^pre), 0 for a missed detection."""
    d = state_diff(x[h], x_pre[h])[:, 0::2]
    S = P_pre[h][:, 0::2, 0::2]
    return quadratic_form(d, S)


def split_off_rates(x: np.ndarray, P: np.ndarray, x_pre: np.ndarray, P_pre: np.ndarray,
                    main: np.ndarray, off: np.ndarray, rate_var: np.ndarray
                    ) -> tuple[np.ndarray, np.ndarray]:
    """Hypotheses x, P (copies) after the 000 split of hypotheses `off` from their tracks'
    heaviest `main` (predictions x_pre, P_pre): a split-off that departs from its
    prediction more than the heaviest from its own (`departure`: it took a measurement
    off the track's prediction) keeps its bearing and level (mean and covariance) but
    takes the rates of a new track (`fresh_rates`).
    Deviation (stated): the seed splits the hypothesis as it is ("con solo una
    hipotesis"), so its rates are the track's, which the measurement that made it does
    not observe (sonar_cross_4dpm_uneq seed 169: a split-off on the weak target kept the
    strong one's rising rate, confirmed at +2.80 +- 0.44 deg/min against the target's
    -2.0, and coalesced with its track in the crossing). A split-off that continues the
    prediction better than the heaviest (the heaviest jumped to another source) keeps
    the track's rates, which are its target's (sonar_hold_cross_eq seed 304: reset, such
    a split-off lost its target and the pair coalesced on the other)."""
    moved = off[departure(x, x_pre, P_pre, off) > departure(x, x_pre, P_pre, main)]
    x, P = x.copy(), P.copy()
    x[moved], P[moved] = fresh_rates(x[moved], P[moved], rate_var)
    return x, P


def track_sums(c: np.ndarray, track: np.ndarray, n_tracks: int) -> np.ndarray:
    """000 c_i = sum_j c_ij per track (also LR_i = sum_h c_ih)."""
    return np.bincount(track, weights=c, minlength=n_tracks)


def heaviest(c: np.ndarray, track: np.ndarray, n_tracks: int) -> np.ndarray:
    """Index of the heaviest hypothesis of every track (main hypothesis), -1 if none."""
    order = np.lexsort((-c, track))
    first = np.full(n_tracks, -1, dtype=np.intp)
    t_sorted = track[order]
    start = np.ones(order.size, dtype=bool)
    start[1:] = t_sorted[1:] != t_sorted[:-1]
    first[t_sorted[start]] = order[start]
    return first


def mixture_moments(
    x: np.ndarray, P: np.ndarray, c: np.ndarray, track: np.ndarray, n_tracks: int
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """000 track moments: c_i = sum c_ij, x_i = sum c_ij x_ij / c_i,
    P_i = sum c_ij [P_ij + (x_ij - x_i)(x_ij - x_i)'] / c_i, for every track with at
    least one hypothesis (bearing mean taken around the track's main hypothesis)."""
    n = x.shape[1]
    ci = track_sums(c, track, n_tracks)
    ref = x[np.maximum(heaviest(c, track, n_tracks), 0)] if x.shape[0] else np.zeros((n_tracks, n))
    w = c / np.where(ci > 0, ci, 1.0)[track]
    d = state_diff(x, ref[track])
    xi = ref + _sum_by(w[:, None] * d, track, n_tracks)  # 000 x_i
    xi[:, 0] = wrap_2pi(xi[:, 0])
    e = state_diff(x, xi[track])
    Pi = _sum_by((w[:, None, None] * (P + e[:, :, None] * e[:, None, :])).reshape(-1, n * n),
                 track, n_tracks).reshape(n_tracks, n, n)  # 000 P_i
    return ci, xi, Pi


def _sum_by(v: np.ndarray, group: np.ndarray, n_groups: int) -> np.ndarray:
    out = np.zeros((n_groups,) + v.shape[1:])
    np.add.at(out, group, v)
    return out


def prune(c: np.ndarray, track: np.ndarray, n_tracks: int, c_krit: float,
          per_track: int, per_cycle: int) -> np.ndarray:
    """Mask of the hypotheses kept: 000 pruning c_ih' < c_krit, then at most `per_track`
    heaviest per track and `per_cycle` heaviest in all (the bounded-cost caps); the
    heaviest hypothesis of every track is always kept (the track's fate is the SPRT's)."""
    keep = c >= c_krit  # 000 c_ih' < c_krit -> suppressed
    order = np.lexsort((-c, track))
    t_sorted = track[order]
    start = np.r_[0, np.flatnonzero(t_sorted[1:] != t_sorted[:-1]) + 1]
    rank = np.arange(order.size) - np.repeat(start, np.diff(np.r_[start, order.size]))
    r = np.empty(order.size, dtype=np.intp)
    r[order] = rank
    keep &= r < per_track
    if keep.sum() > per_cycle:
        cand = np.flatnonzero(keep)
        keep[:] = False
        keep[cand[np.argsort(-c[cand], kind="stable")[:per_cycle]]] = True
    keep[heaviest(c, track, n_tracks)[np.bincount(track, minlength=n_tracks) > 0]] = True
    return keep


def merge_clusters(
    x: np.ndarray, P: np.ndarray, c: np.ndarray, track: np.ndarray, d_merge_hyp: float
) -> np.ndarray:
    """Cluster head of every hypothesis for 000 "fusion de hipotesis" (d^2 < d_merge_hyp^2
    within a track): the heaviest hypothesis of the same track within the distance,
    followed to the end of the chain (see the module docstring)."""
    Hn = c.size
    head = np.arange(Hn)
    if Hn < 2:
        return head
    a, b = _same_track_pairs(track)
    if a.size == 0:
        return head
    close = pair_distance2(x[a], P[a], x[b], P[b]) < d_merge_hyp**2  # 000 d^2 < d_merge,hyp^2
    a, b = a[close], b[close]
    src = np.r_[a, b]
    dst = np.r_[b, a]
    heavier = (c[dst] > c[src]) | ((c[dst] == c[src]) & (dst < src))
    src, dst = src[heavier], dst[heavier]
    best_w = np.full(Hn, -np.inf)
    np.maximum.at(best_w, src, c[dst])
    sel = c[dst] == best_w[src]
    head[src[sel]] = dst[sel]
    for _ in range(Hn):
        nxt = head[head]
        if np.array_equal(nxt, head):
            break
        head = nxt
    return head


def _same_track_pairs(track: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """All index pairs (a < b) of hypotheses of the same track."""
    order = np.argsort(track, kind="stable")
    t_sorted = track[order]
    start = np.r_[0, np.flatnonzero(t_sorted[1:] != t_sorted[:-1]) + 1]
    sizes = np.diff(np.r_[start, order.size])
    a_list, b_list = [], []
    for k in np.unique(sizes[sizes > 1]):
        groups = order[start[sizes == k][:, None] + np.arange(k)]  # (G, k)
        ia, ib = np.triu_indices(k, 1)
        a_list.append(groups[:, ia].ravel())
        b_list.append(groups[:, ib].ravel())
    if not a_list:
        return np.zeros(0, dtype=np.intp), np.zeros(0, dtype=np.intp)
    return np.concatenate(a_list), np.concatenate(b_list)


def merge_apply(
    x: np.ndarray, P: np.ndarray, c: np.ndarray, head: np.ndarray
) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """000 merged hypotheses: c_12 = sum c_r, x_12 = sum c_r x_r / c_12,
    P_12 = sum c_r [P_r + (x_r - x_12)(x_r - x_12)'] / c_12 per cluster; returns the
    heads kept (indices into the input) and their merged x, P, c."""
    heads, inv = np.unique(head, return_inverse=True)
    n = x.shape[1]
    c12 = np.bincount(inv, weights=c)  # 000 c_i,h12
    w = c / c12[inv]
    ref = x[heads]
    x12 = ref + _sum_by(w[:, None] * state_diff(x, ref[inv]), inv, heads.size)  # 000 x_i,h12
    x12[:, 0] = wrap_2pi(x12[:, 0])
    e = state_diff(x, x12[inv])
    P12 = _sum_by((w[:, None, None] * (P + e[:, :, None] * e[:, None, :])).reshape(-1, n * n),
                  inv, heads.size).reshape(-1, n, n)  # 000 P_i,h12
    return heads, x12, P12, c12


def sprt(
    LR: np.ndarray, ZA: np.ndarray, SA: np.ndarray, A: float, B: float, za_krit: int,
    za_max: int,
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """000 sequential test of every track: ZA + 1 when LR > B, ZA - 1 when LR < A (a
    tentative track at ZA = 0 stays at 0), unchanged in between; SA = 1 when
    ZA > ZA_krit, 0 when ZA < ZA_krit, unchanged at ZA_krit. Returns (ZA, SA, normalise)
    where normalise marks the tracks whose weights are divided by their sum (LR > B)."""
    up, down = LR > B, LR < A
    za = ZA + up.astype(np.int64)
    floor = (SA == 0) & (ZA == 0)
    za = np.where(down & ~floor, ZA - 1, za)  # 000 ZA(k+1) = ZA(k) - 1, tentative at 0 stays 0
    za = np.minimum(za, za_max)
    sa = np.where(za > za_krit, 1, np.where(za < za_krit, 0, SA))  # 000 SA by ZA_krit
    return za, sa.astype(SA.dtype), up
