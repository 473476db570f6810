"""Number succession of global tracks through their elementary tracks (complement of 001
module 61, stated).

001 numbers a global track at its creation and recycles the number at deletion. When a
confirmed global track is removed (deleted, or dissolved by common.radar.fusion.merge)
while its aircraft's elementary tracks live on, a new global track is started from them
(module 62) and confirmed under a new number a few cycles later: the aircraft is
renumbered although every base kept following it.

Rule: the number of a removed confirmed track that still holds elementary tracks is held
for `keep` cycles (its slot is not given to new tracks); a track confirmed in that time
that holds at least `min_shared` of the removed track's elementary tracks (same base,
same elementary number) takes its number and birth time, the one with most shared
first (the latest removed on a tie).
Elementary tracks belong to one aircraft by construction, and two of them from two bases
are what module 62 needs to start a track, so two shared are the evidence of one aircraft.

Members dissociated by module 63 ([48]) count as held in two cases (`dissociated`):
a confirmed track removed in the cycle it lost them (dissolved by
common.radar.fusion.merge, its lost members then starting the aircraft's new track),
and a confirmed track they leave without members (an orphan: 001 keeps it in
pure prediction until deletion, while its free elementary tracks start a new track at
once; the new track confirmed on at least `min_shared` of them takes the orphan's slot,
number and birth time, the orphan's predicted state being dropped for the heir's, and a
deleted orphan's number is held as a removed track's).

Only new numbers are replaced (common.radar.fusion.cycle passes the tracks confirmed
this cycle whose number was never published as confirmed): a track confirmed again
under a number it already published keeps it (a track kept by
common.radar.fusion.merge.number_kept, tentative, and confirmed again must not take a
held number).

The cases behind each rule and the switches with and without it:
docs/decisions/006-number-succession.md.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from common.core.track_table import TrackTable


@dataclass
class Held:
    """A confirmed track whose number is held for its elementary tracks (removed, or an
    orphan): cycle of the record, elementary members (B,) and which count, birth time."""

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
        self.vacated: dict[int, Held] = {}  # slot -> the removed track
        self.orphans: dict[int, Held] = {}  # slot -> the live track's lost members
        self.cut: dict[int, np.ndarray] = {}  # slot -> bases dissociated this cycle

    def held(self) -> np.ndarray:
        """Slots whose numbers are held (to be avoided by new tracks)."""
        return np.fromiter(self.vacated, dtype=np.intp, count=len(self.vacated))

    def vacate(self, tab: TrackTable, slots: np.ndarray) -> None:
        """Record the confirmed tracks among `slots` that hold at least min_shared
        elementary tracks, counting those dissociated this cycle (a track deleted after
        coasting holds none: its number is free at once), before the table removes them."""
        for s in slots.tolist():
            members = tab.has[s] | self.cut.get(s, False)
            if s in self.orphans:
                self.vacated[s] = self.orphans.pop(s)
            elif tab.confirmed[s] and members.sum() >= self.min_shared:
                self.vacated[s] = Held(self.cycle, tab.member[s].copy(), members, float(tab.born[s]))

    def dissociated(self, tab: TrackTable, s: np.ndarray, b: np.ndarray) -> None:
        """Note this cycle's memberships dissociated by [48] (slots s, bases b): a track
        removed this cycle holds its number for them too (`vacate`), and a confirmed track
        they leave without members holds it while it coasts (module doc: an orphan)."""
        v, inv = np.unique(s, return_inverse=True)
        lost = np.zeros((v.size, tab.has.shape[1]), dtype=bool)
        lost[inv, b] = True
        self.cut = dict(zip(v.tolist(), lost))
        alone = tab.confirmed[v] & ~tab.has[v].any(axis=1) & (lost.sum(axis=1) >= self.min_shared)
        for k in np.flatnonzero(alone).tolist():
            self.orphans[int(v[k])] = Held(self.cycle, tab.member[v[k]].copy(), lost[k], float(tab.born[v[k]]))

    def held_orphans(self) -> np.ndarray:
        """Slots of the recorded orphans."""
        return np.fromiter(self.orphans, dtype=np.intp, count=len(self.orphans))

    def inherit(self, tab: TrackTable, confirmed_now: np.ndarray) -> np.ndarray:
        """Move each track confirmed this cycle (slots) that holds >= min_shared of a held
        or orphaned track's elementary tracks to that track's slot (number); forget the
        orphans that took a member again, expire the records older than `keep` cycles.
        Returns the numbers given up: the moved tracks' and the replaced orphans'."""
        self.orphans = {v: o for v, o in self.orphans.items() if not tab.has[v].any()}
        left = []
        known = {**self.vacated, **self.orphans}
        for s in confirmed_now.tolist():
            shared = {v: int(np.sum(old.has & tab.has[s] & (old.member == tab.member[s])))
                      for v, old in known.items()}
            best = max(shared, key=lambda v: (shared[v], known[v].cycle), default=None)
            if best is None or shared[best] < self.min_shared:
                continue
            if best in self.orphans:
                left.append(int(tab.id[best]))
            rec = known.pop(best)
            (self.orphans if best in self.orphans else self.vacated).pop(best)
            left.append(_take(tab, s, best, rec.born))
        self.cycle += 1
        self.vacated = {v: old for v, old in self.vacated.items() if self.cycle - old.cycle <= self.keep}
        self.orphans = {v: old for v, old in self.orphans.items() if self.cycle - old.cycle <= self.keep}
        return np.array(left, dtype=np.int64)

    def continue_segments(self, tab: TrackTable, new: np.ndarray, old: np.ndarray) -> np.ndarray:
        """Move each track of `new` (slots confirmed this cycle) to the slot (number) of
        the coasting track of `old` it continues (common.radar.fusion.segments), which is
        dropped for it; returns the numbers given up (both)."""
        left = []
        for s, o in zip(new.tolist(), old.tolist()):
            self.orphans.pop(o, None)
            left.append(int(tab.id[o]))
            left.append(_take(tab, s, o, float(tab.born[o])))
        return np.array(left, dtype=np.int64)


def _take(tab: TrackTable, s: int, dst: int, born: float) -> int:
    """Track of slot s moved to slot dst (its number), with the birth time `born`;
    returns s's number, now free."""
    tab.copy_rows([s], [dst])
    tab.id[dst] = dst + tab.first_id
    tab.born[dst] = born
    gone = int(tab.id[s])
    tab.remove([s])
    return gone
