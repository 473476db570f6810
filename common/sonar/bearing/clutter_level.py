"""Online estimate of the false detections' mean level above the threshold, the parameter
of 000's level-based P_FA (`common.sonar.bearing.model.false_alarm_probability`).

For levels a = D_thr + e with e exponential of mean mu, the maximum-likelihood estimate
of mu from n excesses is their mean, sum(e) / n. Here the sums are exponentially weighted
over cycles (forgetting factor lam = 1 - 1 / window per cycle):
S(k) = lam S(k-1) + sum(e_k), n(k) = lam n(k-1) + n_k, mu(k) = S(k) / n(k), bounded to
[lo, hi] and seeded by a prior worth `PRIOR_WEIGHT` detections. The detections that a
confirmed track took are left out of e_k, so a contact's own detections do not raise it.
Those a tentative track took stay in: tentative tracks are mostly born of clutter, and
with the level-based P_FA they take the strong false detections first, so leaving them
out biases the estimate low (tests/sonar/test_clutter_level.py,
docs/decisions/029-sonar-clutter-estimate.md).
"""

from __future__ import annotations

import numpy as np

PRIOR_WEIGHT = 10.0  # the prior counts as this many false detections


class ClutterLevel:
    """Exponentially weighted mean excess (dB) of the untaken detections' levels over D_thr."""

    def __init__(self, prior_db: float, window: float, bounds_db: tuple[float, float]) -> None:
        self.lam = 1.0 - 1.0 / window
        self.lo, self.hi = bounds_db
        self.n = PRIOR_WEIGHT
        self.s = prior_db * PRIOR_WEIGHT

    @property
    def value(self) -> float:
        """mu(k) = S(k) / n(k), bounded to [lo, hi] (dB)."""
        return float(np.clip(self.s / self.n, self.lo, self.hi))

    def update(self, level: np.ndarray, d_thr: float) -> None:
        """One cycle's untaken detection levels (dB): e = max(a - D_thr, 0) into S and n."""
        e = np.maximum(np.asarray(level, dtype=float) - d_thr, 0.0)
        self.s = self.lam * self.s + float(e.sum())
        self.n = self.lam * self.n + e.size
