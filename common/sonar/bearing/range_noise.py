"""Bearing process noise matched to a contact's TMA range (issue 31, contacts that pass close;
docs/equations.md "Range-matched bearing noise").

Choice (stated; 000 has one Q for every track): the straight relative track of a target
at range r with relative velocity v (v_perp across, v_r along the line of sight) has the
bearing acceleration theta'' = -2 v_perp v_r / r^2, so |theta''| <= v^2 / r^2 (2 a b <=
a^2 + b^2). A track given its contact's TMA solution predicts its manoeuvre model with
q_theta + a^2 T, a = v^2 / r_min^2, r_min the least range of the solution over the cycle
(own ship straight between its two positions) and floored at ``r_floor``, a white
acceleration power matching a held over T seconds.

Guard: the solution widens the prediction's covariance only, never moves its mean, so a
wrong or stale solution cannot pull the track onto another bearing; it is used for
``max_age`` seconds after its time, and only by the track number it was solved for.

Data flow: the TMA service solves on the tracker's cycles and registers; its solutions
come back to the tracker as a hint for later cycles only (the tracker never waits for
them), so the loop is a delayed feedback, not a dependency of a cycle on itself.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np


@dataclass(frozen=True)
class TmaHint:
    """A contact's TMA solution as the tracker uses it: time, position, velocity (ENU m, m/s),
    and whether its range is usable (the solve converged and the range is observable)."""

    t: float
    x: float
    y: float
    vx: float
    vy: float
    usable: bool = True


class RangeNoise:
    """TMA hints per track number and the bearing noise power they give."""

    def __init__(self, max_age: float = 600.0, r_floor: float = 100.0) -> None:
        self.max_age = max_age
        self.r_floor = r_floor
        self.hints: dict[int, TmaHint] = {}
        self.own: tuple[float, float, float] | None = None

    def set(self, track: int, hint: TmaHint) -> None:
        """The latest TMA solution of a track number."""
        self.hints[track] = hint

    def q_theta(self, ids: np.ndarray, q: float, t: float, own_x: float, own_y: float) -> np.ndarray:
        """Bearing noise power (N,) of the tracks ``ids`` for the cycle ending at t: q, raised
        by a^2 T for those with a fresh hint. Call once per cycle (it keeps the own position)."""
        out = np.full(len(ids), q)
        prev, self.own = self.own, (t, own_x, own_y)
        if prev is None or not self.hints or t <= prev[0]:
            return out
        t0, ox0, oy0 = prev
        T = t - t0
        for i, k in enumerate(np.asarray(ids).tolist()):
            h = self.hints.get(int(k))
            if h is None or not h.usable or not 0.0 <= t - h.t <= self.max_age:
                continue
            d0 = np.array([h.x + h.vx * (t0 - h.t) - ox0, h.y + h.vy * (t0 - h.t) - oy0])
            d1 = np.array([h.x + h.vx * (t - h.t) - own_x, h.y + h.vy * (t - h.t) - own_y])
            v = (d1 - d0) / T
            s = float(np.clip(-(d0 @ v) / max(float(v @ v), 1e-12), 0.0, T))  # closest time in the cycle
            r = max(float(np.hypot(*(d0 + v * s))), self.r_floor)
            a = float(v @ v) / r**2  # |theta''| <= v^2 / r^2
            out[i] = q + a * a * T
        return out

    def forget(self, keep: np.ndarray) -> None:
        """Drop the hints of track numbers not in ``keep``."""
        live = set(np.asarray(keep).tolist())
        self.hints = {k: h for k, h in self.hints.items() if k in live}
