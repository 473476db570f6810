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


def memory_groups(labels: np.ndarray, brg: np.ndarray, frozen: np.ndarray) -> list[np.ndarray]:
    """The groups of at least two frozen tracks: rows with one label of 004's ambiguity
    groups (common.core.crossing.ambiguity_groups), each in bearing order (on the circle,
    from its first member)."""
    idx = np.flatnonzero(frozen)
    out = []
    for lab in np.unique(labels[idx]):
        g = idx[labels[idx] == lab]
        if g.size >= 2:
            out.append(g[np.argsort(wrap_pi(brg[g] - brg[g[0]]))])
    return out


def ordered(group: np.ndarray, brg: np.ndarray, P00: np.ndarray, det_brg: np.ndarray) -> bool:
    """True when the group's order is known: every two neighbours in bearing order are at
    least SIGN_SIGMAS of their difference's sigma apart (var d = P_1 + P_2), and GNN gave
    each track a detection, in that order."""
    a, b = group[:-1], group[1:]
    d = wrap_pi(brg[b] - brg[a])  # > 0: the group is in bearing order
    dz = wrap_pi(det_brg[b] - det_brg[a])  # NaN without both detections
    return bool(np.all((d >= SIGN_SIGMAS * np.sqrt(P00[a] + P00[b])) & (dz > 0)))


def release(groups: list[np.ndarray], brg: np.ndarray, P00: np.ndarray, rows: np.ndarray,
            det_brg: np.ndarray) -> np.ndarray:
    """The tracks (N,) mask released from the memory mode for this scan (their group's order
    is known, `ordered`), from the frozen groups (`memory_groups`), the predicted bearings
    brg and variances P00 (N,), and the GNN pairs: track rows and their detections'
    bearings det_brg."""
    det = per_track(brg.size, rows, det_brg)
    released = np.zeros(brg.size, dtype=bool)
    for g in groups:
        released[g] = ordered(g, brg, P00, det)
    return released


def centroid_update(groups: list[np.ndarray], rows: np.ndarray, det_brg: np.ndarray,
                    det_var: np.ndarray, xm: np.ndarray, Pm: np.ndarray) -> None:
    """The common-mode update of the frozen groups, in place on the model states xm, Pm (N,
    J, ...), from the GNN pairs: track rows, their detections' bearings and variances."""
    n = xm.shape[0]
    zb, zv = per_track(n, rows, det_brg), per_track(n, rows, det_var)
    for g in groups:
        zc, rc, seen = centroid_measurement(zb[g], zv[g])
        if seen:
            common_mode_update(xm, Pm, g, zc, rc)


def centroid_measurement(det_brg: np.ndarray, det_var: np.ndarray) -> tuple[float, float, bool]:
    """Centroid bearing (the circular mean), its variance sum R / n^2 and whether the group
    is measured (GNN gave each of its n tracks a detection), from the bearings det_brg (n,)
    and variances det_var of its tracks' detections (NaN: none)."""
    n = det_brg.size
    zc = float(wrap_2pi(det_brg[0] + np.mean(wrap_pi(det_brg - det_brg[0]))))
    return zc, float(np.sum(det_var)) / n**2, not bool(np.isnan(det_brg).any())


def common_mode_update(xm: np.ndarray, Pm: np.ndarray, group: np.ndarray, zc: float,
                       rc: float) -> bool:
    """Update the model states xm (N, J, n), Pm (N, J, n, n) of every track of the group in
    place with its centroid measurement zc, rc, h_c = [h, ..., h] / n (used if every
    model's centroid innovation passes GATE); returns whether the group was updated."""
    n = group.size
    ph = Pm[group, :, :, 0]  # P h' per track and model (n, J, dim)
    S = ph[..., 0].sum(axis=0) / n**2 + rc  # h_c P h_c' + r_c (J,), no cross-covariance
    ref = xm[group[0], :, 0]
    nu = wrap_pi(zc - (ref + np.mean(wrap_pi(xm[group, :, 0] - ref), axis=0)))
    if not np.all(nu**2 / S <= GATE):
        return False
    K = ph / (n * S[None, :, None])  # gain of each track on the centroid: P_k h' / n S
    xm[group] += K * nu[None, :, None]
    Pm[group] -= K[..., :, None] * ph[..., None, :] / n
    xm[group, :, 0] = wrap_2pi(xm[group, :, 0])
    return True
