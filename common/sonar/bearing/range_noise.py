"""A bearing tracker's TMA hints (issue 31, contacts that pass close): the latest solution
of each track number, used two ways, both for later cycles only:
- the bearing prediction near an approach (common.sonar.bearing.tma_prediction, `predictions`);
- bearing process noise matched to the contact's TMA range (docs/equations.md
  "Range-matched bearing noise", `q_theta`), below.

Choice (stated; 000 has one Q for every track): the straight relative track of a target
at range r with relative velocity v (v_perp across, v_r along the line of sight) has the
bearing acceleration theta'' = -2 v_perp v_r / r^2, so |theta''| <= v^2 / r^2 (2 a b <=
a^2 + b^2). A track given its contact's TMA solution predicts its manoeuvre model with
q_theta + a^2 T, a = v^2 / r_min^2, r_min the least range of the solution over the cycle
(own ship straight between its two positions) and floored at ``r_floor``, a white
acceleration power matching a held over T seconds.

Guard of the noise: it widens the model's covariance only, never moves its mean; a hint is
used for ``max_age`` seconds after its time, and only by the track it was solved for: a
number reopened for a new track drops its hint, and a later hint older than that birth is
refused (the prediction's own guards: tma_prediction).

Data flow: the TMA service solves on the tracker's cycles and registers; its solutions
come back to the tracker as a hint for later cycles only (the tracker never waits for
them), so the loop is a delayed feedback, not a dependency of a cycle on itself.
"""

from __future__ import annotations

import numpy as np

from common.sonar.bearing.tma_prediction import TmaHint, predict

__all__ = ["RangeNoise", "TmaHint"]


class RangeNoise:
    """TMA hints per track number and the bearing noise power they give."""

    def __init__(self, max_age: float = 600.0, r_floor: float = 100.0) -> None:
        self.max_age = max_age
        self.r_floor = r_floor
        self.hints: dict[int, TmaHint] = {}
        self.births: dict[int, float] = {}
        self.own: tuple[float, float, float] | None = None
        self.prev: tuple[float, float, float] | None = None

    def set(self, track: int, hint: TmaHint) -> None:
        """The latest TMA solution of a track number; one older than the number's last
        birth (:meth:`born`) was solved for an earlier track under that number: dropped."""
        if hint.t >= self.births.get(track, -np.inf):
            self.hints[track] = hint

    def born(self, ids: np.ndarray, t: float) -> None:
        """Track numbers ``ids`` (re)opened at t: a reused number drops its hint."""
        for k in np.asarray(ids).tolist():
            self.hints.pop(int(k), None)
            self.births[int(k)] = t

    def cycle(self, t: float, own_x: float, own_y: float) -> None:
        """The own position of the cycle ending at t (call once per cycle, first)."""
        self.prev, self.own = self.own, (t, own_x, own_y)

    def _fresh(self, k: int, t: float) -> TmaHint | None:
        h = self.hints.get(k)
        return h if h is not None and 0.0 <= t - h.t <= self.max_age else None

    def solved(self, ids: np.ndarray) -> np.ndarray:
        """(N,) bool: the tracks ``ids`` with a fresh converged hint at the cycle's time."""
        t = self.own[0] if self.own is not None else 0.0
        return np.array([(h := self._fresh(int(k), t)) is not None and h.converged
                         for k in np.asarray(ids).tolist()], dtype=bool)

    def predictions(self, ids: np.ndarray, x0: np.ndarray, P0: np.ndarray, x1: np.ndarray, P1: np.ndarray
                    ) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        """The tracks ``ids`` (N,) predicted with their hints (common.sonar.bearing.tma_prediction):
        their positions k (K,) in ids, [theta, theta'] (K, 2), covariances (K, 2, 2) and
        linearised bearing transitions (K, 2, 2); x0, P0: [theta, theta'] of the previous
        cycle, x1, P1: the model's prediction (with Q)."""
        pos: list[int] = []
        out: list[tuple[np.ndarray, np.ndarray, np.ndarray]] = []
        if self.prev is not None and self.own is not None and self.hints and self.own[0] > self.prev[0]:
            (t0, ox0, oy0), (t, ox, oy) = self.prev, self.own
            for i, k in enumerate(np.asarray(ids).tolist()):
                h = self._fresh(int(k), t)
                o = None if h is None else predict(h, t0, np.array([ox0, oy0]), t, np.array([ox, oy]),
                                                   x0[i], P0[i], x1[i], P1[i])
                if o is not None:
                    pos.append(i)
                    out.append(o)
        if not pos:
            return np.zeros(0, np.intp), np.zeros((0, 2)), np.zeros((0, 2, 2)), np.zeros((0, 2, 2))
        m, C, F = (np.asarray(a) for a in zip(*out))
        return np.asarray(pos, np.intp), m, C, F

    def q_theta(self, ids: np.ndarray, q: float) -> np.ndarray:
        """Bearing noise power (N,) of the tracks ``ids`` for the cycle of :meth:`cycle`: q,
        raised by a^2 T for those with a fresh usable hint."""
        out = np.full(len(ids), q)
        prev = self.prev
        if prev is None or self.own is None or not self.hints or self.own[0] <= prev[0]:
            return out
        t, own_x, own_y = self.own
        t0, ox0, oy0 = prev
        T = t - t0
        for i, k in enumerate(np.asarray(ids).tolist()):
            h = self._fresh(int(k), t)
            if h is not None and h.usable:
                a = self._acceleration(h, t0, np.array([ox0, oy0]), t, np.array([own_x, own_y]))
                out[i] = q + a * a * T
        return out

    def _acceleration(self, h: TmaHint, t0: float, o0: np.ndarray, t: float, o1: np.ndarray) -> float:
        """a = v^2 / r_min^2 of the hint over the cycle t0 -> t (own ship straight between o0, o1)."""
        T = t - t0
        d0 = np.array([h.x + h.vx * (t0 - h.t), h.y + h.vy * (t0 - h.t)]) - o0
        d1 = np.array([h.x + h.vx * (t - h.t), h.y + h.vy * (t - h.t)]) - o1
        v = (d1 - d0) / T
        s = float(np.clip(-(d0 @ v) / max(float(v @ v), 1e-12), 0.0, T))  # closest time in the cycle
        r = max(float(np.hypot(*(d0 + v * s))), self.r_floor)
        return float(v @ v) / r**2  # |theta''| <= v^2 / r^2

    def forget(self, keep: np.ndarray) -> None:
        """Drop the hints of track numbers not in ``keep``."""
        live = set(np.asarray(keep).tolist())
        self.hints = {k: h for k, h in self.hints.items() if k in live}
        self.births = {k: b for k, b in self.births.items() if k in live}
