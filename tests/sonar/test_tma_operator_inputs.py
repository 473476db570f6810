"""Operator TMA inputs per (track, birth) (issue 31 section 3), pure: births from the
btracks cycles, bounds and support values of one track only, nothing inherited by a
reused number, the state kept across a restart (common.sonar.tma.operator_inputs and
their use by common.sonar.tma.manager), and their messages (common.wire.sonar_messages)."""

from __future__ import annotations

import math

import numpy as np
import pytest

from common.core.rejection import Rejected
from common.sonar.tma.bearings_only import Support
from common.sonar.tma.bounds import MINIMAL_BOUNDS, TWO_PI, Bounds
from common.sonar.tma.manager import BoundsParams, BTrack, BTracks, TmaManager, TmaParams, TrackHistory
from common.sonar.tma.operator_inputs import OperatorInputs
from common.wire import protocol
from common.wire.sonar_messages import (
    ack_message,
    bounds_message,
    clear_message,
    support_message,
    tma_message,
)

SIG = 0.01
TARGETS = {1: np.array([6000.0, 4000.0, -2.0, 1.5]), 2: np.array([-5000.0, 7000.0, 3.0, -1.0]),
           3: np.array([2000.0, -6000.0, 1.0, 2.0])}
TIGHT = Bounds(8000.0, 20000.0, 0.0, TWO_PI, 0.1, 15.0)  # track 1 is at ~4.6 km: CTMA


def own_at(t: float) -> tuple[float, float]:
    """Own ship: North at 3 m/s for 900 s, then East at 3 m/s."""
    return (0.0, 3.0 * t) if t <= 900.0 else (3.0 * (t - 900.0), 2700.0)


def brg(tid: int, t: float) -> float:
    ox, oy = own_at(t)
    x, y = TARGETS[tid][:2] + TARGETS[tid][2:] * t
    return math.atan2(x - ox, y - oy) % TWO_PI


def cycle(mgr: TmaManager, t: float, tracks: dict[int, bool]) -> dict:
    """Own ship and a btracks cycle at t ({number: confirmed}); the tma message, each
    confirmed track given its register of true bearings every 20 s up to t."""
    mgr.add_own(t, *own_at(t))
    P = np.zeros(16)
    P[0] = SIG**2
    mgr.push(BTracks(t, "a1", [BTrack(tid, conf, np.array([brg(tid, t), 0.0, 20.0, 0.0]), P)
                               for tid, conf in tracks.items()]))
    (b,), _ = mgr.ready()
    times = np.arange(0.0, t + 1.0, 20.0)
    hist = {}
    for tid in mgr.history_wanted(b):
        own = np.array([own_at(x) for x in times])
        rows = np.column_stack((times, [brg(tid, x) for x in times], np.full(times.size, SIG), own))
        hist[tid] = TrackHistory(tid, "confirmed", rows)
    return protocol.decode("tma", protocol.encode(tma_message(mgr.step(b, hist))))


def sol(msg: dict, tid: int) -> dict:
    return next(s for s in msg["solutions"] if s["track"] == tid)


def test_births_follow_numbers_and_their_reuse():
    ops = OperatorInputs()
    ops.observe(0.0, [(1, False)])
    ops.observe(20.0, [(1, True), (2, False)])
    assert ops.birth == {1: 0.0, 2: 20.0}
    ops.set_bounds(ops.resolve(1, 0.0), TIGHT)
    assert ops.observe(40.0, [(1, True), (2, True)]) == []
    assert ops.observe(60.0, [(1, False), (2, True)]) == [1]  # confirmed -> tentative: a new track
    assert ops.birth == {1: 60.0, 2: 20.0} and ops.of(1) is None
    ops.add_support(ops.resolve(2, None), Support("speed", 3.0, 0.5, 60.0))
    assert ops.observe(80.0, [(1, False)]) == [2]  # absent: ended
    ops.observe(100.0, [(1, False), (2, False)])
    assert ops.birth == {1: 60.0, 2: 100.0} and ops.inputs == {}


def test_an_input_names_a_live_track_of_its_birth():
    ops = OperatorInputs()
    ops.observe(0.0, [(1, True)])
    with pytest.raises(Rejected, match="unknown_track"):
        ops.resolve(2, None)
    with pytest.raises(Rejected, match="stale_birth"):
        ops.resolve(1, 20.0)
    assert (ops.resolve(1, None).birth, ops.resolve(1, 0.0).track) == (0.0, 1)


def test_bounds_of_one_track_make_its_solution_constrained_not_the_others():
    mgr = TmaManager("a1", TmaParams(cycle_dt=0.0))
    cycle(mgr, 1500.0, {1: True, 2: True})
    assert mgr.set_bounds(TIGHT, 1, 1500.0) == [1]
    out = cycle(mgr, 1520.0, {1: True, 2: True})
    assert sol(out, 1)["constrained"] and sol(out, 1)["bounds"][0] == 8000.0
    assert not sol(out, 2)["constrained"] and sol(out, 2)["bounds"][0] == MINIMAL_BOUNDS.r_min
    # the array's bounds (no track) leave a track with its own bounds alone
    assert mgr.set_bounds(Bounds(500.0, 50000.0, 0.0, TWO_PI, 0.1, 15.0)) == [2]
    out = cycle(mgr, 1540.0, {1: True, 2: True})
    assert (sol(out, 1)["bounds"][0], sol(out, 2)["bounds"][0]) == (8000.0, 500.0)
    mgr.clear(1, "bounds")
    out = cycle(mgr, 1560.0, {1: True, 2: True})
    assert not sol(out, 1)["constrained"] and sol(out, 1)["bounds"][0] == 500.0
    assert out["births"] == [{"track": 1, "birth": 1500.0}, {"track": 2, "birth": 1500.0}]


def test_support_values_of_one_track_and_their_clearing():
    mgr = TmaManager("a1", TmaParams(cycle_dt=0.0))
    cycle(mgr, 600.0, {1: True, 2: True})
    ox, oy = own_at(600.0)
    x, y = TARGETS[1][:2] + TARGETS[1][2:] * 600.0
    mgr.add_support(1, Support("range", math.hypot(x - ox, y - oy), 10.0, 600.0, (ox, oy)), 600.0)
    assert [s.kind for s in mgr.tracks[1].tracker.support] == ["range"]
    assert mgr.tracks[2].tracker.support == []
    mgr.clear(1, "support", 600.0)
    assert mgr.tracks[1].tracker.support == [] and mgr.inputs.inputs == {}


def test_a_reused_number_does_not_inherit():
    mgr = TmaManager("a1", TmaParams(cycle_dt=0.0))
    cycle(mgr, 1500.0, {1: True})
    mgr.set_bounds(TIGHT, 1)
    mgr.add_support(1, Support("speed", 9.0, 0.1, 1500.0))
    assert sol(cycle(mgr, 1520.0, {1: True}), 1)["constrained"]
    cycle(mgr, 1540.0, {})  # track 1 deleted
    cycle(mgr, 1560.0, {1: False})  # number 1 reused by a new track
    out = cycle(mgr, 1580.0, {1: True})
    assert out["births"] == [{"track": 1, "birth": 1560.0}]
    assert not sol(out, 1)["constrained"] and sol(out, 1)["bounds"][0] == MINIMAL_BOUNDS.r_min
    assert mgr.tracks[1].tracker.support == [] and mgr.inputs.inputs == {}
    with pytest.raises(Rejected, match="stale_birth"):
        mgr.clear(1, "all", 1500.0)


def test_state_round_trip_keeps_inputs_across_a_restart():
    mgr = TmaManager("a1", TmaParams(cycle_dt=0.0))
    cycle(mgr, 1500.0, {1: True, 2: True, 3: False})
    mgr.set_bounds(TIGHT, 1)
    mgr.add_support(2, Support("range", 5000.0, 50.0, 1500.0, (1.0, 2.0)))
    mgr.set_bounds(Bounds(500.0, 50000.0, 0.0, TWO_PI, 0.1, 15.0))
    assert mgr.inputs.changed
    doc = mgr.inputs.state()
    assert [b[0] for b in doc["births"]] == [1, 2]  # a tentative track's birth is not kept
    again = TmaManager("a1", TmaParams(cycle_dt=0.0))
    again.restore(OperatorInputs.from_state(doc))
    assert again.bounds.r_min == 500.0
    out = cycle(again, 1520.0, {1: True, 2: True})
    assert sol(out, 1)["constrained"] and sol(out, 1)["bounds"][0] == 8000.0
    assert [s.obs_xy for s in again.tracks[2].tracker.support] == [(1.0, 2.0)]
    assert out["births"] == [{"track": 1, "birth": 1500.0}, {"track": 2, "birth": 1500.0}]
    # a track that came back tentative after the restart is a new one
    again = TmaManager("a1")
    again.restore(OperatorInputs.from_state(doc))
    assert again.inputs.observe(1520.0, [(1, False), (2, True)]) == [1]


@pytest.mark.parametrize("doc", [
    {}, {"version": 2, "default": None, "births": [], "inputs": []},
    {"version": 1, "default": None, "births": [], "inputs": [
        {"track": 1, "birth": 0.0, "bounds": None, "support": []}]},
    {"version": 1, "default": [1.0], "births": [], "inputs": []},
    {"version": 1, "default": None, "births": [[1, 0.0, True]], "inputs": [
        {"track": 1, "birth": 0.0, "bounds": None, "support": [["depth", 1.0, 1.0, 0.0, 0.0, 0.0]]}]},
    [],
])
def test_an_unreadable_state_is_rejected(doc):
    with pytest.raises(Rejected, match="bad_state"):
        OperatorInputs.from_state(doc)


def test_operator_messages_decode_as_built():
    b = BoundsParams(1000.0, 2e4, 1.0, 2.0, 0.5, 8.0)
    m = protocol.decode("tma_bounds", protocol.encode(bounds_message(5.0, b, 3, 20.0, "r1")))
    assert (m["track"], m["birth"], m["req"], m["course_min"]) == (3, 20.0, "r1", 1.0)
    m = protocol.decode("tma_bounds", protocol.encode(bounds_message(5.0, b)))
    assert "track" not in m and "req" not in m
    s = Support("range", 4000.0, 40.0, 7.0, (1.0, 2.0))
    m = protocol.decode("tma_support", protocol.encode(support_message(3, s, None, "r2")))
    assert (m["obs_x"], m["obs_y"], m["t"], m["req"]) == (1.0, 2.0, 7.0, "r2") and "birth" not in m
    m = protocol.decode("tma_clear", protocol.encode(clear_message(5.0, 3, "support", 20.0, "r3")))
    assert (m["what"], m["birth"]) == ("support", 20.0)
    a = protocol.decode("tma_ack", protocol.encode(ack_message(9.0, "r3", "accepted", 3, 20.0)))
    assert a["ok"] and (a["track"], a["birth"]) == (3, 20.0)
    n = protocol.decode("tma_ack", protocol.encode(ack_message(9.0, "r4", "stale_birth")))
    assert not n["ok"] and n["reason"] == "stale_birth" and "track" not in n
    with pytest.raises(protocol.DecodeError) as e:
        protocol.decode("tma_clear", protocol.encode(clear_message(5.0, 3, "legs")))
    assert e.value.field == "what"
    assert protocol.kind_of("pf/v1/sonar/tma/ack/a1", "pf/v1") == "tma_ack"
    assert protocol.kind_of("pf/v1/sonar/tma/clear/a1", "pf/v1") == "tma_clear"
