"""Tests for common.sonar.tma.bearings_only (seed 002) and common.sonar.tma.crlb.

Scenario of the literature (Nardone, Lindgren & Gong 1984): own ship 5 kn, course 140 deg;
the course is set to 110, 80, 50, 20 deg at samples 13, 14, 15, 16 (1-based, one
bearing a minute, 32 samples), target at (4.92, 0.85) km from the own start, 4 kn,
course -140 deg, bearing sigma 1.5 deg.
"""

from __future__ import annotations

import numpy as np
import pytest

from common.core.angles import wrap_pi
from common.sonar.tma.bearings_only import (
    Support,
    bearing_model,
    detect_manoeuvre,
    initial_beta,
    leg_times,
    solve_tma,
    state_map,
    support_rows,
)
from common.sonar.tma.crlb import crlb, fisher_information, position_rms_bound

KN = 1852.0 / 3600.0
SIG = np.radians(1.5)


def own_track(n: int = 32, dt: float = 60.0) -> tuple[np.ndarray, np.ndarray]:
    """Own positions at the sample times; course on the interval after sample s (1-based)."""
    crs = np.full(n - 1, 140.0)
    for s, c in zip((13, 14, 15, 16), (110.0, 80.0, 50.0, 20.0)):
        crs[s - 1:] = c
    steps = np.stack((np.sin(np.radians(crs)), np.cos(np.radians(crs))), 1) * 5 * KN * dt
    return np.arange(n) * dt, np.vstack(([0.0, 0.0], np.cumsum(steps, 0)))


T, OWN = own_track()
K_T = np.radians(-140.0)
BETA = np.array([4920.0, 850.0, 4 * KN * np.sin(K_T), 4 * KN * np.cos(K_T)])


def true_bearings(beta: np.ndarray, legs: tuple[float, ...] = ()) -> np.ndarray:
    X = state_map(T, 0.0, legs) @ beta
    return np.arctan2(X[:, 0] - OWN[:, 0], X[:, 1] - OWN[:, 1])


def pos_at(beta: np.ndarray, t: float, legs: tuple[float, ...] = ()) -> np.ndarray:
    return (state_map(np.array([t]), 0.0, legs)[0] @ beta)[:2]


def test_own_track_turn():
    v = np.diff(OWN, axis=0)
    crs = np.degrees(np.arctan2(v[:, 0], v[:, 1])) % 360
    assert crs[:12] == pytest.approx(np.full(12, 140.0))
    assert crs[12:16] == pytest.approx([110.0, 80.0, 50.0, 20.0])
    assert crs[16:] == pytest.approx(np.full(15, 20.0))


def test_leg_times_claim_14():
    got = leg_times(np.array([5.0, 15.0, 25.0]), 0.0, (10.0, 20.0))
    assert got == pytest.approx(np.array([[5, 0, 0], [10, 5, 0], [10, 10, 5]], float))


def test_bearing_model_eq_5_hand_values():
    beta = np.array([1000.0, 1000.0, 1.0, 0.0])
    b, H = bearing_model(beta, np.array([0.0, 10.0]), np.zeros((2, 2)), 0.0)
    assert b[0] == pytest.approx(np.pi / 4)
    assert H[0] == pytest.approx([5e-4, -5e-4, 0.0, 0.0])
    r2 = 1010.0**2 + 1000.0**2
    assert H[1] == pytest.approx([1000 / r2, -1010 / r2, 10000 / r2, -10100 / r2])


def test_bearing_model_jacobian_matches_finite_differences():
    beta = np.array([3000.0, -2000.0, 2.0, -1.5, -3.0, 1.0])
    legs = (300.0,)
    t = np.linspace(0, 900, 7)
    own = np.stack((t * 1.5, t * 0.5), 1)
    _, H = bearing_model(beta, t, own, 100.0, legs)
    eps = 1e-4
    num = np.stack([
        wrap_pi(bearing_model(beta + eps * e, t, own, 100.0, legs)[0]
             - bearing_model(beta - eps * e, t, own, 100.0, legs)[0]) / (2 * eps)
        for e in np.eye(6)
    ], 1)
    assert H == pytest.approx(num, rel=1e-5, abs=1e-12)


def test_support_rows_eq_11_to_14():
    beta = np.array([3000.0, 4000.0, 3.0, 4.0])
    sup = [
        Support("range", 5100.0, 10.0, 0.0, (0.0, 0.0)),
        Support("speed", 6.0, 0.5, 0.0),
        Support("course", 0.7, 0.1, 0.0),
    ]
    d, H = support_rows(beta, sup, 0.0)
    assert d[0] == pytest.approx((5100.0**2 - 25e6) / (2 * 5100 * 10))
    assert H[0] == pytest.approx(np.array([6000.0, 8000.0, 0.0, 0.0]) / 102000.0)
    assert d[1] == pytest.approx(11.0 / 6.0)
    assert H[1] == pytest.approx([0.0, 0.0, 1.0, 8.0 / 6.0])
    assert d[2] == pytest.approx((0.7 - np.arctan2(3.0, 4.0)) / 0.1)
    assert H[2] == pytest.approx(np.array([0.0, 0.0, 4.0, -3.0]) / 25.0 / 0.1)


def test_support_range_row_uses_reference_time():
    beta = np.array([3000.0, 4000.0, 3.0, 4.0])
    d, H = support_rows(beta, [Support("range", 5100.0, 10.0, 100.0, (300.0, 400.0))], 0.0)
    assert d[0] == pytest.approx((5100.0**2 - 25e6) / 102000.0)
    assert H[0] == pytest.approx(2 * np.array([3000.0, 4000.0, 300000.0, 400000.0]) / 102000.0)


def test_noise_free_converges_to_truth_from_scratch():
    b = true_bearings(BETA)
    sol = solve_tma(T, b, SIG, OWN, 0.0)
    assert sol.converged
    assert sol.beta == pytest.approx(BETA, abs=1e-2)
    assert np.max(np.abs(sol.residuals)) < 1e-7


def test_gauss_newton_step_is_eq_7_8():
    b = true_bearings(BETA)
    beta0 = BETA + np.array([200.0, -150.0, 0.3, -0.2])
    sol = solve_tma(T, b, SIG, OWN, 0.0, beta0=beta0, tol=1e9, max_iter=1)
    bhat, H = bearing_model(beta0, T, OWN, 0.0)
    F = np.linalg.inv(H.T @ H) @ H.T
    assert sol.n_iter == 1 and sol.converged
    assert sol.beta == pytest.approx(beta0 + F @ wrap_pi(b - bhat), rel=1e-9)


def test_initial_beta_lands_near_truth_noise_free():
    b = true_bearings(BETA)
    beta0 = initial_beta(T, b, np.full(T.size, SIG), OWN, 0.0)
    assert np.hypot(*(pos_at(beta0, T[-1]) - pos_at(BETA, T[-1]))) < 0.1 * np.hypot(*(pos_at(BETA, T[-1]) - OWN[-1]))


def test_state_at_and_covariance_mapping():
    b = true_bearings(BETA)
    sol = solve_tma(T, b, SIG, OWN, 0.0)
    x, P = sol.state_at(600.0)
    assert x == pytest.approx([BETA[0] + 600 * BETA[2], BETA[1] + 600 * BETA[3], BETA[2], BETA[3]], abs=1e-2)
    G = np.array([[1, 0, 600, 0], [0, 1, 0, 600], [0, 0, 1, 0], [0, 0, 0, 1]], float)
    assert P == pytest.approx(G @ sol.P @ G.T)
    assert sol.P == pytest.approx(crlb(sol.beta, T, OWN, SIG, 0.0), rel=1e-6)


def test_fisher_information_single_bearing():
    J = fisher_information(np.array([1000.0, 0.0, 0.0, 0.0]), np.array([0.0]), np.zeros((1, 2)), 0.1, 0.0)
    expected = np.zeros((4, 4))
    expected[1, 1] = 1e-6 / 0.01
    assert J == pytest.approx(expected)


def test_monte_carlo_rmse_vs_crlb():
    rng = np.random.default_rng(20240601)
    b = true_bearings(BETA)
    truth = pos_at(BETA, T[-1])
    err = np.empty(200)
    for k in range(err.size):
        sol = solve_tma(T, b + SIG * rng.standard_normal(T.size), SIG, OWN, 0.0)
        assert sol.converged
        err[k] = np.hypot(*(sol.state_at(T[-1])[0][:2] - truth))
    ratio = np.sqrt(np.mean(err**2)) / position_rms_bound(BETA, T, OWN, SIG, 0.0, T[-1])
    assert 0.8 < ratio <= 1.1


def test_range_support_reduces_error():
    rng = np.random.default_rng(7)
    b = true_bearings(BETA)
    truth = pos_at(BETA, T[-1])
    r_true = np.hypot(*(truth - OWN[-1]))
    e0, e1 = [], []
    for _ in range(200):
        bn = b + SIG * rng.standard_normal(T.size)
        sup = [Support("range", r_true + 100.0 * rng.standard_normal(), 100.0, T[-1], tuple(OWN[-1]))]
        e0.append(np.hypot(*(solve_tma(T, bn, SIG, OWN, 0.0).state_at(T[-1])[0][:2] - truth)))
        e1.append(np.hypot(*(solve_tma(T, bn, SIG, OWN, 0.0, support=sup).state_at(T[-1])[0][:2] - truth)))
    assert np.sqrt(np.mean(np.square(e1))) < 0.9 * np.sqrt(np.mean(np.square(e0)))


def test_range_support_makes_pre_turn_track_observable():
    rng = np.random.default_rng(8)
    n = 12
    b = true_bearings(BETA)[:n]
    truth = pos_at(BETA, T[n - 1])
    r_true = np.hypot(*(truth - OWN[n - 1]))
    assert np.linalg.cond(fisher_information(BETA, T[:n], OWN[:n], SIG, 0.0)) > 1e8
    err = []
    for _ in range(50):
        sup = [Support("range", r_true + 100.0 * rng.standard_normal(), 100.0, T[n - 1], tuple(OWN[n - 1])),
               Support("speed", 4 * KN + 0.2 * rng.standard_normal(), 0.2, T[n - 1])]
        sol = solve_tma(T[:n], b + SIG * rng.standard_normal(n), SIG, OWN[:n], 0.0, support=sup)
        assert sol.converged
        err.append(np.hypot(*(sol.state_at(T[n - 1])[0][:2] - truth)))
    assert np.sqrt(np.mean(np.square(err))) < 300.0


def test_course_support_pulls_course():
    b = true_bearings(BETA)
    k_obs = np.arctan2(BETA[2], BETA[3]) + 0.2
    sol = solve_tma(T, b, SIG, OWN, 0.0, support=[Support("course", k_obs, 1e-4, T[-1])])
    assert np.arctan2(sol.beta[2], sol.beta[3]) == pytest.approx(k_obs, abs=1e-3)


TM = 16 * 60.0
K2 = np.radians(300.0)
BETA2 = np.concatenate((BETA, [4 * KN * np.sin(K2), 4 * KN * np.cos(K2)]))


def test_two_leg_target_estimated_leg_by_leg():
    rng = np.random.default_rng(11)
    b = true_bearings(BETA2, (TM,))
    E = np.empty((100, 6))
    for k in range(E.shape[0]):
        sol = solve_tma(T, b + SIG * rng.standard_normal(T.size), SIG, OWN, 0.0, legs=(TM,))
        assert sol.converged and sol.manoeuvre_times == (TM,)
        E[k] = sol.beta - BETA2
    ratio = np.sqrt(np.mean(E**2, 0) / np.diag(crlb(BETA2, T, OWN, SIG, 0.0, (TM,))))
    assert np.all(ratio < 1.3)
    v_err = np.sqrt(np.mean(E[:, 4:] ** 2, 0))
    assert np.all(v_err < 1.0)


def test_manoeuvre_detector_finds_leg_change_and_not_a_straight_target():
    rng = np.random.default_rng(12)
    b2 = true_bearings(BETA2, (TM,))
    b1 = true_bearings(BETA)
    hits, false = 0, 0
    for _ in range(15):
        bn = b2 + SIG * rng.standard_normal(T.size)
        ta = detect_manoeuvre(T, bn, SIG, OWN, 0.0, solve_tma(T, bn, SIG, OWN, 0.0))
        hits += ta is not None and abs(ta - TM) <= 60.0
        bn = b1 + SIG * rng.standard_normal(T.size)
        false += detect_manoeuvre(T, bn, SIG, OWN, 0.0, solve_tma(T, bn, SIG, OWN, 0.0)) is not None
    assert hits >= 12
    assert false <= 1
