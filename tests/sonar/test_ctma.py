"""Tests for common.sonar.tma.constrained and common.sonar.tma.bounds (seed 003): CTMA, residual
factor, edge checks, correction, convergence."""

from __future__ import annotations

import numpy as np
import pytest

from common.sonar.tma.bearings_only import solve_tma
from common.sonar.tma.bounds import (
    MINIMAL_BOUNDS,
    Bounds,
    edge_flags,
    effective_bounds,
    recentre,
    rkv,
    state_bounds,
)
from common.sonar.tma.constrained import (
    ConvergenceDetector,
    CtmaParams,
    TmaTracker,
    residual_alarm,
    residual_factor,
    solve_ctma,
)
from common.sonar.tma.crlb import position_rms_bound
from tests.sonar.test_tma import BETA, BETA2, KN, OWN, SIG, TM, T, pos_at, true_bearings

D = np.radians
CFG = CtmaParams()


def test_bounds_contains_wrapping_course():
    b = Bounds(1000.0, 2000.0, D(300.0), D(60.0), 1.0, 5.0)
    assert b.course_width == pytest.approx(D(120.0))
    assert b.contains(1500.0, 0.0, 2.0)
    assert not b.contains(1500.0, D(180.0), 2.0)
    assert not b.contains(2500.0, 0.0, 2.0)
    assert not b.contains(1500.0, 0.0, 6.0)
    assert MINIMAL_BOUNDS.contains(1500.0, D(359.0), 2.0)


def test_residual_factor_hand_value():
    assert residual_factor(np.array([0.1, -0.2]), np.array([0.05, -0.05]), 1.0) == pytest.approx(3.0)
    assert residual_factor(np.array([0.1, -0.2]), np.array([0.05, -0.05]), np.array([1.0, 2.0])) == pytest.approx(
        0.2 / 0.075)


@pytest.mark.parametrize("q, alarm", [
    ([2.5], True), ([1.9], False), ([1.6, 1.6], True), ([1.4, 1.6], False),
    ([1.3, 1.3, 1.3], True), ([1.3, 1.3], False), ([1.3, 1.0, 1.3], False),
])
def test_residual_alarm_three_thresholds(q, alarm):
    assert residual_alarm(q, CFG) is alarm


def test_edge_flags():
    b = Bounds(1000.0, 2000.0, D(0.0), D(180.0), 1.0, 3.0)
    assert list(edge_flags(1500.0, D(90.0), 2.0, b, 0.02)) == [False, False, False]
    assert list(edge_flags(1010.0, D(179.0), 3.0, b, 0.02)) == [True, True, True]
    assert list(edge_flags(1500.0, D(270.0), 0.5, b, 0.02)) == [False, True, True]
    assert not edge_flags(1500.0, 0.0, 2.0, MINIMAL_BOUNDS, 0.02)[1]


def test_state_and_effective_bounds_hand_values():
    b = Bounds(1000.0, 2000.0, D(30.0), D(60.0), 1.0, 2.0)
    lo, hi = state_bounds(b, np.zeros(2), 0.0)
    s30, s60 = np.sin(D(30.0)), np.sin(D(60.0))
    assert lo == pytest.approx([0.0, 1000.0, s30, s30])
    assert hi == pytest.approx([0.0, 2000.0, 2 * s60, 2 * s60])
    eff = effective_bounds(lo, hi, np.zeros(2))
    assert (eff.r_min, eff.r_max) == pytest.approx((1000.0, 2000.0))
    assert (eff.v_min, eff.v_max) == pytest.approx((np.hypot(s30, s30), np.hypot(2 * s60, 2 * s60)))
    assert (eff.k_min, eff.k_max) == pytest.approx((np.arctan2(s30, 2 * s60), np.arctan2(2 * s60, s30)))
    quarter = Bounds(1000.0, 2000.0, 0.0, D(90.0), 1.0, 2.0)
    wide = effective_bounds(*state_bounds(quarter, np.zeros(2), 0.0), np.zeros(2))
    assert wide.v_min == 0.0 and wide.course_width == pytest.approx(2 * np.pi)


def test_recentre_correction_module():
    b = Bounds(1000.0, 3000.0, D(0.0), D(180.0), 1.0, 3.0)
    out = recentre(b, np.array([False, True, True]), 2000.0, D(180.0), 3.0)
    assert (out.v_min, out.v_max) == pytest.approx((2.0, 4.0))
    assert (out.k_min, out.k_max) == pytest.approx((D(90.0), D(270.0)))
    assert (out.r_min, out.r_max) == (1000.0, 3000.0)
    low = recentre(b, np.array([True, False, False]), 200.0, 0.0, 2.0)
    assert (low.r_min, low.r_max) == pytest.approx((100.0, 2100.0))


def test_convergence_detector_relative_spread():
    det = ConvergenceDetector(window=3, threshold=0.05)
    s = np.array([1000.0, 0.0, 0.0, 1.0])
    assert det.update(0.0, np.zeros(2), s) == "pre"
    assert det.update(10.0, np.zeros(2), s + [0.0, 10.0, 0.0, 0.0]) == "pre"
    assert det.update(20.0, np.zeros(2), None) == "pre" and det.roc == np.inf
    jumpy = ConvergenceDetector(window=3, threshold=0.05)
    for k, r in enumerate((1000.0, 2000.0, 1000.0)):
        assert jumpy.update(float(k), np.zeros(2), np.array([r, 0.0, 0.0, 0.0])) == "pre"
    assert jumpy.roc == pytest.approx(np.std([1000, 2000, 1000]) / np.mean([1000, 2000, 1000]))
    still = ConvergenceDetector(window=3, threshold=0.05)
    for k in range(3):
        ph = still.update(10.0 * k, np.zeros(2), np.array([1000.0, 10.0 * k, 0.0, 1.0]))
    assert ph == "post" and still.roc == pytest.approx(0.0, abs=1e-12)


def test_ctma_equals_tma_inside_bounds_and_sits_on_edge_outside():
    b = true_bearings(BETA)
    tma = solve_tma(T, b, SIG, OWN, 0.0)
    inside = solve_ctma(T, b, SIG, OWN, 0.0, Bounds(500.0, 20e3, D(180.0), D(260.0), 2 * KN, 6 * KN), tma)
    assert inside.beta == pytest.approx(BETA, abs=0.05)
    bad = Bounds(500.0, 20e3, D(180.0), D(260.0), 1 * KN, 3 * KN)
    out = solve_ctma(T, b, SIG, OWN, 0.0, bad, tma)
    r, k, v = rkv(out.state_at(T[-1])[0], OWN[-1])
    assert v == pytest.approx(3 * KN, rel=1e-6)
    assert bad.contains(r, k, v)
    assert residual_factor(out.residuals, tma.residuals + 1e-3, SIG) > 1.0


def test_ctma_with_two_legs_bounds_current_leg():
    b = true_bearings(BETA2, (TM,))
    tma = solve_tma(T, b, SIG, OWN, 0.0, legs=(TM,))
    out = solve_ctma(T, b, SIG, OWN, 0.0, Bounds(500.0, 20e3, D(250.0), D(350.0), 2 * KN, 6 * KN), tma, legs=(TM,))
    assert out.beta == pytest.approx(BETA2, abs=0.1)


def run_tracker(bounds: Bounds | None, seed: int, cfg: CtmaParams = CFG, legs: tuple[float, ...] = ()):
    rng = np.random.default_rng(seed)
    b = true_bearings(BETA2 if legs else BETA, legs) + SIG * rng.standard_normal(T.size)
    trk = TmaTracker(bounds, cfg)
    outs = [trk.update(T[i], b[i], SIG, OWN[i]) for i in range(T.size)]
    assert outs[:3] == [None] * 3
    return outs[3:]


def test_tracker_output_fields_and_correct_bounds_untouched():
    good = Bounds(1000.0, 30e3, D(150.0), D(300.0), 2 * KN, 8 * KN)
    outs = run_tracker(good, 1)
    o = outs[-1]
    assert o.t == T[-1] and o.P.shape == (4, 4) and o.phase == "post"
    assert not any(x.bounds_modified for x in outs)
    assert o.bounds == good and not o.constrained and o.residual_factor == 1.0
    assert o.range == pytest.approx(np.hypot(o.x - OWN[-1, 0], o.y - OWN[-1, 1]))
    assert o.speed == pytest.approx(4 * KN, rel=0.15)


@pytest.mark.parametrize("wrong, runs", [
    (Bounds(1000.0, 30e3, D(0.0), D(180.0), 1 * KN, 3 * KN), 40),
    (Bounds(1000.0, 30e3, D(150.0), D(300.0), 1 * KN, 3 * KN), 20),
    (Bounds(1000.0, 30e3, D(240.0), D(30.0), 1 * KN, 8 * KN), 20),
])
@pytest.mark.slow
def test_wrong_bounds_detected_and_corrected_monte_carlo(wrong: Bounds, runs: int):
    truth = pos_at(BETA, T[-1])
    err = []
    for seed in range(runs):
        outs = run_tracker(wrong, 100 + seed)
        post = [k + 4 for k, o in enumerate(outs) if o.phase == "post"]
        assert post and post[0] > 16
        for o in outs:
            if o.phase == "pre":
                assert o.bounds == wrong and not o.bounds_modified
                assert wrong.v_min - 1e-6 <= o.speed <= wrong.v_max + 1e-6
                assert (o.course - wrong.k_min + 1e-6) % (2 * np.pi) <= wrong.course_width + 2e-6
        final = outs[-1]
        assert any(o.bounds_modified for o in outs)
        assert final.bounds.contains(final.range, final.course, final.speed)
        assert final.bounds.v_min - 1e-6 <= 4 * KN <= final.bounds.v_max + 1e-6
        assert (D(220.0) - final.bounds.k_min + 1e-6) % (2 * np.pi) <= final.bounds.course_width + 2e-6
        err.append(np.hypot(final.x - truth[0], final.y - truth[1]))
    ratio = np.sqrt(np.mean(np.square(err))) / position_rms_bound(BETA, T, OWN, SIG, 0.0, T[-1])
    assert ratio <= 1.5


def test_hopeless_bounds_fall_back_to_minimal_bounds():
    narrow = Bounds(20e3, 20.1e3, D(0.0), D(10.0), 1 * KN, 1.1 * KN)
    outs = run_tracker(narrow, 5)
    assert outs[-1].bounds == MINIMAL_BOUNDS
    assert not outs[-1].constrained
    first = next(o for o in outs if o.bounds == MINIMAL_BOUNDS)
    assert first.phase == "post" and first.bounds_modified


def test_tracker_detects_target_manoeuvre():
    cfg = CtmaParams(detect_manoeuvres=True)
    outs = run_tracker(None, 21, cfg, legs=(TM,))
    assert len(outs[-1].legs) == 1 and abs(outs[-1].legs[0] - TM) <= 120.0
    assert outs[-1].speed == pytest.approx(4 * KN, rel=0.3)
