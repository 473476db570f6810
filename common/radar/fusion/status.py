"""Reported status of the global tracks (001 module 61: tentative, confirmed, coasting =
maintained in pure prediction mode).

001 puts a global track in pure prediction when it has no contributing elementary track.
Complement (stated): a confirmed track whose contributing elementary tracks were all
reported but none updated at its base (each in pure prediction, e.g. the target has
left) for `coast_cycles` consecutive cycles is reported coasting too; it is confirmed
again at the next cycle with an updated contributor.

Why: an elementary track coasts up to 5 scans ([radar.tracker] max_coast) after its
target left, and the global track was reported confirmed all that time: a large share
of the false track-scans of a dense scene. One cycle (coast_cycles 1) would also report
the present targets that every base missed in one scan ((1 - Pd)^k for k bases: 2 % at
Pd 0.85, k = 2); two consecutive cycles ((1 - Pd)^2k) make that rare. Figures and the
command: docs/decisions/005-coasting-status.md.
"""

from __future__ import annotations

import numpy as np

from common.core.track_table import Status


def quiet_cycles(n_quiet: np.ndarray, contributed: np.ndarray) -> np.ndarray:
    """Consecutive cycles without any updated contributing elementary track."""
    return np.where(contributed, 0, n_quiet + 1)


def reported_status(confirmed: np.ndarray, reporting: np.ndarray, new: np.ndarray,
                    n_quiet: np.ndarray, coast_cycles: int) -> np.ndarray:
    """Status of each track: coasting without a reported contributor (001) or after
    `coast_cycles` quiet cycles (module doc); else confirmed or tentative. A new track
    is never coasting."""
    coast = (~reporting | (confirmed & (n_quiet >= coast_cycles))) & ~new
    return np.where(coast, Status.COASTING,
                    np.where(confirmed, Status.CONFIRMED, Status.TENTATIVE))
