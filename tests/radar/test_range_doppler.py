"""Range-Doppler bases (no azimuth): 001 [5]-[7] on (r_b, v_b), F / Q [19]-[20]
restricted to the range block, H, the chi-square(2) gate, module 42 without theta, the
tracker on simulated plots of two targets, and no azimuth on the way to global fusion."""

from __future__ import annotations

import tomllib

import numpy as np
import pytest
from scipy.stats import chi2

from common.core.rejection import Rejected
from common.core.track_table import Status
from common.deploy.config import RadarBase, parse
from common.radar.elementary.initiation import compatible, initial_state, propagate
from common.radar.elementary.model import AZIMUTH, RANGE_DOPPLER, model_of
from common.radar.elementary.tracker import (
    ElementaryParams,
    ElementaryTracker,
    RadarCrossingParams,
    gate_pairs,
)
from common.radar.fusion.cycle import GlobalFusion
from common.radar.geometry.bistatic import bistatic_range, bistatic_range_rate
from common.radar.plots.channel_fusion import PlotFusion, Plots, fuse_scan
from common.sim.simulator import load_scenario
from common.wire import protocol
from common.wire.radar_chain import global_fusion
from common.wire.radar_messages import etracks_message, etracks_of, fused_message, plots_of
from common.wire.sim_messages import run_scenario
from tests.radar.test_elementary import seed_F, seed_Q
from tests.sim.test_simulator import SCENARIOS

SIG = (100.0, 2.0)


def rd_plots(rows: list[tuple[float, float]], n_ch: int = 1, sig: tuple[float, float] = SIG) -> Plots:
    a = np.asarray(rows, dtype=float).reshape(-1, 2)
    n = len(a)
    return Plots(a[:, 0], a[:, 1], None, np.full(n, sig[0]), np.full(n, sig[1]), None,
                 np.full(n, n_ch, dtype=np.int64))


def test_plots_without_azimuth() -> None:
    p = rd_plots([(1e4, 3.0), (2e4, -1.0)])
    assert not p.azimuth and p.y.shape == (2, 2) and p.sigma.shape == (2, 2)
    assert p.take(np.array([1])).az is None and len(Plots.concat([p, p], azimuth=False)) == 4
    with pytest.raises(ValueError):
        Plots(p.rb, p.vb, p.rb, p.srb, p.svb, None)  # az without saz
    with pytest.raises(ValueError):
        Plots.concat([p, Plots.empty()], azimuth=False)


def test_eq5_eq7_fusion_on_range_and_doppler_only() -> None:
    # 2 sigma intervals: |dr| <= 2 (100 + 100) = 400, |dv| <= 2 (2 + 2) = 8
    a, b = rd_plots([(1e4, 0.0)]), rd_plots([(1e4 + 400.0, 8.0)])
    f = fuse_scan([a, b], 2, 0, azimuth=False)
    assert len(f) == 1 and f.n_ch.tolist() == [2] and f.az is None and f.saz is None
    np.testing.assert_allclose([f.rb[0], f.vb[0]], [1e4 + 200.0, 4.0])  # 001 [6], equal weights
    np.testing.assert_allclose([f.srb[0], f.svb[0]], np.array(SIG) / np.sqrt(2))  # 001 [7]
    assert len(fuse_scan([a, rd_plots([(1e4 + 400.1, 0.0)])], 2, 0, azimuth=False)) == 2


def test_plot_fusion_rejects_the_other_kind() -> None:
    core = PlotFusion(["c1", "c2"], 1, azimuth=False)
    with pytest.raises(Rejected) as e:
        core.push("c1", 1.0, Plots.empty(azimuth=True))
    assert e.value.reason == "azimuth_mismatch"
    out = core.push("c1", 1.0, rd_plots([(1e4, 1.0)])) + core.push("c2", 1.0, Plots.empty(False))
    assert len(out) == 1 and out[0][1].az is None and "az" not in fused_message("b", *out[0])


def test_eq19_eq20_restricted_to_the_range_block() -> None:
    for T in (0.5, 1.0, 2.5):
        np.testing.assert_array_equal(RANGE_DOPPLER.F(T), seed_F(T)[:3, :3])  # 001 [19]
        np.testing.assert_allclose(RANGE_DOPPLER.Q(T, 0.7, 0.002), seed_Q(T, 0.7, 0.002)[:3, :3],
                                   rtol=1e-15)  # 001 [20], no sigma_omega term left
        np.testing.assert_array_equal(AZIMUTH.F(T), seed_F(T))
    np.testing.assert_array_equal(RANGE_DOPPLER.H, [[1, 0, 0], [0, 1, 0]])
    assert RANGE_DOPPLER.m == 2 and RANGE_DOPPLER.n == 3 and model_of(False) is RANGE_DOPPLER
    assert model_of(True) is AZIMUTH


def test_gate_chi_square_2_dof() -> None:
    trk = ElementaryTracker(ElementaryParams(gate_prob=0.99), model=RANGE_DOPPLER)
    assert trk.gamma == pytest.approx(chi2.ppf(0.99, 2))
    gamma = chi2.ppf(0.99, 2)
    z = np.array([[10000.0, 10.0]])
    S_pred = np.diag([300.0, 5.0])[None]
    s_v = np.sqrt(5.0 + SIG[1] ** 2)
    inside = rd_plots([(10000.0, 10.0 + 0.999 * np.sqrt(gamma) * s_v)])
    outside = rd_plots([(10000.0, 10.0 + 1.001 * np.sqrt(gamma) * s_v)])
    _, j, d = gate_pairs(z, S_pred, inside, gamma, RANGE_DOPPLER.angles)
    assert j.tolist() == [0] and d[0] == pytest.approx(0.999**2 * gamma)  # 001 [8]-[10]
    assert gate_pairs(z, S_pred, outside, gamma, RANGE_DOPPLER.angles)[1].tolist() == []


def test_module42_without_theta() -> None:
    prev = rd_plots([(10000.0, -50.0)])
    y, s = propagate(prev, dt=2.0, sigma_gamma=0.5, sigma_omega=0.01)
    np.testing.assert_allclose(y, [[9900.0, -50.0]])  # 001 [13]
    np.testing.assert_allclose(s[0], [np.sqrt(100.0**2 + 4 * 2.0**2 + 32 * 0.25 / 20),
                                      np.sqrt(2.0**2 + 8 * 0.25 / 3)])  # 001 [14]
    ys, ss = np.array([[10000.0, 0.0]]), np.array([[50.0, 2.0]])
    inside = rd_plots([(10450.0, 0.0), (10000.0, -40.0)])  # 001 [15]: 3 (100 + 50), Delta_vb
    outside = rd_plots([(10450.5, 0.0), (10000.0, 40.5)])
    assert sorted(compatible(ys, ss, inside, 40.0)[1].tolist()) == [0, 1]
    assert compatible(ys, ss, outside, 40.0)[1].tolist() == []
    cur = rd_plots([(9900.0, -46.0)], sig=(80.0, 1.5))
    x, P = initial_state(prev, cur, np.array([0]), np.array([0]), 2.0, 7.0, 0.03)
    np.testing.assert_allclose(x, [[9900.0, -46.0, 2.0]])  # 001 [16]
    np.testing.assert_allclose(P[0], np.diag([80.0**2, 1.5**2, 49.0]))  # 001 [17]


def test_tracker_update_matches_eq27_eq31() -> None:
    p = ElementaryParams(sigma_gamma=2.0)
    trk = ElementaryTracker(p, RadarCrossingParams(enabled=False), RANGE_DOPPLER)
    trk.step(0.0, rd_plots([(10000.0, -50.0)], 2))
    rep = trk.step(1.0, rd_plots([(9950.0, -50.0)], 2))
    assert rep.x.shape == (1, 3) and rep.P.shape == (1, 3, 3)
    x0, P0 = rep.x[0], rep.P[0]
    F, Q = seed_F(1.0)[:3, :3], seed_Q(1.0, 2.0, 0.0)[:3, :3]
    xp, Pp = F @ x0, F @ P0 @ F.T + Q
    y, H, R = np.array([9905.0, -49.0]), RANGE_DOPPLER.H, np.diag(np.square(SIG))
    K = Pp @ H.T @ np.linalg.inv(H @ Pp @ H.T + R)  # 001 [28]-[29]
    rep = trk.step(2.0, rd_plots([tuple(y)], 2))
    np.testing.assert_allclose(rep.x[0], xp + K @ (y - H @ xp), rtol=1e-9)  # 001 [30]
    np.testing.assert_allclose(rep.P[0], (np.eye(3) - K @ H) @ Pp, rtol=1e-6, atol=1e-9)  # [31]
    with pytest.raises(Rejected) as e:
        trk.step(3.0, Plots.empty(azimuth=True))
    assert e.value.reason == "azimuth_mismatch"


def test_crossing_on_range_and_doppler() -> None:
    """004 on (r_b, v_b): two confirmed tracks on one (r_b, v_b) are flagged ambiguous,
    the same two tracks apart in v_b are not (at an azimuth base the pair is (r_b, theta))."""
    def pair(dv: float) -> np.ndarray:
        trk = ElementaryTracker(ElementaryParams(confirm_score=1.0), RadarCrossingParams(method="supnorm"),
                                RANGE_DOPPLER)
        for k in range(4):
            trk.step(float(k), rd_plots([(2e4 - 50.0 * k, -50.0), (2e4 + 20.0 - 50.0 * k, -50.0 + dv)]))
        return trk.report().ambiguous

    assert pair(0.0).all()
    assert not pair(40.0).any()


def rd_config(n_scans: int) -> tuple[dict, list[RadarBase]]:
    doc = tomllib.loads((SCENARIOS / "two_targets.toml").read_text())
    for b in doc["radar"]["base"]:
        b["azimuth"] = False
    doc["sim"]["n_scans"] = n_scans
    return doc, parse(doc).bases


def run_rd_base(n_scans: int, base_id: str = "b1"):
    """The simulated scans of one range-Doppler base through the wire and both cores:
    yields (plots messages, fused message, etracks payload, tracks, truth) per scan."""
    doc, bases = rd_config(n_scans)
    base = next(b for b in bases if b.id == base_id)
    plotter = PlotFusion(base.channels, base.p, azimuth=False)
    tracker = ElementaryTracker(model=model_of(base.azimuth))
    truth = None
    for _, msgs in run_scenario(load_scenario(doc), bases, [], 3, None):
        sent, scans = [], []
        for key, msg in msgs:
            if key == "sim/truth/radar":
                truth = msg
            elif key.startswith(f"radar/plots/{base_id}/"):
                dec = protocol.decode("plots", protocol.encode(msg))
                sent.append(dec)
                scans += plotter.push(dec["channel"], dec["t"], plots_of(dec, azimuth=False))
        for t, fused in scans:
            fmsg = protocol.decode("fused", protocol.encode(fused_message(base_id, t, fused)))
            tracks = tracker.step(t, plots_of(fmsg, azimuth=False))
            yield sent, fmsg, protocol.encode(etracks_message(base_id, tracks)), tracks, truth, base


def test_range_doppler_base_tracks_two_targets() -> None:
    """Elementary tracks of a range-Doppler base against the truth's r_b, v_b (001 [1]-[2])."""
    held = 0
    for _, _, _, tracks, truth, base in run_rd_base(90):
        if tracks.t < 20.0:
            continue
        pos = np.column_stack([truth[c] for c in "xyz"])
        vel = np.column_stack([truth[f"v{c}"] for c in "xyz"])
        rb, vb = bistatic_range(pos, base.tx, base.rx), bistatic_range_rate(pos, vel, base.tx, base.rx)
        conf = tracks.status != Status.TENTATIVE
        x, P = tracks.x[conf], tracks.P[conf]
        assert x.shape[1] == 3
        for r, v in zip(rb, vb):  # each target has a confirmed track within 4 sigma on r_b and v_b
            err = np.abs(x[:, :2] - [r, v]) / np.sqrt(np.diagonal(P, axis1=1, axis2=2)[:, :2])
            assert (err <= 4.0).all(axis=1).any(), (tracks.t, r, v, x[:, :2])
        assert conf.sum() <= 3, (tracks.t, x)  # two targets, at most one extra (clutter)
        held += 1
    assert held == 70


def test_no_azimuth_reaches_global_fusion_input() -> None:
    """Plots, fused plots and etracks of a range-Doppler base carry no azimuth: the
    etracks payload (global fusion's input) has x = [r_b, v_b, gamma_b], P 3x3, and
    decodes to ElementaryTracks of 3 columns."""
    seen = 0
    for sent, fmsg, payload, tracks, _, _ in run_rd_base(15):
        assert all("az" not in m and "saz" not in m for m in sent)
        assert "az" not in fmsg and "saz" not in fmsg
        raw = protocol.unpack(payload)
        assert raw["azimuth"] is False
        assert all(len(e["x"]) == 3 and len(e["P"]) == 9 for e in raw["tracks"])
        base, et = etracks_of(payload)
        assert et.x.shape == (len(tracks), 3) and et.P.shape == (len(tracks), 3, 3)
        np.testing.assert_array_equal(et.x, tracks.x)  # [r_b, v_b, gamma_b], in that order
        np.testing.assert_array_equal(et.P, tracks.P)
        seen += len(et)
    assert seen > 0


def test_global_fusion_refuses_range_doppler_bases() -> None:
    doc, bases = rd_config(1)
    with pytest.raises(ValueError, match="azimuth = false"):
        GlobalFusion(bases)
    with pytest.raises(ValueError, match="b1, b2, b3"):
        global_fusion(parse(doc))
    az_bases = [RadarBase(b.id, b.tx, b.rx, b.channels, b.p) for b in bases]
    tracks = next(tr for *_, tr, _, _ in run_rd_base(5) if len(tr))
    with pytest.raises(Rejected) as e:  # 3-state tracks sent by a base declared with azimuth
        GlobalFusion(az_bases).push("b1", tracks)
    assert e.value.reason == "no_azimuth"
