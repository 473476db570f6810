"""The bearing register served "as of" a btracks cycle (sonar/history with ``as_of``,
docs/protocol.md): the tma service names the btracks time it works on, and a bearing
tracker that has already taken later detection lists answers as it would have right
after that cycle: the track's status then (from :class:`ConfirmedLog`) and its rows then
(the trackers' ``history_of(track_id, as_of)``; the multiple-hypothesis register keeps
its retrodiction window per cycle, common.sonar.mht.register_versions). So the chain
through the processes reads what the chain in one process reads.
"""

from __future__ import annotations

import math
from collections import OrderedDict

import numpy as np

from common.core.rejection import Rejected
from common.sonar.trackers import BearingTrackerCore

Found = tuple[str, dict[str, np.ndarray]]


class ConfirmedLog:
    """The confirmed track numbers of each of the last ``keep`` cycles, by cycle time."""

    def __init__(self, keep: int) -> None:
        self.keep = keep
        self._by_t: OrderedDict[float, frozenset[int]] = OrderedDict()

    def record(self, t: float, ids: np.ndarray, confirmed: np.ndarray) -> None:
        """One cycle's tracks (numbers and confirmed flags, as in its btracks message)."""
        self._by_t[float(t)] = frozenset(int(i) for i in ids[confirmed])
        while len(self._by_t) > self.keep:
            self._by_t.popitem(last=False)

    def at(self, t: float) -> frozenset[int] | None:
        """The confirmed numbers of the cycle at time t, None if that cycle is not kept."""
        return self._by_t.get(t)


def history_as_of(core: BearingTrackerCore, log: ConfirmedLog, track_id: int,
                  as_of: float | None) -> tuple[Found | None, bool]:
    """The history reply of a track as of cycle time ``as_of`` (None: now, as before
    the parameter existed), and whether it is that cycle's (False: the cycle is no
    longer kept, or never was: the current register up to ``as_of``). As of a kept
    cycle: None unless the track was confirmed then; its status then, "confirmed"."""
    if as_of is None:
        return core.history_of(track_id), True
    confirmed = log.at(as_of)
    found = core.history_of(track_id, as_of)
    if confirmed is None:
        return found, False
    if track_id not in confirmed or found is None:
        return None, True
    return ("confirmed", found[1]), True


def parse_as_of(text: str | None) -> float | None:
    """The ``as_of`` selector parameter: a finite time (s), or None when absent;
    Rejected ("bad_history_as_of") otherwise."""
    if text is None:
        return None
    try:
        t = float(text)
    except ValueError:
        t = math.nan
    if not math.isfinite(t):
        raise Rejected("bad_history_as_of", f"as_of '{text}' is not a time")
    return t
