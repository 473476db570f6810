"""Gating (001 [8]-[10]) and angle wrapping."""

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from common.core import gating
from common.core.angles import wrap_2pi, wrap_pi

angles = st.floats(min_value=-1e4, max_value=1e4, allow_nan=False)


@given(angles)
def test_wrap_pi_range_and_equivalence(a):
    w = wrap_pi(a)
    assert -np.pi <= w < np.pi
    assert abs(np.sin(w) - np.sin(a)) < 1e-9 and abs(np.cos(w) - np.cos(a)) < 1e-9


@given(angles)
def test_wrap_2pi_range_and_equivalence(a):
    w = wrap_2pi(a)
    assert 0.0 <= w < 2 * np.pi
    assert abs(np.sin(w) - np.sin(a)) < 1e-9 and abs(np.cos(w) - np.cos(a)) < 1e-9


def test_wrap_values_scalars_and_arrays():
    assert wrap_pi(np.pi) == -np.pi
    assert isinstance(wrap_pi(1.0), float)
    np.testing.assert_allclose(wrap_pi(np.array([3 * np.pi / 2, -3 * np.pi / 2])), [-np.pi / 2, np.pi / 2])
    np.testing.assert_allclose(wrap_2pi(np.array([-np.pi / 2, 5 * np.pi])), [3 * np.pi / 2, np.pi])


def test_pairwise_innovations_shape_and_wrap():
    z_pred = np.array([[10.0, 6.2], [20.0, 0.0]])
    z = np.array([[11.0, 0.1], [19.0, 3.0], [0.0, -0.1]])
    y = gating.pairwise_innovations(z_pred, z, angle_idx=(1,))
    assert y.shape == (2, 3, 2)
    np.testing.assert_allclose(y[0, 0], [1.0, 0.1 + 2 * np.pi - 6.2])
    np.testing.assert_allclose(y[1, 1], [-1.0, 3.0])
    np.testing.assert_allclose(y[1, 2], [-20.0, -0.1])


def test_mahalanobis_hand_computed():
    # S = diag(4, 1): y = (2, 1) -> 1 + 1 = 2; y = (0, 3) -> 9
    y = np.array([[[2.0, 1.0], [0.0, 3.0]]])
    S = np.array([[[4.0, 0.0], [0.0, 1.0]]])
    np.testing.assert_allclose(gating.mahalanobis_sq(y, S), [[2.0, 9.0]])


@settings(max_examples=30, deadline=None)
@given(st.integers(1, 5), st.integers(1, 6), st.integers(1, 4), st.integers(0, 2**31 - 1))
def test_mahalanobis_vs_explicit_inverse(N, M, m, seed):
    rng = np.random.default_rng(seed)
    A = rng.normal(size=(N, m, m))
    S = A @ np.swapaxes(A, 1, 2) + 0.1 * np.eye(m)
    y = rng.normal(size=(N, M, m))
    expected = np.einsum("nmi,nij,nmj->nm", y, np.linalg.inv(S), y)
    np.testing.assert_allclose(gating.mahalanobis_sq(y, S), expected, rtol=1e-7, atol=1e-9)


def test_mahalanobis_empty():
    assert gating.mahalanobis_sq(np.zeros((3, 0, 2)), np.tile(np.eye(2), (3, 1, 1))).shape == (3, 0)


def test_chi2_gate_and_gate():
    assert abs(gating.chi2_gate(0.99, 3) - 11.3449) < 1e-3  # chi-square table, 3 dof
    assert abs(gating.chi2_gate(0.95, 1) - 3.8415) < 1e-3
    d2 = np.array([[1.0, 12.0], [5.0, 2.0]])
    np.testing.assert_array_equal(gating.gate(d2, 11.34), [[True, False], [True, True]])
    np.testing.assert_array_equal(
        gating.gate(d2, np.array([20.0, 3.0])), [[True, True], [False, True]]
    )


def test_pair_distances_equal_the_dense_form_and_accept_diagonal_R():
    rng = np.random.default_rng(3)
    N, M, m = 4, 5, 3
    z_pred, z = rng.normal(size=(N, m)), rng.normal(size=(M, m)) * 3.0
    B = rng.normal(size=(N, m, m))
    A = B @ np.swapaxes(B, 1, 2) + np.eye(m)
    r = rng.uniform(0.5, 2.0, size=(M, m))
    t, j = (a.ravel() for a in np.meshgrid(np.arange(N), np.arange(M), indexing="ij"))
    y, S, d2 = gating.pair_distances(z_pred, A, z, r, t, j, angle_idx=(1,))
    _, _, d2_full = gating.pair_distances(z_pred, A, z, np.stack([np.diag(v) for v in r]), t, j,
                                          angle_idx=(1,))
    np.testing.assert_allclose(d2, d2_full, rtol=1e-12)
    Y = gating.pairwise_innovations(z_pred, z, angle_idx=(1,))
    np.testing.assert_allclose(y, Y.reshape(-1, m), rtol=1e-12)
    for k in range(t.size):  # 001 [8]-[10]: d = i' (A_t + R_j)^-1 i, pair by pair
        Sk = A[t[k]] + np.diag(r[j[k]])
        np.testing.assert_allclose(S[k], Sk)
        assert d2[k] == pytest.approx(y[k] @ np.linalg.solve(Sk, y[k]), rel=1e-10)


def test_pair_distances_of_no_pair_and_per_pair_gate():
    y, S, d2 = gating.pair_distances(np.zeros((2, 2)), np.tile(np.eye(2), (2, 1, 1)),
                                     np.zeros((3, 2)), np.ones((3, 2)), np.zeros(0, int),
                                     np.zeros(0, int))
    assert y.shape == (0, 2) and S.shape == (0, 2, 2) and d2.shape == (0,)
    np.testing.assert_array_equal(gating.gate(np.array([1.0, 5.0, 2.0]), np.array([2.0, 6.0, 1.0])),
                                  [True, True, False])


def test_sweep_pairs_match_brute_force() -> None:
    rng = np.random.default_rng(3)
    lo = rng.uniform(0, 100, 200)
    hi = lo + rng.uniform(0, 5, 200)
    a, b = gating.overlap_pairs(lo, hi)
    got = {tuple(sorted(p)) for p in zip(a.tolist(), b.tolist())}
    want = {(i, j) for i in range(200) for j in range(i + 1, 200)
            if lo[i] <= hi[j] and lo[j] <= hi[i]}
    assert got == want
    v = rng.uniform(0, 100, 150)
    i, j = gating.window_pairs(lo, hi, v)
    assert set(zip(i.tolist(), j.tolist())) == {
        (p, q) for p in range(200) for q in range(150) if lo[p] <= v[q] <= hi[p]}
