"""Retrodiction of the 000 multiple-hypothesis mode (common.sonar.mht.retrodiction)."""

import math

import numpy as np

from common.core.motion import bearing_F, bearing_Q
from common.sonar.mht.retrodiction import CycleRecord, Retrodiction, smooth

H = np.array([[1.0, 0, 0, 0], [0, 0, 1.0, 0]])
R = np.diag([1e-4, 4.0])


def _filter(n: int, seed: int = 0):
    """Kalman filter of a straight bearing track; per cycle (x, P, x_pre, P_pre, F)."""
    rng = np.random.default_rng(seed)
    F, Q = bearing_F(10.0), bearing_Q(10.0, 1e-9, 1e-4)
    x, P = np.array([1.0, 0.0, 10.0, 0.0]), np.diag([1e-4, 1e-6, 4.0, 1e-2])
    out = [(x, P, x, P, np.eye(4))]
    for k in range(1, n):
        xp, Pp = F @ x, F @ P @ F.T + Q
        z = np.array([1.0 + 2e-4 * 10 * k, 10.0]) + rng.normal(0, [1e-2, 2.0])
        S = H @ Pp @ H.T + R
        K = Pp @ H.T @ np.linalg.inv(S)
        x, P = xp + K @ (z - H @ xp), Pp - K @ S @ K.T
        out.append((x, P, xp, Pp, F))
    return out


def _records(steps):
    recs = []
    for k, (x, P, xp, Pp, F) in enumerate(steps):
        recs.append(CycleRecord(x[None], P[None], np.ones(1), np.zeros(1, dtype=np.intp),
                                np.array([7]), np.array([0 if k else -1]), xp[None], Pp[None], F,
                                np.array([[10.0 * k, x[0], math.sqrt(P[0, 0]), 0.0, 0.0, np.nan, np.nan]]),
                                np.array([[x[0] + 0.01, 0.02]])))
    return recs


def test_single_hypothesis_retrodiction_is_the_rts_smoother():
    steps = _filter(8)
    got = smooth(_records(steps))
    xs, Ps = steps[-1][0], steps[-1][1]
    for k in range(len(steps) - 2, -1, -1):  # textbook Rauch-Tung-Striebel
        x, P = steps[k][0], steps[k][1]
        xp, Pp, F = steps[k + 1][2], steps[k + 1][3], steps[k + 1][4]
        W = P @ F.T @ np.linalg.inv(Pp)  # 000 W = P F' P^pre^-1
        xs, Ps = x + W @ (xs - xp), P + W @ (Ps - Pp) @ W.T
        np.testing.assert_allclose(got[k][0][0], xs, rtol=1e-9, atol=1e-12)
        np.testing.assert_allclose(got[k][1][0], Ps, rtol=1e-7, atol=1e-14)
        assert got[k][2][0] == 1.0
        assert Ps[0, 0] <= steps[k][1][0, 0]


def test_retro_weight_is_the_sum_of_the_children_weights():
    steps = _filter(2)
    (x0, P0, *_), (x1, P1, xp, Pp, F) = steps
    r0 = CycleRecord(np.stack([x0, x0 + 0.01]), np.stack([P0, P0]), np.array([0.5, 0.5]),
                     np.zeros(2, dtype=np.intp), np.array([1]), np.array([-1, -1]),
                     np.stack([x0, x0]), np.stack([P0, P0]), F, np.zeros((1, 7)), np.zeros((2, 2)))
    r1 = CycleRecord(np.stack([x1, x1, x1]), np.stack([P1] * 3), np.array([0.2, 0.3, 0.5]),
                     np.zeros(3, dtype=np.intp), np.array([1]), np.array([0, 0, 1]),
                     np.stack([xp] * 3), np.stack([Pp] * 3), F, np.zeros((1, 7)), np.zeros((3, 2)))
    out = smooth([r0, r1])
    np.testing.assert_allclose(out[0][2], [0.5, 0.5])  # 000 c^retro = sum of children
    r1.c[:] = [0.1, 0.1, 0.8]
    np.testing.assert_allclose(smooth([r0, r1])[0][2], [0.2, 0.8])


def test_register_rows_are_retrodicted_inside_the_window_and_frozen_after():
    steps = _filter(12, seed=2)
    recs = _records(steps)
    rd = Retrodiction(n_retro=4)
    seen = []
    for rec in recs:
        rd.push(rec)
        seen.append(rd.smoothed(7)["brg"].copy())
    final = seen[-1]
    assert final.size == 12
    # a row leaves the window after 4 cycles and keeps its last smoothed value
    assert final[3] == seen[6][3]
    filtered = np.array([s[0][0] for s in steps])
    assert not np.allclose(final[:-1], filtered[:-1])
    assert final[-1] == filtered[-1]
    rd.inherit(9, 7, t=55.0)
    assert rd.rows(9)["t"].tolist() == [10.0 * k for k in range(6)]


def test_register_serves_the_detection_of_the_main_hypothesis_by_the_retro_weights():
    steps = _filter(3)
    (x0, P0, *_), (x1, P1, xp, Pp, F), (x2, P2, xp2, Pp2, F2) = steps

    def rec(x, P, c, parent, xpre, Ppre, F, t, det):
        H = len(c)
        return CycleRecord(np.stack([x] * H), np.stack([P] * H), np.array(c), np.zeros(H, dtype=np.intp),
                           np.array([3]), np.array(parent), np.stack([xpre] * H), np.stack([Ppre] * H),
                           F, np.array([[t, x[0], 0.01, 5.0, 6.0, np.nan, np.nan]]), np.array(det))

    rd = Retrodiction(n_retro=5)
    rd.push(rec(x0, P0, [0.6, 0.4], [-1, -1], x0, P0, np.eye(4), 0.0, [[1.00, 0.02], [1.10, 0.03]]))
    assert rd.rows(3)["brg"].tolist() == [1.00]  # filtered main hypothesis: the first
    # its children at the next cycle outweigh it: the second detection was the track's
    rd.push(rec(x1, P1, [0.1, 0.9], [0, 1], xp, Pp, F, 10.0, [[1.01, 0.02], [np.nan, np.nan]]))
    h = rd.rows(3)
    assert h["t"].tolist() == [0.0] and h["brg"].tolist() == [1.10] and h["sbrg"].tolist() == [0.03]
    assert h["own_x"].tolist() == [5.0] and h["own_y"].tolist() == [6.0]
    assert rd.smoothed(3)["t"].tolist() == [0.0, 10.0]  # a missed main: a smoothed row only
    rd.push(rec(x2, P2, [1.0], [0], xp2, Pp2, F2, 20.0, [[1.02, 0.02]]))
    assert rd.rows(3)["brg"].tolist() == [1.00, 1.01, 1.02]  # the first lineage won after all
