"""Track segment association: a confirmed global track whose elementary tracks all ended
is continued by the track confirmed after it on the same aircraft (complement of 001
module 61, stated; Yeom, Kirubarajan, Bar-Shalom, "Track segment association, fine-step
IMM and initialization with Doppler for improved track performance", IEEE TAES 40(1),
2004).

001 keeps a global track without contributors in pure prediction until deletion. When
every base loses the aircraft at once (a turn's onset: the elementary trackers' one
motion model [19]-[20] gates the plots out; a pass near the receiver, whose azimuth is
common to all bases), new elementary tracks start a new global track, confirmed under a
new number while the old one still coasts, often far outside a gate on the two
covariances alone (a turn is not in the straight prediction), inside it with the
envelope below.

Test, for an old segment o (confirmed, no member, coasting for tau seconds since its
last update) and a new one n (confirmed this cycle, born after o's last update):
    d = x_n - x_o(t),   S = P_n + P_o(t) + M(tau),   d' S^-1 d <= chi-square(6, gate)
where x_o(t), P_o(t) is o's prediction to the cycle and M(tau) the envelope of an unknown
constant plan acceleration of standard deviation `accel` per axis held since the last
update: per plan axis the covariance of (a tau^2 / 2, a tau),
    accel^2 [[tau^4/4, tau^3/2], [tau^3/2, tau^2]]
(a turn is a sustained acceleration, which the white-noise models of [51] and the IMM
understate over a coast: their position variance grows as q tau^3 / 3). The vertical is
left to the tracks' covariances (aircraft climb and descend gently; the altitude is the
weakest coordinate of both). A pair is taken only when it is unique both ways (o gates
no other new track, n no other old segment) and n was born after o's last update (two
segments of one aircraft do not overlap in time; overlapping tracks are
common.radar.fusion.merge's duplicates). The new track then takes o's number and birth
time, and o's coasting state is dropped (common.radar.fusion.succession).

The case behind the rule, the continuations and switches with and without it, and the
command that gives them: docs/decisions/004-track-segment-association.md.
"""

from __future__ import annotations

import numpy as np

from common.core.gating import quadratic_form

PLAN_AXES = ((0, 1), (2, 3))  # (position, velocity) of x and y in [x vx y vy z vz]


def manoeuvre_envelope(tau: np.ndarray, accel: float) -> np.ndarray:
    """M(tau) (n, 6, 6) of the module doc for coasts of tau (n,) seconds."""
    M = np.zeros((tau.size, 6, 6))
    block = accel**2 * np.stack([np.stack([tau**4 / 4, tau**3 / 2], -1),
                                 np.stack([tau**3 / 2, tau**2], -1)], -2)
    for p, v in PLAN_AXES:
        M[:, [[p], [v]], [p, v]] = block
    return M


def segment_pairs(x_old: np.ndarray, P_old: np.ndarray, tau: np.ndarray, x_new: np.ndarray,
                  P_new: np.ndarray, accel: float, gate: float) -> tuple[np.ndarray, np.ndarray]:
    """Indices (i into the old segments, j into the new) of the pairs that pass the
    module doc's test and are unique both ways."""
    if x_old.shape[0] == 0 or x_new.shape[0] == 0:
        return np.zeros(0, dtype=np.intp), np.zeros(0, dtype=np.intp)
    d = x_new[None, :, :] - x_old[:, None, :]
    S = P_new[None] + (P_old + manoeuvre_envelope(tau, accel))[:, None]
    d2 = quadratic_form(d, S)
    ok = d2 <= gate
    ok &= (ok.sum(axis=1, keepdims=True) == 1) & (ok.sum(axis=0, keepdims=True) == 1)
    return np.nonzero(ok)
