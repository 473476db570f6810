"""Tests of common.core.crossing (seed 004 eq. 12, eq. 13, sup-norm test, modes, duration)."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from common.core.angles import TWO_PI
from common.core.crossing import (
    CUTOFF_RADIUS,
    DENSITY_CUTOFF,
    CrossingManager,
    CrossingParams,
    eq13_ambiguous,
    far_density,
    near_pairs,
    neighbour_sum,
    progressive_weight,
    proportions,
    supnorm_ambiguous,
    wrapped_diff,
)


def pairwise_diff(a: np.ndarray, b: np.ndarray, angle_idx=()) -> np.ndarray:
    """Reference: d[k, j] = a_k - b_j (N, M, m), angle components wrapped."""
    return wrapped_diff(np.asarray(a)[:, None, :], np.asarray(b)[None, :, :], angle_idx)


def pairwise_density(d: np.ndarray, cov: np.ndarray) -> np.ndarray:
    """Reference: g_j(d[k, j]) with the covariance cov[j] of track j, shape (N, M)."""
    m = d.shape[-1]
    d2 = np.einsum("kjp,jpq,kjq->kj", d, np.linalg.inv(cov), d)
    return np.exp(-0.5 * d2) / np.sqrt((2.0 * np.pi) ** m * np.linalg.det(cov))[None, :]


def _per_track(cov: np.ndarray, n: int) -> np.ndarray:
    return np.broadcast_to(cov, (n, *cov.shape[-2:])) if cov.ndim == 2 else cov


def dense_sum(points, z_pred, cov, q, angle_idx=()) -> np.ndarray:
    """Reference all-pairs sum_{j != k} q^j g_j(points_k - Z^j) (004 eq. 12-13)."""
    g = pairwise_density(pairwise_diff(points, z_pred, angle_idx), _per_track(cov, len(z_pred)))
    np.fill_diagonal(g, 0.0)
    return g @ q


def dense_supnorm(z_pred, cov, S, angle_idx=()) -> np.ndarray:
    """Reference all-pairs sup-norm test: ambiguous iff some j != k has ||Z^k - Z^j|| <= S."""
    c = _per_track(cov, len(z_pred))
    sigma = np.sqrt(np.diagonal(c, axis1=1, axis2=2))
    norm = np.max(np.abs(pairwise_diff(z_pred, z_pred, angle_idx)) / sigma[None], axis=2)
    np.fill_diagonal(norm, np.inf)
    return ~np.all(norm > S, axis=1)


SIG = 0.01  # bearing noise standard deviation (rad)
COV = np.array([[SIG**2]])
Q = np.array([0.5, 0.5])


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


def test_sum_uses_covariance_of_track_j():
    # d = (1, 2) under cov_1 = diag(1, 4): g = e^-1 / (2 pi sqrt(4)); d = (-1, -2) under
    # cov_0 = I: g = e^-2.5 / (2 pi). With q = 1 the sums are those densities.
    z = np.array([[1.0, 2.0], [0.0, 0.0]])
    cov = np.array([np.diag([1.0, 4.0]), np.eye(2)])
    s = neighbour_sum(z, z, cov, np.ones(2))
    np.testing.assert_allclose(s, [np.exp(-2.5) / (2.0 * np.pi), 0.029274915762159584],
                               rtol=1e-12)


def test_cutoff_radius_matches_density_cutoff():
    assert np.exp(-0.5 * CUTOFF_RADIUS**2) == pytest.approx(DENSITY_CUTOFF, rel=1e-9)


@st.composite
def problems(draw):
    """Random crossing problems: clustered tracks (with duplicates and sigma-grid points),
    angle components anywhere on the real line, shared or per-track (full) covariances."""
    n = draw(st.integers(0, 30))
    m = draw(st.integers(1, 3))
    angle_idx = [p for p in range(m) if draw(st.booleans())]
    rng = np.random.default_rng(draw(st.integers(0, 2**32 - 1)))
    base = 10.0 ** rng.uniform(-3.0, 3.0, m)
    base[angle_idx] = 10.0 ** rng.uniform(-3.0, 0.6, len(angle_idx))
    per_track = draw(st.booleans())
    spread = draw(st.sampled_from([0.5, 3.0, 10.0, 50.0]))
    if draw(st.booleans()):  # sigma grid: sup-norm distances exactly on integers
        per_track = False
        z = base * rng.integers(-6, 7, (n, m))
    else:
        z = rng.uniform(-1e4, 1e4, m) * base + rng.normal(0.0, spread, (n, m)) * base
    z[:, angle_idx] += 2.0 * np.pi * rng.integers(-3, 4, (n, len(angle_idx)))
    if n > 1 and draw(st.booleans()):
        z[rng.integers(0, n, n // 3)] = z[rng.integers(0, n, n // 3)]
    sig = base * rng.uniform(1.0, draw(st.sampled_from([1.0, 3.0, 30.0])) if per_track else 1.0,
                             (n, m))
    rho = rng.uniform(-0.9, 0.9, (n, m, m)) if draw(st.booleans()) else np.zeros((n, m, m))
    corr = np.triu(rho, 1) + np.swapaxes(np.triu(rho, 1), 1, 2) + np.eye(m)
    corr = corr @ np.swapaxes(corr, 1, 2)
    corr /= np.sqrt(np.einsum("kii->ki", corr)[:, :, None] * np.einsum("kii->ki", corr)[:, None])
    cov = sig[:, :, None] * corr * sig[:, None, :]
    if not per_track:
        cov = cov[0] if n else np.diag(base**2)
    x = z + rng.normal(0.0, draw(st.sampled_from([0.0, 1.0, 5.0])), (n, m)) * base
    q = rng.uniform(0.05, 0.95, n)
    return z, x, cov, q, angle_idx


def _sum_tol(dense: np.ndarray, z: np.ndarray, cov: np.ndarray, q: np.ndarray) -> np.ndarray:
    """Tolerance of the sparse sums: rounding plus the dropped terms of the cutoff."""
    c = _per_track(cov, len(z))
    peak = 1.0 / np.sqrt((2.0 * np.pi) ** z.shape[1] * np.linalg.det(c))
    return 1e-9 * dense + DENSITY_CUTOFF * np.sum(q * peak) + 1e-300


@settings(max_examples=300, deadline=None)
@given(problems(), st.sampled_from([0.5, 1.0, 3.0, 6.0]))
def test_near_pairs_are_exactly_the_brute_force_pairs(problem, radius):
    z, x, cov, _, angle_idx = problem
    n, m = z.shape
    sigma = np.sqrt(np.diagonal(_per_track(cov, n), axis1=1, axis2=2))
    for pts in (z, x):
        k, j, d = near_pairs(z, sigma, radius, angle_idx, None if pts is z else pts)
        ref = np.all(np.abs(pairwise_diff(pts, z, angle_idx)) / sigma[None] <= radius, axis=2)
        np.fill_diagonal(ref, False)
        assert sorted(zip(k.tolist(), j.tolist())) == sorted(zip(*np.nonzero(ref)))
        np.testing.assert_array_equal(d, pairwise_diff(pts, z, angle_idx)[k, j])


@settings(max_examples=300, deadline=None)
@given(problems(), st.sampled_from([1.0, 2.0, 3.0, 4.5]))
def test_sparse_tests_match_all_pairs_reference(problem, S):
    z, x, cov, q, angle_idx = problem
    for pts in (z, x):
        dense = dense_sum(pts, z, cov, q, angle_idx)
        sparse = neighbour_sum(pts, z, cov, q, angle_idx)
        assert np.all(np.abs(sparse - dense) <= _sum_tol(dense, z, cov, q))
    np.testing.assert_array_equal(supnorm_ambiguous(z, cov, S, angle_idx),
                                  dense_supnorm(z, cov, S, angle_idx))
    thr = 0.1 * far_density(q, TWO_PI)
    dense = dense_sum(z, z, cov, q, angle_idx)
    clear = np.abs(dense - thr) > _sum_tol(dense, z, cov, q)
    np.testing.assert_array_equal(eq13_ambiguous(z, cov, q, TWO_PI, 0.1, angle_idx)[clear],
                                  ~(dense < thr)[clear])  # 004 eq. 13


@pytest.mark.parametrize("method", ["eq13", "supnorm"])
@pytest.mark.parametrize("mode", ["memory", "progressive"])
@settings(max_examples=100, deadline=None)
@given(problem=problems())
def test_step_matches_all_pairs_reference(method, mode, problem):
    z, x, cov, _, angle_idx = problem
    p = CrossingParams(method=method, mode=mode, volume=1e-3)
    n = len(z)
    q = np.full(n, p.q_prior)  # proportions of tracks never seen
    r = far_density(q, p.volume)
    if method == "eq13":
        dense = dense_sum(z, z, cov, q, angle_idx)
        amb = ~(dense < p.epsilon * r)  # 004 eq. 13
        clear = np.abs(dense - p.epsilon * r) > _sum_tol(dense, z, cov, q)
    else:
        amb, clear = dense_supnorm(z, cov, p.S, angle_idx), np.ones(n, dtype=bool)
    if mode == "memory":
        alpha = np.where(amb, 0.0, 1.0)
    else:
        alpha = np.where(amb, r / (r + dense_sum(x, z, cov, q, angle_idx)), 1.0)  # 004 eq. 12
    got_alpha, got_amb = CrossingManager(p).step(0.0, np.arange(n), z, cov, x, n, angle_idx)
    np.testing.assert_array_equal(got_amb[clear], amb[clear])
    np.testing.assert_allclose(got_alpha[clear], alpha[clear], rtol=1e-9, atol=1e-9)
