"""The bearing-rate models of the multiple-hypothesis mode (common.sonar.mht.models): a model
label per hypothesis, branching with the Markov chain of the IMM, the quiet model only in a
resolution conflict."""

from __future__ import annotations

import math

import numpy as np

from common.sonar.bearing.tracker import TrackerParams
from common.sonar.mht.models import branch
from common.sonar.mht.params import MhtParams
from common.sonar.mht.tracker import MhtTracker

DEG = math.radians(1.0)
P = TrackerParams(mode="broadband")  # IMM defaults: q_theta_quiet 1e-10 < q_theta 1e-8


def _run(rates: np.ndarray, seed: int = 0, dt: float = 5.0) -> tuple[MhtTracker, list]:
    """One contact whose bearing rate (rad/s) per cycle is `rates`, 1 deg noise; returns the
    tracker and per cycle (true bearing, ids, confirmed, x, P)."""
    rng = np.random.default_rng(seed)
    trk = MhtTracker(P, MhtParams(), "cylindrical", DEG)
    brg, out = 1.0, []
    for k, r in enumerate(rates):
        brg += r * dt
        c = trk.step(k * dt, np.array([brg + DEG * rng.standard_normal()]), np.array([30.0]), 0.0)
        out.append((brg, c.ids, c.confirmed, c.x, c.P))
    return trk, out


def test_branch_keeps_each_weight_and_sends_conflicting_hypotheses_to_the_quiet_model() -> None:
    x, Pm = np.arange(12.0).reshape(3, 4), np.repeat(np.eye(4)[None], 3, axis=0)
    c, track, model = np.array([1.0, 0.5, 0.2]), np.array([0, 0, 1]), np.array([0, 1, 0])
    quiet = np.array([False, False, True])
    bx, _, bc, bt, bm, src = branch(x, Pm, c, track, model, 5.0, np.array([600.0, 60.0]), quiet)
    assert src.tolist() == [0, 1, 2, 0, 1] and bm.tolist() == [0, 0, 0, 1, 1]
    np.testing.assert_allclose(bx, x[src])
    np.testing.assert_allclose(np.bincount(src, weights=bc), c)  # sum_j c p_mj = c
    assert 0.0 < bc[3] < 0.01 * c[0]  # quiet -> manoeuvre: rare
    assert bc[1] > bc[3]  # manoeuvre -> quiet faster (60 s sojourn)
    assert bc[2] == c[2]  # in conflict: the quiet model only
    assert bt.tolist() == track[src].tolist()


def test_a_straight_contact_keeps_a_quiet_bearing_rate() -> None:
    trk, out = _run(np.full(80, DEG / 60.0))
    _, ids, conf, x, Pc = out[-1]
    assert conf.tolist() == [True]
    # with the manoeuvre Q alone (the mode before the models) about 1.8 deg/min
    assert math.degrees(math.sqrt(Pc[0, 1, 1])) * 60.0 < 0.8
    assert abs(math.degrees(x[0, 1]) * 60.0 - 1.0) < 0.5
    main = np.argmax(trk.hc)
    assert trk.hm[main] == 0 and (trk.hm == 1).any()  # the light manoeuvre copy is kept


def test_a_bearing_rate_change_is_followed_by_the_manoeuvre_model() -> None:
    ramp = np.linspace(0.0, 10.0 * DEG / 60.0, 12)  # 0 -> 10 deg/min in 60 s
    _, out = _run(np.r_[np.zeros(40), ramp, np.full(40, ramp[-1])], seed=1)
    ids = {int(i) for _, i, conf, _, _ in out[10:] for i in i[conf]}
    assert len(ids) == 1  # one number throughout (the quiet model alone loses the contact)
    brg, _, conf, x, _ = out[-1]
    assert abs(x[conf][0, 0] - brg) < 2 * DEG


def test_the_hypotheses_of_tracks_in_a_resolution_conflict_stay_in_the_quiet_model() -> None:
    trk = MhtTracker(P, MhtParams(), "cylindrical", DEG)
    rng = np.random.default_rng(2)
    rate, checked = 1.0 * DEG / 60.0, 0
    prev: set[int] = set()
    for k in range(140):
        t = 5.0 * k
        truth = np.array([85 * DEG + rate * t, 95 * DEG - rate * t])
        c = trk.step(t, truth + DEG * rng.standard_normal(2), np.array([30.0, 30.0]), 0.0)
        in_conflict = trk.tr.uid[trk.ht]
        was = np.isin(in_conflict, list(prev))
        if was.any():
            assert (trk.hm[was] == 0).all()
            checked += 1
        prev = set(c.ids[c.ambiguous].tolist())
    assert checked > 0
