"""Track merging of seed 000 (second embodiment, "d_merge"), used by the single-hypothesis
bearing tracker too: a tentative track statistically indistinguishable from a confirmed
track is the same target seen twice, and the newer one is dropped.

Test: d^2 = (x_t - x_c)' (P_t + P_c)^-1 (x_t - x_c) <= d_merge over the whole state
(bearing wrapped, bearing rate, level, level rate [, frequency, frequency rate]), 000's
d_{i1,i2}^2, the distance of two independent estimates of one state. The rates count: at
a crossing the second target's young track lies within the confirmed track's bearing
sigmas but its bearing rate has the other sign (a distance over the measurement
components only, as first written, dropped that track on sonar_cross_4dpm_eq seed 33,
and the target had no track through the crossing). Deviation (stated): the seed merges
hypotheses of its multiple-hypothesis tracks; here a whole single-hypothesis tentative track is merged
into (dropped in favour of) the confirmed one, whose state is kept unchanged. Without it
a tentative track opened by a detection just outside a lagging confirmed track's gate
(own-ship turn, young track) takes part of the target's detections by GNN, confirms,
and replaces the older track or makes a second confirmed track on the target
(benchmarks/sonar_hold.py: sonar_hold5, the North crossing during the turn).
"""

from __future__ import annotations

import numpy as np

from common.core.gating import pair_distances


def merged_tentative(
    x: np.ndarray, P: np.ndarray, confirmed: np.ndarray, d_merge: float
) -> np.ndarray:
    """Mask (N,) of the tentative tracks (~confirmed) within d_merge of a confirmed track,
    for tracks x (N, n), P (N, n, n) at one time (bearing first)."""
    out = np.zeros(x.shape[0], dtype=bool)
    tent, conf = np.flatnonzero(~confirmed), np.flatnonzero(confirmed)
    if tent.size == 0 or conf.size == 0:
        return out
    t = np.repeat(np.arange(tent.size), conf.size)
    c = np.tile(np.arange(conf.size), tent.size)
    _, _, d2 = pair_distances(x[tent], P[tent], x[conf], P[conf], t, c, angle_idx=[0])
    out[tent] = (d2.reshape(tent.size, conf.size) <= d_merge).any(axis=1)  # 000 d_merge
    return out
