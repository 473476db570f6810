"""Tests of common.evaluation.metrics on hand-computed cases."""

from __future__ import annotations

import math

import numpy as np
import pytest

from common.evaluation.metrics import (
    MetricsAccumulator,
    SwitchCounts,
    count_switches,
    gospa,
    ospa,
    switching_cost,
)


def test_gospa_perfect_match_is_zero():
    r = gospa([[0.0, 0.0], [5.0, 5.0]], [[5.0, 5.0], [0.0, 0.0]], c=10.0)
    assert r.distance == 0.0
    assert sorted(zip(r.rows.tolist(), r.cols.tolist())) == [(0, 1), (1, 0)]


def test_gospa_one_missed_target_costs_half_c_power_p():
    r = gospa([[0.0, 0.0], [100.0, 100.0]], [[0.0, 0.0]], c=10.0, p=2.0)
    assert r.missed == 50.0 and r.false == 0.0 and r.localisation == 0.0
    assert r.distance == pytest.approx(math.sqrt(50.0))


def test_gospa_one_false_track_p1():
    r = gospa(np.empty((0, 2)), [[1.0, 1.0]], c=4.0, p=1.0)
    assert r.false == 2.0 and r.missed == 0.0
    assert r.distance == pytest.approx(2.0)


def test_gospa_localisation_and_cutoff():
    r = gospa([[0.0, 0.0]], [[3.0, 4.0]], c=10.0)
    assert r.localisation == pytest.approx(25.0) and r.distance == pytest.approx(5.0)
    far = gospa([[0.0, 0.0]], [[20.0, 0.0]], c=10.0)
    assert far.rows.size == 0
    assert (far.missed, far.false) == (50.0, 50.0)
    assert far.distance == pytest.approx(10.0)


def test_gospa_optimal_assignment():
    r = gospa([[0.0, 0.0], [10.0, 0.0]], [[9.0, 0.0], [1.0, 0.0]], c=5.0)
    assert r.localisation == pytest.approx(2.0)
    assert r.distance == pytest.approx(math.sqrt(2.0))


def test_ospa_hand_values():
    # n = 1, m = 2: ((25 + 100) / 2)^(1/2).
    assert ospa([[0.0, 0.0]], [[3.0, 4.0], [100.0, 0.0]], c=10.0) == pytest.approx(math.sqrt(62.5))
    assert ospa(np.empty((0, 2)), np.empty((0, 2)), c=10.0) == 0.0
    assert ospa([[0.0, 0.0]], np.empty((0, 2)), c=10.0) == pytest.approx(10.0)
    g = gospa([[0.0, 0.0]], [[3.0, 4.0], [100.0, 0.0]], c=10.0)
    assert g.distance == pytest.approx(math.sqrt(75.0))


def test_switch_counted_once_not_at_every_later_step():
    c = count_switches([{1: 7}, {1: 7}, {1: 8}, {1: 8}, {1: 8}])
    assert c == SwitchCounts(switches=1, breaks=0, full=1, half=0)


def test_swap_between_two_truths_counts_one_switch_per_truth():
    c = count_switches([{1: 7, 2: 8}, {1: 7, 2: 8}, {1: 8, 2: 7}, {1: 8, 2: 7}])
    assert c == SwitchCounts(switches=2, breaks=0, full=2, half=0)


def test_events_before_start_are_not_counted_but_set_the_state():
    series = [{1: 7, 2: 5}, {1: 8, 2: None}, {1: 8, 2: 9}, {1: 9, 2: 9}]
    assert count_switches(series) == SwitchCounts(switches=3, breaks=1, full=2, half=2)
    # from step 2: truth 2's new number after the gap (5 -> 9) and truth 1's 8 -> 9
    assert count_switches(series, start=2) == SwitchCounts(switches=2, breaks=0, full=1, half=1)
    assert count_switches(series, start=4) == SwitchCounts(0, 0, 0, 0)


def test_breaks():
    assert count_switches([{1: 7}, {1: None}, {1: 7}]) == SwitchCounts(0, 1, 0, 2)
    assert count_switches([{1: 7}, {1: None}, {1: 8}]) == SwitchCounts(1, 1, 0, 2)
    # A truth leaving the scene is not a break; a new number after a gap is a switch.
    assert count_switches([{1: 7}, {}, {1: 8}]) == SwitchCounts(1, 0, 0, 0)
    assert count_switches([{1: 7, 2: 8}, {1: 7}]) == SwitchCounts(0, 0, 0, 0)


def test_switching_cost():
    assert switching_cost(SwitchCounts(1, 1, 1, 2), gamma=2.0, p=2.0) == pytest.approx(8.0)


def test_accumulator_crossing_with_swap_and_loss():
    acc = MetricsAccumulator(c=10.0, p=2.0, gamma=4.0)
    truths = np.array([[0.0, 0.0], [20.0, 0.0]])
    acc.add(0.0, [1, 2], truths, [7, 8], [[1.0, 0.0], [20.0, 2.0]])
    acc.add(1.0, [1, 2], truths, [7, 8], [[20.0, 0.0], [0.0, 1.0]])
    acc.add(2.0, [1, 2], truths, [8], [[0.0, 0.0]])
    s = acc.summary()
    assert acc.associations == [{1: 7, 2: 8}, {1: 8, 2: 7}, {1: 8, 2: None}]
    assert s.steps == 3
    assert (s.localisation, s.missed, s.false) == pytest.approx((6.0, 50.0, 0.0))
    assert (s.switches, s.breaks) == (2, 1)
    assert s.switching == pytest.approx(16.0 * 2.5)
    assert s.gospa == pytest.approx(math.sqrt(96.0))
    assert s.mean_gospa == pytest.approx((math.sqrt(5.0) + 1.0 + math.sqrt(50.0)) / 3.0)
    assert s.mean_ospa == pytest.approx((math.sqrt(2.5) + math.sqrt(0.5) + math.sqrt(50.0)) / 3.0)
    assert s.rmse == pytest.approx({1: math.sqrt(2.0 / 3.0), 2: math.sqrt(2.0)})


def test_accumulator_rejects_non_increasing_time():
    acc = MetricsAccumulator(c=10.0)
    acc.add(1.0, [1], [[0.0, 0.0]], [], np.empty((0, 2)))
    with pytest.raises(ValueError):
        acc.add(1.0, [1], [[0.0, 0.0]], [], np.empty((0, 2)))
