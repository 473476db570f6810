"""Resolution conflicts of the 000 multiple-hypothesis mode (common.sonar.mht.conflict):
the unresolved measurement by the unscented transform, interpretations (1)-(5) reduced
by moment matching, the re-link choice at the end of a conflict."""

import math

import numpy as np

from common.sonar.mht.conflict import h_unresolved, interpret, relink_choice, unresolved_probability, unscented

DEG = math.radians(1.0)


def _pair(sep_deg: float) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    x1 = np.array([math.radians(90.0), 1e-4, 13.0, 0.0])
    x2 = np.array([math.radians(90.0 + sep_deg), -1e-4, 10.0, 0.0])
    P = np.diag([(0.5 * DEG) ** 2, 1e-8, 1.0, 1e-3])
    return x1, P.copy(), x2, P.copy()


def test_unresolved_measurement_of_two_states():
    x1, _, x2, _ = _pair(2.0)
    z = h_unresolved(np.r_[x1, x2], 4)
    assert math.isclose(z[0], -2.0 * DEG, rel_tol=1e-9)  # 000 theta_i - theta_j
    assert math.isclose(z[1], math.radians(91.0), rel_tol=1e-12)  # 000 centre
    assert math.isclose(z[2], 10 * math.log10(10 ** 1.3 + 10 ** 1.0))  # power sum (deviation)


def test_unscented_transform_matches_monte_carlo():
    x1, P1, x2, P2 = _pair(1.0)
    X, P = np.r_[x1, x2], np.zeros((8, 8))
    P[:4, :4], P[4:, 4:] = P1, P2
    zm, Pzz, Pxz = unscented(X, P, 4)
    rng = np.random.default_rng(3)
    Z = h_unresolved(rng.multivariate_normal(X, P, 200_000), 4)
    assert np.all(np.abs(zm - Z.mean(axis=0)) < [2e-5, 2e-5, 0.02])
    C = np.cov(Z.T)
    np.testing.assert_allclose(np.diag(Pzz), np.diag(C), rtol=0.02)
    corr = (Pzz - C) / np.sqrt(np.outer(np.diag(C), np.diag(C)))
    assert np.abs(corr).max() < 0.01  # sampling noise of 200,000 draws: ~0.002
    # separation and centre are linear: the transform is exact for them
    J = np.zeros((2, 8))
    J[0, 0], J[0, 4], J[1, 0], J[1, 4] = 1.0, -1.0, 0.5, 0.5
    np.testing.assert_allclose(Pzz[:2, :2], J @ P @ J.T, rtol=1e-9, atol=1e-15)
    np.testing.assert_allclose(Pxz[:, :2], P @ J.T, rtol=1e-9, atol=1e-15)


def test_unresolved_probability_falls_with_separation():
    assert unresolved_probability(0.0, DEG) == 1.0
    assert math.isclose(unresolved_probability(DEG, DEG), math.exp(-0.5))
    assert unresolved_probability(10 * DEG, DEG) < 1e-20


def _hits(x, P, zs, R, which):
    """Kalman-updated children of a predicted (x, P) for measurements zs[which]."""
    H = np.array([[1.0, 0, 0, 0], [0, 0, 1.0, 0]])
    out = {}
    for l in which:
        S = H @ P @ H.T + R
        y = zs[l] - H @ x
        K = P @ H.T @ np.linalg.inv(S)
        lg = -0.5 * (y @ np.linalg.solve(S, y) + 2 * math.log(2 * math.pi) + math.log(np.linalg.det(S)))
        out[l] = (x + K @ y, P - K @ S @ K.T, lg)
    return out


def test_far_apart_pair_reduces_to_independent_single_target_weights():
    x1, P1, x2, P2 = _pair(8.0)
    z = np.array([[x1[0] + 0.2 * DEG, 13.5], [x2[0] - 0.1 * DEG, 9.0]])
    Rd = np.array([[DEG**2, 4.0]] * 2)
    R = np.diag(Rd[0])
    h1, h2 = _hits(x1, P1, z, R, [0]), _hits(x2, P2, z, R, [1])
    out = interpret(((x1, P1), (x2, P2)), (h1, h2), (0.9, 0.8), z, Rd, 0.05, DEG, 0.9, 3.0)
    # P_u ~ 0: (3)-(5) only, a product of the single-target terms
    s1 = {-1: 0.1, 0: 0.9 * math.exp(h1[0][2]) / 0.05}
    s2 = {-1: 0.2, 1: 0.8 * math.exp(h2[1][2]) / 0.05}
    for res, s in ((out[0], s1), (out[1], s2)):
        tot = sum(s.values())
        assert set(res) == set(s)
        for k in s:
            assert math.isclose(res[k][2], s[k] / tot, rel_tol=1e-9)
    np.testing.assert_allclose(out[0][0][0], h1[0][0])  # the same updated state
    assert math.isclose(sum(v[2] for v in out[0].values()), 1.0)


def test_unresolved_interpretations_pull_both_tracks_to_the_group_measurement():
    x1, P1, x2, P2 = _pair(0.6)
    centre = 0.5 * (x1[0] + x2[0])
    z = np.array([[centre, 14.5]])  # one detection of the unresolved group
    Rd = np.array([[DEG**2, 4.0]])
    R = np.diag(Rd[0])
    h1, h2 = _hits(x1, P1, z, R, [0]), _hits(x2, P2, z, R, [0])
    out = interpret(((x1, P1), (x2, P2)), (h1, h2), (0.9, 0.9), z, Rd, 0.05, DEG, 0.9, 3.0)
    for r in out:
        assert math.isclose(sum(v[2] for v in r.values()), 1.0)
        assert 0 in r and -1 in r
    # interpretation (1) (and the fictitious separation 0) brings the two states together
    sep_pred = abs(x1[0] - x2[0])
    sep_upd = abs(out[0][0][0][0] - out[1][0][0][0])
    assert sep_upd < sep_pred
    # with the unresolved model both tracks may own the one detection: its key carries
    # more weight in both tracks than with resolved interpretations only (P_u = 0)
    resolved = interpret(((x1, P1), (x2, P2)), (h1, h2), (0.9, 0.9), z, Rd, 0.05, 1e-9, 0.9, 3.0)
    assert out[0][0][2] + out[1][0][2] > resolved[0][0][2] + resolved[1][0][2]
    assert resolved[0][0][2] + resolved[1][0][2] <= 1.0 + 1e-12  # one detection, one owner


def test_relink_choice_by_rate_sign_then_amplitude():
    assert relink_choice(+1e-4, 10.0, +2e-4, -2e-4, 20.0, 10.0) == 0  # only i's sign agrees
    assert relink_choice(-1e-4, 10.0, +2e-4, -2e-4, 10.0, 20.0) == 1  # only j's sign agrees
    assert relink_choice(+1e-4, 12.0, +2e-4, +3e-4, 20.0, 11.0) == 1  # both: nearer level
    assert relink_choice(+1e-4, 19.0, +2e-4, +3e-4, 20.0, 11.0) == 0
