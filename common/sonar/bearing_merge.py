"""Track merging of seed 000 (second embodiment, "d_merge"), used by the single-hypothesis
bearing tracker too: a tentative track statistically indistinguishable from a confirmed
track is the same target seen twice, and the newer one is dropped.

Test: d^2 = (H x_t - H x_c)' (H P_t H' + H P_c H')^-1 (H x_t - H x_c) <= d_merge over the
measurement components (bearing wrapped, level [, frequency]), the distance of two
independent estimates of one state. Deviation (stated): the seed merges hypotheses of
its multiple-hypothesis tracks; here a whole single-hypothesis tentative track is merged
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
    x: np.ndarray, P: np.ndarray, H: np.ndarray, confirmed: np.ndarray, d_merge: float
) -> np.ndarray:
    """Mask (N,) of the tentative tracks (~confirmed) within d_merge of a confirmed track,
    for tracks x (N, n), P (N, n, n) at one time."""
    out = np.zeros(x.shape[0], dtype=bool)
    tent, conf = np.flatnonzero(~confirmed), np.flatnonzero(confirmed)
    if tent.size == 0 or conf.size == 0:
        return out
    z = x @ H.T
    A = H @ P @ H.T
    t = np.repeat(np.arange(tent.size), conf.size)
    c = np.tile(np.arange(conf.size), tent.size)
    _, _, d2 = pair_distances(z[tent], A[tent], z[conf], A[conf], t, c, angle_idx=[0])
    out[tent] = (d2.reshape(tent.size, conf.size) <= d_merge).any(axis=1)  # 000 d_merge
    return out
