"""Tests of module 65 (common.radar.fusion.ekf) and of the cycle / management of module 61
(common.radar.fusion.cycle) on elementary tracks synthesised from truth."""

from __future__ import annotations

import numpy as np
import pytest

from common.core import kalman
from common.core.track_table import STATUS_NAME, Status
from common.deploy.config import RadarBase
from common.radar.elementary.tracker import ElementaryParams, ElementaryTracker, RadarCrossingParams
from common.radar.fusion.cycle import GlobalFusion
from common.radar.fusion.ekf import fused_update, observation
from common.radar.fusion.params import FusionParams
from common.radar.geometry.bistatic import POS, project
from common.radar.plots.channel_fusion import Plots
from common.wire.radar_messages import etracks_from, gtracks_message

RX = np.array([0.0, 0.0, 30.0])
TX = np.array([[-35000.0, 20000.0, 300.0], [45000.0, 10000.0, 500.0], [5000.0, -52000.0, 400.0]])
BASES = [RadarBase(f"b{k + 1}", TX[k], RX, ["c1"]) for k in range(3)]
SIG = np.array([60.0, 0.7, np.radians(0.5)])


def test_h_jacobian_finite_differences() -> None:
    x = np.array([[-30000.0, 200.0, 50000.0, -50.0, 9000.0, 3.0],
                  [50000.0, -120.0, -20000.0, 160.0, 7000.0, -2.0]])
    h, H = observation(x, TX, np.tile(RX, (3, 1)))  # [53]-[54], [57]
    for j in range(6):
        dx = np.zeros(6)
        dx[j] = 1e-2
        num = (observation(x + dx, TX, np.tile(RX, (3, 1)))[0]
               - observation(x - dx, TX, np.tile(RX, (3, 1)))[0]) / 2e-2
        np.testing.assert_allclose(H[:, :, j], num, rtol=1e-6, atol=1e-9)
    np.testing.assert_allclose(h[:, :3], x[:, POS])


def test_padded_rows_equal_variable_dimension_update() -> None:
    x = np.array([[-30000.0, 200.0, 50000.0, -50.0, 9000.0, 0.0]])
    P = np.diag([1e4, 25.0, 1e4, 25.0, 4e4, 4.0])[None]
    pos = x[:, POS] + [[50.0, -40.0, 300.0]]
    pos_cov = np.diag([80.0**2, 100.0**2, 500.0**2])[None]
    vb = np.array([[project(x, TX[k], RX)[0, 1] + 1.0 for k in range(3)]])
    active = np.array([[True, False, True]])
    rx = np.tile(RX, (3, 1))
    x1, P1, loglik = fused_update(x, P, pos, pos_cov, vb, np.full((1, 3), 0.5), active, TX, rx)
    # reference: observation [x y z v_b1 v_b3] of dimension 3 + 2 only
    h, H = observation(x, TX, rx)
    keep = [0, 1, 2, 3, 5]
    R = np.zeros((1, 5, 5))
    R[0, :3, :3] = pos_cov[0]
    R[0, 3, 3] = R[0, 4, 4] = 0.5
    z = np.concatenate([pos, vb[:, [0, 2]]], axis=1)
    x2, P2, S, _ = kalman.ekf_update(x, P, z, h[:, keep], H[:, keep], R)
    np.testing.assert_allclose(x1, x2, rtol=1e-9)
    np.testing.assert_allclose(P1, P2, rtol=1e-9, atol=1e-9)
    y = z - h[:, keep]
    nis = y[0] @ np.linalg.solve(S[0], y[0])
    assert loglik[0] == pytest.approx(-0.5 * (nis + np.linalg.slogdet(2 * np.pi * S[0])[1]))


def _truth(t: float) -> np.ndarray:
    p0 = np.array([[-30000.0, 50000.0, 9000.0], [50000.0, -20000.0, 7000.0]])
    v = np.array([[200.0, -50.0, 0.0], [-120.0, 160.0, 0.0]])
    s = np.zeros((2, 6))
    s[:, POS], s[:, [1, 3, 5]] = p0 + v * t, v
    return s


class _Synth:
    """etracks messages of the three bases as the chain produces them: truth through
    g [47] plus white noise (plots of 3 channels) fed to real elementary trackers, one
    per base and target so that elementary track number i + 1 is target i."""

    def __init__(self, rng: np.random.Generator) -> None:
        self.rng = rng
        self.trk = {(b.id, i): ElementaryTracker(ElementaryParams(),
                                                 RadarCrossingParams(enabled=False))
                    for b in BASES for i in range(2)}

    def messages(self, t: float, drop: set[int] = frozenset(),
                 gone: set[int] = frozenset()) -> list[dict]:
        """One message per base at t; targets in `drop` are left out of the reports,
        those in `gone` give no plot (their elementary tracks coast)."""
        s = _truth(t)
        out = []
        for b in BASES:
            y = project(s, b.tx, b.rx) + self.rng.standard_normal((2, 3)) * SIG
            y[:, 2] %= 2 * np.pi
            tracks = []
            for i in range(2):
                plot = Plots(*(np.array([v])[:int(i not in gone)] for v in (*y[i], *SIG)),
                             np.array([3])[:int(i not in gone)])
                r = self.trk[(b.id, i)].step(t, plot)
                if i in drop:
                    continue
                tracks += [{"id": i + 1, "status": STATUS_NAME[Status(int(r.status[k]))], "x": r.x[k].tolist(),
                            "P": r.P[k].ravel().tolist(), "score": float(r.score[k]),
                            "n_ch": int(r.n_ch[k]), "updated": bool(r.updated[k]),
                            "ambiguous": bool(r.ambiguous[k])} for k in range(len(r))]
            out.append({"v": 1, "t": t, "base": b.id, "tracks": tracks})
        return out


def push(gf: GlobalFusion, msg: dict, stale: frozenset[str] = frozenset()) -> list[dict]:
    """The gtracks messages of the cycles completed by one etracks message."""
    return [gtracks_message(o) for o in gf.push(*etracks_from(msg), stale)]


def test_fusion_on_synthetic_elementary_tracks() -> None:
    syn = _Synth(np.random.default_rng(4))
    gf = GlobalFusion(BASES, FusionParams())
    ids_of: dict[int, set[int]] = {0: set(), 1: set()}
    nees, err = [], []
    for k in range(60):
        msgs = syn.messages(float(k))
        outs = [o for m in msgs for o in push(gf, m)]
        assert [o["t"] for o in outs] == [float(k)]  # the third base completes the cycle
        tracks = outs[0]["tracks"]
        if k < 2:  # elementary tracks open at k = 1 and are confirmed at k = 2
            continue
        assert len(tracks) == 2
        escore = {(m["base"], e["id"]): e["score"] for m in msgs for e in m["tracks"]}
        s = _truth(float(k))
        for tr in tracks:
            x, P = np.array(tr["x"]), np.array(tr["P"]).reshape(6, 6)
            i = int(np.argmin(np.linalg.norm(s[:, POS] - x[POS], axis=1)))
            ids_of[i].add(tr["id"])
            assert tr["score"] == pytest.approx(sum(escore[tuple(e)] for e in tr["etracks"]))
            assert len(tr["etracks"]) == 3
            if k >= 10:
                assert tr["status"] == "confirmed"
                e = x - s[i]
                nees.append(e @ np.linalg.solve(P, e))
                err.append(np.linalg.norm(e[POS]))
    assert all(len(v) == 1 for v in ids_of.values())  # stable numbers
    assert np.sqrt(np.mean(np.square(err))) < 150.0
    assert 4.0 < np.mean(nees) < 9.0, np.mean(nees)


def test_pure_prediction_deletion_and_recycling() -> None:
    syn = _Synth(np.random.default_rng(8))
    gf = GlobalFusion(BASES, FusionParams(max_coast=3))
    for k in range(8):
        out = [o for m in syn.messages(float(k)) for o in push(gf, m)][0]
    ids = sorted(tr["id"] for tr in out["tracks"])
    assert ids == [1, 2]
    lost = None
    for k in range(8, 14):  # target index 0 is no longer reported by any base
        out = [o for m in syn.messages(float(k), drop={0}) for o in push(gf, m)][0]
        if lost is None:
            lost = {tr["id"] for tr in out["tracks"] if not tr["etracks"]}
            assert len(lost) == 1
            gone = next(tr for tr in out["tracks"] if not tr["etracks"])
            assert gone["score"] == 0.0 and gone["status"] == "coasting"
    assert len(out["tracks"]) == 1  # deleted after max_coast cycles without contributors
    for k in range(14, 18):  # the target comes back: a new track takes the freed number
        out = [o for m in syn.messages(float(k)) for o in push(gf, m)][0]
    assert sorted(tr["id"] for tr in out["tracks"]) == [1, 2]


def test_track_of_a_departed_target_is_reported_coasting() -> None:
    """Target 0 leaves: every base still reports its elementary track, in pure
    prediction. The global track stays confirmed one cycle and is reported coasting
    from the second (coast_cycles = 2, common.radar.fusion.status); the other target's
    track stays confirmed."""
    syn = _Synth(np.random.default_rng(8))
    gf = GlobalFusion(BASES, FusionParams())
    for k in range(8):
        out = [o for m in syn.messages(float(k)) for o in push(gf, m)][0]
    assert [tr["status"] for tr in out["tracks"]] == ["confirmed", "confirmed"]
    status = []
    for k in range(8, 11):
        out = [o for m in syn.messages(float(k), gone={0}) for o in push(gf, m)][0]
        status.append({len(tr["etracks"]) and tr["etracks"][0][1]: tr["status"]
                       for tr in out["tracks"]})
    assert [s[1] for s in status] == ["confirmed", "coasting", "coasting"]
    assert [s[2] for s in status] == ["confirmed"] * 3
    out = [o for m in syn.messages(11.0) for o in push(gf, m)][0]  # back: confirmed again
    assert [tr["status"] for tr in out["tracks"]] == ["confirmed", "confirmed"]


def test_cycle_waits_for_every_base_unless_stale() -> None:
    syn = _Synth(np.random.default_rng(9))
    gf = GlobalFusion(BASES, FusionParams())
    m0, m1, m2 = syn.messages(0.0), syn.messages(1.0), syn.messages(2.0)
    assert push(gf, m0[0]) == [] and push(gf, m0[1]) == []
    assert push(gf, m1[0]) == [] and push(gf, m2[0]) == []  # b1 runs ahead: wait for b3
    out = push(gf, m1[1], frozenset({"b3"}))  # b3 silent: cycles 0, 1 run without it
    assert [o["t"] for o in out] == [0.0, 1.0]
    assert gf.is_late(1.0) and not gf.is_late(2.0)
    assert push(gf, m2[1]) == []  # b3 no longer stale: cycle 2 waits for it
    assert [o["t"] for o in push(gf, m2[2])] == [2.0]


def _outputs(batches: list[list[dict]]) -> list[dict]:
    gf = GlobalFusion(BASES, FusionParams())
    return [o for msgs in batches for m in msgs for o in push(gf, m)]


def test_output_independent_of_arrival_order() -> None:
    """Same etracks, three arrival orders: configured order per cycle, a random
    permutation per cycle, and base streams far apart (b3 25 scans behind b2, b2 behind
    b1): identical gtracks messages."""
    syn = _Synth(np.random.default_rng(11))
    cycles = [syn.messages(float(k)) for k in range(30)]
    rng = np.random.default_rng(3)
    ref = _outputs(cycles)
    assert [o["t"] for o in ref] == [float(k) for k in range(30)]
    assert len(ref[-1]["tracks"]) == 2
    permuted = _outputs([[c[i] for i in rng.permutation(3)] for c in cycles])
    skewed = _outputs([[c[b] for c in cycles] for b in (0, 1, 2)])
    assert permuted == ref
    assert skewed == ref


def test_confirmed_track_bridges_a_gap_of_eight_cycles() -> None:
    """Target 0 is reported by no base for 8 cycles (dense1000.toml: an aircraft
    overflying the receiver loses every elementary track for 6-7 scans, the azimuth
    rate being shared by all bases), then comes back: with the default max_coast its
    global track coasts through the gap instead of being deleted, and is confirmed at
    once when its elementary tracks return (a new track would be tentative)."""
    syn = _Synth(np.random.default_rng(8))
    gf = GlobalFusion(BASES, FusionParams())
    for k in range(8):
        out = [o for m in syn.messages(float(k)) for o in push(gf, m)][0]
    assert sorted(tr["id"] for tr in out["tracks"]) == [1, 2]
    for k in range(8, 16):
        out = [o for m in syn.messages(float(k), drop={0}) for o in push(gf, m)][0]
        assert len(out["tracks"]) == 2
    out = [o for m in syn.messages(16.0) for o in push(gf, m)][0]
    assert sorted(tr["id"] for tr in out["tracks"]) == [1, 2]
    assert all(tr["status"] == "confirmed" and tr["etracks"] for tr in out["tracks"])
