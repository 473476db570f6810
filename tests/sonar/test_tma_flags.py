"""What a TMA solution does not know (issue 31 section 3): ``converged`` (002 claim 17
stop rule), ``ctma_exhausted`` (003 error handling out of corrections) and
``range_observable`` (sigma_R <= 0.5 R) of common.sonar.tma.constrained, on the scene of
tests/sonar/test_tma.py (own-ship turn at samples 13-16) and on the same own ship
without its turn."""

from __future__ import annotations

import numpy as np
import pytest

from common.sonar.tma.bearings_only import state_map
from common.sonar.tma.bounds import MINIMAL_BOUNDS, Bounds
from common.sonar.tma.constrained import CtmaParams, CycleOutput, TmaTracker, range_observable
from tests.sonar.test_tma import BETA, KN, OWN, SIG, T

D = np.radians
STRAIGHT = np.column_stack((T * 5 * KN * np.sin(D(140.0)), T * 5 * KN * np.cos(D(140.0))))
T_TURN = T[12]  # the own ship leaves course 140 after sample 13
FAST = np.array([4920.0, 850.0, 40 * KN * np.sin(D(-140.0)), 40 * KN * np.cos(D(-140.0))])


def run(own: np.ndarray, bounds: Bounds | None, cfg: CtmaParams = CtmaParams(), beta: np.ndarray = BETA,
        seed: int = 3) -> list[CycleOutput]:
    """One TmaTracker cycle per noisy bearing (outputs from the fourth bearing on)."""
    X = state_map(T, 0.0, ()) @ beta
    b = np.arctan2(X[:, 0] - own[:, 0], X[:, 1] - own[:, 1])
    b = b + SIG * np.random.default_rng(seed).standard_normal(T.size)
    trk = TmaTracker(bounds, cfg)
    outs = [trk.update(T[i], b[i], SIG, own[i]) for i in range(T.size)]
    return [o for o in outs if o is not None]


def test_range_observable_rule_hand_values():
    x = np.array([3000.0, 4000.0, 1.0, 2.0])  # R = 5000 m from the origin
    P = np.diag([2400.0**2, 2400.0**2, 1.0, 1.0])
    assert range_observable(x, P, np.zeros(2))
    assert not range_observable(x, P * (2600.0 / 2400.0) ** 2, np.zeros(2))
    across = np.diag([1e12, 1.0, 1.0, 1.0])  # huge sigma across the line of sight only
    assert range_observable(np.array([0.0, 5000.0, 0.0, 0.0]), across, np.zeros(2))
    assert not range_observable(x, np.full((4, 4), np.nan), np.zeros(2))


@pytest.mark.parametrize("bounds", [None, MINIMAL_BOUNDS])
def test_one_leg_scene_says_range_unobservable(bounds: Bounds | None):
    outs = run(STRAIGHT, bounds)
    assert outs and not any(o.range_observable for o in outs)


def test_two_leg_scene_says_range_observable_after_the_turn():
    outs = run(OWN, MINIMAL_BOUNDS)
    assert not any(o.range_observable for o in outs if o.t <= T_TURN)
    assert all(o.range_observable for o in outs[-10:])
    assert outs[-1].converged and not outs[-1].ctma_exhausted and not outs[-1].constrained


def test_max_iter_stop_says_not_converged():
    outs = run(OWN, None, CtmaParams(max_iter=1))
    assert not any(o.converged for o in outs)
    assert all(o.converged for o in run(OWN, None)[-10:])


def test_ctma_exhausted_when_corrections_cannot_fix_the_bounds():
    """A 40 kn target against the minimal bounds (at most 15 m/s): after convergence the
    CTMA solution stays on the speed edge through the corrections allowed (none, or three
    re-centred speed intervals with the residual factor below q_minimal)."""
    for mc in (0, 3):
        outs = run(OWN, MINIMAL_BOUNDS, CtmaParams(max_corrections=mc), FAST, seed=5)
        done = [o for o in outs if o.ctma_exhausted]
        assert done and all(o.constrained and o.phase == "post" for o in done)
    good = Bounds(1000.0, 30e3, D(150.0), D(300.0), 2 * KN, 8 * KN)
    assert not any(o.ctma_exhausted for o in run(OWN, good))
