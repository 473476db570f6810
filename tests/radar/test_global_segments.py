"""Track segment association (common.radar.fusion.segments): a confirmed global track
whose elementary tracks all ended keeps its number in the track confirmed after it on the
same aircraft, when the aircraft turned in between (dense1000 seed 9, aircraft 905)."""

from __future__ import annotations

import dataclasses

import numpy as np

from common.core.gating import chi2_gate
from common.core.track_table import Status
from common.deploy.config import RadarBase
from common.radar.elementary.tracker import ElementaryParams, ElementaryTracker, RadarCrossingParams
from common.radar.fusion.cycle import GlobalFusion
from common.radar.fusion.params import FusionParams
from common.radar.fusion.segments import manoeuvre_envelope, segment_pairs
from common.radar.geometry.bistatic import project
from common.radar.plots.channel_fusion import Plots

GATE = chi2_gate(0.999, 6)
P_TRACK = np.diag([60.0**2, 5.0**2, 60.0**2, 5.0**2, 300.0**2, 2.0**2])


def test_envelope_is_the_covariance_of_a_constant_plan_acceleration() -> None:
    """Per plan axis accel^2 J J' with J = (tau^2 / 2, tau); nothing on the vertical."""
    tau, accel = np.array([3.0, 8.0]), 10.0
    M = manoeuvre_envelope(tau, accel)
    for n, T in enumerate(tau):
        J = np.array([T**2 / 2, T])
        for p, v in ((0, 1), (2, 3)):
            np.testing.assert_allclose(M[n][np.ix_([p, v], [p, v])], accel**2 * np.outer(J, J))
        np.testing.assert_array_equal(M[n][4:], 0.0)
        np.testing.assert_array_equal(M[n][:4][:, 4:], 0.0)
        np.testing.assert_array_equal(M[n][0:2, 2:4], 0.0)


def _turned(tau: float, a: float, v: float = 250.0) -> tuple[np.ndarray, np.ndarray]:
    """Straight-line prediction after tau s at v m/s east from the origin, and the state
    of an aircraft that turned left at a constant lateral acceleration a (m/s^2)."""
    w = a / v
    straight = np.array([v * tau, v, 0.0, 0.0, 0.0, 0.0])
    turned = np.array([v / w * np.sin(w * tau), v * np.cos(w * tau),
                       v / w * (1 - np.cos(w * tau)), v * np.sin(w * tau), 0.0, 0.0])
    return straight, turned


def test_a_turn_is_continued_with_the_envelope_only() -> None:
    """The 905 case: a 1.6 g turn, 8 s of coast; the straight prediction's own
    covariance rejects the new segment, the envelope of a 1 g sigma takes it."""
    old, new = _turned(8.0, 16.0)
    args = (old[None], P_TRACK[None], np.array([8.0]), new[None], P_TRACK[None])
    assert segment_pairs(*args, 0.0, GATE)[0].size == 0
    i, j = segment_pairs(*args, 10.0, GATE)
    assert i.tolist() == [0] and j.tolist() == [0]


def test_pairs_must_be_unique_both_ways() -> None:
    old, new = _turned(4.0, 5.0)
    twin = new + [150.0, 0.0, 150.0, 0.0, 0.0, 0.0]
    one_old = (old[None], P_TRACK[None], np.array([4.0]))
    assert segment_pairs(*one_old, np.array([new, twin]), np.array([P_TRACK] * 2), 10.0,
                         GATE)[0].size == 0  # two new segments in the old one's gate
    assert segment_pairs(np.array([old, old + [100.0, 0, 0, 0, 0, 0]]), np.array([P_TRACK] * 2),
                         np.array([4.0, 4.0]), new[None], P_TRACK[None], 10.0,
                         GATE)[0].size == 0  # the new segment gates two old ones
    far = new + [5000.0, 0.0, 0.0, 0.0, 0.0, 0.0]
    i, j = segment_pairs(*one_old, np.array([far, new]), np.array([P_TRACK] * 2), 10.0, GATE)
    assert j.tolist() == [1]


RX = np.array([0.0, 0.0, 30.0])
TX = np.array([[-35000.0, 20000.0, 300.0], [45000.0, 10000.0, 500.0], [5000.0, -52000.0, 400.0]])
BASES = [RadarBase(f"b{k + 1}", TX[k], RX, ["c1"]) for k in range(3)]
SIG = np.array([60.0, 0.7, np.radians(0.5)])
TURN_AT, LOST, BACK = 10.0, 10.0, 15.0  # the turn starts when every base loses the aircraft


def _aircraft(t: float, a: float = 16.0) -> np.ndarray:
    """30 km north-east of the receiver at 250 m/s east, then a left turn at a m/s^2."""
    start = np.array([-20000.0 + 250.0 * min(t, TURN_AT), 0.0, 30000.0, 0.0, 6000.0, 0.0])
    straight, turned = _turned(max(t - TURN_AT, 0.0), a)
    return start + (turned if t > TURN_AT else straight * [0, 1, 0, 0, 0, 0])


def _numbers(segment_accel: float) -> list[list[int]]:
    """Confirmed global track numbers per cycle: every base's elementary track of the
    aircraft ends at LOST, new ones (other numbers) start at BACK."""
    rng = np.random.default_rng(3)
    gf = GlobalFusion(BASES, FusionParams(segment_accel=segment_accel, max_coast=15))
    trackers = {}
    out = []
    for k in range(30):
        t = float(k)
        era = 0 if t < LOST else (1 if t >= BACK else None)  # None: no plot of the aircraft
        for b in BASES:
            trk = trackers.setdefault((b.id, era), ElementaryTracker(
                ElementaryParams(), RadarCrossingParams(enabled=False)))
            n = int(era is not None)
            y = np.zeros(3)
            if n:
                y = project(_aircraft(t)[None], b.tx, b.rx)[0] + rng.standard_normal(3) * SIG
                y[2] %= 2 * np.pi
            r = trk.step(t, Plots(*(np.array([v])[:n] for v in (*y, *SIG)), np.array([3])[:n]))
            for g in gf.push(b.id, dataclasses.replace(r, id=r.id + 10 * (era or 0))):
                out.append(sorted(g.id[g.status == Status.CONFIRMED].tolist()))
    return out


def test_a_turning_aircraft_lost_by_every_base_keeps_its_number() -> None:
    """The old track coasts from LOST (reported coasting), the new one is confirmed
    about 6 s after BACK, 11 s into the turn (968 m from the straight line)."""
    without, with_ = _numbers(0.0), _numbers(FusionParams().segment_accel)
    assert with_[:20] == without[:20] and without[8] == [1] and without[12] == []
    assert with_[20:] == [[1]] * 10  # the new segment took the old number
    assert without[-1] == [2]  # without the association: a new number
