"""Number succession of global tracks through their elementary tracks (complement of 001
module 61, stated).

001 numbers a global track at its creation and recycles the number at deletion. When a
confirmed global track is removed (deleted, or dissolved by common.radar.global_merge)
while its aircraft's elementary tracks live on, a new global track is started from them
(module 62) and confirmed under a new number a few cycles later: the aircraft is
renumbered although every base kept following it. Measured on dense1000.toml (seed 5):
aircraft 94 and 102 renumbered that way at t = 59-64 and 89-95, the new track holding
two and three of the old track's elementary tracks.

Rule: the number of a removed confirmed track that still holds elementary tracks is held
for `keep` cycles (its slot is not given to new tracks); a track confirmed in that time
that holds at least `min_shared` of the removed track's elementary tracks (same base,
same elementary number) takes its number and birth time, the one with most shared
first (the latest removed on a tie).
Elementary tracks belong to one aircraft by construction, and two of them from two bases
are what module 62 needs to start a track, so two shared are the evidence of one aircraft.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from common.core.track_table import TrackTable


@dataclass
class Vacated:
    """A removed confirmed track: cycle of removal, elementary members (B,), birth time."""

    cycle: int
    member: np.ndarray
    has: np.ndarray
    born: float


class Succession:
    """Numbers of removed confirmed tracks, held for the track that takes their
    elementary tracks (module doc)."""

    def __init__(self, keep: int, min_shared: int = 2) -> None:
        self.keep, self.min_shared = keep, min_shared
        self.cycle = 0
        self.vacated: dict[int, Vacated] = {}  # slot -> the removed track

    def held(self) -> np.ndarray:
        """Slots whose numbers are held (to be avoided by new tracks)."""
        return np.fromiter(self.vacated, dtype=np.intp, count=len(self.vacated))

    def vacate(self, tab: TrackTable, slots: np.ndarray) -> None:
        """Record the confirmed tracks among `slots` that hold at least min_shared
        elementary tracks (a track deleted after coasting holds none: its number is
        free at once), before the table removes them."""
        heirs = tab.confirmed[slots] & (tab.has[slots].sum(axis=1) >= self.min_shared)
        for s in slots[heirs].tolist():
            self.vacated[s] = Vacated(self.cycle, tab.member[s].copy(), tab.has[s].copy(),
                                      float(tab.born[s]))

    def inherit(self, tab: TrackTable, confirmed_now: np.ndarray) -> np.ndarray:
        """Move each track confirmed this cycle (slots) that holds >= min_shared of a held
        track's elementary tracks to that track's slot (number); expire the holds older
        than `keep` cycles. Returns the numbers given up by the moved tracks."""
        left = []
        for s in confirmed_now.tolist():
            shared = {v: int(np.sum(old.has & tab.has[s] & (old.member == tab.member[s])))
                      for v, old in self.vacated.items()}
            best = max(shared, key=lambda v: (shared[v], self.vacated[v].cycle), default=None)
            if best is None or shared[best] < self.min_shared:
                continue
            tab.copy_rows([s], [best])
            tab.id[best] = best + tab.first_id
            tab.born[best] = self.vacated.pop(best).born
            left.append(int(tab.id[s]))
            tab.remove([s])
        self.cycle += 1
        self.vacated = {v: old for v, old in self.vacated.items() if self.cycle - old.cycle <= self.keep}
        return np.array(left, dtype=np.int64)
