"""Batched Kalman filter: hand-computed steps, Joseph vs standard form, gain_scale."""

import numpy as np
from filterpy.kalman import KalmanFilter

from common.core import kalman, motion

H5 = np.array([[1, 0, 0, 0, 0], [0, 1, 0, 0, 0], [0, 0, 0, 1, 0]], dtype=float)  # 001 [11]


def _random_batch(rng, N=6, n=5):
    A = rng.normal(size=(N, n, n))
    P = A @ np.swapaxes(A, 1, 2) + n * np.eye(n)
    return rng.normal(size=(N, n)), P


def test_predict_hand_computed():
    x = np.array([[1.0, 2.0]])
    P = np.eye(2)[None]
    F = np.array([[1.0, 2.0], [0.0, 1.0]])
    Q = np.array([[0.1, 0.0], [0.0, 0.2]])
    xp, Pp = kalman.predict(x, P, F, Q)
    np.testing.assert_allclose(xp, [[5.0, 2.0]])
    np.testing.assert_allclose(Pp, [[[5.1, 2.0], [2.0, 1.2]]])


def test_predict_per_track_F_Q_matches_loop():
    rng = np.random.default_rng(0)
    x, P = _random_batch(rng)
    T = rng.uniform(0.5, 3.0, size=6)
    F, Q = motion.bistatic_F(T), motion.bistatic_Q(T, 1.0, 0.01)
    xp, Pp = kalman.predict(x, P, F, Q)
    for k in range(6):
        np.testing.assert_allclose(xp[k], F[k] @ x[k])
        np.testing.assert_allclose(Pp[k], F[k] @ P[k] @ F[k].T + Q[k])


def test_update_hand_computed():
    # S = 4 + 4 = 8, K = [4, 2]/8 = [0.5, 0.25], y = 2 -> x+ = [1, 0.5]
    # P+ = P - K S K' = [[4-2, 2-1], [2-1, 3-0.5]]
    x = np.zeros((1, 2))
    P = np.array([[[4.0, 2.0], [2.0, 3.0]]])
    H = np.array([[1.0, 0.0]])
    R = np.array([[4.0]])
    for joseph in (True, False):
        xu, Pu, S, K = kalman.update(x, P, np.array([[2.0]]), H, R, joseph=joseph)
        np.testing.assert_allclose(S, [[[8.0]]])
        np.testing.assert_allclose(K, [[[0.5], [0.25]]])
        np.testing.assert_allclose(xu, [[1.0, 0.5]])
        np.testing.assert_allclose(Pu, [[[2.0, 1.0], [1.0, 2.5]]])


def test_joseph_equals_standard_for_optimal_gain():
    rng = np.random.default_rng(1)
    x, P = _random_batch(rng)
    R = np.diag([25.0, 1.0, 1e-4])
    y = rng.normal(size=(6, 3))
    xj, Pj, _, _ = kalman.update(x, P, y, H5, R, joseph=True)
    xs, Ps, _, _ = kalman.update(x, P, y, H5, R, joseph=False)
    np.testing.assert_allclose(xj, xs)
    np.testing.assert_allclose(Pj, Ps, atol=1e-10)
    np.testing.assert_array_equal(Pj, np.swapaxes(Pj, 1, 2))


def test_matches_filterpy_single_track():
    rng = np.random.default_rng(2)
    x, P = _random_batch(rng, N=1)
    R = np.diag([4.0, 0.5, 0.01])
    z = rng.normal(size=(1, 3))
    kf = KalmanFilter(dim_x=5, dim_z=3)
    kf.x, kf.P, kf.H, kf.R = x[0].copy(), P[0].copy(), H5, R
    kf.update(z[0])
    xu, Pu, _, _ = kalman.update(x, P, z - x @ H5.T, H5, R)
    np.testing.assert_allclose(xu[0], kf.x, rtol=1e-10)
    np.testing.assert_allclose(Pu[0], kf.P, rtol=1e-9, atol=1e-12)


def test_gain_scale_zero_one_and_between():
    rng = np.random.default_rng(3)
    x, P = _random_batch(rng)
    R = np.diag([4.0, 0.5, 0.01])
    y = rng.normal(size=(6, 3))
    x0, P0, _, _ = kalman.update(x, P, y, H5, R, gain_scale=np.zeros(6))
    np.testing.assert_allclose(x0, x, atol=0)
    np.testing.assert_allclose(P0, P, atol=1e-12)
    x1, P1, _, _ = kalman.update(x, P, y, H5, R, gain_scale=np.ones(6))
    xr, Pr, _, K = kalman.update(x, P, y, H5, R)
    np.testing.assert_allclose(x1, xr)
    np.testing.assert_allclose(P1, Pr)
    a = np.linspace(0.0, 1.0, 6)
    xa, Pa, S, _ = kalman.update(x, P, y, H5, R, gain_scale=a)
    _, Pa_std, _, _ = kalman.update(x, P, y, H5, R, joseph=False, gain_scale=a)
    np.testing.assert_allclose(xa, x + a[:, None] * (K @ y[..., None])[..., 0])
    KSK = K @ S @ np.swapaxes(K, 1, 2)
    np.testing.assert_allclose(Pa, P - (a * (2 - a))[:, None, None] * KSK, atol=1e-9)
    np.testing.assert_allclose(Pa_std, Pa, atol=1e-9)


def test_innovation_wraps_across_zero():
    z = np.array([[100.0, 0.1]])
    z_pred = np.array([[90.0, 2 * np.pi - 0.1]])
    np.testing.assert_allclose(kalman.innovation(z, z_pred, angle_idx=(1,)), [[10.0, 0.2]])
    np.testing.assert_allclose(
        kalman.innovation(z_pred, z, angle_idx=(1,)), [[-10.0, -0.2]]
    )
    assert kalman.innovation(z, z_pred)[0, 1] < -6.0  # no wrapping when not listed


def test_ekf_update_equals_update_with_wrapped_innovation():
    rng = np.random.default_rng(4)
    x, P = _random_batch(rng)
    H = rng.normal(size=(6, 3, 5))
    R = np.tile(np.diag([1.0, 2.0, 0.01]), (6, 1, 1))
    h = rng.normal(size=(6, 3))
    z = h + np.array([0.0, 0.0, 2 * np.pi])  # angle residual of exactly one turn
    xe, Pe, _, _ = kalman.ekf_update(x, P, z, h, H, R, angle_idx=(2,))
    xu, Pu, _, _ = kalman.update(x, P, np.zeros((6, 3)), H, R)
    np.testing.assert_allclose(xe, xu, atol=1e-9)
    np.testing.assert_allclose(Pe, Pu)
