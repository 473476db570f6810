"""Tests of common.evaluation.pcrlb: the recursive information matrix against the equivalent
EKF covariance recursion, channel information, NEES helpers."""

from __future__ import annotations

import numpy as np
import pytest

from common.core import kalman
from common.core.motion import cv_F, cv_Q
from common.evaluation.pcrlb import (
    Evaluation,
    channel_information,
    mean_nees_interval,
    nees,
    pcrlb,
    score_targets,
)
from common.radar.geometry.bistatic import POS, project_jacobian

RX = np.zeros((3, 3))
TX = np.array([[-35000.0, 20000.0, 0.0], [45000.0, 10000.0, 0.0], [5000.0, -52000.0, 0.0]])


def _trajectory(K: int) -> tuple[np.ndarray, np.ndarray]:
    t = np.arange(K, dtype=float)
    s = np.zeros((K, 2, 6))
    s[:, 0, POS] = np.array([-30000.0, 50000.0, 9000.0]) + np.outer(t, [200.0, -50.0, 0.0])
    s[:, 0, [1, 3, 5]] = [200.0, -50.0, 0.0]
    s[:, 1, POS] = np.array([50000.0, -20000.0, 7000.0]) + np.outer(t, [-120.0, 160.0, 0.0])
    s[:, 1, [1, 3, 5]] = [-120.0, 160.0, 0.0]
    return t, s


def test_information_recursion_equals_riccati_on_truth() -> None:
    t, s = _trajectory(30)
    present = np.ones((30, 2), dtype=bool)
    present[:10, 1] = False  # the second target appears at k = 10
    info = np.stack([channel_information(np.array([0.9, 0.8]), np.array([150.0, 200.0]),
                                         np.array([1.5, 2.0]), np.radians([1.0, 2.0]))] * 3)
    P0 = np.diag([1e6, 1e4, 1e6, 1e4, 1e6, 1e2])
    B = pcrlb(t, s, present, TX, RX, info, 4.0, 1.0, P0)
    assert np.isnan(B[:10, 1]).all() and np.isfinite(B[10:, 1]).all()
    R = np.linalg.inv(info[0])
    for j, k0 in ((0, 0), (1, 10)):
        P = P0.copy()
        for k in range(k0, 30):
            if k > k0:
                _, P = kalman.predict(np.zeros((1, 6)), P[None], cv_F(1.0), cv_Q(1.0, 4.0, 1.0))
                P = P[0]
            H = np.concatenate([project_jacobian(s[k, j][None], TX[b], RX[b])[0] for b in range(3)])
            Rb = np.kron(np.eye(3), R)
            _, P, _, _ = kalman.update(np.zeros((1, 6)), P[None], np.zeros((1, 9)), H, Rb)
            P = P[0]
            np.testing.assert_allclose(B[k, j], P, rtol=1e-6, atol=1e-9)
    # more information never loosens the bound
    B2 = pcrlb(t, s, present, TX, RX, 2 * info, 4.0, 1.0, P0)
    assert np.all(np.trace(B2[-1, :, :, :], axis1=1, axis2=2) < np.trace(B[-1], axis1=1, axis2=2))


def test_channel_information_sums_pd_weighted_inverses() -> None:
    I = channel_information(np.array([0.5, 1.0]), np.array([100.0, 200.0]),
                            np.array([1.0, 2.0]), np.array([0.01, 0.02]))
    np.testing.assert_allclose(np.diag(I), [0.5 / 1e4 + 1 / 4e4, 0.5 + 0.25, 0.5e4 + 0.25e4])


def test_nees_and_interval() -> None:
    rng = np.random.default_rng(0)
    P = np.array([[4.0, 1.0], [1.0, 2.0]])
    e = rng.multivariate_normal([0, 0], P, 20000)
    n = nees(e, np.broadcast_to(P, (20000, 2, 2)))
    lo, hi = mean_nees_interval(2, 20000)
    assert lo <= n.mean() <= hi
    assert mean_nees_interval(3, 100) == pytest.approx((2.539, 3.499), abs=1e-3)  # chi2(300)/100


def test_score_targets_ratio_for_bound_sized_errors() -> None:
    t, s = _trajectory(40)
    info = np.stack([np.diag([1 / 60.0**2, 1 / 0.5, 1 / np.radians(0.5) ** 2])] * 3)
    P0 = np.diag([1e6, 1e4, 1e6, 1e4, 1e6, 1e2])
    B = pcrlb(t, s, np.ones((40, 2), bool), TX, RX, info, 4.0, 1.0, P0)
    rng = np.random.default_rng(3)
    ev = Evaluation(c=5000.0, gamma=5000.0)
    for k in range(40):  # estimates drawn from the bound itself: ratio ~ 1, NEES ~ 3 / 6
        est = np.stack([rng.multivariate_normal(s[k, j], B[k, j]) for j in range(2)])
        ev.add(t[k], np.array([1, 2]), s[k], np.array([7, 8]), est, B[k])
    sc = score_targets(ev, TX, RX, info, 4.0, 1.0, P0, settle=10.0)
    assert set(sc) == {1, 2}
    for v in sc.values():
        assert v.n == 30 and 0.7 < v.rmse / v.bound < 1.3
        assert 1.5 < v.nees_pos < 4.5


def test_joint_pairs_score_a_truth_against_its_own_track() -> None:
    """Truth 1's track 7 is 1.5 km off in altitude (sigma 1 km: consistent); at one scan
    a neighbour's track 8 (for truth 2, which leaves the scene) is nearer truth 1 in 3-D.
    Per-step GOSPA pairs truth 1 with 8 there (NEES of a foreign track); the series of
    the trajectory assignment keeps it on 7."""
    P = np.diag([30.0, 5.0, 30.0, 5.0, 1000.0, 5.0]) ** 2
    ev = Evaluation(c=2000.0, gamma=2000.0, keep_steps=True)
    truth = np.array([[0.0, 0.0, 0.0, 0.0, 3000.0, 0.0], [5000.0, 0, 0, 0, 3000.0, 0]])
    for k in range(6):
        own = truth[0] + [0, 0, 0, 0, -1500.0, 0]
        if k == 3:  # truth 2 gone, its track passes 1 km from truth 1
            ev.add(float(k), np.array([1]), truth[:1], np.array([7, 8]),
                   np.stack([own, truth[0] + [1000.0, 0, 0, 0, 0, 0]]), np.stack([P, P]))
        else:
            ev.add(float(k), np.array([1, 2]), truth, np.array([7, 8]), np.stack([own, truth[1]]),
                   np.stack([P, P]))
    step = ev.after(0.0)[1]
    joint = ev.after(0.0, ev.metrics.joint_associations())[1]
    assert step[:, 1].max() > 1000.0  # track 8 against truth 1: (1000 / 30)^2
    assert joint.shape[0] == 6 and np.allclose(joint[:, 1], 2.25)  # (1500 / 1000)^2


def test_per_target_pd_scales_each_base_information() -> None:
    t, s = _trajectory(20)
    present = np.ones((20, 2), dtype=bool)
    info = np.stack([channel_information(np.ones(1), np.array([300.0]), np.array([0.5]),
                                         np.array([np.inf]))] * 3)
    P0 = np.diag([1e8, 1e4, 1e8, 1e4, 1e8, 1e4])
    pd = np.full((20, 2, 3), 0.7)
    np.testing.assert_allclose(pcrlb(t, s, present, TX, RX, info, 1.0, 0.25, P0, pd),
                               pcrlb(t, s, present, TX, RX, 0.7 * info, 1.0, 0.25, P0), rtol=1e-9)
    pd[:, 1, 2] = 0.0  # base 3 never sees the second target: as if it had no base 3
    B = pcrlb(t, s, present, TX, RX, info, 1.0, 0.25, P0, pd)
    B2 = pcrlb(t, s, present, TX[:2], RX[:2], 0.7 * info[:2], 1.0, 0.25, P0)
    np.testing.assert_allclose(B[:, 1], B2[:, 1], rtol=1e-9)
