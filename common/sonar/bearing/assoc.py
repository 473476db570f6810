"""Gated global-nearest-neighbour association of the single-hypothesis bearing tracker
(000 d^2, gate G, GNN), with the detection probability of each track from its predicted
amplitude and the false-alarm probability of each detection from its level.

The mask of detections inside a confirmed track's gate implements 000 "medidas superfluas
... el inicio de una nueva traza": such a detection that lost the GNN assignment opens no
track. Deviation from "every unassociated detection": otherwise a clutter detection next
to a target opens a duplicate track that takes the target over (seen on sonar_tma). For
the same reason the confirmed tracks are served first: GNN over the confirmed tracks, then
GNN of the tentative tracks over the detections no confirmed track took (a duplicate
beside a lagging confirmed track loses the target's detection to it). A detection inside
a confirmed gate that the confirmed track did not take (it took a nearer one) stays open
to a tentative track: a second target's young track keeps its detections while it
approaches a confirmed track (once such detections were barred from tentative tracks,
sonar_cross_4dpm_eq seed 33 lost its second target: its tentative track starved 3 deg
from the confirmed one, and the target had no track until the two were 4 deg apart again).
A bearing-only pre-gate d_brg^2 <= G_max keeps the full computation to the plausible
pairs and loses none (the marginal d^2 never exceeds the full one, |S| >= |R| and
P_D <= P_D_max bound G from above).
"""

from __future__ import annotations

import numpy as np

from common.core.angles import wrap_pi
from common.core.assignment import gnn
from common.core.gating import gate, pair_distances
from common.sonar.bearing.model import gate_value


def associate(
    x: np.ndarray, P: np.ndarray, H: np.ndarray, z: np.ndarray, Rd: np.ndarray,
    confirmed: np.ndarray, p_d: np.ndarray, p_d_max: float, p_fa: np.ndarray, beam: float,
) -> tuple[np.ndarray, ...]:
    """Predicted tracks x (N, n), P, their confirmed mask and P_D (N,); detections z
    (M, m) with diagonal R (M, m) and P_FA (M,) -> assigned track rows, detection cols,
    innovations y, |S| and d^2 of the pairs, and the mask (M,) of detections inside the
    gate of a confirmed track."""
    N, (M, m) = x.shape[0], z.shape
    empty = np.zeros(0, dtype=np.intp)
    gated = np.zeros(M, dtype=bool)
    if N == 0 or M == 0:
        return empty, empty, np.zeros((0, m)), np.zeros(0), np.zeros(0), gated
    zp = x @ H.T
    A = H @ P @ H.T  # H P^pre H'
    yb = wrap_pi(z[None, :, 0] - zp[:, None, 0])
    d2b = yb**2 / (A[:, 0, 0, None] + Rd[None, :, 0])
    G_max = gate_value(p_d_max, p_fa, beam, np.prod(Rd, axis=1), m)
    ti, dj = np.nonzero(d2b <= G_max[None, :])
    y, S, d2 = pair_distances(zp, A, z, Rd, ti, dj, angle_idx=(0,))  # 000 y, S, d_1^2
    detS = np.linalg.det(S)
    ok = gate(d2, gate_value(p_d[ti], p_fa[dj], beam, detS, m))  # 000 gate G
    ti, dj, y, d2, detS = ti[ok], dj[ok], y[ok], d2[ok], detS[ok]
    conf = confirmed[ti]
    gated[dj[conf]] = True
    cost = np.full((N, M), np.inf)
    cost[ti, dj] = d2
    pair = np.full((N, M), -1, dtype=np.intp)
    pair[ti, dj] = np.arange(ti.size)
    rows, cols = gnn(np.where(confirmed[:, None], cost, np.inf))  # 000 GNN on d^2, confirmed first
    rest = np.where(confirmed[:, None], np.inf, cost)
    rest[:, cols] = np.inf  # the tentative tracks: the detections no confirmed track took
    r2, c2 = gnn(rest)
    rows, cols = np.r_[rows, r2].astype(np.intp), np.r_[cols, c2].astype(np.intp)
    k = pair[rows, cols]
    return rows, cols, y[k], detS[k], d2[k], gated
