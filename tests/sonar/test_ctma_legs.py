"""Tests of 003 claim 9 / paragraph 55 (common.sonar.tma.constrained_solve, ctma): bounds per target leg.

Scene: own ship 8 kn zig-zagging 45/135 deg every 6 min, one bearing every 20 s for an
hour, sigma 0.5 deg. The target (2, 6) km from the own start runs 5 kn on 239.5 deg, and
turns at 30 min to 290 deg, 5 kn. Original bounds: 2-25 km, course 160-240 deg, 3-8 kn:
the first leg's course is inside them (0.5 deg from the edge, so that the unconstrained
TMA (course sigma about 1 deg) leaves them in about a third of the runs), the second
leg's course 50 deg outside.
"""

from __future__ import annotations

import numpy as np
import pytest

from common.core.angles import TWO_PI
from common.sonar.tma.bearings_only import solve_tma, state_map
from common.sonar.tma.bounds import Bounds
from common.sonar.tma.constrained import CtmaParams, TmaTracker
from common.sonar.tma.constrained_solve import new_leg_bounds, solve_ctma
from common.sonar.tma.crlb import position_rms_bound

D = np.radians
KN = 1852.0 / 3600.0
SIG = D(0.5)
DT, N = 20.0, 181
T = np.arange(N) * DT
TA = 1800.0
ORIG = Bounds(2000.0, 25e3, D(160.0), D(240.0), 3 * KN, 8 * KN)
RUNS = 20


def _own() -> np.ndarray:
    crs = np.where((T[:-1] // 360.0) % 2 == 0, D(45.0), D(135.0))
    steps = np.stack((np.sin(crs), np.cos(crs)), 1) * 8 * KN * DT
    return np.vstack(([0.0, 0.0], np.cumsum(steps, 0)))


OWN = _own()
K1, K2 = D(239.5), D(290.0)
BETA = np.array([2000.0, 6000.0, 5 * KN * np.sin(K1), 5 * KN * np.cos(K1), 5 * KN * np.sin(K2), 5 * KN * np.cos(K2)])
X = state_map(T, 0.0, (TA,)) @ BETA
BRG = np.arctan2(X[:, 0] - OWN[:, 0], X[:, 1] - OWN[:, 1])
CRLB = position_rms_bound(BETA, T, OWN, SIG, 0.0, T[-1], (TA,))


def rms(e: list[float]) -> float:
    return float(np.sqrt(np.mean(np.square(e))))


def course_speed(v: np.ndarray) -> tuple[float, float]:
    return float(np.arctan2(v[0], v[1]) % TWO_PI), float(np.hypot(v[0], v[1]))


def inside(b: Bounds, v: np.ndarray) -> bool:
    """Course and speed of the leg velocity v within b (tolerance 1e-6)."""
    k, s = course_speed(v)
    return (k - b.k_min + 1e-6) % TWO_PI <= b.course_width + 2e-6 and b.v_min - 1e-6 <= s <= b.v_max + 1e-6


@pytest.fixture(scope="module")
def runs() -> list[dict[str, np.ndarray]]:
    """TMA, single-bound CTMA (only the current leg bounded, by the original bounds) and
    per-leg CTMA (claim 9) of RUNS noisy bearing sets."""
    out = []
    for seed in range(RUNS):
        b = BRG + SIG * np.random.default_rng(300 + seed).standard_normal(N)
        tma = solve_tma(T, b, SIG, OWN, 0.0, legs=(TA,))
        single = solve_ctma(T, b, SIG, OWN, 0.0, ORIG, tma, legs=(TA,))
        legs = solve_ctma(T, b, SIG, OWN, 0.0, new_leg_bounds(ORIG), tma, legs=(TA,), leg_bounds=(ORIG,))
        out.append({"tma": tma.beta, "single": single.beta, "legs": legs.beta,
                    **{f"x_{k}": s.state_at(T[-1])[0] for k, s in (("tma", tma), ("single", single), ("legs", legs))}})
    return out


def test_scene_legs_inside_and_outside_original_bounds():
    assert ORIG.contains(2500.0, K1, 5 * KN) and not ORIG.contains(2500.0, K2, 5 * KN)
    v = np.diff(OWN, axis=0)
    assert set(np.round(np.degrees(np.arctan2(v[:, 0], v[:, 1])))) == {45.0, 135.0}


def test_new_leg_bounds_free_course_keep_range_and_speed():
    nb = new_leg_bounds(ORIG)
    assert nb.course_width == TWO_PI
    assert (nb.r_min, nb.r_max, nb.v_min, nb.v_max) == (ORIG.r_min, ORIG.r_max, ORIG.v_min, ORIG.v_max)


def test_per_leg_bounds_recover_new_leg_where_single_bounds_are_biased(runs):
    truth = X[-1, :2]
    err = {k: [float(np.hypot(*(r[f"x_{k}"][:2] - truth))) for r in runs] for k in ("tma", "single", "legs")}
    assert rms(err["legs"]) <= 1.5 * CRLB
    assert rms(err["legs"]) <= 1.2 * rms(err["tma"])
    assert rms(err["single"]) >= 5.0 * CRLB
    k_err = [np.degrees(abs((course_speed(r["legs"][4:])[0] - K2 + np.pi) % TWO_PI - np.pi)) for r in runs]
    assert rms(k_err) < 5.0


def test_earlier_leg_course_and_speed_stay_within_original_bounds(runs):
    assert sum(not inside(ORIG, r["tma"][2:4]) for r in runs) >= 3
    assert all(inside(ORIG, r["legs"][2:4]) for r in runs)
    assert not all(inside(ORIG, r["single"][2:4]) for r in runs)


def track(bounds: Bounds | None, seed: int) -> tuple[TmaTracker, list]:
    """A tracker with manoeuvre detection fed the scene in 2-minute batches."""
    b = BRG + SIG * np.random.default_rng(300 + seed).standard_normal(N)
    trk = TmaTracker(bounds, CtmaParams(detect_manoeuvres=True))
    outs = [trk.update(T[i:i + 6], b[i:i + 6], SIG, OWN[i:i + 6]) for i in range(0, N, 6)]
    return trk, outs


@pytest.mark.slow
def test_tracker_gives_earlier_leg_its_bounds_at_the_manoeuvre_and_frees_the_new_course():
    err, err_tma, one_leg = [], [], 0
    for seed in range(RUNS):
        trk, outs = track(ORIG, seed)
        assert trk.legs and len(trk.leg_bounds) == len(trk.legs)
        one_leg += len(trk.legs) == 1 and abs(trk.legs[0] - TA) <= 120.0
        at_ta = [o.bounds for o in outs if o is not None and o.t <= trk.legs[0]][-1]
        assert trk.leg_bounds[0] == at_ta and at_ta.course_width == pytest.approx(ORIG.course_width)
        assert trk.bounds.course_width == TWO_PI
        err.append(np.hypot(outs[-1].x - X[-1, 0], outs[-1].y - X[-1, 1]))
        o = track(None, seed)[1][-1]
        err_tma.append(np.hypot(o.x - X[-1, 0], o.y - X[-1, 1]))
    assert one_leg >= 18
    assert rms(err) <= 1.1 * rms(err_tma)
