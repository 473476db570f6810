"""Elementary tracker (001 modules 41-44): [13]-[17], F/Q [19]-[20] in the prediction,
the chi-square(3) gate [8]-[12], score, status and deletion rules, crossing flag."""

from __future__ import annotations

import numpy as np
import pytest
from scipy.stats import chi2

from common.core.rejection import Rejected
from common.core.track_table import Status
from common.radar.elementary.initiation import compatible, initial_state, propagate
from common.radar.elementary.model import AZIMUTH
from common.radar.elementary.tracker import (
    ElementaryParams,
    ElementaryTracker,
    RadarCrossingParams,
    drop_acceleration,
    gate_pairs,
)
from common.radar.plots.channel_fusion import Plots

H = AZIMUTH.H

SIG = (100.0, 2.0, 0.01)


def plots(rows: list[tuple[float, float, float]], n_ch: int | list[int] = 1,
          sig: tuple[float, float, float] = SIG) -> Plots:
    a = np.asarray(rows, dtype=float).reshape(-1, 3)
    n = len(a)
    return Plots(a[:, 0], a[:, 1], a[:, 2], np.full(n, sig[0]), np.full(n, sig[1]),
                 np.full(n, sig[2]), np.broadcast_to(np.asarray(n_ch, dtype=np.int64), (n,)).copy())


def test_eq13_eq14_propagation_hand_computed() -> None:
    prev = plots([(10000.0, -50.0, 1.0)])
    y, s = propagate(prev, dt=2.0, sigma_gamma=0.5, sigma_omega=0.01)
    np.testing.assert_allclose(y, [[9900.0, -50.0, 1.0]])  # 001 [13]
    np.testing.assert_allclose(s[0], [  # 001 [14]
        np.sqrt(100.0**2 + 4 * 2.0**2 + 32 * 0.25 / 20),
        np.sqrt(2.0**2 + 8 * 0.25 / 3),
        np.sqrt(0.01**2 + 8 * 1e-4 / 3),
    ])


def test_eq15_compatibility_edges() -> None:
    y = np.array([[10000.0, 0.0, 1.0]])
    s = np.array([[50.0, 2.0, 0.25]])
    # limits: |dr| <= 3 (100 + 50) = 450, |dv| <= Delta_vb = 40, |dtheta| <= 3 (0.25 + 0.25)
    sig = (100.0, 2.0, 0.25)
    inside = plots([(10450.0, 0.0, 1.0), (10000.0, -40.0, 1.0), (10000.0, 0.0, 2.5)], sig=sig)
    outside = plots([(10450.5, 0.0, 1.0), (10000.0, 40.5, 1.0), (10000.0, 0.0, 2.5001)], sig=sig)
    assert sorted(compatible(y, s, inside, 40.0)[1].tolist()) == [0, 1, 2]
    assert compatible(y, s, outside, 40.0)[1].tolist() == []
    # across North: 0.1 and 2 pi - 0.1 are 0.2 apart
    north = plots([(10000.0, 0.0, 2 * np.pi - 0.1)], sig=sig)
    assert compatible(np.array([[10000.0, 0.0, 0.1]]), s, north, 40.0)[1].tolist() == [0]


def test_eq16_eq17_initial_state() -> None:
    prev = plots([(10000.0, -50.0, 2 * np.pi - 0.01)])
    cur = plots([(9900.0, -46.0, 0.01)], sig=(80.0, 1.5, 0.02))
    x, P = initial_state(prev, cur, np.array([0]), np.array([0]), 2.0, 7.0, 0.03)
    np.testing.assert_allclose(x[0], [9900.0, -46.0, 2.0, 0.01, 0.01], atol=1e-12)  # 001 [16]
    np.testing.assert_allclose(P[0], np.diag([80.0**2, 1.5**2, 49.0, 0.02**2, 0.03**2]))  # [17]


def seed_F(T: float) -> np.ndarray:
    """001 [19] written out."""
    return np.array([[1, T, T**2 / 2, 0, 0], [0, 1, T, 0, 0], [0, 0, 1, 0, 0],
                     [0, 0, 0, 1, T], [0, 0, 0, 0, 1]], dtype=float)


def seed_Q(T: float, sg: float, so: float) -> np.ndarray:
    """001 [20] written out."""
    Q = np.zeros((5, 5))
    Q[:3, :3] = sg**2 * np.array([[T**5 / 20, T**4 / 8, T**3 / 6],
                                  [T**4 / 8, T**3 / 3, T**2 / 2],
                                  [T**3 / 6, T**2 / 2, T]])
    Q[3:, 3:] = so**2 * np.array([[T**3 / 3, T**2 / 2], [T**2 / 2, T]])
    return Q


def started(params: ElementaryParams, n_ch: int = 2, crossing: bool = False
            ) -> ElementaryTracker:
    """A tracker with one track opened from plots at t = 0 and t = 1."""
    trk = ElementaryTracker(params, RadarCrossingParams(enabled=crossing))
    trk.step(0.0, plots([(10000.0, -50.0, 1.0)], n_ch))
    rep = trk.step(1.0, plots([(9950.0, -50.0, 1.001)], n_ch))
    assert len(rep) == 1
    return trk


def test_pure_prediction_uses_eq19_eq20() -> None:
    p = ElementaryParams(sigma_gamma=0.7, sigma_omega=0.002)
    trk = started(p)
    x0, P0 = trk.report().x[0].copy(), trk.report().P[0].copy()
    rep = trk.step(3.5, Plots.empty())  # T = 2.5, no plot: pure prediction
    F, Q = seed_F(2.5), seed_Q(2.5, 0.7, 0.002)
    np.testing.assert_allclose(rep.x[0], F @ x0)  # 001 [25]
    np.testing.assert_allclose(rep.P[0], F @ P0 @ F.T + Q, rtol=1e-12)  # 001 [26]
    assert not rep.updated[0]


def test_update_matches_eq27_eq31() -> None:
    p = ElementaryParams(sigma_gamma=2.0, sigma_omega=1e-3)
    trk = started(p)
    x0, P0 = trk.report().x[0], trk.report().P[0]
    F, Q = seed_F(1.0), seed_Q(1.0, 2.0, 1e-3)
    xp, Pp = F @ x0, F @ P0 @ F.T + Q
    y = np.array([9905.0, -49.0, 1.0015])
    R = np.diag(np.square(SIG))
    S = H @ Pp @ H.T + R  # 001 [28]
    K = Pp @ H.T @ np.linalg.inv(S)  # 001 [29]
    rep = trk.step(2.0, plots([tuple(y)], 2))
    np.testing.assert_allclose(rep.x[0], xp + K @ (y - H @ xp), rtol=1e-9)  # 001 [30]
    np.testing.assert_allclose(rep.P[0], (np.eye(5) - K @ H) @ Pp, rtol=1e-6, atol=1e-9)  # [31]


def test_gate_chi_square_3_dof_edges() -> None:
    gamma = chi2.ppf(0.99, 3)
    z = np.array([[10000.0, 10.0, 1.0]])
    S_pred = np.diag([300.0, 5.0, 1e-4])[None]
    s_tot = np.sqrt(np.diag(S_pred[0]) + np.square(SIG))
    # d = (dr / s_r)^2 on a plot offset in r_b only
    inside = plots([(10000.0 + 0.999 * np.sqrt(gamma) * s_tot[0], 10.0, 1.0)])
    outside = plots([(10000.0 + 1.001 * np.sqrt(gamma) * s_tot[0], 10.0, 1.0)])
    t, j, d = gate_pairs(z, S_pred, inside, gamma)
    assert j.tolist() == [0] and d[0] == pytest.approx(0.999**2 * gamma)
    assert gate_pairs(z, S_pred, outside, gamma)[1].tolist() == []
    # a full-covariance case against a direct computation [8]-[10]
    S_pred = np.array([[[400.0, 30.0, 0.01], [30.0, 9.0, 0.0], [0.01, 0.0, 2e-4]]])
    pl = plots([(10030.0, 12.0, 1.002), (10300.0, 10.0, 1.0)])
    t, j, d = gate_pairs(z, S_pred, pl, gamma)
    for jj, dd in zip(j, d):
        i = pl.y[jj] - z[0]
        S = S_pred[0] + np.diag(np.square(SIG))
        assert dd == pytest.approx(i @ np.linalg.solve(S, i))
    full = [pl.y[k] - z[0] for k in range(2)]
    want = [k for k in range(2)
            if full[k] @ np.linalg.solve(S_pred[0] + np.diag(np.square(SIG)), full[k]) <= gamma]
    assert j.tolist() == want


def test_score_confirmation_coasting_deletion_and_recycling() -> None:
    p = ElementaryParams(confirm_score=6.0, max_coast=2, miss_penalty=1.0, score_per_channel=1.0)
    trk = started(p, n_ch=2)
    rep = trk.report()
    assert rep.score.tolist() == [2.0] and rep.status.tolist() == [Status.TENTATIVE]
    rep = trk.step(2.0, plots([(9900.0, -50.0, 1.002)], 3))
    assert rep.score.tolist() == [5.0] and rep.status.tolist() == [Status.TENTATIVE]
    rep = trk.step(3.0, plots([(9850.0, -50.0, 1.003)], 1))
    assert rep.score.tolist() == [6.0] and rep.status.tolist() == [Status.CONFIRMED]
    tid = int(rep.id[0])
    rep = trk.step(4.0, Plots.empty())
    assert rep.score.tolist() == [5.0] and rep.status.tolist() == [Status.COASTING]
    rep = trk.step(5.0, plots([(9750.0, -50.0, 1.005)], 2))
    assert rep.score.tolist() == [7.0] and rep.status.tolist() == [Status.CONFIRMED]
    trk.step(6.0, Plots.empty())
    assert len(trk.step(7.0, Plots.empty())) == 1  # 2 scans in prediction: kept
    assert len(trk.step(8.0, Plots.empty())) == 0  # more than max_coast: deleted
    # the freed number is reused by the next track
    trk.step(9.0, plots([(50000.0, 10.0, 3.0)], 2))
    rep = trk.step(10.0, plots([(50010.0, 10.0, 3.0)], 2))
    assert rep.id.tolist() == [tid]


def test_ambiguous_association_penalty_and_tentative_death() -> None:
    p = ElementaryParams(ambiguity_penalty=0.5, max_coast_tentative=1)
    trk = started(p, n_ch=2)
    # two plots inside the gate: the decision is ambiguous, the score gets the penalty
    rep = trk.step(2.0, plots([(9900.0, -50.0, 1.002), (9910.0, -50.0, 1.002)], 2))
    assert rep.score[0] == pytest.approx(2.0 + 2.0 - 0.5)
    trk.step(3.0, Plots.empty())
    rep = trk.step(4.0, Plots.empty())
    assert 1 not in rep.id.tolist()  # tentative: deleted after max_coast_tentative misses


def test_several_tracks_from_one_plot_and_unsupported_ones_die() -> None:
    trk = ElementaryTracker(ElementaryParams(), RadarCrossingParams(enabled=False))
    trk.step(0.0, plots([(10000.0, -50.0, 1.0), (10020.0, -45.0, 1.001)], 2))
    rep = trk.step(1.0, plots([(9950.0, -50.0, 1.0)], 2))
    assert len(rep) == 2  # both previous plots are compatible with the new one
    for k in range(2, 12):
        rep = trk.step(float(k), plots([(10000.0 - 50.0 * k, -50.0, 1.0)], 2))
    assert len(rep) == 1 and rep.status.tolist() == [Status.CONFIRMED]


def test_time_must_increase() -> None:
    trk = ElementaryTracker()
    trk.step(1.0, Plots.empty())
    with pytest.raises(Rejected, match="time_backwards"):
        trk.step(1.0, Plots.empty())


def test_crossing_flag_and_memory_mode() -> None:
    # two confirmed tracks converging in (r_b, theta): flagged, memory mode (alpha = 0)
    trk = ElementaryTracker(ElementaryParams(), RadarCrossingParams(method="supnorm", S=3.0))
    for k in range(8):
        trk.step(float(k), plots([(10000.0 + 40.0 * k, 40.0, 1.0), (11000.0 - 40.0 * k, -40.0, 1.0)], 3))
    rep = trk.report()
    assert rep.status.tolist() == [Status.CONFIRMED] * 2 and not rep.ambiguous.any()
    k = 12.0  # both at r_b = 10480 / 10520, same azimuth: within 3 sigma
    prev = trk.report().x.copy()
    rep = trk.step(k, plots([(10480.0, 40.0, 1.0), (10520.0, -40.0, 1.0)], 3))
    assert rep.ambiguous.all()
    F = seed_F(k - 7.0)
    want = prev @ F.T  # memory mode: prediction only, then gamma_b dropped
    want[:, 2] = 0.0
    np.testing.assert_allclose(rep.x, want)
    # the next memory scan extrapolates the linear model: r_b + v_b T, theta + omega T
    nxt = trk.step(k + 2.0, plots([(10560.0, 40.0, 1.0), (10440.0, -40.0, 1.0)], 3))
    assert nxt.ambiguous.all()
    np.testing.assert_allclose(nxt.x[:, 0], rep.x[:, 0] + 2.0 * rep.x[:, 1])
    np.testing.assert_allclose(nxt.x[:, [1, 2, 4]], rep.x[:, [1, 2, 4]])


def test_drop_acceleration_keeps_the_estimate_as_variance() -> None:
    x = np.array([[1e4, 40.0, 3.0, 1.0, 0.01], [2e4, -40.0, -2.0, 1.0, 0.0]])
    P = np.stack([np.eye(5) * 4.0, np.eye(5) * 4.0])
    P0 = P.copy()
    drop_acceleration(x, P, np.array([True, False]))
    assert x[:, 2].tolist() == [0.0, -2.0]
    assert P[0, 2, 2] == 4.0 + 9.0
    P0[0, 2, 2] = 13.0
    np.testing.assert_array_equal(P, P0)


def test_crossing_candidates_match_brute_force() -> None:
    from common.radar.elementary.tracker import neighbours
    rng = np.random.default_rng(5)
    z = np.column_stack([rng.uniform(0, 2e4, 300), rng.uniform(0, 2 * np.pi, 300)])
    s = np.column_stack([rng.uniform(50, 150, 300), rng.uniform(0.005, 0.02, 300)])
    d_rb = np.abs(z[:, None, 0] - z[None, :, 0]) <= 8 * (s[:, None, 0] + s[None, :, 0])
    d_az = np.abs((z[:, None, 1] - z[None, :, 1] + np.pi) % (2 * np.pi) - np.pi)
    close = d_rb & (d_az <= 8 * (s[:, None, 1] + s[None, :, 1]))
    np.fill_diagonal(close, False)
    assert neighbours(z, s, 8.0).tolist() == close.any(axis=1).tolist()
