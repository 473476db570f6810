"""Equations of the 000 multiple-hypothesis mode on flat hypothesis arrays
(common.sonar.mht.hypotheses), one test per equation."""

import math

import numpy as np
from scipy.stats import multivariate_normal

from common.sonar.mht.hypotheses import (
    heaviest,
    hit_weights,
    merge_apply,
    merge_clusters,
    miss_weights,
    mixture_moments,
    pair_distance2,
    prune,
    sprt,
    track_sums,
)


def test_hit_and_miss_weights_hand_values():
    # c_rel P_D exp(-d2/2) / (rho_F sqrt(det(2 pi S))), S 2x2 with det 4
    got = hit_weights(np.array([0.5]), np.array([0.8]), np.array([1.0]), np.array([4.0]), 2, 0.1)
    assert math.isclose(got[0], 0.5 * 0.8 * math.exp(-0.5) / (0.1 * math.sqrt((2 * math.pi) ** 2 * 4.0)))
    assert miss_weights(np.array([0.5]), np.array([0.8]))[0] == 0.5 * (1.0 - 0.8)


def test_hit_weight_is_the_gaussian_density_of_the_innovation():
    rng = np.random.default_rng(1)
    S = np.array([[2e-4, 1e-5], [1e-5, 4.0]])
    y = rng.multivariate_normal(np.zeros(2), S, 5)
    d2 = np.einsum("ki,ij,kj->k", y, np.linalg.inv(S), y)
    got = hit_weights(np.full(5, 0.3), np.full(5, 0.9), d2, np.full(5, np.linalg.det(S)), 2, 0.05)
    want = 0.3 * 0.9 * multivariate_normal(np.zeros(2), S).pdf(y) / 0.05
    np.testing.assert_allclose(got, want, rtol=1e-10)


def test_track_sums_and_heaviest():
    c = np.array([0.2, 0.5, 0.1, 0.7, 0.3])
    track = np.array([0, 0, 1, 1, 2])
    np.testing.assert_allclose(track_sums(c, track, 4), [0.7, 0.8, 0.3, 0.0])
    assert heaviest(c, track, 4).tolist() == [1, 3, 4, -1]


def test_mixture_moments_match_the_seed_formulas_across_north():
    x = np.array([[2 * math.pi - 0.01, 1e-4, 10.0, 0.0], [0.02, 3e-4, 12.0, 0.1]])
    P = np.stack([np.eye(4) * 1e-4, np.eye(4) * 2e-4])
    c = np.array([0.75, 0.25])
    ci, xi, Pi = mixture_moments(x, P, c, np.zeros(2, dtype=np.intp), 1)
    assert math.isclose(ci[0], 1.0)
    unwrapped = np.array([[-0.01, 1e-4, 10.0, 0.0], [0.02, 3e-4, 12.0, 0.1]])
    mean = 0.75 * unwrapped[0] + 0.25 * unwrapped[1]
    cov = sum(w * (P[i] + np.outer(unwrapped[i] - mean, unwrapped[i] - mean))
              for i, w in enumerate(c))
    assert math.isclose(xi[0, 0], mean[0] % (2 * math.pi), abs_tol=1e-12)
    np.testing.assert_allclose(xi[0, 1:], mean[1:], atol=1e-12)
    np.testing.assert_allclose(Pi[0], cov, atol=1e-12)


def test_pair_distance_hand_value():
    xa, xb = np.array([[0.1, 0, 0, 0]]), np.array([[0.0, 0, 0, 0]])
    P = np.eye(4)[None] * 0.005
    assert math.isclose(pair_distance2(xa, P, xb, P)[0], 0.01 / 0.01)


def test_prune_threshold_and_caps_keep_the_heaviest():
    c = np.array([0.5, 1e-4, 0.3, 0.2, 0.1, 1e-5])
    track = np.array([0, 0, 1, 1, 1, 2])
    keep = prune(c, track, 3, c_krit=1e-3, per_track=2, per_cycle=100)
    # 000 c < c_krit pruned; track 1 capped at its 2 heaviest; track 2 keeps its only one
    assert keep.tolist() == [True, False, True, True, False, True]
    keep = prune(c, track, 3, c_krit=1e-3, per_track=10, per_cycle=2)
    assert keep.tolist() == [True, False, True, False, False, True]


def test_merge_moment_matches_close_hypotheses_only():
    x = np.array([[1.0, 0, 10, 0], [1.001, 0, 10, 0], [1.5, 0, 10, 0]])
    P = np.stack([np.eye(4) * 1e-3] * 3)
    c = np.array([0.6, 0.2, 0.2])
    head = merge_clusters(x, P, c, np.zeros(3, dtype=np.intp), d_merge_hyp=2.0)
    assert head.tolist() == [0, 0, 2]
    heads, x12, P12, c12 = merge_apply(x, P, c, head)
    assert heads.tolist() == [0, 2]
    np.testing.assert_allclose(c12, [0.8, 0.2])
    m = (0.6 * x[0] + 0.2 * x[1]) / 0.8
    np.testing.assert_allclose(x12[0], m, atol=1e-12)
    cov = (0.6 * (P[0] + np.outer(x[0] - m, x[0] - m)) + 0.2 * (P[1] + np.outer(x[1] - m, x[1] - m))) / 0.8
    np.testing.assert_allclose(P12[0], cov, atol=1e-15)
    np.testing.assert_allclose(x12[1], x[2])


def test_hypotheses_of_different_tracks_never_merge():
    x = np.array([[1.0, 0, 10, 0], [1.0, 0, 10, 0]])
    P = np.stack([np.eye(4)] * 2)
    head = merge_clusters(x, P, np.array([0.5, 0.5]), np.array([0, 1]), 2.0)
    assert head.tolist() == [0, 1]


def test_sprt_counter_status_and_normalisation():
    LR = np.array([3.0, 0.1, 1.0, 0.1, 3.0, 0.1])
    ZA = np.array([3, 5, 2, 0, 6, 4])
    SA = np.array([0, 1, 1, 0, 1, 1], dtype=np.int8)
    za, sa, norm = sprt(LR, ZA, SA, A=0.5, B=2.0, za_krit=3, za_max=6)
    # +1 above B, -1 below A, unchanged between; a tentative track at 0 stays at 0; cap 6
    assert za.tolist() == [4, 4, 2, 0, 6, 3]
    # SA = 1 above ZA_krit, 0 below, unchanged at ZA_krit
    assert sa.tolist() == [1, 1, 0, 0, 1, 1]
    assert norm.tolist() == [True, False, False, False, True, False]
