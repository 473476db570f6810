"""The bearing register "as of" a cycle (common.sonar.history_as_of,
common.sonar.mht.register_versions): the history reply a tracker already at a later cycle
gives for an earlier btracks time is the reply it gave right after that cycle."""

import math

import numpy as np
import pytest

from common.core.rejection import Rejected
from common.sonar.bearing.tracker import BearingTracker
from common.sonar.history_as_of import ConfirmedLog, history_as_of, parse_as_of
from common.sonar.mht.params import MhtParams
from common.sonar.mht.register_versions import RegisterVersions
from common.sonar.mht.tracker import MhtTracker
from tests.sonar.test_mht_tracker import DEG, P, scene


def _same(a, b) -> bool:
    return a[0] == b[0] and a[1].keys() == b[1].keys() and all(
        np.array_equal(a[1][k], b[1][k], equal_nan=True) for k in a[1])


def _run(trk, cyc, log):
    """Step through the cycles; per cycle time, every confirmed track's reply then."""
    replies = {}
    for t, b, a, _ in cyc:
        c = trk.step(t, b, a, 0.0)
        log.record(c.t, c.ids, c.confirmed)
        replies[t] = {int(i): trk.history_of(int(i)) for i in c.ids[c.confirmed]}
    return replies


def _upto(found, t):
    """A reply's register cut at time t (the register columns by t, the retro ones by t_retro)."""
    cols = found[1]
    return found[0], {k: v[cols["t_retro" if k.endswith("_retro") else "t"] <= t] for k, v in cols.items()}


def test_mht_rows_revised_after_cycle_k_are_answered_as_of_k():
    trk = MhtTracker(P, MhtParams(rho_f=1.0 / (2 * math.pi * 10.0)), "cylindrical", DEG)
    log = ConfirmedLog(keep=16)
    cyc = scene([1.0, 1.3], [2e-4, -1e-4], 40, seed=3, clutter=1.0, pd=0.8)
    replies = _run(trk, cyc, log)
    times = [t for t, *_ in cyc]
    revised = 0
    for t in times[-16:-1]:  # kept cycles, the tracker since at later ones
        for tid, then in replies[t].items():
            revised += not _same(then, _upto(trk.history_of(tid), t))
            got, kept = history_as_of(trk, log, tid, t)
            assert kept and _same(got, then), (t, tid)
    assert revised > 0  # retrodiction rewrote rows: the register of now cut at t is not the reply then
    tid = next(iter(replies[times[-1]]))
    got, kept = history_as_of(trk, log, tid, times[5])  # no longer kept: the register of now up to t
    assert not kept and got is not None and _same(got, _upto(trk.history_of(tid), times[5]))


def test_as_of_status_is_the_one_of_that_cycle():
    trk = BearingTracker(P, "cylindrical", DEG)
    log = ConfirmedLog(keep=64)
    cyc = scene([1.0], [0.0], 12, seed=5)
    replies = _run(trk, cyc, log)
    tid = next(iter(replies[cyc[-1][0]]))
    first = min(t for t, r in replies.items() if tid in r)
    for t, b, a, _ in [(120.0 + 10.0 * k, np.zeros(0), np.zeros(0), None) for k in range(30)]:
        c = trk.step(t, b, a, 0.0)
        log.record(c.t, c.ids, c.confirmed)
    assert trk.history_of(tid)[0] == "deleted"
    got, kept = history_as_of(trk, log, tid, 110.0)
    assert kept and _same(got, replies[110.0][tid])  # confirmed then, rows up to then
    assert history_as_of(trk, log, tid, first - 10.0) == (None, True)  # not confirmed yet then
    assert history_as_of(trk, log, tid, None)[0][0] == "deleted"  # no as_of: the reply of now


def test_versions_are_bounded_and_copies():
    v = RegisterVersions(keep=2)
    rows = np.array([[10.0, 1, 0.1, 0, 0, 1, 0.1]])
    for t in (10.0, 20.0, 30.0):
        rows[0, 0] = t
        v.record([(np.array([7]), rows)])
    assert not v.has(10.0) and v.has(20.0) and v.has(30.0)
    rows[0, 1] = 99.0  # later rewrites of the register leave the kept version alone
    cur = np.array([[5.0, 2, 0.1, 0, 0, 2, 0.1], [30.0, 99, 0.1, 0, 0, 99, 0.1]])
    assert v.rows_as_of(7, cur, 30.0)[:, 1].tolist() == [2.0, 1.0]
    assert v.rows_as_of(7, cur, 10.0)[:, 0].tolist() == [5.0]  # not kept: current rows up to t


def test_parse_as_of():
    assert parse_as_of(None) is None and parse_as_of("1380.5") == 1380.5
    for bad in ("x", "nan", "inf", ""):
        with pytest.raises(Rejected):
            parse_as_of(bad)
