"""Per-base clock offsets of an unsynchronised network (issue 29, docs/networks.md).

A base whose stamps are c_b late reports at stamp t the range of true time t - c_b:
r_b(t - c_b) = r_b(t) - v_b c_b to first order (001 [1], [2]). Each c_b is a slowly
varying bias (random walk of power `clock_drift`, prior N(0, clock_sigma^2)) estimated
by a scalar Kalman filter from the range innovations of confirmed tracks,

    y_r,i = -v_b,i (c_b - c^_b) + e_i,   var e_i = (H P~ H' + R)_rr                [C1]
    c^_b += V sum_i (-v_b,i y_r,i / S_i),  V = 1 / (1 / V + sum_i v_b,i^2 / S_i)     [C2]

(information form of the Kalman update for a batch of independent scalar
measurements), and applied to the base's reports as a shift of their time to first
order, with the estimate's own uncertainty:

    r_b += v_b c^_b,   R_rr += v_b^2 V                                            [C3]

A common offset of every base is a shift of the network's time: unobservable from the
ranges; the tracks then run in a time frame shifted by it (they move along their own
path). Bases declared as references (clocks trusted, e.g. GPS-disciplined) keep c_b = 0
and V_b = 0: they anchor that common part. Without a reference, the mean of the
estimates is that common part, which the per-base filters move at random (each takes
the tracks, made of the other bases, as its reference), and the network's time is
anchored to the mean of its clocks instead: [C3] applies

    c^_b - mean_k c^_k                                                           [C4]

so that the applied offsets have mean 0 (docs/decisions/024-network-altitude.md).
"""

from __future__ import annotations

import numpy as np


class Clocks:
    """Per base: offset estimate c (B,) s, its variance V (B,) s^2, time of its last
    update t (B,); reference (B,) the bases whose clocks are trusted (never estimated)."""

    def __init__(self, n_bases: int, sigma: float, drift: float,
                 reference: np.ndarray | None = None) -> None:
        self.reference = np.zeros(n_bases, dtype=bool) if reference is None else reference
        self.c = np.zeros(n_bases)
        self.V = np.where(self.reference, 0.0, sigma ** 2)
        self.t = np.full(n_bases, np.nan)
        self.drift = drift
        self.floor = np.where(self.reference, 0.0, sigma ** 2)

    def correct(self, b: int, z: np.ndarray, R: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """[C3] on z (N, m) [r_b, v_b, ...] and R (N, m, m) of base b; copies."""
        z, R = z.copy(), R.copy()
        z[:, 0] += z[:, 1] * self.applied(b)
        R[:, 0, 0] += z[:, 1] ** 2 * max(self.V[b], self.floor[b])
        return z, R

    def applied(self, b: int) -> float:
        """The offset [C3] applies to base b: c^_b, less the mean of the estimates when
        no base is a reference [C4]."""
        if self.reference.any():
            return float(self.c[b])
        return float(self.c[b] - self.c.mean())

    def update(self, b: int, t: float, v: np.ndarray, y: np.ndarray, S: np.ndarray) -> None:
        """[C1]-[C2] at t from range rates v (K,), range innovations y (K,) of corrected
        measurements and their variances S (K,) without the clock term. A reference
        base is not updated."""
        if self.reference[b]:
            return
        if np.isfinite(self.t[b]):
            self.V[b] += self.drift * max(t - self.t[b], 0.0)
        self.t[b] = t
        if v.size == 0:
            return
        info = 1.0 / self.V[b] + np.sum(v ** 2 / S)
        self.c[b] += np.sum(-v * y / S) / info
        self.V[b] = 1.0 / info
