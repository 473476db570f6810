"""Equivalent measurements (common.radar.fusion.decorrelation) recovered from the reports of the real
elementary tracker (common.radar.elementary.tracker) equal the fused plots it used."""

from __future__ import annotations

import numpy as np

from common.radar.elementary.tracker import ElementaryParams, ElementaryTracker, RadarCrossingParams
from common.radar.fusion.decorrelation import Decorrelator
from common.radar.plots.channel_fusion import Plots

SIG = np.array([150.0, 1.5, np.radians(1.0)])


def _scan(y: np.ndarray, sig: np.ndarray) -> Plots:
    n = y.shape[0]
    return Plots(y[:, 0].copy(), y[:, 1].copy(), y[:, 2].copy(), np.full(n, sig[0]),
                 np.full(n, sig[1]), np.full(n, sig[2]), np.full(n, 3, dtype=np.int64))


def _run(scans: list[tuple[float, np.ndarray, np.ndarray]]) -> list[tuple]:
    """Feed (t, plots (n, 3), sigmas (3,)) to a tracker and a decorrelator."""
    p = ElementaryParams()
    trk = ElementaryTracker(p, RadarCrossingParams(enabled=False))
    dec = Decorrelator(p.sigma_gamma, p.sigma_omega, gate=30.0)
    out = []
    for t, y, sig in scans:
        r = trk.step(t, _scan(y, sig))
        eq = dec.step(0, t, r.id, r.x, r.P, r.updated, r.ambiguous)
        out.append((r, eq))
    return out


def _target(t: float) -> np.ndarray:
    """A target with bistatic acceleration and azimuth rate, across North."""
    return np.array([60000.0 - 150.0 * t + 0.6 * t * t, -150.0 + 1.2 * t,
                     (2 * np.pi - 0.05 + 0.004 * t) % (2 * np.pi)])


def test_equivalent_measurement_is_the_plot_used() -> None:
    rng = np.random.default_rng(3)
    scans = []
    for k in range(40):
        t = float(k)
        sig = SIG * (1.0 + 0.5 * (k % 3))  # the plot accuracy changes from scan to scan
        y = _target(t) + rng.standard_normal(3) * sig
        y[2] %= 2 * np.pi
        scans.append((t, y[None], sig))
    res = _run(scans)
    checked = 0
    for k, (r, eq) in enumerate(res):
        if k < 2:
            continue
        assert len(r) == 1 and r.updated[0] and eq.ok[0]
        _, y, sig = scans[k]
        d = eq.z[0] - y[0]
        d[2] = (d[2] + np.pi) % (2 * np.pi) - np.pi
        assert np.all(np.abs(d) <= [1e-6, 1e-8, 1e-10]), d
        np.testing.assert_allclose(eq.R[0], np.diag(sig**2), rtol=1e-5, atol=1e-12)
        checked += 1
    assert checked == 38
    # first report of the track: its own estimate, once
    r, eq = res[1]
    assert eq.ok[0]
    np.testing.assert_allclose(eq.z[0], r.x[0, [0, 1, 3]])


def test_coasting_and_missed_scans_give_no_measurement() -> None:
    rng = np.random.default_rng(4)
    scans = []
    for k in range(20):
        t = float(k)
        y = (_target(t) + rng.standard_normal(3) * SIG)[None] if k not in (8, 9) else np.zeros((0, 3))
        scans.append((t, y, SIG))
    res = _run(scans)
    for k in (8, 9):
        r, eq = res[k]
        assert len(r) == 1 and not r.updated[0] and not eq.ok[0]
    r, eq = res[10]  # updated again: the plot of scan 10 only (not 8-9)
    assert eq.ok[0]
    np.testing.assert_allclose(eq.z[0, 0], scans[10][1][0, 0], atol=1e-3)


def test_skipped_report_or_ambiguous_track_gives_no_measurement() -> None:
    """A report that follows a lost one (two plots since the stored report: the gain is
    not H' R^-1 H of one plot) and an ambiguous track (004, gain scaled by alpha: not
    recoverable) give no measurement; the next regular report gives one again."""
    rng = np.random.default_rng(5)
    scans = [(float(k), (_target(float(k)) + rng.standard_normal(3) * SIG)[None], SIG)
             for k in range(25)]
    res = _run(scans)
    p = ElementaryParams()
    dec = Decorrelator(p.sigma_gamma, p.sigma_omega, gate=30.0)
    for k in (5, 7, 8):  # report 6 lost on the way
        r, _ = res[k]
        amb = np.zeros(1, dtype=bool)
        eq = dec.step(0, float(k), r.id, r.x, r.P, r.updated, amb)
        assert bool(eq.ok[0]) is (k != 7), k  # 5: first report, its own estimate
    r, _ = res[9]
    assert not dec.step(0, 9.0, r.id, r.x, r.P, r.updated, np.ones(1, dtype=bool)).ok[0]
    r, _ = res[10]  # report 9 was stored: 10 is exact again
    eq = dec.step(0, 10.0, r.id, r.x, r.P, r.updated, np.zeros(1, dtype=bool))
    assert eq.ok[0] and abs(eq.z[0, 0] - scans[10][1][0, 0]) < 1e-6
