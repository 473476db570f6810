"""Tests of common.crossing (seed 004 eq. 12, eq. 13, sup-norm test, modes, duration)."""

from __future__ import annotations

import numpy as np
import pytest

from common.crossing import (
    CrossingManager,
    CrossingParams,
    eq13_ambiguous,
    neighbour_sum,
    pairwise_density,
    pairwise_diff,
    progressive_weight,
    proportions,
    supnorm_ambiguous,
)

SIG = 0.01  # bearing noise standard deviation (rad)
COV = np.array([[SIG**2]])
Q = np.array([0.5, 0.5])
TWO_PI = 2.0 * np.pi


def test_pairwise_density_uses_covariance_of_track_j():
    # d = (1, 2) under cov_j = diag(1, 4): d2 = 1 + 1 = 2, g = e^-1 / (2 pi sqrt(4)).
    d = np.array([[[0.0, 0.0], [1.0, 2.0]], [[-1.0, -2.0], [0.0, 0.0]]])
    cov = np.array([np.eye(2), np.diag([1.0, 4.0])])
    g = pairwise_density(d, cov)
    assert g[0, 1] == pytest.approx(0.029274915762159584, rel=1e-12)
    assert g[1, 0] == pytest.approx(np.exp(-2.5) / (2.0 * np.pi), rel=1e-12)


def test_eq13_sum_hand_value():
    # Two tracks 2 sigma apart: sum = 0.5 * exp(-2) / sqrt(2 pi 1e-4) = 2.69954832...
    z = np.array([[0.0], [2.0 * SIG]])
    s = neighbour_sum(z, z, COV, Q)
    np.testing.assert_allclose(s, [2.6995483256594026, 2.6995483256594026], rtol=1e-12)


def test_eq13_threshold_hand_value():
    # eps r = 0.1 * 0.5 / (2 pi) = 0.0079577; equality at d = 3.95644 sigma.
    for sep, expected in [(3.9, True), (3.95, True), (3.96, False), (4.0, False), (10.0, False)]:
        z = np.array([[0.0], [sep * SIG]])
        flags = eq13_ambiguous(z, COV, Q, TWO_PI, 0.1)
        assert flags.tolist() == [expected, expected], sep


def test_eq13_single_track_not_ambiguous():
    assert not eq13_ambiguous(np.array([[0.3]]), COV, np.array([0.5]), TWO_PI, 0.1)[0]


def test_eq12_hand_value():
    # X^0 = 0.01 is 1 sigma from Z^1 = 0.02: g = 24.19707, r = 0.0795775,
    # alpha = r / (r + 0.5 g) = 0.00653447.
    z_pred = np.array([[0.0], [2.0 * SIG]])
    x = np.array([[SIG], [10.0]])
    alpha = progressive_weight(x, z_pred, COV, Q, TWO_PI)
    assert alpha[0] == pytest.approx(0.006534466135117747, rel=1e-10)
    assert alpha[1] == pytest.approx(1.0, abs=1e-12)


def test_supnorm_hand_value():
    # |2| / 1 = 2 and |0.5| / 0.1 = 5: sup = 5.
    z = np.array([[0.0, 0.0], [2.0, 0.5]])
    cov = np.diag([1.0, 0.01])
    assert supnorm_ambiguous(z, cov, 3.0).tolist() == [False, False]
    assert supnorm_ambiguous(z, cov, 6.0).tolist() == [True, True]


def test_proportions_hand_value():
    # (3 + 0.5 * 2) / (12 + 2) = 2/7, and a track owning every point is clipped.
    q = proportions(np.array([3.0, 100.0]), np.array([12.0, 100.0]), 0.5, 2.0, 0.95)
    np.testing.assert_allclose(q, [2.0 / 7.0, 0.95])


def test_wrapped_difference_across_north():
    z = np.array([[TWO_PI - 0.005], [0.005]])
    d = pairwise_diff(z, z, angle_idx=[0])
    assert d[0, 1, 0] == pytest.approx(-0.01, abs=1e-12)
    assert eq13_ambiguous(z, COV, Q, TWO_PI, 0.1, angle_idx=[0]).all()
    assert not eq13_ambiguous(z, COV, Q, TWO_PI, 0.1).any()
    assert supnorm_ambiguous(z, COV, 3.0, angle_idx=[0]).all()


def test_far_tracks_get_alpha_one():
    for mode in ("memory", "progressive"):
        mgr = CrossingManager(CrossingParams(mode=mode))
        z = np.array([[0.0], [0.5], [1.0]])
        alpha, amb = mgr.step(0.0, [1, 2, 3], z, COV, z_meas=z + 0.001, n_meas=3)
        assert not amb.any()
        np.testing.assert_array_equal(alpha, [1.0, 1.0, 1.0])


def _bearings(t: float) -> np.ndarray:
    """Two straight bearing tracks crossing at t = 50 s (0.002 rad/s each)."""
    return np.array([[-0.1 + 0.002 * t], [0.1 - 0.002 * t]])


@pytest.mark.parametrize("method", ["eq13", "supnorm"])
def test_flag_during_crossing_only(method):
    mgr = CrossingManager(CrossingParams(method=method, mode="memory", max_duration=1e3))
    flags = {}
    for t in np.arange(0.0, 101.0, 1.0):
        z = _bearings(t)
        alpha, amb = mgr.step(t, [7, 8], z, COV, z_meas=z, n_meas=2, angle_idx=[0])
        np.testing.assert_array_equal(alpha, np.where(amb, 0.0, 1.0))
        flags[t] = amb
    assert not flags[0.0].any() and not flags[30.0].any()
    assert flags[50.0].all() and flags[48.0].all() and flags[52.0].all()
    assert not flags[70.0].any() and not flags[100.0].any()


def test_progressive_alpha_falls_then_rises():
    mgr = CrossingManager(CrossingParams(mode="progressive", max_duration=1e3))
    alphas = []
    for t in np.arange(0.0, 101.0, 1.0):
        z = _bearings(t)
        alpha, _ = mgr.step(t, [7, 8], z, COV, z_meas=z, n_meas=2)
        alphas.append(alpha[0])
    alphas = np.array(alphas)
    assert alphas[0] == 1.0 and alphas[-1] == 1.0
    assert alphas[50] < 1e-2
    assert np.all(np.diff(alphas[40:51]) <= 0.0)
    assert np.all(np.diff(alphas[50:61]) >= 0.0)
    assert np.all((alphas > 0.0) & (alphas <= 1.0))


def test_max_duration_releases_and_rearms():
    mgr = CrossingManager(CrossingParams(max_duration=5.0))
    together = np.array([[0.0], [0.0]])
    apart = np.array([[0.0], [1.0]])
    out = [mgr.step(float(t), [1, 2], together, COV) for t in range(11)]
    assert all(amb.all() for _, amb in out[:6])
    assert all(not amb.any() for _, amb in out[6:])
    np.testing.assert_array_equal(out[-1][0], [1.0, 1.0])
    assert not mgr.step(11.0, [1, 2], apart, COV)[1].any()
    alpha, amb = mgr.step(12.0, [1, 2], together, COV)
    assert amb.all() and not alpha.any()


def test_forget_resets_clock():
    mgr = CrossingManager(CrossingParams(max_duration=5.0))
    together = np.array([[0.0], [0.0]])
    for t in range(10):
        mgr.step(float(t), [1, 2], together, COV)
    assert not mgr.step(10.0, [1, 2], together, COV)[1].any()
    mgr.forget([1, 2])
    assert mgr.step(11.0, [1, 2], together, COV)[1].all()


def test_counts_update_proportions_used_by_eq12():
    p = CrossingParams(mode="progressive")
    mgr = CrossingManager(p)
    z_far = np.array([[0.0], [1.0]])
    for t in range(3):
        mgr.step(float(t), [1, 2], z_far, COV, z_meas=z_far, n_meas=4)
    # q = (3 + 1) / (12 + 2) = 2/7 for both tracks at the next step.
    z = np.array([[0.0], [2.0 * SIG]])
    x = np.array([[SIG], [SIG]])
    alpha, amb = mgr.step(3.0, [1, 2], z, COV, z_meas=x, n_meas=4)
    q = np.full(2, 2.0 / 7.0)
    assert amb.all()
    np.testing.assert_allclose(alpha, progressive_weight(x, z, COV, q, p.volume))
    assert alpha[0] != pytest.approx(0.006534466135117747, rel=1e-3)
