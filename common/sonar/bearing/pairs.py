"""The pairs of tracks in seed 004's memory mode, in the single-hypothesis bearing tracker
(deviations from 004, stated here; steps 4-5 of common.sonar.bearing.tracker).

004 claim 5 freezes an ambiguous track: no detection of the crossing may update it, since
it could be the other target's. The ambiguity is which detection belongs to which track
of a pair (mutual nearest frozen tracks, `memory_pairs`), a permutation. Two rules use
what does not depend on it:
- Release (`ordered`): when the pair's predicted difference d = b_1 - b_2 is at least
  SIGN_SIGMAS sigma from 0 (var d = P_1 + P_2: the prediction is sure of the order) and
  GNN gave each track a detection, in that order, both tracks are updated with them as
  outside the ambiguity (alpha = 1) for this scan. The flags stay as eq. 13 sets them.
- Centroid (`centroid_measurements`, `common_mode_update`): a pair not released that GNN
  gave two detections has its centroid c = (b_1 + b_2) / 2 updated by theirs (variance
  (R_1 + R_2) / 4), and its difference stays on 004's memory (extrapolation). The joint
  update of (x_1, x_2) with h_c = [h, h] / 2, per IMM model, keeps the marginals and
  drops the cross-covariance it creates; a centroid innovation beyond GATE (a clutter
  detection in the pair's GNN result) is not used. One detection is not used: taken as
  either contact (c +- d / 2, variance R + (d^2 + var d) / 4), it moved a target's track
  away from it when the pair's other track was a duplicate, on no target (sonar_hold_cpa
  seed 12: a break).
Why: frozen for the whole ambiguity, a pair coasted on the bearing rates it entered with.
An own-ship turn changes both contacts' bearing rates (by the own ship's velocity change
across the line of sight over the range, which a bearing tracker has not): on
sonar_hold_cross_turn seed 67 the pair overshot by 3 deg, one track took the other
target's detection 7 deg off when both left the memory mode, and the two then coasted
side by side beside one target for minutes, eq. 13 testing only their predictions. A
young track's bearing-rate error did the same on the fast crossings (sonar_cross_4dpm_*).
Swap and break runs, bearing RMSE with and without these rules, and the command:
docs/decisions/007-sonar-memory-pairs.md.
"""

from __future__ import annotations

import numpy as np

from common.core.angles import wrap_2pi, wrap_pi

GATE = 10.83  # chi-square(1) 0.999 quantile of the centroid innovation
SIGN_SIGMAS = 3.0  # the pair's order is known when |b_1 - b_2| >= 3 sigma


def per_track(n: int, rows: np.ndarray, values: np.ndarray) -> np.ndarray:
    """(n,) the value of the detection GNN gave each of n tracks (rows), NaN for none."""
    out = np.full(n, np.nan)
    out[rows] = values
    return out


def memory_pairs(brg: np.ndarray, var: np.ndarray, frozen: np.ndarray) -> np.ndarray:
    """Pairs (K, 2) of track rows: frozen tracks that are each other's nearest frozen
    neighbour in bearing (d^2 = (b_i - b_j)^2 / (var_i + var_j))."""
    idx = np.flatnonzero(frozen)
    if idx.size < 2:
        return np.zeros((0, 2), dtype=np.intp)
    d = wrap_pi(brg[idx, None] - brg[None, idx])
    d2 = d**2 / (var[idx, None] + var[None, idx])
    np.fill_diagonal(d2, np.inf)
    near = np.argmin(d2, axis=1)
    first = np.flatnonzero((near[near] == np.arange(idx.size)) & (np.arange(idx.size) < near))
    return np.column_stack([idx[first], idx[near[first]]])


def ordered(pairs: np.ndarray, brg: np.ndarray, P00: np.ndarray, det_brg: np.ndarray) -> np.ndarray:
    """Mask of the pairs whose order is known: the predicted difference d = b_1 - b_2 is at
    least SIGN_SIGMAS of its sigma from 0 (var d = P_1 + P_2), and GNN gave each track a
    detection, in that order."""
    a, b = pairs[:, 0], pairs[:, 1]
    d = wrap_pi(brg[a] - brg[b])
    dz = wrap_pi(det_brg[a] - det_brg[b])  # NaN without both detections
    return (np.abs(d) >= SIGN_SIGMAS * np.sqrt(P00[a] + P00[b])) & (d * dz > 0)


def release(frozen: np.ndarray, brg: np.ndarray, P00: np.ndarray, rows: np.ndarray,
            det_brg: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The tracks (N,) mask released from the memory mode for this scan (their pair's order is
    known, `ordered`) and the pairs (K, 2) that stay frozen, from the frozen mask, the
    predicted bearings brg and variances P00 (N,), and the GNN pairs: track rows and
    their detections' bearings det_brg."""
    pairs = memory_pairs(brg, P00, frozen)
    known = ordered(pairs, brg, P00, per_track(brg.size, rows, det_brg))
    released = np.zeros(brg.size, dtype=bool)
    released[pairs[known].ravel()] = True
    return released, pairs[~known]


def centroid_update(pairs: np.ndarray, rows: np.ndarray, det_brg: np.ndarray, det_var: np.ndarray,
                    xm: np.ndarray, Pm: np.ndarray) -> None:
    """The common-mode update of the frozen pairs, in place on the model states xm, Pm (N, J,
    ...), from the GNN pairs: track rows, their detections' bearings and variances."""
    n = xm.shape[0]
    zc, rc, seen = centroid_measurements(pairs, per_track(n, rows, det_brg), per_track(n, rows, det_var))
    common_mode_update(xm, Pm, pairs[seen], zc[seen], rc[seen])


def centroid_measurements(pairs: np.ndarray, det_brg: np.ndarray, det_var: np.ndarray
                          ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Centroid bearing (the circular mean), its variance (R_1 + R_2) / 4 and the mask of
    the pairs measured (GNN gave each track a detection), from the bearing det_brg (N,)
    and variance det_var of the detection of each track (NaN: none)."""
    za, zb = det_brg[pairs[:, 0]], det_brg[pairs[:, 1]]
    zc = wrap_2pi(zb + wrap_pi(za - zb) / 2.0)
    return zc, (det_var[pairs[:, 0]] + det_var[pairs[:, 1]]) / 4.0, ~np.isnan(za) & ~np.isnan(zb)


def common_mode_update(xm: np.ndarray, Pm: np.ndarray, pairs: np.ndarray, zc: np.ndarray,
                       rc: np.ndarray) -> np.ndarray:
    """Update the model states xm (N, J, n), Pm (N, J, n, n) of both tracks of each pair in
    place with its centroid measurement zc, rc (a pair is used if every model's centroid
    innovation passes GATE); returns the mask of the pairs updated."""
    a, b = pairs[:, 0], pairs[:, 1]
    ph_a, ph_b = Pm[a, :, :, 0], Pm[b, :, :, 0]  # P h' per model (K, J, n)
    S = (ph_a[..., 0] + ph_b[..., 0]) / 4.0 + rc[:, None]  # h_c P h_c' + r_c
    nu = wrap_pi(zc[:, None] - (xm[b, :, 0] + wrap_pi(xm[a, :, 0] - xm[b, :, 0]) / 2.0))
    ok = np.all(nu**2 / S <= GATE, axis=1)
    for k, ph in ((a[ok], ph_a[ok]), (b[ok], ph_b[ok])):
        K = ph / (2.0 * S[ok, :, None])  # gain of track k on the centroid: P_k h' / 2 S
        xm[k] += K * nu[ok, :, None]
        Pm[k] -= K[..., :, None] * ph[..., None, :] / 2.0
        xm[k, :, 0] = wrap_2pi(xm[k, :, 0])
    return ok
