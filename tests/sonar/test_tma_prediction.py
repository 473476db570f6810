"""The bearing predicted from a contact's TMA solution (issue 31 section 1,
common.sonar.bearing.tma_prediction) and the issue's geometry in one process
(benchmarks/sonar_cpa.py's chain: simulator -> bearing tracker -> TMA manager -> the
solutions back to the tracker as the bearing-tracker service takes them)."""

from __future__ import annotations

import math
import sys
from pathlib import Path

import numpy as np
import pytest

from common.sonar.bearing.range_noise import RangeNoise
from common.sonar.bearing.tma_prediction import TmaHint, bearing_and_rate, predict, propagate

REPO = Path(__file__).resolve().parents[2]
COARSE = REPO / "scenarios" / "sonar_cpa_coarse.toml"
OWN_V = np.array([0.0, 3.0])  # own ship North at 3 m/s
TGT = np.array([600.0, 3000.0, 0.0, -5.0])  # target: passes 600 m East of the own ship, heading South
T_CPA = 3000.0 / 8.0  # s: relative speed 8 m/s


def own(t: float) -> np.ndarray:
    return OWN_V * t


def truth(t: float) -> np.ndarray:
    """[theta, theta'] of the target from the own ship at t."""
    d = TGT[:2] + TGT[2:] * t - own(t)
    w = TGT[2:] - OWN_V
    return np.array([math.atan2(d[0], d[1]), (d[1] * w[0] - d[0] * w[1]) / (d @ d)])


def hint(P_scale: float = 1.0, converged: bool = True, usable: bool = True, at: float = 0.0,
         shift: np.ndarray | None = None) -> TmaHint:
    s = TGT.copy() + (0.0 if shift is None else shift)
    p = s[:2] + s[2:] * at
    return TmaHint(at, p[0], p[1], s[2], s[3], usable, np.diag([100.0**2, 100.0**2, 0.3**2, 0.3**2]) * P_scale,
                   converged)


def track_at(t: float, sigma: float = math.radians(1.5)) -> tuple[np.ndarray, np.ndarray]:
    """A track's [theta, theta'] and covariance sitting on the truth at t."""
    return truth(t), np.diag([sigma**2, (sigma / 60.0) ** 2])


def model(t0: float, T: float) -> tuple[np.ndarray, np.ndarray]:
    """000's constant-rate prediction over T from the track of t0 (no process noise)."""
    x0, P0 = track_at(t0)
    F = np.array([[1.0, T], [0.0, 1.0]])
    return F @ x0, F @ P0 @ F.T


def test_bearing_and_rate_and_its_jacobian() -> None:
    m, J = bearing_and_rate(TGT[:2], TGT[2:], 0.0, 300.0, own(300.0), OWN_V)
    assert m == pytest.approx(truth(300.0), abs=1e-12)
    eps = 1e-3
    for i in range(4):
        e = np.eye(4)[i] * eps
        hi, _ = bearing_and_rate((TGT + e)[:2], (TGT + e)[2:], 0.0, 300.0, own(300.0), OWN_V)
        lo, _ = bearing_and_rate((TGT - e)[:2], (TGT - e)[2:], 0.0, 300.0, own(300.0), OWN_V)
        assert J[:, i] == pytest.approx((hi - lo) / (2.0 * eps), rel=1e-5, abs=1e-12)


def test_bearing_and_rate_are_scale_invariant() -> None:
    """The direction bearings alone leave open (d -> k d, w -> k w) moves neither theta
    nor theta': J (d, w) = 0, so J P J' stays finite when the range is not observable."""
    d, w = TGT[:2], TGT[2:] - OWN_V
    _, J = bearing_and_rate(TGT[:2], TGT[2:], 0.0, 0.0, own(0.0), OWN_V)
    assert J @ np.r_[d, w] == pytest.approx(np.zeros(2), abs=1e-15)


def test_far_from_the_approach_the_model_predicts() -> None:
    """At 3 km the bearing rate is nearly constant over 60 s: an unobservable solution does
    not switch, an observable one propagates the track's own state along its relative
    track, which there is 000's constant rate within a fraction of its sigma."""
    x0, P0 = track_at(0.0)
    x1, P1 = model(0.0, 60.0)
    assert predict(hint(usable=False), 0.0, own(0.0), 60.0, own(60.0), x0, P0, x1, P1) is None
    out = predict(hint(), 0.0, own(0.0), 60.0, own(60.0), x0, P0, x1, P1)
    assert out is not None
    assert abs(out[0][0] - x1[0]) < 0.2 * math.sqrt(P1[0, 0])


def test_near_the_approach_the_track_follows_the_relative_track() -> None:
    """In the last minute before the closest approach (600 m) the bearing moves 39 deg;
    000's constant rate from the track on the truth misses it by 10 deg. With an observable
    solution the track's own [theta, theta'] propagated along the solution's relative track
    (s = r'/r from it) is on the truth; the linearised transition F is the Jacobian."""
    t0, t1 = T_CPA - 60.0, T_CPA
    x0, P0 = track_at(t0)
    x1, P1 = model(t0, 60.0)
    out = predict(hint(), t0, own(t0), t1, own(t1), x0, P0, x1, P1)
    assert out is not None
    m, C, F = out
    assert abs(truth(t1)[0] - x1[0]) > math.radians(9.0)
    assert m == pytest.approx(truth(t1), abs=1e-9)
    assert math.sqrt(C[0, 0]) < math.radians(20.0)
    s = float(np.dot(TGT[:2] + TGT[2:] * t0 - own(t0), TGT[2:] - OWN_V)) / float(
        np.sum((TGT[:2] + TGT[2:] * t0 - own(t0)) ** 2))
    eps = 1e-7
    for i in range(2):
        e = np.eye(2)[i] * eps
        hi, lo = propagate(x0 + e, s, 60.0)[0], propagate(x0 - e, s, 60.0)[0]
        assert F[:, i] == pytest.approx((hi - lo) / (2.0 * eps), rel=1e-4, abs=1e-9)


def test_near_the_approach_an_unobservable_solution_predicts_the_bearing() -> None:
    """The same minute with a solution whose range is not observable: the solution's own
    bearing and rate (026) are on the truth within its sigma."""
    t0, t1 = T_CPA - 60.0, T_CPA
    x0, P0 = track_at(t0)
    x1, P1 = model(t0, 60.0)
    out = predict(hint(usable=False), t0, own(t0), t1, own(t1), x0, P0, x1, P1 * 20.0)
    assert out is not None
    m, C, _ = out
    assert abs(m[0] - truth(t1)[0]) < math.sqrt(C[0, 0]) < math.radians(20.0)


@pytest.mark.parametrize(("bad", "usable"), [(b, u) for b in ("not converged", "no P", "another contact")
                                             for u in (True, False)] + [("far from the model", False)])
def test_a_wrong_solution_cannot_capture_the_track(bad: str, usable: bool) -> None:
    """(An observable solution propagates the track's own state: there is no bearing of its
    own to be far from the model's.)"""
    t0, t1 = T_CPA - 60.0, T_CPA
    x0, P0 = track_at(t0)
    x1, P1 = model(t0, 60.0)
    h = {"not converged": hint(converged=False, usable=usable),
         "no P": TmaHint(0.0, *TGT, usable, None, True),
         # the mirror contact, passing 600 m West: 77 deg off the track at t0
         "another contact": hint(shift=np.array([-1200.0, 0.0, 0.0, 0.0]), usable=usable),
         "far from the model": hint(usable=usable)}[bad]
    if bad == "far from the model":  # the model's prediction tight and 90 deg away
        x1 = x1 + np.array([math.pi / 2.0, 0.0])
    if bad == "another contact":  # the model's prediction so wide that only the track's last estimate tells
        P1 = P1 * 1e6
    assert predict(h, t0, own(t0), t1, own(t1), x0, P0, x1, P1) is None


def test_a_stale_or_other_numbers_hint_is_not_used() -> None:
    t0, t1 = T_CPA - 60.0, T_CPA
    x0, P0 = track_at(t0)
    x1, P1 = model(t0, 60.0)
    args = (x0[None], P0[None], x1[None], P1[None] * 100.0)
    for age, number, used in ((0.0, 5, True), (700.0, 5, False), (0.0, 6, False)):
        rn = RangeNoise(max_age=600.0)
        rn.set(5, hint(at=t0 - age))
        rn.cycle(t0, *own(t0))
        rn.cycle(t1, *own(t1))
        k, m, C, _ = rn.predictions(np.array([number]), *args)
        assert (k.size == 1) == used, (age, number)


@pytest.mark.parametrize("mode", ["gnn", "mht"])
@pytest.mark.parametrize("seed", [1, 2, 4])
def test_issue_31_geometry_is_followed_through_the_approach(mode: str, seed: int) -> None:
    """sonar_cpa_coarse (the issue's 60 s / 0.5 km geometry), in one process: one number,
    confirmed at >= 90 % of the samples after its confirmation, a TMA solution after the
    approach within 1.5 CRLB (measured 0.16-0.71) and NEES below 8 (1.1-7.2). Before the
    TMA-predicted bearing (``feedback=False``: the tracker without the solutions, and with
    the constant P_D and P_FA of that time) none of these runs meets the goals: the track
    loses the bearing at the approach. (With the estimated clutter level of decision 029,
    gnn seeds 1 and 2 meet them without the solutions too.)"""
    sys.path.insert(0, str(REPO))
    from benchmarks.sonar_cpa import run_once

    def good(r) -> bool:  # type: ignore[no-untyped-def]
        return (r.numbers == 1 and r.held >= 0.9 and r.solved_after and r.err <= 1.5 * r.crlb
                and r.nees < 8.0)

    r = run_once(COARSE, seed, mode)
    assert good(r), r
    assert not good(run_once(COARSE, seed, mode, feedback=False, tracker={"clutter_estimate": False}))



@pytest.mark.parametrize(("case", "seed"), [("sonar_cpa_fine_1km_turn", 8), ("sonar_cpa_coarse", 3)])
def test_the_runs_that_lost_the_contact_keep_it(case: str, seed: int) -> None:
    """The single-hypothesis runs that lost the contact with 026's prediction alone (decision
    028): fine_1km_turn seed 8, the track's bearing rate lagging the approach (held 0.83, no
    solution after it); coarse seed 3, a one-sample-after-the-turn solution 3.3 km off that
    replaced the track's rate (held 0.64). With the track's own state propagated along an
    observable solution's relative track both keep one number through the approach and TMA
    solves after it within 1.5 CRLB, its NEES below chi-square 4 dof at 99 % (13.3)."""
    sys.path.insert(0, str(REPO))
    from benchmarks.sonar_cpa import run_once

    r = run_once(REPO / "scenarios" / f"{case}.toml", seed, "gnn")
    assert r.numbers == 1 and r.held >= 0.9 and r.solved_after, r
    assert r.err <= 1.5 * r.crlb and r.nees < 13.3, r


def test_a_smoothed_variance_that_loses_precision_keeps_the_filtered_row() -> None:
    """sonar_cpa_fine_300m, MHT mode, seed 14: a TMA-predicted cycle's Q dwarfs P and the
    retrodicted (smoothed) bearing variance came out negative (a NaN sigma in the
    bearing register); common.sonar.mht.retrodiction keeps the filtered row instead."""
    import warnings

    sys.path.insert(0, str(REPO))
    from benchmarks.sonar_cpa import run_once

    with warnings.catch_warnings():
        warnings.simplefilter("error", RuntimeWarning)
        run_once(REPO / "scenarios" / "sonar_cpa_fine_300m.toml", 14, "mht")
