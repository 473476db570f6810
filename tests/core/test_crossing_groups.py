"""Tests of common.core.crossing_groups: the groups of tracks crossing together (links of
004 eq. 13 and of the sup-norm test) and the V of a pair's separations."""

from __future__ import annotations

import math

import numpy as np
import pytest

from common.core.crossing import CrossingManager, CrossingParams, eq13_test, supnorm_test
from common.core.crossing_groups import ambiguity_groups, crossing_time

SIG = math.radians(1.0)
COV = np.array([[SIG**2]])


def test_groups_are_the_connected_components_of_the_links() -> None:
    labels = ambiguity_groups(5, np.array([0, 1, 3]), np.array([1, 2, 4]))
    assert labels[0] == labels[1] == labels[2] != labels[3] == labels[4]
    assert len(set(ambiguity_groups(3, np.zeros(0, int), np.zeros(0, int)).tolist())) == 3


def test_eq13_links_chain_three_tracks_whose_outer_two_are_not_neighbours() -> None:
    """Tracks 3 sigma apart are linked by one term of eq. 13 (q = 0.5: a term alone exceeds
    eps r within 3.8 sigma), 6 sigma apart they are not: the group holds all three."""
    z = np.radians([[10.0], [13.0], [16.0], [60.0]])
    q = np.full(4, 0.5)
    amb, k, j = eq13_test(z, COV, q, 2 * math.pi, 0.1)
    assert amb.tolist() == [True, True, True, False]
    assert (0, 2) not in set(zip(k.tolist(), j.tolist()))
    labels = ambiguity_groups(4, k, j)
    assert labels[0] == labels[1] == labels[2] != labels[3]
    _, k, j = supnorm_test(z, COV, 3.5)
    assert len(set(ambiguity_groups(4, k, j)[:3].tolist())) == 1


def test_the_manager_publishes_the_groups_of_its_last_step() -> None:
    m = CrossingManager(CrossingParams())
    m.step(0.0, [7, 8, 9], np.radians([[10.0], [13.0], [40.0]]), COV, angle_idx=[0])
    assert m.groups[0] == m.groups[1] != m.groups[2]


def test_the_v_of_a_crossing_has_its_apex_at_the_crossing() -> None:
    rng = np.random.default_rng(1)
    t = np.arange(0.0, 300.0, 5.0)
    a = np.abs(np.radians(2.0 / 60.0) * (t - 170.0) + SIG * np.sqrt(2) * rng.standard_normal(t.size))
    tc, rms = crossing_time(t, a)
    assert tc == pytest.approx(170.0, abs=20.0)
    assert rms < 2.0 * SIG


def test_separations_that_only_shrink_put_the_apex_after_the_last_sample() -> None:
    t = np.arange(0.0, 100.0, 5.0)
    tc, _ = crossing_time(t, np.radians(4.0) - np.radians(0.02) * t)
    assert tc > t[-1]
    assert math.isnan(crossing_time(t[:2], t[:2])[0])
