"""Number succession of global tracks through their elementary tracks
(common.radar.global_succession)."""

from __future__ import annotations

import numpy as np

from common.core.track_table import Status, TrackTable
from common.radar.global_succession import Succession

B = 4


def _table() -> TrackTable:
    return TrackTable(6, capacity=4, extra={"member": ((B,), np.int64), "has": ((B,), bool),
                                            "born": ((), float), "confirmed": ((), bool)})


def _track(tab: TrackTable, members: dict[int, int], confirmed: bool, born: float,
           avoid: np.ndarray = np.zeros(0, dtype=np.intp)) -> int:
    s = int(tab.add(1, avoid=avoid)[0])
    for b, e in members.items():
        tab.has[s, b], tab.member[s, b] = True, e
    tab.confirmed[s], tab.born[s] = confirmed, born
    tab.status[s] = Status.CONFIRMED if confirmed else Status.TENTATIVE
    return s


def test_a_track_confirmed_on_two_of_a_removed_tracks_elementary_tracks_takes_its_number() -> None:
    tab, suc = _table(), Succession(keep=3)
    old = _track(tab, {0: 7, 1: 12, 3: 5}, True, born=2.0)
    other = _track(tab, {2: 9}, True, born=3.0)
    suc.vacate(tab, np.array([old]))
    tab.remove([old])
    assert suc.held().tolist() == [old]
    new = _track(tab, {0: 7, 1: 12, 2: 4}, False, born=20.0, avoid=suc.held())
    assert new not in (old, other)  # the held number is not given to a new track
    assert suc.inherit(tab, np.zeros(0, dtype=np.intp)).size == 0  # not confirmed yet
    tab.confirmed[new] = True
    given_up = suc.inherit(tab, np.array([new]))
    assert given_up.tolist() == [new + tab.first_id]
    assert tab.alive[old] and not tab.alive[new]
    assert tab.id[old] == old + tab.first_id and tab.born[old] == 2.0
    assert tab.member[old, 2] == 4 and tab.has[old].tolist() == [True, True, True, False]
    assert suc.held().size == 0


def test_one_shared_elementary_track_is_no_evidence_and_holds_expire() -> None:
    tab, suc = _table(), Succession(keep=2)
    old = _track(tab, {0: 7, 1: 12}, True, born=2.0)
    suc.vacate(tab, np.array([old]))
    tab.remove([old])
    new = _track(tab, {0: 7, 2: 4}, True, born=20.0, avoid=suc.held())
    assert suc.inherit(tab, np.array([new])).size == 0 and tab.alive[new]
    suc.inherit(tab, np.zeros(0, dtype=np.intp))
    assert suc.held().tolist() == [old]
    suc.inherit(tab, np.zeros(0, dtype=np.intp))
    assert suc.held().size == 0  # more than keep cycles: the number is free again


def test_a_track_without_elementary_tracks_or_not_confirmed_holds_no_number() -> None:
    tab, suc = _table(), Succession(keep=3)
    coasted = _track(tab, {}, True, born=1.0)
    tentative = _track(tab, {0: 3, 1: 4}, False, born=1.0)
    suc.vacate(tab, np.array([coasted, tentative]))
    assert suc.held().size == 0
