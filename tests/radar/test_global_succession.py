"""Number succession of global tracks through their elementary tracks
(common.radar.fusion.succession)."""

from __future__ import annotations

import numpy as np

from common.core.track_table import Status, TrackTable
from common.radar.fusion.succession import Succession

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


def _orphaned(tab: TrackTable, suc: Succession, members: dict[int, int]) -> int:
    """A confirmed track whose every member fails [48] this cycle (dissociated)."""
    old = _track(tab, members, True, born=2.0)
    tab.has[old] = False
    suc.dissociated(tab, np.full(len(members), old), np.array(list(members), dtype=np.intp))
    return old


def test_a_track_confirmed_on_an_orphans_lost_elementary_tracks_takes_its_number() -> None:
    """Seed 9's aircraft 468: #762 lost its four members to [48] in one scan; the track
    started from three of them takes #762's number at its confirmation, the orphan's
    coasting state is dropped, and both numbers given up are returned."""
    tab, suc = _table(), Succession(keep=3)
    old = _orphaned(tab, suc, {0: 7, 1: 12, 3: 5})
    new = _track(tab, {0: 7, 1: 12, 2: 4}, False, born=20.0)
    assert suc.inherit(tab, np.zeros(0, dtype=np.intp)).size == 0  # not confirmed yet
    tab.confirmed[new] = True
    given_up = suc.inherit(tab, np.array([new]))
    assert sorted(given_up.tolist()) == sorted([old + tab.first_id, new + tab.first_id])
    assert tab.alive[old] and not tab.alive[new]
    assert tab.id[old] == old + tab.first_id and tab.born[old] == 2.0
    assert tab.has[old].tolist() == [True, True, True, False] and tab.member[old, 2] == 4
    assert suc.held_orphans().size == 0


def test_an_orphan_that_takes_a_member_again_or_lost_one_keeps_no_claim() -> None:
    tab, suc = _table(), Succession(keep=3)
    old = _orphaned(tab, suc, {0: 7, 1: 12})
    tab.has[old, 2], tab.member[old, 2] = True, 9  # a member again: no longer an orphan
    new = _track(tab, {0: 7, 1: 12}, True, born=20.0)
    assert suc.inherit(tab, np.array([new])).size == 0 and tab.alive[new]
    single = _orphaned(tab, suc, {3: 5})  # one lost member is no evidence of the aircraft
    assert single not in suc.held_orphans().tolist()


def test_a_deleted_orphan_holds_its_number_for_its_lost_elementary_tracks() -> None:
    tab, suc = _table(), Succession(keep=3)
    old = _orphaned(tab, suc, {0: 7, 1: 12})
    suc.vacate(tab, np.array([old]))
    tab.remove([old])
    assert suc.held().tolist() == [old] and suc.held_orphans().size == 0


def test_a_track_removed_in_the_cycle_it_lost_members_holds_its_number_for_them() -> None:
    """Seed 9's aircraft 468: #762 lost b0 and b3 to [48] and was dissolved the same cycle
    holding b1 and b2 (b2's elementary track then ended); the track started from the lost
    b0 and b3 tracks takes its number at its confirmation."""
    tab, suc = _table(), Succession(keep=3)
    old = _track(tab, {0: 7, 1: 12, 2: 3, 3: 5}, True, born=2.0)
    tab.has[old, [0, 3]] = False
    suc.dissociated(tab, np.array([old, old]), np.array([0, 3]))
    suc.vacate(tab, np.array([old]))
    tab.remove([old])
    new = _track(tab, {0: 7, 2: 8, 3: 5}, True, born=74.0, avoid=suc.held())
    assert suc.inherit(tab, np.array([new])).tolist() == [new + tab.first_id]
    assert tab.alive[old] and tab.born[old] == 2.0
