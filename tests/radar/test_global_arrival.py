"""Global fusion's arrival rule (common.radar.fusion.arrival), wall time given: one branch
per test, then the fault sequence of tests/integration/test_faults.py on a known clock."""

from __future__ import annotations

import pytest

from common.core.rejection import Rejected
from common.radar.elementary.tracker import ElementaryTracks
from common.radar.fusion.arrival import Arrival
from common.radar.fusion.cycle import GlobalFusion
from common.radar.fusion.params import FusionParams
from common.wire.radar_messages import etracks_from
from tests.radar.test_global_ekf import BASES

ALL = ("b1", "b2", "b3")


def report(base: str, t: float) -> ElementaryTracks:
    """An empty report of `base` at t (the rule looks at times only)."""
    return etracks_from({"base": base, "t": t, "tracks": []})[1]


class Feed:
    """An Arrival over BASES (max_wait 3 s, max_lead 20 s) and the cycles it ran."""

    def __init__(self) -> None:
        self.arrival = Arrival(GlobalFusion(BASES, FusionParams(max_wait=3.0, max_lead=20.0)))
        self.cycles: list[float] = []

    def send(self, t: float, now: float, *bases: str) -> None:
        for b in bases:
            self.cycles += [g.t for g in self.arrival.push(b, report(b, t), now)]

    def reject(self, base: str, t: float, now: float) -> str:
        with pytest.raises(Rejected) as e:
            self.arrival.push(base, report(base, t), now)
        return e.value.reason


def test_bases_in_step_are_waited_for() -> None:
    f = Feed()
    for k in range(10):
        f.send(float(k), 0.9 * k, "b3", "b1")
        assert f.cycles == [float(j) for j in range(k)]  # waits for b2
        f.send(float(k), 0.9 * k + 0.1, "b2")
        assert f.cycles == [float(j) for j in range(k + 1)]


def test_a_base_silent_for_more_than_max_wait_is_stale() -> None:
    f = Feed()
    f.send(0.0, 0.0, *ALL)
    for k in (1, 2, 3):
        f.send(float(k), float(k), "b1", "b2")  # b3 silent 3 s: not yet stale
    assert f.cycles == [0.0]
    f.send(4.0, 4.0, "b1")  # 4 s: stale; b2's 4 still missing
    assert f.cycles == [0.0, 1.0, 2.0, 3.0]
    f.send(4.0, 4.0, "b2")
    assert f.cycles[-1] == 4.0


def test_a_base_never_heard_of_is_silent_since_the_first_report() -> None:
    f = Feed()
    f.send(0.0, 0.0, "b1", "b2")
    f.send(1.0, 3.0, "b1", "b2")
    assert f.cycles == []
    f.send(2.0, 3.5, "b1", "b2")
    assert f.cycles == [0.0, 1.0, 2.0]


def stale_b3() -> Feed:
    """Cycles 0-4 ran, the last four without b3 (silent since wall time 0)."""
    f = Feed()
    f.send(0.0, 0.0, *ALL)
    for k in (1, 2, 3, 4):
        f.send(float(k), float(k), "b1", "b2")
    assert f.cycles == [0.0, 1.0, 2.0, 3.0, 4.0]
    return f


def test_a_late_report_just_behind_makes_its_base_live_again() -> None:
    f = stale_b3()
    assert f.reject("b3", 4.0, 4.5) == "time_backwards"  # behind the cycle of 4, by 0 s
    f.send(5.0, 5.0, "b1", "b2")
    assert f.cycles[-1] == 4.0  # the cycle of 5 waits for b3
    f.send(5.0, 5.1, "b3")
    assert f.cycles[-1] == 5.0


def test_a_late_report_further_behind_than_max_wait_does_not() -> None:
    f = stale_b3()
    assert f.reject("b3", 0.0, 4.5) == "time_backwards"  # 4 s behind the cycle of 4
    f.send(5.0, 5.0, "b1", "b2")
    assert f.cycles[-1] == 5.0


def test_a_stale_base_that_comes_back_in_time_is_waited_for() -> None:
    f = stale_b3()
    f.send(5.0, 5.0, "b3")  # back, ahead of the others
    f.send(5.0, 5.0, "b1")
    assert f.cycles[-1] == 4.0
    f.send(5.0, 5.0, "b2")
    assert f.cycles[-1] == 5.0


def test_a_duplicate_is_rejected() -> None:
    f = Feed()
    f.send(0.0, 0.0, "b1")
    assert f.reject("b1", 0.0, 0.1) == "duplicate"


def test_a_base_whose_clock_is_ahead_is_stale_at_once_until_back_in_reach() -> None:
    f = Feed()
    f.send(0.0, 0.0, *ALL)
    assert f.reject("b1", 1021.0, 1.0) == "clock_ahead"  # more than 20 s after the cycle of 0
    f.send(1.0, 1.0, "b2", "b3")
    assert f.cycles == [0.0, 1.0]  # without b1, at once
    f.send(2.0, 2.0, "b1")  # in reach again: waited for
    f.send(2.0, 2.0, "b2")
    assert f.cycles == [0.0, 1.0]
    f.send(2.0, 2.0, "b3")
    assert f.cycles == [0.0, 1.0, 2.0]


def test_a_base_ahead_that_sends_a_late_report_is_waited_for() -> None:
    f = Feed()
    f.send(0.0, 0.0, *ALL)
    assert f.reject("b1", 1021.0, 1.0) == "clock_ahead"
    assert f.reject("b1", 0.0, 1.0) == "time_backwards"  # its clock is back
    f.send(1.0, 1.0, "b2", "b3")
    assert f.cycles == [0.0]


def test_the_fault_sequence_of_the_process_test() -> None:
    """tests/integration/test_faults.py's fusion faults (max_wait 1 s, max_lead 20 s),
    wall time 0.05 s per scan and b3 silent 1.75 s: every cycle, in order, and the
    counts the process reports."""
    arrival = Arrival(GlobalFusion(BASES, FusionParams(max_wait=1.0, max_lead=20.0)))
    cycles: list[float] = []
    rejected: dict[str, int] = {}
    now = 0.0

    def put(base: str, t: float) -> None:
        try:
            cycles.extend(g.t for g in arrival.push(base, report(base, t), now))
        except Rejected as e:
            rejected[e.reason] = rejected.get(e.reason, 0) + 1

    for k in range(60):
        t = {b: float(k) for b in ALL}
        if k == 10:
            put("b1", 10.0)  # duplicate
        if k == 11:
            put("b1", 12.0)  # out of order: 12 before 11
        if k == 12:
            del t["b1"]
        if k == 13:
            put("b2", 12.0)  # late
        if 14 <= k < 19:
            del t["b3"]  # silent
            now += 0.3
        if 24 <= k < 34:
            t["b1"] = k + 1000.0  # clock ahead
        if 40 <= k < 45:
            t["b2"] = k - 10.0  # clock back
        for b, tb in t.items():
            put(b, tb)
        now += 0.05
    assert cycles == [float(k) for k in range(60)]
    assert rejected == {"duplicate": 1, "time_backwards": 7, "clock_ahead": 10}
