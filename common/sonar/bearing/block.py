"""004's block estimator (common.core.block_estimator, eq. 6-10) on the confirmed bearing
tracks of one array while 004 flags them ambiguous (step 5b of
common.sonar.bearing.tracker, `[sonar.tracker] block_estimator`).

How it combines with the memory mode (004 claim 5): the memory mode keeps the Kalman
filter from taking the crossing's mixed detections, and its frozen extrapolations are
the lines the estimator needs from the previous block; the estimator takes the mixed
detections, weighted by eq. 10, and gives the line the filter resumes from. An episode
opens when a confirmed track's flag rises, with the track's own register rows of the last
`window_s` seconds as its first points (weight 1 / r^k: eq. 8, the track was not
ambiguous then). At every scan of the episode (blocks of N = 1 scan) the detections
within GATE sigma of the track's prediction are its points X_n, each with 1 / den_n of
eq. 10 computed then, from the proportions q^j of 004's counts and the predictions of the
other confirmed tracks that eq. 7 does not separate from it over the episode. When the
flag clears (or 004 claim 6 ends it) the track's bearing and rate (every IMM model's)
become the line at t, with the covariance `line_covariance` gives, if the fit converged
on at least MIN_POINTS points (and points worth MIN_POINTS by their share); otherwise the
Kalman state stays.
Deviations: the lines of block l - 1 (the neighbours' in den, the start of the ascent)
are the tracker's predictions, 004's memory-mode extrapolations, not the estimator's own
(with its own lines, two tracks in one episode drew each other onto one line between the
contacts: tests/sonar/test_bearing_block.py's scene); q^k is 004's smoothed count of the
track's associated detections (not the proportion `share` assigns); the pre-episode
points are the register's, not every detection; only the bearing is fitted (the level
keeps the Kalman estimate).
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from common.core.angles import wrap_pi
from common.core.block_estimator import Line, line_covariance, maximise, separated, share, weights
from common.core.crossing import CUTOFF_RADIUS

GATE = 4.0  # points within 4 sigma (detection and prediction) of a track's prediction
MIN_POINTS = 6
NEAR = np.radians(20.0)  # neighbours farther in bearing than this are not tested by eq. 7


@dataclass
class Episode:
    """One ambiguity episode of a track: its start time and points (t, X, var, 1 / den)."""

    t0: float
    t: list[np.ndarray] = field(default_factory=list)
    X: list[np.ndarray] = field(default_factory=list)
    var: list[np.ndarray] = field(default_factory=list)
    w: list[np.ndarray] = field(default_factory=list)

    def points(self) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        """(t, X (P, 1), cov (P, 1, 1), w) of every point so far (P may be 0)."""
        v = np.concatenate([np.zeros(0), *self.var])
        return (np.concatenate([np.zeros(0), *self.t]), np.concatenate([np.zeros(0), *self.X])[:, None],
                v[:, None, None], np.concatenate([np.zeros(0), *self.w]))


@dataclass(frozen=True)
class Exit:
    """The line of a track leaving its episode at t: bearing, rate and their covariance."""

    uid: int
    brg: float
    rate: float
    cov: np.ndarray


class CrossingBlocks:
    """Episodes of 004's block estimator, keyed by track uid (see module docstring)."""

    def __init__(self, volume: float, window_s: float) -> None:
        self.volume, self.window_s = volume, window_s
        self.episodes: dict[int, Episode] = {}
        self.last: list[Exit] = []  # the exits of the latest scan

    @staticmethod
    def _lines(x: np.ndarray, t: float) -> list[Line]:
        """Each track's line at t from the tracker: its Kalman bearing and rate (in 004's
        memory mode, the extrapolation of the state it entered with)."""
        return [Line(xk[1:2].copy(), xk[0:1].copy(), t) for xk in x]

    def _neighbours(self, k: int, lines: list[Line], conf: np.ndarray, x: np.ndarray,
                    t0: float, t: float, var: float) -> np.ndarray:
        """Rows j != k of confirmed tracks whose lines eq. 7 does not separate from k's over
        [t0, t] (threshold CUTOFF_RADIUS^2 in the metric of the detection noise)."""
        near = np.flatnonzero(conf & (np.abs(wrap_pi(x[:, 0] - x[k, 0])) < NEAR))
        near = near[near != k]
        # the lines of the tracks at t (x): their values at t0 by their rates
        C0 = x[near, 0:1] - x[near, 1:2] * (t - t0)
        sep = separated(lines[k], x[near, 1:2], C0, t0, t, np.array([[var]]), CUTOFF_RADIUS**2, [0])
        return near[~sep]

    def step(self, t: float, uids: np.ndarray, conf: np.ndarray, flagged: np.ndarray,
             x: np.ndarray, P: np.ndarray, q: np.ndarray, z_brg: np.ndarray, z_var: np.ndarray,
             history: dict[int, tuple[np.ndarray, np.ndarray, np.ndarray]]) -> list[Exit]:
        """One scan: tracks uids (N,) with confirmed mask, 004 flags, states x, P, proportions
        q; detections (bearing, variance); history: uid -> (t, brg, sbrg) register rows of
        the tracks whose flag rose. Returns the tracks leaving their episode with a line."""
        live = set(uids.tolist())
        for u in [u for u in self.episodes if u not in live]:
            del self.episodes[u]
        for k in np.flatnonzero(conf & flagged):
            u = int(uids[k])
            if u not in self.episodes:
                self.episodes[u] = self._open(t, float(q[k]), history.get(u))
        lines = self._lines(x, t)
        exits = []
        for k in [int(k) for k in range(uids.size) if int(uids[k]) in self.episodes]:
            u = int(uids[k])
            e = self.episodes[u]
            self._add_points(e, k, t, lines, conf, x, P, q, z_brg, z_var)
            if conf[k] and flagged[k]:
                continue
            ex = self._exit(u, e, lines[k], t, float(q[k]))
            if ex is not None:
                exits.append(ex)
            del self.episodes[u]
        self.last = exits
        return exits

    def _open(self, t: float, qk: float,
              rows: tuple[np.ndarray, np.ndarray, np.ndarray] | None) -> Episode:
        """A new episode with the register's last window_s seconds as its first points."""
        e = Episode(t)
        if rows is not None:
            tr, br, sr = rows
            keep = (tr >= t - self.window_s) & (tr < t)
            r = (1.0 - qk) / self.volume
            e.t.append(tr[keep])
            e.X.append(br[keep])
            e.var.append(sr[keep] ** 2)
            e.w.append(np.full(int(keep.sum()), 1.0 / r))  # eq. 8 before the episode
        return e

    def _add_points(self, e: Episode, k: int, t: float, lines: list[Line], conf: np.ndarray,
                    x: np.ndarray, P: np.ndarray, q: np.ndarray, z_brg: np.ndarray,
                    z_var: np.ndarray) -> None:
        """The scan's detections within GATE sigma of the track's prediction (its
        variance and theirs), with 1 / den of eq. 10."""
        near = np.abs(wrap_pi(z_brg - x[k, 0])) <= GATE * np.sqrt(z_var + P[k, 0, 0])
        if not near.any():
            return
        X, var = z_brg[near], z_var[near]
        tt = np.full(X.size, t)
        t0 = e.t0 - self.window_s
        nb = self._neighbours(k, lines, conf, x, t0, t, float(np.median(var)))
        r = (1.0 - float(q[k])) / self.volume
        w = weights(X[:, None], tt, var[:, None, None], r, q[nb], [lines[j] for j in nb.tolist()], [0])
        e.t.append(tt)
        e.X.append(X)
        e.var.append(var)
        e.w.append(w)

    def _exit(self, u: int, e: Episode, start: Line, t: float, qk: float) -> Exit | None:
        """The line at t with the covariance of (bearing, rate), or None without a fit:
        the local maximum of eq. 10 reached from the tracker's prediction `start`."""
        tp, X, cov, w = e.points()
        if tp.size < MIN_POINTS:
            return None
        line, ok = maximise(X, tp, cov, w, start, [0])
        if not ok:
            return None
        p = share(X, tp, cov, w, qk, line, [0])
        if p.sum() < MIN_POINTS:
            return None
        C = line_covariance(tp, cov, p, line.t_ref)  # [A, B]
        J = np.array([[t - line.t_ref, 1.0], [1.0, 0.0]])  # [brg(t), rate] = J [A, B]
        return Exit(u, float(line.at(np.array([t]))[0, 0]), float(line.A[0]), J @ C @ J.T)
