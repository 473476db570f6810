"""Unit tests of the seed 000 bearing tracker: formulas, filter, life cycle, wrap-around,
multi-line grouping (claims 12-13) and the bearing register."""

from __future__ import annotations

import math
from dataclasses import replace

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from common.core.crossing import CrossingParams
from common.core.rejection import Rejected
from common.sonar.bearing.model import (
    gate_value,
    linear_array_sigma,
    measurement_matrix,
    missed_increment,
    quality_increment,
    thresholds,
)
from common.sonar.bearing.multiline import NEW, MultiLineGrouper
from common.sonar.bearing.tracker import BearingTracker, TrackerParams

DEG = math.pi / 180.0
BB = TrackerParams(mode="broadband")
NB = TrackerParams(mode="narrowband")


def test_gate_value_formula() -> None:
    # 000: G = 2 ln(P_D dTheta / ((1 - P_D) (2 pi)^(M/2) P_FA sqrt|S|)), by hand
    pd, pfa, dth, detS, M = 0.8, 1e-3, 0.03, 4e-4, 2
    want = 2.0 * math.log(pd * dth / ((1 - pd) * (2 * math.pi) ** (M / 2) * pfa * math.sqrt(detS)))
    assert gate_value(pd, pfa, dth, detS, M) == pytest.approx(want)
    # larger |S| -> smaller gate
    assert gate_value(pd, pfa, dth, 1e-2, M) < gate_value(pd, pfa, dth, 1e-4, M)


def test_quality_increment_formula_and_gate_is_break_even() -> None:
    pd, pfa, dth, detS, M = 0.9, 1e-3, 0.035, 2.5e-3, 2
    d2 = 3.0
    want = math.log(pd * dth / (pfa * math.sqrt(detS))) - (d2 + M * math.log(2 * math.pi)) / 2
    assert quality_increment(pd, pfa, dth, detS, d2, M) == pytest.approx(want)
    G = float(gate_value(pd, pfa, dth, detS, M))
    # at d^2 = G a hit is worth exactly a miss, ln(1 - P_D)
    assert quality_increment(pd, pfa, dth, detS, G, M) == pytest.approx(missed_increment(pd))
    assert missed_increment(pd) == pytest.approx(math.log(0.1))


def test_thresholds() -> None:
    T1, T2 = thresholds(alpha=1e-3, beta=1e-2)
    assert T1 == pytest.approx(math.log(1e-2 / (1 - 1e-3)))
    assert T2 == pytest.approx(math.log((1 - 1e-2) / 1e-3))
    assert T1 < 0 < T2


def test_linear_array_sigma_law_and_endfire_cap() -> None:
    s0, head = 0.02, 0.3
    brg = np.array([head + math.pi / 2, head + math.pi / 6, head + 1e-4, head + math.pi])
    amp = np.array([4.0, 9.0, 4.0, 1.0])
    sig = linear_array_sigma(brg, amp, head, s0, endfire=10 * DEG)
    assert sig[0] == pytest.approx(s0 / (1.0 * 2.0))  # broadside
    assert sig[1] == pytest.approx(s0 / (0.5 * 3.0))  # 000 claim 6
    cap = s0 / (math.sin(10 * DEG) * 2.0)
    assert sig[2] == pytest.approx(cap)  # endfire floor
    assert sig[3] == pytest.approx(s0 / math.sin(10 * DEG))


def test_tracker_uses_linear_law_or_constant_sigma() -> None:
    lin = BearingTracker(BB, "linear", 0.02)
    cyl = BearingTracker(BB, "cylindrical", 0.02)
    b, a = np.array([1.0 + math.pi / 2]), np.array([4.0])
    assert lin.bearing_sigma(b, a, 1.0)[0] == pytest.approx(0.01)
    assert cyl.bearing_sigma(b, a, 1.0)[0] == pytest.approx(0.02)


def test_measurement_matrix() -> None:
    H = measurement_matrix(False)
    assert H.tolist() == [[1, 0, 0, 0], [0, 0, 1, 0]]  # 000 H
    Hn = measurement_matrix(True)
    assert Hn.shape == (3, 6) and (Hn @ np.arange(6.0)).tolist() == [0.0, 2.0, 4.0]


def test_first_update_is_joseph_form() -> None:
    tr = BearingTracker(replace(BB, q_theta_quiet=0.0), "cylindrical", 0.02)  # one model: 000 F, Q
    tr.step(0.0, np.array([1.0]), np.array([100.0]), 0.0)
    x0, P0 = tr.table.x[0].copy(), tr.table.P[0].copy()
    T = 5.0
    F = np.array([[1, T, 0, 0], [0, 1, 0, 0], [0, 0, 1, T], [0, 0, 0, 1.0]])
    Q = np.zeros((4, 4))
    for i, q in ((0, BB.q_theta), (2, BB.q_a)):
        Q[i:i + 2, i:i + 2] = q * np.array([[T**3 / 3, T**2 / 2], [T**2 / 2, T]])
    xp, Pp = F @ x0, F @ P0 @ F.T + Q
    z = np.array([1.01, 10 * math.log10(110.0)])
    H = measurement_matrix(False)
    R = np.diag([0.02**2, BB.sigma_amp_db**2])
    K = Pp @ H.T @ np.linalg.inv(H @ Pp @ H.T + R)
    I_KH = np.eye(4) - K @ H
    P_want = I_KH @ Pp @ I_KH.T + K @ R @ K.T  # 000 P^(k/k), Joseph form
    x_want = xp + K @ (z - H @ xp)
    c = tr.step(T, np.array([1.01]), np.array([110.0]), 0.0)
    np.testing.assert_allclose(c.x[0], x_want, rtol=1e-9)
    np.testing.assert_allclose(c.P[0], P_want, rtol=1e-9, atol=1e-15)


def _run_target(brg0: float, rate: float, n: int, tracker: BearingTracker, dt: float = 10.0):
    cycles = []
    for k in range(n):
        b = np.array([(brg0 + rate * k * dt) % (2 * math.pi)])
        cycles.append(tracker.step(k * dt, b, np.array([100.0]), 0.0))
    return cycles


def test_life_cycle_confirm_then_delete_after_misses() -> None:
    tr = BearingTracker(replace(BB, clutter_level_db=0.0, clutter_estimate=False), "cylindrical", 0.01)  # constant P_D
    cycles = _run_target(2.0, 1e-4, 6, tr)
    assert not cycles[0].confirmed.any()
    assert cycles[-1].confirmed.tolist() == [True]
    tid = int(cycles[-1].ids[0])
    L_max = float(cycles[-1].quality[0])
    k, t = 0, 60.0
    while True:  # misses: prediction continues, L falls by ln(1 - P_D) each cycle
        c = tr.step(t + 10.0 * k, np.zeros(0), np.zeros(0), 0.0)
        if c.ids.size == 0:
            break
        assert c.quality[0] == pytest.approx(L_max + (k + 1) * missed_increment(BB.p_d))
        k += 1
    assert k == math.floor(BB.delete_drop / -missed_increment(BB.p_d))
    assert tr.history_of(tid)[0] == "deleted"


def test_tentative_deleted_below_T1() -> None:
    tr = BearingTracker(BB, "cylindrical", 0.01)
    tr.step(0.0, np.array([1.0]), np.array([100.0]), 0.0)
    n = 0
    while len(tr.table):
        n += 1
        tr.step(10.0 * n, np.zeros(0), np.zeros(0), 0.0)
    assert n == math.floor(tr.T1 / missed_increment(BB.p_d)) + 1


def test_time_must_increase() -> None:
    tr = BearingTracker(BB, "cylindrical", 0.01)
    tr.step(5.0, np.array([1.0]), np.array([100.0]), 0.0)
    with pytest.raises(Rejected, match="time_order"):
        tr.step(5.0, np.array([1.0]), np.array([100.0]), 0.0)


def test_crossing_north_is_one_track() -> None:
    tr = BearingTracker(BB, "cylindrical", 0.005)
    ids = set()
    for k in range(80):
        b = (2 * math.pi - 0.1 + 0.0025 * k) % (2 * math.pi)
        c = tr.step(10.0 * k, np.array([b]), np.array([100.0]), 0.0)
        ids |= set(c.ids[c.confirmed].tolist())
    assert ids == {1}
    assert c.x[0, 0] == pytest.approx(-0.1 + 0.0025 * 79) and c.x[0, 1] == pytest.approx(2.5e-4)


@settings(max_examples=25, deadline=None)
@given(
    brg0=st.floats(0.0, 2 * math.pi, exclude_max=True),
    rate=st.floats(-2e-3, 2e-3),
    dt=st.sampled_from([1.0, 10.0, 20.0]),
)
def test_noiseless_target_one_confirmed_track_never_breaks(brg0: float, rate: float, dt: float) -> None:
    tr = BearingTracker(BB, "cylindrical", 0.01)
    cycles = _run_target(brg0, rate, 40, tr, dt)
    first = next(k for k, c in enumerate(cycles) if c.confirmed.any())
    assert first <= 5
    for c in cycles[first:]:
        assert c.ids.tolist() == [1] and c.confirmed.tolist() == [True]
    err = (cycles[-1].x[0, 0] - (brg0 + rate * 39 * dt) + math.pi) % (2 * math.pi) - math.pi
    assert abs(err) < 1e-3


def test_clutter_inside_confirmed_gate_opens_no_track() -> None:
    tr = BearingTracker(BB, "cylindrical", 0.01)
    _run_target(1.0, 0.0, 6, tr)
    c = tr.step(60.0, np.array([1.0, 1.005]), np.array([100.0, 100.0]), 0.0)
    assert c.ids.tolist() == [1]
    c = tr.step(70.0, np.array([1.0, 2.5]), np.array([100.0, 100.0]), 0.0)
    assert c.ids.tolist() == [1, 2]


def test_history_includes_pre_confirmation_part_and_own_ship() -> None:
    tr = BearingTracker(BB, "cylindrical", 0.01)
    for k in range(8):
        c = tr.step(10.0 * k, np.array([1.0]), np.array([100.0]), 0.0, own_x=k, own_y=-k)
        if k == 0:
            assert tr.history_of(1) is None  # tentative: not served
    status, h = tr.history_of(1)
    assert status == "confirmed" and c.confirmed[0]
    np.testing.assert_allclose(h["t"], 10.0 * np.arange(8))
    np.testing.assert_allclose(h["own_x"], np.arange(8.0))
    np.testing.assert_allclose(h["own_y"], -np.arange(8.0))
    assert np.all(h["sbrg"] > 0) and np.allclose(h["brg"], 1.0, atol=1e-6)


def test_multiline_grouping_and_split() -> None:
    g = MultiLineGrouper(2 * DEG, 0.1 * DEG)
    labels = g.step(np.array([NEW, NEW, NEW]), np.array([0.0, 1 * DEG, 90 * DEG]), np.zeros(3))
    assert labels[0] == labels[1] != labels[2]
    # claim 13: line 1 departs from the average of its group -> new multi-line track
    labels2 = g.step(labels, np.array([0.0, 6 * DEG, 90 * DEG]), np.zeros(3))
    assert labels2[2] == labels[2] and labels2[0] != labels2[1]
    assert labels[0] in labels2[:2] and len(set(labels2.tolist())) == 3
    # claim 12: a newly confirmed line joins the existing agreeing group
    labels3 = g.step(np.append(labels2, NEW), np.array([0.0, 6 * DEG, 90 * DEG, 89.5 * DEG]),
                     np.zeros(4))
    assert labels3[3] == labels2[2] and (labels3[:3] == labels2).all()
    # rates must agree too
    labels4 = g.step(np.array([NEW, NEW]), np.array([0.0, 0.0]), np.array([0.0, 1 * DEG]))
    assert labels4[0] != labels4[1]


def test_narrowband_two_lines_one_multiline_track() -> None:
    tr = BearingTracker(NB, "cylindrical", 0.01)
    for k in range(10):
        b = np.array([3.0, 3.0 + 0.002, 5.0])
        c = tr.step(10.0 * k, b, np.full(3, 100.0), 0.0, freq=np.array([50.0, 100.0, 50.0]))
    assert c.confirmed.all() and c.x.shape == (3, 6)
    np.testing.assert_allclose(c.x[:, 4], [50.0, 100.0, 50.0], atol=1e-6)
    groups = sorted(sorted(m.lines.tolist()) for m in c.multiline)
    assert groups == [[1, 2], [3]]
    assert c.ml[0] == c.ml[1] != c.ml[2]


def _converge_until_ambiguous(tr: BearingTracker, rate: float, dt: float = 10.0) -> float:
    """Two noiseless targets converging on bearing 1.0 (+-rate) until both tracks are
    flagged ambiguous (004); returns the time of that scan."""
    k = 0
    while True:
        t = k * dt
        b = np.array([1.0 - 0.05 + rate * t, 1.0 + 0.05 - rate * t])
        c = tr.step(t, b, np.array([100.0, 100.0]), 0.0)
        if c.ambiguous.all():
            return t
        k += 1


def test_track_leaving_memory_mode_drops_a_detection_nearer_another_track() -> None:
    cp = CrossingParams(method="supnorm", S=8.0, max_duration=20.0)
    tr = BearingTracker(BB, "cylindrical", 0.005, cp)
    rate = 5e-5
    t = _converge_until_ambiguous(tr, rate)
    for _ in range(2):  # memory mode up to max_duration
        t += 10.0
        c = tr.step(t, np.array([1.0 - 0.05 + rate * t, 1.0 + 0.05 - rate * t]),
                    np.array([100.0, 100.0]), 0.0)
        assert c.ambiguous.all()
    low, high = np.argsort(c.x[:, 0])
    pred = c.x[:, 0] + c.x[:, 1] * 10.0
    gap = pred[high] - pred[low]
    t += 10.0
    # exit scan (claim 6): the upper target is missed; its own detection is absent and
    # two detections (target and clutter) lie beyond the lower track's prediction
    det = np.array([pred[low] - 0.1 * gap, pred[low] - 0.3 * gap])
    c = tr.step(t, det, np.array([100.0, 100.0]), 0.0)
    assert not c.ambiguous.any()
    assert c.x[high, 0] == pytest.approx(pred[high], abs=1e-12)  # miss, not a jump
    assert c.x[low, 0] < pred[low]
    assert c.ids.size == 2  # the unused detection opens no track
