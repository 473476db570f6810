"""Confirmation of global tracks (001 module 61, `confirm_cycles`, `confirm_bases`): a
scan counts only when the track's contributors were located together (module 64's
chi-square test passed), so a track of two targets' elementary tracks is not confirmed
(dense1000.toml: number switches 4.7 -> 4.4 per 100 targets, a target first scored on
such a track); with four bases three must be located together (two give a curve); a
tentative track that loses a member counts its cycles again."""

from __future__ import annotations

import numpy as np

from common.core.track_table import Status
from common.deploy.config import RadarBase
from common.radar.elementary.tracker import ElementaryTracks
from common.radar.fusion.assoc import ETrackSet
from common.radar.fusion.cycle import GlobalFusion
from common.radar.fusion.params import FusionParams
from common.radar.geometry.bistatic import project

RX = np.zeros((4, 3)) + [0.0, 0.0, 30.0]
TX = np.array([[-35000.0, 20000.0, 300.0], [45000.0, 10000.0, 500.0],
               [5000.0, -52000.0, 400.0], [-22000.0, -18000.0, 250.0]])
TRUTH = np.array([18000.0, 120.0, 30000.0, -150.0, 3000.0, 0.0])
R1 = np.diag([40.0**2, 0.5**2, np.radians(0.3) ** 2])


def _at(state: np.ndarray, t: float) -> np.ndarray:
    return state + t * np.array([state[1], 0.0, state[3], 0.0, state[5], 0.0])


def _fusion_with_a_track(n_bases: int) -> tuple[GlobalFusion, np.ndarray]:
    """GlobalFusion over the first `n_bases` bases and one tentative track at TRUTH (one
    live component), without memberships yet: (fusion, its slot)."""
    gf = GlobalFusion([RadarBase(f"b{k}", TX[k], RX[k], ["c1"]) for k in range(n_bases)],
                      FusionParams())
    tab = gf.table
    s = tab.add(1)
    P = np.diag([200.0**2, 10.0**2, 200.0**2, 10.0**2, 300.0**2, 3.0**2])
    tab.x[s], tab.P[s], tab.xm[s], tab.Pm[s] = TRUTH, P, TRUTH, P
    tab.mu[s] = np.eye(1, tab.mu.shape[1])
    return gf, s


def _confirmed_after(second: np.ndarray, scans: int = 5, n_bases: int = 3) -> bool:
    """One global track on bases 0 and 1 of a deployment of `n_bases`, fed base 0's
    elementary track of TRUTH and base 1's of `second` for `scans` scans: is it confirmed?"""
    gf, s = _fusion_with_a_track(n_bases)
    tab = gf.table
    tab.has[s] = np.arange(n_bases) < 2
    tab.t_last[s] = 0.0
    row = np.full((tab.capacity, n_bases), -1, dtype=np.intp)
    row[s[0], :2] = [0, 1]
    for k in range(1, scans + 1):
        t = float(k)
        y = np.array([project(_at(TRUTH, t)[None], TX[0], RX[0])[0],
                      project(_at(second, t)[None], TX[1], RX[1])[0]])
        R = np.tile(R1, (2, 1, 1))
        ones = np.ones(2, dtype=bool)
        E = ETrackSet(np.array([0, 1]), np.arange(2), y, R, np.ones(2), ones, ones, ~ones,
                      y, R, ones)
        live = tab.active_indices()
        x, Pp, xm, Pm, c = gf.filter.predict(tab, t, live)
        gf._update(t, live, np.zeros(0, dtype=np.intp), x, Pp, (xm, Pm, c), E, row,
                   np.zeros(row.shape, dtype=bool))
    return bool(tab.confirmed[s[0]])


def test_a_track_whose_two_bases_see_one_target_is_confirmed() -> None:
    assert _confirmed_after(TRUTH)


def test_of_four_bases_two_do_not_confirm() -> None:
    """confirm_bases 3, capped at all bases but one: three of four bases, two of three."""
    assert not _confirmed_after(TRUTH, scans=8, n_bases=4)


def test_a_track_whose_bases_see_two_targets_is_not_confirmed() -> None:
    """Base 1's elementary track follows an aircraft 3 km away: the two ranges and
    azimuths cannot be located together, no scan counts."""
    assert not _confirmed_after(TRUTH + [3000.0, 0.0, -2000.0, 0.0, 0.0, 0.0])


def _one_cycle_after_two_good(base2: np.ndarray) -> tuple[bool, int]:
    """A tentative track on the four bases with two counted cycles, at TRUTH; one cycle
    (GlobalFusion.cycle) in which bases 0, 1, 3 report TRUTH's elementary track and base 2
    the one of `base2`: (confirmed, counted cycles) after it."""
    gf, s = _fusion_with_a_track(4)
    tab = gf.table
    tab.has[s], tab.member[s] = True, 7
    tab.t_last[s], tab.n_good[s] = 0.0, 2
    msgs = {}
    for k in range(4):
        y = project(_at(base2 if k == 2 else TRUTH, 1.0)[None], TX[k], RX[k])[0]
        one = np.ones(1, dtype=bool)
        msgs[k] = ElementaryTracks(1.0, np.array([7]), np.array([Status.CONFIRMED]),
                                   np.array([[y[0], y[1], 0.0, y[2], 0.0]]),
                                   np.diag([R1[0, 0], R1[1, 1], 1.0, R1[2, 2], 1e-8])[None],
                                   np.array([10.0]), np.array([2]), one, ~one)
    gf.cycle(1.0, msgs)
    return bool(tab.confirmed[s[0]]), int(tab.n_good[s[0]])


def test_a_tentative_track_counts_again_after_losing_a_member() -> None:
    """Base 2's elementary track follows an aircraft 3.6 km away: [48] dissociates it and
    the count starts again (1: this cycle, located on bases 0, 1, 3); held, the same
    cycle is the third and confirms the track."""
    assert _one_cycle_after_two_good(TRUTH) == (True, 3)
    assert _one_cycle_after_two_good(TRUTH + [3000.0, 0.0, -2000.0, 0.0, 0.0, 0.0]) == (False, 1)
