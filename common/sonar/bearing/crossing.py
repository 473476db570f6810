"""Seed 004 crossing management on the bearing tracks of one array (step 4 of
common.sonar.bearing.tracker): gain weights alpha and ambiguity flags from the
CrossingManager on the confirmed tracks' predicted bearings (and frequencies), and the
detection a track leaving the ambiguity may keep.

Deviations (stated): tentative tracks are left out (alpha = 1, not ambiguous): a
clutter track next to a confirmed track would otherwise freeze it in memory mode; the
re-acquisition rule of `BearingCrossing.exit_pairs` is not in 004; nor are the rules on
pairs of frozen tracks (release, centroid) of common.sonar.bearing.pairs.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import replace

import numpy as np

from common.core.crossing import CrossingManager, CrossingParams, wrapped_diff


class BearingCrossing:
    """Seed 004 for one bearing tracker with measurement matrix H (z = [brg, amp] or
    [brg, amp, freq]); the crossing components are the bearing, and the frequency in
    narrowband."""

    def __init__(self, params: CrossingParams, H: np.ndarray,
                 band_hz: list[float] | None = None) -> None:
        """band_hz: the narrowband frequency band (None: broadband)."""
        self.H = H
        self.dims = [0, 2] if band_hz is not None else [0]
        if band_hz is not None:  # seed 004 c: volume of the (bearing, frequency) space
            params = replace(params, volume=2.0 * math.pi * (band_hz[1] - band_hz[0]))
        self.manager = CrossingManager(params)
        self.memory = params.mode == "memory"  # 004 claim 5: alpha = 0 while ambiguous
        self.groups = np.empty(0, dtype=np.intp)  # ambiguity group labels of the last `gains`

    def gains(
        self, t: float, ids: np.ndarray, confirmed: np.ndarray, x: np.ndarray, z: np.ndarray,
        rows: np.ndarray, cols: np.ndarray, R_diag: Callable[[np.ndarray], np.ndarray],
        n_det: int,
    ) -> tuple[np.ndarray, np.ndarray]:
        """Alpha (N,) gain weights and ambiguity flags of the N predicted tracks x (ids,
        confirmed mask) given the GNN pairs (rows, cols) into the detections z; R_diag
        maps predicted measurements (K, m) to the diagonals of their R (K, m)."""
        N = ids.size
        alpha, amb = np.ones(N), np.zeros(N, dtype=bool)
        self.groups = -1 - np.arange(N)  # a tentative track is alone
        conf = np.flatnonzero(confirmed)
        if conf.size == 0:
            return alpha, amb
        dims = self.dims
        zp = x[conf] @ self.H.T
        cov = R_diag(zp)[:, dims, None] * np.eye(len(dims))  # 004: g is the measurement noise density
        zm = np.full((N, self.H.shape[0]), np.nan)
        zm[rows] = z[cols]
        a, f = self.manager.step(t, ids[conf], zp[:, dims], cov, zm[conf][:, dims], n_det,
                                 angle_idx=[0])
        alpha[conf], amb[conf] = a, f
        self.groups[conf] = self.manager.groups
        return alpha, amb

    def exit_pairs(
        self, confirmed: np.ndarray, was_ambiguous: np.ndarray, ambiguous: np.ndarray,
        x: np.ndarray, z: np.ndarray, Rd: np.ndarray, rows: np.ndarray, cols: np.ndarray,
    ) -> np.ndarray:
        """Mask (K,) of the GNN pairs kept for the update. A confirmed track that leaves
        the ambiguity at this scan (flagged at the previous cycle, not now: the end of
        the memory mode of 004 claim 5, or claim 6) keeps its detection only if no
        other confirmed track's prediction is nearer to it, in the measurement noise
        metric of 004 g on the crossing components; otherwise the scan is a miss for it
        (no update, dL = ln(1 - P_D)); the detection still opens no track, it lies in a
        confirmed gate.
        Deviation (not in 004, which leaves the re-acquisition to the tracker): the
        track's P has grown by Q over the whole memory mode, so its gate is wide and
        its first gain near one; with a missed detection of its own target (P_D < 1)
        GNN hands it the other target's detection (or a clutter detection nearer the
        other track), which moves it onto the other target in one update. Seen on
        sonar_cross_1dpm_uneq (both tracks on the weak target, the strong one lost)."""
        keep = np.ones(rows.size, dtype=bool)
        if rows.size == 0:
            return keep
        leaving = confirmed[rows] & was_ambiguous[rows] & ~ambiguous[rows]
        if not leaving.any():
            return keep
        dims = self.dims
        zp = (x[confirmed] @ self.H.T)[:, dims]
        pos = np.flatnonzero(confirmed)
        k = np.flatnonzero(leaving)
        diff = wrapped_diff(z[cols[k]][:, None, dims], zp[None, :, :], [0])
        dist = np.sum(diff**2 / Rd[cols[k]][:, None, dims], axis=2)  # (k, confirmed)
        keep[k] = pos[np.argmin(dist, axis=1)] == rows[k]
        return keep

    def forget(self, ids: np.ndarray) -> None:
        """Deleted tracks leave the crossing state."""
        self.manager.forget(ids)
