"""The online clutter level (common.sonar.bearing.clutter_level): the exponentially
weighted mean excess of the untaken detections over D_thr, the parameter of 000's
level-based P_FA."""

from __future__ import annotations

import math

import numpy as np
import pytest

from common.core.params import ParamError
from common.sonar.bearing.clutter_level import ClutterLevel
from common.sonar.bearing.tracker import BearingTracker, TrackerParams

AUTO = TrackerParams(mode="broadband", clutter_estimate=True)
CONTACTS = np.radians([40.0, 150.0, 260.0])


def _scene(mu: float, contacts: bool, cycles: int = 300, seed: int = 3):
    """Clutter-only (or with three 15 dB contacts) detection lists: 6 false detections a
    cycle on average, uniform bearings, levels D_thr + Exponential(mu) as common.sim.sonar."""
    rng = np.random.default_rng(seed)
    for k in range(cycles):
        n = rng.poisson(6.0)
        brg = rng.uniform(0.0, 2.0 * math.pi, n)
        lvl = AUTO.d_thr + rng.exponential(mu, n)
        if contacts:
            brg = np.r_[CONTACTS + rng.normal(0.0, 0.005, 3), brg]
            lvl = np.r_[15.0 + rng.normal(0.0, 1.0, 3), lvl]
        yield 10.0 * k, brg % (2.0 * math.pi), 10.0 ** (lvl / 10.0)


def test_estimator_is_the_mean_excess_bounded_and_seeded() -> None:
    est = ClutterLevel(2.0, 50.0, (0.5, 20.0))
    assert est.value == 2.0  # the prior before any detection
    rng = np.random.default_rng(1)
    for _ in range(400):
        est.update(3.0 + rng.exponential(5.0, 8), 3.0)
    assert est.value == pytest.approx(5.0, rel=0.1)
    for _ in range(400):
        est.update(np.full(8, 2.0), 3.0)  # below D_thr: excess 0, held at the lower bound
    assert est.value == 0.5


@pytest.mark.parametrize("mu", [1.0, 4.0])
@pytest.mark.parametrize("contacts", [False, True])
def test_tracker_estimate_converges_and_tracks_do_not_bias_it(mu: float, contacts: bool) -> None:
    tr = BearingTracker(AUTO, "cylindrical", 0.01)
    assert tr.clutter is not None
    seen: list[float] = []
    late = []
    for k, (t, brg, amp) in enumerate(_scene(mu, contacts)):
        c = tr.step(t, brg, amp, 0.0)
        if k >= 150:
            late.append(tr.clutter.value)
        if contacts:
            seen.extend(10.0 * np.log10(amp) - AUTO.d_thr)
    if contacts:
        assert int(c.confirmed.sum()) >= 3
        assert np.mean(seen) > 1.5 * mu  # every detection's mean would be far off
    assert np.mean(late) == pytest.approx(mu, rel=0.1)
    assert max(abs(v / mu - 1.0) for v in late) < 0.35


def test_a_known_level_takes_precedence_and_bounds_are_checked() -> None:
    with pytest.raises(ParamError):
        TrackerParams(clutter_bounds_db=[5.0, 1.0])
    known = TrackerParams(mode="broadband", clutter_estimate=True, clutter_level_db=2.0)
    assert BearingTracker(known, "cylindrical", 0.01).clutter is None
    off = TrackerParams(mode="broadband", clutter_estimate=False)
    assert BearingTracker(off, "cylindrical", 0.01).clutter is None
