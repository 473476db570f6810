"""Bearing tracks that hold (issue 13): the bearing-rate IMM (common.sonar.bearing.imm) and
the merging of a tentative track into a confirmed one (common.sonar.bearing.merge)."""

from __future__ import annotations

import math
from dataclasses import replace

import numpy as np
import pytest

from common.sonar.bearing.merge import merged_tentative
from common.sonar.bearing.tracker import BearingTracker, TrackerParams

BB = TrackerParams(mode="broadband", crossing=False, clutter_level_db=2.0)
SIG = math.radians(1.0)


def _run(tr: BearingTracker, rates: np.ndarray, dt: float = 5.0, seed: int = 0):
    """One contact whose bearing rate (rad/s) per cycle is `rates`; returns per cycle the
    manoeuvre-model probability and the bearing error of the first track while it lives."""
    rng = np.random.default_rng(seed)
    brg, mu, err = 1.0, [], []
    for k, r in enumerate(rates):
        brg += r * dt
        tr.step(k * dt, np.array([brg + SIG * rng.standard_normal()]), np.array([30.0]), 0.0)
        first = np.flatnonzero(tr.table.alive & (tr.table.uid == 0))
        if first.size == 0:
            break
        mu.append(tr.table.mu[first[0], 1])
        err.append(tr.table.x[first[0], 0] - brg)
    return np.array(mu), np.array(err)


def test_imm_manoeuvre_model_takes_over_at_a_bearing_rate_change() -> None:
    ramp = np.linspace(0.0, math.radians(10.0) / 60.0, 12)  # 0 -> 10 deg/min in 60 s
    rates = np.r_[np.zeros(60), ramp, np.full(48, ramp[-1])]
    mu, err = _run(BearingTracker(BB, "cylindrical", SIG), rates)
    assert mu.size == rates.size  # one number throughout
    assert mu[40:60].mean() < 0.15  # straight: the quiet model
    assert mu[60:80].max() > 0.5  # the rate change: the manoeuvre model
    assert mu[110:].mean() < 0.2  # the new rate learnt: quiet again


def test_imm_beats_the_single_model_on_a_straight_contact() -> None:
    rates = np.full(120, math.radians(1.0) / 60.0)
    _, e_imm = _run(BearingTracker(BB, "cylindrical", SIG), rates, seed=3)
    _, e_one = _run(BearingTracker(replace(BB, q_theta_quiet=0.0), "cylindrical", SIG), rates, seed=3)
    assert np.sqrt(np.mean(e_imm[40:] ** 2)) < 0.8 * np.sqrt(np.mean(e_one[40:] ** 2))


def test_a_tentative_track_on_a_confirmed_one_is_merged_a_distant_one_kept() -> None:
    P = np.diag([SIG**2, 1e-6, 4.0, 0.01])
    x = np.array([[1.0, 0.0, 15.0, 0.0],        # confirmed
                  [1.0 + 2 * SIG, 0.0, 15.0, 0.0],   # tentative, d^2 = 2 < 9.21
                  [1.0 + 6 * SIG, 0.0, 15.0, 0.0],   # tentative, d^2 = 18
                  [1.0 - 6 * SIG, 0.0, 15.0, 0.0]])  # confirmed
    conf = np.array([True, False, False, True])
    out = merged_tentative(x, np.repeat(P[None], 4, axis=0), conf, 9.21)
    assert out.tolist() == [False, True, False, False]
    wrapped = x.copy()
    wrapped[0, 0], wrapped[1, 0] = 0.001, 2 * math.pi - 0.001  # across North
    assert merged_tentative(wrapped[:2], np.repeat(P[None], 2, axis=0), conf[:2], 9.21)[1]


def test_register_holds_the_associated_detections_not_the_estimates() -> None:
    """TMA is fed the bearing register: the raw detections (independent, sigma known)."""
    tr = BearingTracker(BB, "cylindrical", SIG)
    rng = np.random.default_rng(5)
    z = 1.0 + SIG * rng.standard_normal(12)
    seen = [k for k in range(12) if k != 7]  # cycle 7: no detection
    for k in range(12):
        b = np.array([z[k]]) if k in seen else np.zeros(0)
        tr.step(10.0 * k, b, np.full(b.size, 30.0), 0.0, own_x=float(k))
    status, h = tr.history_of(int(tr.table.id[tr.table.active_indices()[0]]))
    assert status == "confirmed"
    np.testing.assert_allclose(h["t"], 10.0 * np.array(seen))
    np.testing.assert_allclose(h["brg"], z[seen])
    np.testing.assert_allclose(h["sbrg"], SIG)
    np.testing.assert_allclose(h["own_x"], seen)
    assert not np.allclose(h["brg"], tr.table.x[tr.table.active_indices()[0], 0])


def test_amplitude_weak_detections_raise_the_quality_less_and_weak_tracks_lose_less() -> None:
    """P_FA from the detection's level, P_D from the track's predicted amplitude (000 erfc)."""
    def quality(levels_db: list[float], miss_at_end: bool) -> list[float]:
        tr = BearingTracker(BB, "cylindrical", SIG)
        out = []
        for k, a in enumerate(levels_db):
            tr.step(10.0 * k, np.array([1.0]), np.array([10 ** (a / 10.0)]), 0.0)
            out.append(float(tr.table.score[tr.table.active_indices()[0]]))
        if miss_at_end:
            tr.step(10.0 * len(levels_db), np.zeros(0), np.zeros(0), 0.0)
            out.append(float(tr.table.score[tr.table.active_indices()[0]]))
        return out
    strong, weak = quality([15.0] * 4, True), quality([4.0] * 4, True)
    assert strong[3] - strong[2] > weak[3] - weak[2] + 3.0  # 11 dB above: ~5.5 nats
    miss_strong, miss_weak = strong[4] - strong[3], weak[4] - weak[3]
    assert miss_strong == pytest.approx(math.log(1 - BB.p_d), abs=1e-3)
    assert miss_weak > miss_strong + 0.1  # a track near the threshold is often missed
