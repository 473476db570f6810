"""Crossings that hold (issue 13): the bearing tracker's IMM in seed 004's memory mode
(common.sonar.bearing.imm, common.sonar.bearing.tracker)."""

from __future__ import annotations

import math

import numpy as np

from common.core.crossing import CrossingParams
from common.core.motion import bearing_F, bearing_Q
from common.sonar.bearing.imm import BearingImm
from common.sonar.bearing.tracker import BearingTracker, TrackerParams

BB = TrackerParams(mode="broadband", q_theta=1e-6, q_theta_quiet=1e-10)
SIG = math.radians(0.5)


def _Q(T: np.ndarray, q: float) -> np.ndarray:
    return bearing_Q(T, q, 1e-4)


def test_imm_in_memory_mode_predicts_both_models_with_the_quiet_q() -> None:
    rng = np.random.default_rng(0)
    mu = np.array([[0.7, 0.3], [0.6, 0.4]])
    xm = np.array([[[1.0, 1e-4, 20.0, 0.0], [1.01, 2e-4, 21.0, 0.01]]] * 2)
    A = rng.standard_normal((2, 2, 4, 4)) * 1e-3
    Pm = A @ np.swapaxes(A, 2, 3) + 1e-6 * np.eye(4)
    T = np.full(2, 10.0)
    imm = BearingImm((1e-10, 1e-6), (600.0, 60.0))
    quiet = BearingImm((1e-10, 1e-10), (600.0, 60.0))
    memory = np.array([True, False])
    got = imm.predict(mu, xm, Pm, T, bearing_F(T), _Q, memory)
    want_mem = quiet.predict(mu, xm, Pm, T, bearing_F(T), _Q)
    want_free = imm.predict(mu, xm, Pm, T, bearing_F(T), _Q)
    for g, wm, wf in zip(got, want_mem, want_free):
        np.testing.assert_allclose(g[0], wm[0], rtol=1e-12, atol=1e-18)  # memory: quiet Q
        np.testing.assert_allclose(g[1], wf[1], rtol=1e-12, atol=1e-18)  # free: both Qs
    assert got[4][0, 1, 1] < want_free[4][0, 1, 1]


def test_tracks_in_memory_mode_coast_without_the_manoeuvre_noise() -> None:
    """Two noiseless contacts converge; while 004 flags them (memory mode, alpha = 0) their
    bearing-rate variance grows by the quiet q_theta T only, not by the manoeuvre one."""
    cp = CrossingParams(method="supnorm", S=8.0, max_duration=1e6)
    tr = BearingTracker(BB, "cylindrical", SIG, cp)
    rate, dt, k = 2e-5, 10.0, 0
    while True:
        t = k * dt
        c = tr.step(t, np.array([1.0 - 0.05 + rate * t, 1.0 + 0.05 - rate * t]),
                    np.array([100.0, 100.0]), 0.0)
        k += 1
        if c.ambiguous.all():
            break
    p0 = c.P[:, 1, 1].copy()
    for _ in range(5):
        t = k * dt
        c = tr.step(t, np.array([1.0 - 0.05 + rate * t, 1.0 + 0.05 - rate * t]),
                    np.array([100.0, 100.0]), 0.0)
        k += 1
        assert c.ambiguous.all()
    growth = c.P[:, 1, 1] - p0
    assert np.all(growth < 10 * 5 * dt * BB.q_theta_quiet)  # 5 T q_quiet, x10 margin
