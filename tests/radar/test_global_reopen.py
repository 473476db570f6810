"""Tests of the altitude re-opened after a lost member (common.radar.fusion.reopen): a
track held at a wrong altitude with a small variance (dense1000 seed 7, aircraft 931)
is rebuilt from its sound members and then admits its own elementary track of the base
it had lost; when they leave the altitude open its vertical variances are floored at
theirs; a track its members agree with keeps its state."""

from __future__ import annotations

import numpy as np

from common.core.gating import chi2_gate
from common.radar.fusion.assoc import ETrackSet, component_gate
from common.radar.fusion.params import FusionParams
from common.radar.fusion.reopen import contradicted, floor_vertical, reopen, sound_members
from common.radar.fusion.track_filter import MixtureFilter
from common.radar.geometry.bistatic import POS, project
from common.radar.geometry.localisation import Constraints, gauss_newton

RX = np.array([0.0, 0.0, 30.0])
TX = np.array([[-35000.0, 20000.0, 300.0], [45000.0, 10000.0, 500.0],
               [5000.0, -52000.0, 400.0], [-22000.0, -18000.0, 250.0]])  # dense1000.toml
B = TX.shape[0]
RXS = np.tile(RX, (B, 1))
TRUTH = np.array([38000.0, -150.0, 21000.0, 90.0, 5000.0, 0.0])
R1 = np.diag([40.0**2, 1.0**2, np.radians(0.3) ** 2])
GAMMA = chi2_gate(0.999, 3)


def _etracks(updated: np.ndarray, R1: np.ndarray = R1) -> ETrackSet:
    """One elementary track per base, at the truth, covariance R1."""
    y = np.vstack([project(TRUTH[None], TX[b], RXS[b]) for b in range(B)])
    R = np.tile(R1, (B, 1, 1))
    ones = np.ones(B, dtype=bool)
    return ETrackSet(np.arange(B), np.arange(B), y, R, np.ones(B), ones, updated, ~ones, y, R, ones)


def _predicted(f: MixtureFilter, E: ETrackSet, z: float) -> tuple[np.ndarray, ...]:
    """Predicted arrays (x, P, xm, Pm, c) of one track with a single live component, sigma
    150 m in altitude: at the least-squares point of the ranges and azimuths of bases 0, 1
    and 3 at altitude z (where those bases' elementary tracks hold a wrong altitude)."""
    m = np.array([0, 1, 3])
    sig = np.sqrt(np.diag(R1))
    cons = Constraints(E.y[m, 0][None], np.full((1, 3), sig[0]), E.y[m, 2][None],
                       np.full((1, 3), sig[2]), np.ones((1, 3), bool), TX[m], RXS[m])
    pos, _ = gauss_newton(TRUTH[POS][None], cons, z_prior=(np.array([z]), np.array([1.0])))
    K = f.A * f.M
    x = TRUTH.copy()
    x[POS] = pos[0]
    P = np.diag([60.0, 5.0, 60.0, 5.0, 150.0, 3.0]) ** 2
    xm, Pm, c = np.tile(x, (1, K, 1)), np.tile(P, (1, K, 1, 1)), np.zeros((1, K))
    c[0, 0] = 1.0
    return x[None].copy(), P[None].copy(), xm, Pm, c


def test_sound_members_are_confirmed_and_updated() -> None:
    E = _etracks(np.array([True, False, True, True]))
    row = np.array([[0, 1, -1, 3]])
    np.testing.assert_array_equal(sound_members(row, E), [[0, -1, -1, 3]])


def test_contradicted_ignores_light_bands() -> None:
    x, P = TRUTH[None], np.diag([50.0, 5.0, 50.0, 5.0, 100.0, 3.0])[None] ** 2
    xb = np.stack([TRUTH + [0, 0, 0, 0, 3000.0, 0], TRUTH])[None]
    Pb = np.tile(P[0], (1, 2, 1, 1))
    assert not contradicted(x, P, xb, Pb, np.array([[0.5, 0.5]]), GAMMA)[0]
    assert contradicted(x, P, xb, Pb, np.array([[1.0, 1e-6]]), GAMMA)[0]


def test_a_track_at_a_wrong_altitude_is_rebuilt_and_admits_its_lost_base() -> None:
    """Truth 5 km; the track at 7.5 km with sigma 150 m holds bases 0, 1, 3. Base 2's own
    elementary track fails [48] against it; after the rebuild the heaviest band is within
    200 m of the truth and base 2 passes [48] against the mixture."""
    f = MixtureFilter(FusionParams(), TX, RXS)
    E = _etracks(np.ones(B, dtype=bool))
    pred = _predicted(f, E, 7500.0)
    row = np.array([[0, 1, -1, 3]])
    b2 = (E.y[2:3], E.R[2:3], TX[2:3], RXS[2:3])
    assert not component_gate(pred[4], pred[2], pred[3], *b2, GAMMA)[0]
    slots = reopen(np.array([0]), f, pred, row, E, TX, RXS, FusionParams(), 0.999)
    np.testing.assert_array_equal(slots, [0])
    x, P, xm, Pm, c = pred
    heavy = xm[0, np.argmax(c[0])]
    assert abs(heavy[4] - TRUTH[4]) < 200.0
    assert np.hypot(*(heavy[[0, 2]] - TRUTH[[0, 2]])) < 200.0
    assert component_gate(c, xm, Pm, *b2, GAMMA)[0]


def test_a_track_its_members_agree_with_keeps_its_state() -> None:
    f = MixtureFilter(FusionParams(), TX, RXS)
    E = _etracks(np.ones(B, dtype=bool))
    pred = _predicted(f, E, TRUTH[4])
    before = [a.copy() for a in pred]
    slots = reopen(np.array([0]), f, pred, np.array([[0, 1, -1, 3]]), E, TX, RXS,
                   FusionParams(), 0.999)
    assert slots.size == 0
    for a, b in zip(before, pred):
        np.testing.assert_array_equal(a, b)


def test_fewer_than_three_sound_members_rebuild_nothing() -> None:
    """One of the three members was not updated this scan: its estimate is a prediction."""
    f = MixtureFilter(FusionParams(), TX, RXS)
    E = _etracks(np.array([True, False, True, True]))
    pred = _predicted(f, E, 7500.0)
    slots = reopen(np.array([0]), f, pred, np.array([[0, 1, -1, 3]]), E, TX, RXS,
                   FusionParams(), 0.999)
    assert slots.size == 0


def test_members_that_leave_the_altitude_open_floor_its_vertical_variances() -> None:
    """Ranges ten times less accurate (sigma 400 m): the rebuilt bands contradict the
    track (z 7.5 km) but leave sigma_z at 2 km, above band_linear times the height; the
    track is not rebuilt, keeps its mean, and its altitude and vertical-velocity variances
    (sigma 150 m and 3 m/s) rise to the bands' (floor_vertical), in every component: base
    2's own elementary track, which failed [48] against it, then passes."""
    f = MixtureFilter(FusionParams(), TX, RXS)
    E = _etracks(np.ones(B, dtype=bool), R1 * np.diag([100.0, 1.0, 1.0]))
    pred = _predicted(f, _etracks(np.ones(B, dtype=bool)), 7500.0)
    before = [a.copy() for a in pred]
    b2 = (E.y[2:3], E.R[2:3], TX[2:3], RXS[2:3])
    assert not component_gate(pred[4], pred[2], pred[3], *b2, GAMMA)[0]
    slots = reopen(np.array([0]), f, pred, np.array([[0, 1, -1, 3]]), E, TX, RXS,
                   FusionParams(), 0.999)
    assert slots.size == 0
    x, P, xm, Pm, c = pred
    np.testing.assert_array_equal(x, before[0])
    np.testing.assert_array_equal(xm, before[2])
    assert np.sqrt(P[0, 4, 4]) > 1000.0 and np.sqrt(P[0, 5, 5]) > 3.0
    assert np.all(np.sqrt(Pm[0, :, 4, 4]) > 1000.0)
    np.testing.assert_array_equal(P[0, :4, :4], before[1][0, :4, :4])
    assert component_gate(c, xm, Pm, *b2, GAMMA)[0]


def test_floor_vertical_never_lowers_a_variance() -> None:
    P = np.diag([1.0, 1.0, 1.0, 1.0, 400.0, 1.0])[None]
    Pm = np.tile(P, (1, 2, 1, 1))
    Pm[0, 1, 4, 4] = 900.0
    floor_vertical(P, Pm, np.array([0]), np.diag([0, 0, 0, 0, 625.0, 4.0])[None])
    np.testing.assert_array_equal(np.diag(P[0]), [1, 1, 1, 1, 625, 4])
    np.testing.assert_array_equal(Pm[0, :, 4, 4], [625, 900])
    np.testing.assert_array_equal(Pm[0, :, 5, 5], [4, 4])


def test_the_watch_rebuilds_a_contradicted_track_and_floors_nothing() -> None:
    """`floor=False` (FusionParams.reopen_watch: every confirmed track, lost member or
    not; dense1000 seed 34, aircraft 931's track fed by its own four elementary tracks
    1.7 km low with sigma_z 196 m): the contradicted track is rebuilt as above, and a
    track whose members leave the altitude open keeps its state untouched."""
    f = MixtureFilter(FusionParams(), TX, RXS)
    E = _etracks(np.ones(B, dtype=bool))
    pred = _predicted(f, E, 7500.0)
    slots = reopen(np.array([0]), f, pred, np.array([[0, 1, -1, 3]]), E, TX, RXS,
                   FusionParams(), 0.999, floor=False)
    np.testing.assert_array_equal(slots, [0])
    assert abs(pred[2][0, np.argmax(pred[4][0])][4] - TRUTH[4]) < 200.0
    E_open = _etracks(np.ones(B, dtype=bool), R1 * np.diag([100.0, 1.0, 1.0]))
    pred = _predicted(f, _etracks(np.ones(B, dtype=bool)), 7500.0)
    before = [a.copy() for a in pred]
    slots = reopen(np.array([0]), f, pred, np.array([[0, 1, -1, 3]]), E_open, TX, RXS,
                   FusionParams(), 0.999, floor=False)
    assert slots.size == 0
    for a, b in zip(before, pred):
        np.testing.assert_array_equal(a, b)
