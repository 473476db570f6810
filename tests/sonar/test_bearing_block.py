"""004's block estimator in the single-hypothesis bearing tracker (common.sonar.bearing.block,
step 5b of common.sonar.bearing.tracker)."""

from __future__ import annotations

import math
from dataclasses import replace

import numpy as np

from common.core.angles import wrap_pi
from common.core.crossing import CrossingParams
from common.sonar.bearing.block import CrossingBlocks
from common.sonar.bearing.tracker import BearingTracker, TrackerParams

SIG = math.radians(1.0)
RATE = math.radians(1.0) / 60.0  # each contact 1 deg/min, 2 deg/min relative
CP = CrossingParams(max_duration=600.0)


def truth(t: float) -> np.ndarray:
    """Two contacts crossing on bearing 090 at t = 150 s."""
    return np.array([math.radians(87.5) + RATE * t, math.radians(92.5) - RATE * t])


def run(block: bool, seed: int):
    """The tracker over 600 s of 5 s scans (P_D 1, no clutter); yields (tracker, cycle, t)."""
    p = replace(TrackerParams(mode="broadband"), block_estimator=block)
    tr = BearingTracker(p, "cylindrical", SIG, CP)
    rng = np.random.default_rng(seed)
    for k in range(121):
        t = 5.0 * k
        z = truth(t) + rng.normal(0.0, SIG, 2)
        amp = 10 ** (rng.normal(15.0, 1.0, 2) / 10.0)
        yield tr, tr.step(t, z, amp, 0.0), t


def test_a_track_leaving_the_ambiguity_resumes_from_its_block_line() -> None:
    """At every scan where a flag clears, the track's bearing and rate are those of the
    line the estimator fitted, and that line is near a contact (seeds 1-5: 11 exits,
    errors 0.3-0.9 deg but one of 2.5 deg, an episode of 35 s 1.8 deg before the crossing)."""
    errs = []
    for seed in range(1, 6):
        for tr, c, t in run(True, seed):
            assert tr.blocks is not None
            for ex in tr.blocks.last:
                slot = int(np.flatnonzero(tr.table.uid == ex.uid)[0])
                row = int(np.flatnonzero(c.ids == tr.table.id[slot])[0])
                assert math.isclose(c.x[row, 0], ex.brg % (2 * math.pi), abs_tol=1e-12)
                assert c.x[row, 1] == ex.rate
                errs.append(np.abs(wrap_pi(truth(t) - ex.brg)).min())
    assert len(errs) >= 10
    assert np.median(errs) < math.radians(1.0) and max(errs) < math.radians(3.0)


def test_off_keeps_no_episode() -> None:
    """Off (the default), the tracker has no block estimator."""
    for tr, _c, _t in run(False, 1):
        assert tr.blocks is None


def test_an_episode_without_points_leaves_the_state() -> None:
    """A flag that rises and clears with no register rows and no detection near the
    track gives no line (the Kalman state stays), and no error."""
    blocks = CrossingBlocks(2 * math.pi, 120.0)
    x = np.array([[1.0, 0.0, 15.0, 0.0]])
    P = np.eye(4)[None] * 1e-4
    args = (np.array([5]), np.array([True]))
    far = (np.array([2.0]), np.array([1e-4]))
    assert blocks.step(0.0, *args, np.array([True]), x, P, np.array([0.5]), *far, {}) == []
    assert blocks.step(5.0, *args, np.array([False]), x, P, np.array([0.5]), *far, {}) == []
    assert blocks.episodes == {}
