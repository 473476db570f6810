"""Motion models vs. the seed matrices, hand-computed at T = 2."""

import numpy as np
import pytest

from common.core import motion


def test_bistatic_F_001_19():
    # 001 [19] at T = 2: T^2/2 = 2
    expected = np.array(
        [
            [1, 2, 2, 0, 0],
            [0, 1, 2, 0, 0],
            [0, 0, 1, 0, 0],
            [0, 0, 0, 1, 2],
            [0, 0, 0, 0, 1],
        ],
        dtype=float,
    )
    np.testing.assert_array_equal(motion.bistatic_F(2.0), expected)


def test_bistatic_Q_001_20():
    # 001 [20], T = 2, sigma_gamma = 3 (x9), sigma_omega = 0.5 (x0.25)
    # T^5/20 = 1.6, T^4/8 = 2, T^3/6 = 4/3, T^3/3 = 8/3, T^2/2 = 2, T = 2
    g = 9.0 * np.array([[1.6, 2.0, 4 / 3], [2.0, 8 / 3, 2.0], [4 / 3, 2.0, 2.0]])
    w = 0.25 * np.array([[8 / 3, 2.0], [2.0, 2.0]])
    expected = np.zeros((5, 5))
    expected[:3, :3] = g
    expected[3:, 3:] = w
    np.testing.assert_allclose(motion.bistatic_Q(2.0, 3.0, 0.5), expected)


def test_cv_F_001_51_ordering():
    F = motion.cv_F(2.0)
    x = np.array([1.0, 10.0, 2.0, 20.0, 3.0, 30.0])  # [x vx y vy z vz]
    np.testing.assert_allclose(F @ x, [21.0, 10.0, 42.0, 20.0, 63.0, 30.0])


def test_cv_Q_001_51_blocks():
    Q = motion.cv_Q(2.0, 4.0, 1.0)
    b = np.array([[8 / 3, 2.0], [2.0, 2.0]])
    np.testing.assert_allclose(Q[0:2, 0:2], 4.0 * b)
    np.testing.assert_allclose(Q[2:4, 2:4], 4.0 * b)
    np.testing.assert_allclose(Q[4:6, 4:6], 1.0 * b)  # z block on (z, vz), see docstring
    assert np.count_nonzero(Q) == 12
    np.testing.assert_allclose(motion.cv_Q(2.0, 4.0), motion.cv_Q(2.0, 4.0, 4.0))


def test_bearing_F_Q_000():
    F = motion.bearing_F(2.0)
    np.testing.assert_array_equal(
        F, [[1, 2, 0, 0], [0, 1, 0, 0], [0, 0, 1, 2], [0, 0, 0, 1]]
    )
    Q = motion.bearing_Q(2.0, 0.1, 10.0)
    # f1 = T^3/3, f2 = T^2/2 (deviation from the printed T^2/3), f3 = T
    np.testing.assert_allclose(Q[:2, :2], 0.1 * np.array([[8 / 3, 2.0], [2.0, 2.0]]))
    np.testing.assert_allclose(Q[2:, 2:], 10.0 * np.array([[8 / 3, 2.0], [2.0, 2.0]]))
    assert np.all(Q[:2, 2:] == 0)


def test_bearing_freq_extends_bearing():
    F6 = motion.bearing_freq_F(3.0)
    Q6 = motion.bearing_freq_Q(3.0, 0.1, 10.0, 0.5)
    np.testing.assert_array_equal(F6[:4, :4], motion.bearing_F(3.0))
    np.testing.assert_allclose(Q6[:4, :4], motion.bearing_Q(3.0, 0.1, 10.0))
    np.testing.assert_allclose(Q6[4:, 4:], 0.5 * np.array([[9.0, 4.5], [4.5, 3.0]]))


@pytest.mark.parametrize(
    "F_fn, Q_fn",
    [
        (motion.bistatic_F, lambda T: motion.bistatic_Q(T, 2.0, 0.1)),
        (motion.cv_F, lambda T: motion.cv_Q(T, 3.0, 0.2)),
        (motion.bearing_F, lambda T: motion.bearing_Q(T, 0.1, 5.0)),
        (motion.bearing_freq_F, lambda T: motion.bearing_freq_Q(T, 0.1, 5.0, 0.3)),
    ],
)
def test_batched_T_matches_scalar_and_is_psd(F_fn, Q_fn):
    T = np.array([0.5, 1.0, 4.0])
    Fb, Qb = F_fn(T), Q_fn(T)
    assert Fb.shape[0] == 3 and Qb.shape[0] == 3
    for k, t in enumerate(T):
        np.testing.assert_allclose(Fb[k], F_fn(float(t)))
        np.testing.assert_allclose(Qb[k], Q_fn(float(t)))
        assert np.linalg.eigvalsh(Qb[k]).min() > -1e-12
    # semigroup: F(a) F(b) = F(a + b)
    np.testing.assert_allclose(F_fn(1.0) @ F_fn(4.0), F_fn(5.0))


def test_Q_is_additive_over_steps():
    # Integrated white noise: F(b) Q(a) F(b)' + Q(b) = Q(a + b) (exact for f2 = T^2/2)
    a, b = 1.5, 2.5
    for F_fn, Q_fn in [
        (motion.bistatic_F, lambda T: motion.bistatic_Q(T, 2.0, 0.1)),
        (motion.bearing_F, lambda T: motion.bearing_Q(T, 0.1, 5.0)),
    ]:
        lhs = F_fn(b) @ Q_fn(a) @ F_fn(b).T + Q_fn(b)
        np.testing.assert_allclose(lhs, Q_fn(a + b), rtol=1e-12)
