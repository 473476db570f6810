"""The multiple-hypothesis bearing register "as of" a cycle: retrodiction
(common.sonar.mht.retrodiction) rewrites the rows of its last n_retro cycles at every
cycle, so the register served after cycle k is not the one served after k + 1. A history
query that names the btracks time k it works on (docs/protocol.md, ``as_of``) is
answered from the register as it was right after cycle k.

Kept: for each of the last ``keep`` cycles, a copy of the rows of the retrodiction window
as that cycle left them (rows older than the window are never rewritten again, so the
current register holds them as they were). Bounded memory: at most
``keep x n_retro x tracks`` rows of 7 floats.
"""

from __future__ import annotations

from collections import OrderedDict
from dataclasses import dataclass

import numpy as np


@dataclass(frozen=True)
class Version:
    """The register's window as one cycle left it: its first row time ``start``, and
    uid (R,) and rows (R, 7) of every window record (common.sonar.mht.retrodiction)."""

    start: float
    uid: np.ndarray
    rows: np.ndarray


class RegisterVersions:
    """The window rows as published at each of the last ``keep`` cycles, by cycle time."""

    def __init__(self, keep: int) -> None:
        self.keep = keep
        self._by_t: OrderedDict[float, Version] = OrderedDict()

    def record(self, blocks: list[tuple[np.ndarray, np.ndarray]]) -> None:
        """Copy the window blocks (uid (T,), rows (T, 7)), oldest first, as the cycle of
        the newest block's time left them (a cycle without tracks has nothing to keep)."""
        if self.keep <= 0 or not blocks or blocks[-1][1].shape[0] == 0:
            return
        uid = np.concatenate([u for u, _ in blocks])
        rows = np.concatenate([r for _, r in blocks])
        t = float(blocks[-1][1][0, 0])
        self._by_t[t] = Version(float(rows[:, 0].min()), uid, rows)
        while len(self._by_t) > self.keep:
            self._by_t.popitem(last=False)

    def has(self, t: float) -> bool:
        """Whether the register as of cycle time t is kept."""
        return t in self._by_t

    def rows_as_of(self, uid: int, rows: np.ndarray, t: float) -> np.ndarray:
        """The rows (time order) of track ``uid`` as of cycle time t, from its current
        ``rows``: the kept window of t in place of the current rows from its start on;
        without a kept version, the current rows up to t."""
        v = self._by_t.get(t)
        if v is None:
            return rows[rows[:, 0] <= t]
        return np.concatenate([rows[rows[:, 0] < v.start], v.rows[v.uid == uid]])
