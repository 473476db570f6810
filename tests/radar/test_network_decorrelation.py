"""Equivalent measurements of 3-state range-Doppler elementary tracks: the decorrelation
of common.radar.fusion.decorrelation recovers the (r_b, v_b) plot each update used."""

from __future__ import annotations

import numpy as np
import pytest

from common.core import kalman
from common.core.motion import bistatic_F, bistatic_Q
from common.radar.fusion.decorrelation import Decorrelator, measured


def test_three_state_equivalent_is_the_plot_used() -> None:
    rng = np.random.default_rng(4)
    dec = Decorrelator(5.0, 1e-3, gate=30.0)
    x = np.array([[80e3, -120.0, 0.0]])
    P = np.diag([300.0 ** 2, 1.0, 400.0])[None]
    t_prev, checked = 0.0, 0
    for k in range(1, 40):
        t = 0.73 * k
        dt = t - t_prev
        xp, Pp = kalman.predict(x, P, bistatic_F(dt)[:3, :3], bistatic_Q(dt, 5.0, 0.0)[:3, :3])
        sig = np.array([300.0, 1.0]) * (1.0 + 0.5 * (k % 3))
        z = np.array([[80e3 - 120.0 * t + 0.4 * t * t, -120.0 + 0.8 * t]]) + rng.standard_normal(2) * sig
        x, P, _, _ = kalman.update(xp, Pp, z - xp[:, :2], np.eye(3)[:2], np.diag(sig ** 2))
        eq = dec.step(0, t, np.array([7]), x, P, np.array([True]), np.array([False]))
        t_prev = t
        assert eq.z.shape == (1, 2)
        if k > 1:
            assert eq.ok[0]
            assert np.all(np.abs(eq.z[0] - z[0]) <= [1e-5, 1e-8]), eq.z[0] - z[0]
            np.testing.assert_allclose(eq.R[0], np.diag(sig ** 2), rtol=1e-5, atol=1e-10)
            checked += 1
    assert checked == 38


def test_measured_components() -> None:
    assert measured(5).tolist() == [0, 1, 3] and measured(3).tolist() == [0, 1]
    with pytest.raises(ValueError):
        measured(4)
